"""ctypes bindings of the flight SOCP runtime: bad input, updates, iteration log, errors."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from socp_problems import badly_scaled, random_feasible

from guidance import csocp
from guidance.conic import ConicProblem, same_pattern, solve_clarabel
from guidance.conic import session as conic_session

TESTS = Path(__file__).resolve().parent


def small_soc() -> ConicProblem:
    """min -x1 - x2  s.t. |(x1, x2)| <= 1,  x1 + x2 >= -5,  x1 - x2 = 0."""
    A = sp.csc_matrix(np.array([[1.0, -1.0], [-1.0, -1.0], [0.0, 0.0], [-1.0, 0.0], [0, -1.0]]))
    b = np.array([0.0, 5.0, 1.0, 0.0, 0.0])
    return ConicProblem(
        P=None, q=np.array([-1.0, -1.0]), A=A, b=b, cones=[("zero", 1), ("nonneg", 1), ("soc", 3)]
    )


def test_banded_method_refused_without_structure() -> None:
    """A random dense SOCP has no stage structure: the banded method, asked for, refuses at
    setup with its message; the default falls back to the sparse LDL' method."""
    prob = random_feasible(7, n=40)
    sol = csocp.solve(prob, kkt_backend=csocp.KKT_BANDED)
    assert sol.status == "invalid_input"
    assert "no structure for the banded KKT method" in sol.info["message"]
    auto = csocp.solve(prob)
    assert auto.status == "solved" and int(auto.info["kkt_backend"]) == csocp.KKT_STATIC


def test_banded_method_without_equalities() -> None:
    """Cones only (no equality rows: Y is empty): the banded method solves it, as Clarabel."""
    A = sp.csc_matrix(np.array([[-1.0, 0.0], [0.0, -1.0], [0.0, 0.0], [-1.0, 0.0], [0.0, -1.0]]))
    prob = ConicProblem(  # min -x1 - x2 s.t. x >= 0, |(x1, x2)| <= 1
        P=None,
        q=np.array([-1.0, -1.0]),
        A=A,
        b=np.array([0.0, 0.0, 1.0, 0.0, 0.0]),
        cones=[("nonneg", 2), ("soc", 3)],
    )
    sol = csocp.solve(prob, kkt_backend=csocp.KKT_BANDED)
    ref = solve_clarabel(prob)
    assert sol.status == "solved" and int(sol.info["kkt_backend"]) == csocp.KKT_BANDED
    assert np.allclose(sol.x, ref.x, atol=1e-7)


def test_small_soc_solution_and_duals() -> None:
    prob = small_soc()
    sol = csocp.solve(prob)
    ref = solve_clarabel(prob)
    assert sol.status == "solved"
    assert np.allclose(sol.x, [np.sqrt(0.5)] * 2, atol=1e-8)
    assert np.allclose(sol.z, ref.z, atol=1e-6)
    assert np.allclose(sol.s, ref.s, atol=1e-6)
    assert sol.s[0] == 0.0  # zero-cone slack


@pytest.mark.parametrize(
    ("mutate", "needle"),
    [
        (lambda p: p.q.__setitem__(0, np.nan), "(c[0] = nan;"),  # the entry named
        (lambda p: p.b.__setitem__(2, np.inf), "NaN or infinity"),
        (lambda p: p.b.__setitem__(2, np.inf), "(h[1] = inf;"),  # row 2: the cones' second
        (lambda p: p.A.data.__setitem__(0, np.nan), "(Ax[0] = nan;"),
        (lambda p: p.cones.__setitem__(2, ("soc", 4)), "cones cover more rows"),
        (lambda p: p.cones.__setitem__(2, ("soc", 2)), "cones cover 4 rows"),
        (lambda p: p.cones.__setitem__(0, ("box", 1)), "unknown cone kind"),
        (lambda p: p.cones.__setitem__(0, ("zero", 0)), "dimension must be >= 1"),
    ],
)
def test_bad_input_is_invalid_input(mutate, needle: str) -> None:
    prob = small_soc()
    prob.A = prob.A.copy()
    mutate(prob)
    sol = csocp.solve(prob)
    assert sol.status == "invalid_input"
    assert needle in sol.info["message"]


def test_dimension_mismatch_and_bad_P() -> None:
    prob = small_soc()
    bad = ConicProblem(P=None, q=np.ones(3), A=prob.A, b=prob.b, cones=prob.cones)
    assert csocp.solve(bad).status == "invalid_input"
    lower = sp.csc_matrix(np.array([[1.0, 0.0], [0.5, 1.0]]))  # entry below the diagonal
    bad = ConicProblem(P=lower, q=prob.q, A=prob.A, b=prob.b, cones=prob.cones)
    sol = csocp.solve(bad)
    assert sol.status == "invalid_input"
    assert "upper triangle" in sol.info["message"]
    wrong = ConicProblem(P=sp.csc_matrix(np.eye(3)), q=prob.q, A=prob.A, b=prob.b, cones=prob.cones)
    assert csocp.solve(wrong).status == "invalid_input"


def test_update_equals_fresh_setup_and_no_new_symbolic_work() -> None:
    rng = np.random.default_rng(7)
    prob = random_feasible(3, n=30, with_P=True)
    solver = csocp.Solver(prob)
    first = solver.solve()
    info0 = solver.info()
    for _ in range(3):
        q2 = prob.q + 0.1 * rng.standard_normal(prob.n)
        A2 = prob.A.copy()
        A2.data = A2.data * (1 + 0.05 * rng.standard_normal(A2.nnz))
        b2 = prob.b + 0.1 * np.abs(rng.standard_normal(prob.m))
        P2 = prob.P.copy()
        P2.data = P2.data * 1.1
        assert solver.update(q=q2, A_values=A2.data, b=b2, P_values=P2.data) == 0
        upd = solver.solve()
        fresh = csocp.solve(ConicProblem(P=P2, q=q2, A=A2, b=b2, cones=prob.cones))
        assert upd.status == fresh.status == "solved"
        # the same steps as a fresh setup (equilibration redone on the new numbers)
        assert upd.iterations == fresh.iterations
        np.testing.assert_allclose(upd.x, fresh.x, rtol=0, atol=1e-10)
        assert abs(upd.obj - fresh.obj) <= 1e-12 * max(1, abs(fresh.obj))
        assert solver.info()["factor_nnz"] == info0["factor_nnz"]
    assert first.ok
    # a NaN update makes the workspace refuse to solve until valid data arrive
    assert solver.update(q=np.full(prob.n, np.nan)) != 0
    assert solver.solve().status == "invalid_input"
    assert solver.update(q=prob.q) == 0
    assert solver.solve().status == "solved"


def test_iteration_log_and_info() -> None:
    prob = random_feasible(11)
    solver = csocp.Solver(prob)
    sol = solver.solve(log=True)
    log = sol.info["log"]
    assert len(log) == sol.iterations + 1
    assert [row["iter"] for row in log] == list(range(sol.iterations + 1))
    assert set(log[0]) == {"iter", "pcost", "dcost", "gap", "pres", "dres", "mu", "step"}
    assert log[-1]["pcost"] == pytest.approx(sol.obj)
    assert log[-1]["mu"] < log[0]["mu"]
    # the workspace holds part of the arena it was given; setup's scratch may have used more
    assert 0 < sol.info["arena_used"] <= sol.info["arena_high_water"] <= solver.arena_bytes


def test_max_iterations_status() -> None:
    sol = csocp.solve(random_feasible(5), max_iter=2)
    assert sol.status == "max_iterations"
    assert sol.iterations == 2


def test_unknown_setting_is_an_error() -> None:
    with pytest.raises(TypeError):
        csocp.Solver(small_soc(), tolerance=1)


def _lp_stopped_early() -> ConicProblem:
    """min -x1 - x2 over x >= 0, x1 + x2 <= 10, |x| <= 8: optimum -10 at (5, 5)."""
    A = sp.csc_matrix(np.array([[-1, 0], [0, -1], [1, 1], [0, 0], [-1, 0], [0, -1]], float))
    b = np.array([0.0, 0.0, 10.0, 8.0, 0.0, 0.0])
    return ConicProblem(None, np.array([-1.0, -1.0]), A, b, [("nonneg", 3), ("soc", 3)])


@pytest.mark.parametrize("name", ["tol_gap_abs", "tol_gap_rel", "tol_feas"])
@pytest.mark.parametrize("value", [1.0, 100.0])
def test_a_tolerance_of_one_or_more_is_refused_naming_it(name: str, value: float) -> None:
    """A gap or residual as large as its data certifies nothing (tol_infeas was bounded so
    before): with tol_gap_abs = tol_gap_rel = 1 the runtime stopped this problem at its first
    iterate, objective -7.3, and called it solved (Clarabel: -10)."""
    prob = _lp_stopped_early()
    ref = solve_clarabel(prob)
    assert ref.status == "solved" and ref.obj == pytest.approx(-10.0, abs=1e-6)
    sol = csocp.solve(prob, **{name: value})
    assert sol.status == "invalid_input", (sol.status, sol.obj)
    assert f"{name} must lie within (0, 1), got {value:g}" in sol.info["message"]
    loose = csocp.solve(prob, tol_gap_abs=0.999, tol_gap_rel=0.999, tol_feas=0.999)
    assert loose.status == "solved"  # values below 1 are still taken


@pytest.mark.parametrize(
    ("setting", "value", "named"),
    [("max_iter", 0, "max_iter must lie within 1..500, got 0"),
     ("tol_infeas", 5.0, "tol_infeas must lie within (0, 1), got 5"),
     ("tol_feas_inacc", -1.0, "tol_feas_inacc must be finite and > 0, got -1"),
     ("tol_gap_abs", float("nan"), "tol_gap_abs must be finite and > 0, got nan"),
     ("step_fraction", 1.0, "step_fraction must lie within (0, 1), got 1"),
     ("static_reg", 2.0, "static_reg must lie within (0, 1), got 2"),
     ("refine_iters", 21, "refine_iters must lie within 0..20, got 21"),
     ("ruiz_iters", -1, "ruiz_iters must lie within 0..50, got -1"),
     ("soc_dense_max", 0, "soc_dense_max must be >= 1, got 0"),
     ("kkt_backend", 7,
      "kkt_backend must be TSCVX_KKT_AUTO, _LDL, _STATIC or _BANDED (0..3), got 7")],
)  # fmt: skip
def test_a_bad_setting_is_named_with_its_range(setting: str, value: float, named: str) -> None:
    """The runtime's refusal said only "a setting is out of range", not which one
    (tscvx_check_settings names it; the bindings pass it on)."""
    sol = csocp.solve(random_feasible(3), **{setting: value})
    assert sol.status == "invalid_input"
    assert sol.info["message"] == f"a setting is out of range: {named}"


def test_missing_library_message(monkeypatch, tmp_path) -> None:
    monkeypatch.setenv("TSCVX_LIB", str(tmp_path / "nope.so"))
    monkeypatch.setattr(csocp, "_lib_cache", None)
    with pytest.raises(csocp.LibraryNotBuiltError, match="make lib"):
        csocp.solve(small_soc())


def test_session_reuses_the_workspace() -> None:
    prob = random_feasible(21, n=25)
    session = csocp.Session()
    for scale in (1.0, 1.5, 2.0):
        p = ConicProblem(P=prob.P, q=prob.q * scale, A=prob.A, b=prob.b * scale, cones=prob.cones)
        sol = session.solve(p)
        ref = solve_clarabel(p)
        assert sol.status == "solved"
        assert abs(sol.obj - ref.obj) <= 1e-6 * max(1, abs(ref.obj))
    assert session.setups == 1


@pytest.mark.parametrize("backend", ["clarabel", "c"])
def test_a_session_given_another_pattern_solves_that_problem(backend: str) -> None:
    """A session fed a problem whose A has another pattern (same size, same number of
    entries) solves that problem, as a fresh solve does; the Clarabel session used to write
    the new numbers into the old pattern and return the answer of another problem."""
    q, b = np.array([1.0, 2.0]), np.array([-1.0, -3.0])  # min x1 + 2 x2, rows >= (1, 3)
    diag = sp.csc_matrix(np.array([[-1.0, 0.0], [0.0, -1.0]]))  # x1 >= 1, x2 >= 3
    anti = sp.csc_matrix(np.array([[0.0, -1.0], [-1.0, 0.0]]))  # x2 >= 1, x1 >= 3
    session = conic_session(backend)
    for A, x in ((diag, [1.0, 3.0]), (anti, [3.0, 1.0]), (diag, [1.0, 3.0])):
        prob = ConicProblem(P=None, q=q, A=A, b=b, cones=[("nonneg", 2)])
        sol = session.solve(prob)
        assert sol.status == "solved"
        assert np.allclose(sol.x, x, atol=1e-7)
        assert np.allclose(sol.x, solve_clarabel(prob).x, atol=1e-7)


@pytest.mark.parametrize("backend", ["clarabel", "c"])
def test_a_session_given_another_p_pattern_solves_that_problem(backend: str) -> None:
    """The same for P: a box QP whose P = 4 I sits on columns 0..2, then on columns 3..5
    (same size, same number of entries, same A). Matching patterns on A alone would write
    the second P's numbers into the first's pattern and solve another problem (review of
    26 Nov: a Pattern.matches that ignored P failed no test)."""
    n = 6
    q = -np.array([1.0, 2.0, 3.0, 5.0, 6.0, 7.0])  # no x_j on its bound with a zero dual
    A = sp.csc_matrix(np.vstack([np.eye(n), -np.eye(n)]))  # -1 <= x <= 1
    b = np.ones(2 * n)

    def box_qp(cols: list[int]) -> ConicProblem:
        P = sp.csc_matrix((4.0 * np.ones(3), (cols, cols)), shape=(n, n))
        return ConicProblem(P=P, q=q, A=A, b=b, cones=[("nonneg", 2 * n)])

    first, second = box_qp([0, 1, 2]), box_qp([3, 4, 5])
    assert not same_pattern(first, second)
    session = conic_session(backend)
    for prob in (first, second, first):
        # x_j = min(1, -q_j / 4) where P has the column, else the bound 1
        x = np.ones(n)
        cols = prob.P.indices
        x[cols] = np.minimum(1.0, -q[cols] / 4.0)
        sol = session.solve(prob)
        assert sol.status == "solved"
        np.testing.assert_allclose(sol.x, x, atol=1e-7)
        assert abs(sol.obj - solve_clarabel(prob).obj) <= 1e-7


def test_threads_sharing_a_solver_or_a_session_take_turns() -> None:
    """One workspace, two threads solving at once: each call is served whole, every answer
    is the lone solve's to the bit (unguarded, the C workspace was corrupted: a crash)."""
    prob = random_feasible(3, n=50)
    solver, session = csocp.Solver(prob), csocp.Session()
    alone = solver.solve()
    answers: list = []

    def solve_repeatedly() -> None:
        for _ in range(20):
            answers.append(solver.solve())
            answers.append(session.solve(prob))

    threads = [threading.Thread(target=solve_repeatedly) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(answers) == 80
    for sol in answers:
        assert sol.status == alone.status == "solved"
        np.testing.assert_array_equal(sol.x, alone.x)


# ---- status logic against Clarabel and hand-checked bounds ----------------------------------


def _c_defaults() -> dict[str, float]:
    import ctypes as ct

    st = csocp._Settings()
    csocp.load_library().tscvx_default_settings(ct.byref(st))
    return {name: getattr(st, name) for name, _ in csocp._SETTING_FIELDS}


def test_reduced_tolerances_default_to_clarabels() -> None:
    """The 'solved_inaccurate' bars are Clarabel's reduced tolerances (DefaultSettings)."""
    clarabel = pytest.importorskip("clarabel")
    ref = clarabel.DefaultSettings()
    d = _c_defaults()
    assert d["tol_feas_inacc"] == ref.reduced_tol_feas
    assert d["tol_gap_abs_inacc"] == ref.reduced_tol_gap_abs
    assert d["tol_gap_rel_inacc"] == ref.reduced_tol_gap_rel


def test_iteration_limit_feasibility_above_the_reduced_tolerance_is_not_inaccurate() -> None:
    """Two iterations leave residuals of ~1e-3 (> 1e-4, the default reduced feasibility
    tolerance); with the gap bars opened up only that tolerance decides: max_iterations by
    default, solved_inaccurate once tol_feas_inacc is raised above the residuals."""
    prob = random_feasible(0, n=20)
    loose = {"max_iter": 2, "tol_gap_abs_inacc": 1e3, "tol_gap_rel_inacc": 1.0}
    sol = csocp.solve(prob, **loose)
    worst = max(sol.info["pres"], sol.info["dres"])
    assert 1e-4 < worst < 1e-2, worst
    assert sol.status == "max_iterations"
    assert csocp.solve(prob, tol_feas_inacc=1e-2, **loose).status == "solved_inaccurate"


@pytest.mark.parametrize("seed", range(4))
def test_iteration_limit_returns_the_best_iterate(seed: int) -> None:
    """Stopped one or two iterations short, the solver hands back its best iterate: residuals
    no worse than the last logged iterate's, x close to Clarabel's, solved_inaccurate."""
    prob = random_feasible(seed, n=20)
    ref = solve_clarabel(prob)
    full = csocp.solve(prob)
    assert ref.status == full.status == "solved"
    for short in (1, 2):
        sol = csocp.solve(prob, log=True, max_iter=full.iterations - short)
        assert sol.status == "solved_inaccurate", (short, sol.status)
        scale = max(1.0, float(np.abs(ref.x).max()))
        assert float(np.abs(sol.x - ref.x).max()) <= 1e-3 * scale
        log = sol.info["log"]
        assert max(sol.info["pres"], sol.info["dres"]) <= max(log[-1]["pres"], log[-1]["dres"])


def _distance(pres: float, dres: float, gap: float, pcost: float, optimum: float) -> float:
    """How far an iterate is from the answer: its relative residuals, and its gap and
    objective error relative to the optimum's size (Clarabel's optimum), floored at 1e-8
    (Clarabel's own accuracy)."""
    size = max(1.0, abs(optimum))
    return max(pres, dres, gap / size, abs(pcost - optimum) / size, 1e-8)


def _check_iteration_limits(prob: ConicProblem, limits: range, **settings: float) -> bool:
    """Stopped by each limit in `limits`, the runtime's point is within 10 x the distance
    (_distance) of the best iterate it went through (its log). False (nothing checked) where
    Clarabel does not solve the problem at 1e-9 or 1e-8."""
    ref = solve_clarabel(prob)
    if ref.status != "solved":
        ref = solve_clarabel(prob, tol=1e-8)
    if ref.status != "solved":
        return False
    for limit in limits:
        sol = csocp.solve(prob, log=True, max_iter=limit, **settings)
        if sol.status == "solved":
            break
        assert sol.status in ("max_iterations", "solved_inaccurate"), (limit, sol.status)
        inf = sol.info
        got = _distance(inf["pres"], inf["dres"], inf["gap_abs"], inf["pcost"], ref.obj)
        each = [_distance(r["pres"], r["dres"], r["gap"], r["pcost"], ref.obj) for r in inf["log"]]
        best = int(np.argmin(each))
        assert got <= 10.0 * each[best], (limit, got, best, each[best])
    return True


@pytest.mark.parametrize("family", [random_feasible, badly_scaled])
@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4, 5, 6, 8])
def test_iteration_limit_returns_no_clearly_worse_iterate(family, seed: int) -> None:
    """Every iteration limit short of the answer: the point returned is no more than 10 times
    as far from the answer (residuals, gap, objective against Clarabel's) as the best iterate
    the solve went through. The best iterate was picked by each iterate's gap relative to its
    own costs: an early iterate with costs far off (in the hundreds) scored a relative gap
    near 1 and was returned in place of a later one 20 to 100 times closer (seed 4 at limit
    3: iterate 1). With tolerances (1e-15) below what the arithmetic reaches, the last iterates
    get worse again (residuals 1e-15, then 1e-4): the last iterate is not the answer either."""
    prob = family(seed)
    assert _check_iteration_limits(prob, range(1, 40))
    tight = {"tol_feas": 1e-15, "tol_gap_abs": 1e-15, "tol_gap_rel": 1e-15}
    assert _check_iteration_limits(prob, range(10, 41, 10), **tight)


def test_iteration_limit_on_landing_subproblems_returns_no_clearly_worse_iterate() -> None:
    """The same on the default landing's subproblems (subproblem 7 at limit 4 returned iterate
    2, 100 times as far from the answer as iterate 4)."""
    scvx = pytest.importorskip("guidance.scvx")
    catalog = pytest.importorskip("guidance.catalog")
    probs = scvx.collect_subproblems(catalog.SCENARIOS["default"])
    checked = sum(_check_iteration_limits(prob, range(1, 40)) for prob in probs)
    assert checked >= len(probs) - 3, (checked, len(probs))


@pytest.mark.parametrize("seed", range(4))
def test_cost_scaled_by_1e6_still_solves(seed: int) -> None:
    """Cost x 1e6: the relative gap still stops the solver (the absolute one cannot); the
    objective is Clarabel's x 1e6."""
    prob = random_feasible(seed, n=20)
    ref = solve_clarabel(prob)
    P = None if prob.P is None else prob.P * 1e6
    big = ConicProblem(P=P, q=prob.q * 1e6, A=prob.A, b=prob.b, cones=prob.cones)
    sol = csocp.solve(big)
    base = csocp.solve(prob)
    assert sol.status == "solved", sol.status
    assert abs(sol.obj / 1e6 - ref.obj) <= 1e-6 * max(1.0, abs(ref.obj))
    assert sol.iterations <= base.iterations + 6


@pytest.mark.parametrize("seed", range(6))
def test_feasibility_problem_is_solved(seed: int) -> None:
    """c = 0, P = 0 on strictly feasible constraints: solved (as Clarabel), with a feasible
    point (Clarabel's primal residual), never declared infeasible."""
    prob = random_feasible(seed, n=20)
    feas = ConicProblem(P=None, q=np.zeros(prob.n), A=prob.A, b=prob.b, cones=prob.cones)
    ref = solve_clarabel(feas)
    sol = csocp.solve(feas)
    assert ref.status == "solved"
    assert sol.status == "solved", sol.status
    pres = np.linalg.norm(feas.A @ sol.x + sol.s - feas.b, np.inf) / (
        1.0 + np.linalg.norm(feas.b, np.inf)
    )
    assert pres <= 1e-7


@pytest.mark.parametrize("c", [0.0, 1.0])
def test_weakly_infeasible_soc_is_not_solved(c: float) -> None:
    """x1 = x2 with (x1, x2, 1) in a second-order cone: infeasible, yet at distance 0 from
    feasibility (no certificate). Clarabel ends it numerical_error; so must the runtime,
    well within max_iter, and never report it solved."""
    A = sp.csc_matrix(np.array([[1.0, -1.0], [-1.0, 0.0], [0.0, -1.0], [0.0, 0.0]]))
    prob = ConicProblem(
        P=None,
        q=np.array([c, 0.0]),
        A=A,
        b=np.array([0.0, 0.0, 0.0, 1.0]),
        cones=[("zero", 1), ("soc", 3)],
    )
    ref = solve_clarabel(prob)
    sol = csocp.solve(prob)
    assert ref.status == sol.status == "numerical_error"
    assert sol.iterations < 100


def test_empty_rows_do_not_stall_equilibration() -> None:
    """T-SCvx's masked-out cones are rows of G without entries (h = e, trivially met). Ruiz
    equilibration cannot balance an empty row, so it must judge balance on the others: the
    padded problem takes the same passes as the plain one (fewer than the limit) and the
    same optimal value, Clarabel's."""
    plain = random_feasible(1, n=30)
    extra = 3 * 3  # three empty 3-dim SOCs, each [1; 0; 0]
    padded = ConicProblem(
        P=plain.P,
        q=plain.q,
        A=sp.vstack([plain.A, sp.csc_matrix((extra, plain.n))]).tocsc(),
        b=np.concatenate([plain.b, np.tile([1.0, 0.0, 0.0], 3)]),
        cones=plain.cones + [("soc", 3)] * 3,
    )
    limit = 15  # the default
    a, b = csocp.solve(plain, ruiz_iters=limit), csocp.solve(padded, ruiz_iters=limit)
    assert a.status == b.status == "solved"
    assert int(b.info["ruiz_passes"]) == int(a.info["ruiz_passes"]) < limit
    assert b.obj == pytest.approx(a.obj, rel=1e-7)
    assert b.obj == pytest.approx(solve_clarabel(padded).obj, rel=1e-6)


def test_initial_mu_by_hand() -> None:
    """min x1 + 2 x2 s.t. x >= 0, no equilibration (ruiz_iters = 0). By hand: cost scaling
    cs = 1/|c|_inf = 1/2, so c_s = (1/2, 1). Initial primal point: x = 0, s = h - G x = 0,
    shifted so its smallest entry is 1: s = (1, 1). Dual: z = c_s = (1/2, 1), shifted by
    1 - 1/2: z = (1, 3/2). tau = kappa = 1. mu = (s'z + tau kappa) / (degree + 1)
    = (1 + 3/2 + 1) / 3 = 7/6."""
    prob = ConicProblem(
        P=None,
        q=np.array([1.0, 2.0]),
        A=sp.csc_matrix(-np.eye(2)),
        b=np.zeros(2),
        cones=[("nonneg", 2)],
    )
    sol = csocp.solve(prob, log=True, ruiz_iters=0)
    assert sol.status == "solved"
    assert sol.info["log"][0]["mu"] == pytest.approx(7.0 / 6.0, rel=1e-9)


def _scrambled(M: sp.csc_matrix, rng: np.random.Generator) -> sp.csc_matrix:
    """M with the entries of every column stored in a random order (a valid CSC matrix whose
    row indices are not sorted)."""
    M = sp.csc_matrix(M)
    order = np.concatenate(
        [lo + rng.permutation(hi - lo) for lo, hi in zip(M.indptr[:-1], M.indptr[1:], strict=True)]
    )
    S = sp.csc_matrix((M.data[order], M.indices[order], M.indptr.copy()), M.shape)
    assert not S.has_sorted_indices
    return S


@pytest.mark.parametrize("seed", [3, 4, 6, 7])
def test_unsorted_rows_are_solved_as_stored_and_left_as_given(seed: int) -> None:
    """A and P whose columns store their rows out of order are the same matrices: the runtime
    gives the answer of the sorted copies to the bit (Clarabel's optimum), and the caller's
    matrices keep their arrays (the pattern map once sorted them in place, moving the rows
    under the values); update() takes values in the caller's stored order."""
    rng = np.random.default_rng(seed)
    ref_prob = random_feasible(seed, n=20, with_P=True)
    A, P = _scrambled(ref_prob.A, rng), _scrambled(sp.triu(ref_prob.P, format="csc"), rng)
    kept = [a.copy() for a in (A.indices, A.data, P.indices, P.data)]
    prob = ConicProblem(P=P, q=ref_prob.q, A=A, b=ref_prob.b, cones=ref_prob.cones)
    solver = csocp.Solver(prob)
    sol, sorted_sol, ref = solver.solve(), csocp.solve(ref_prob), solve_clarabel(ref_prob)
    assert sol.status == sorted_sol.status == ref.status == "solved"
    assert np.array_equal(sol.x, sorted_sol.x)
    assert abs(sol.obj - ref.obj) <= 1e-6 * max(1.0, abs(ref.obj))
    for a, b in zip((A.indices, A.data, P.indices, P.data), kept, strict=True):
        assert np.array_equal(a, b)
    # new values in each one's stored order: the same problem again, the same bits
    sorted_solver = csocp.Solver(ref_prob)
    assert solver.update(A_values=np.sqrt(2.0) * A.data) == 0
    assert sorted_solver.update(A_values=np.sqrt(2.0) * sp.csc_matrix(ref_prob.A).data) == 0
    assert np.array_equal(solver.solve().x, sorted_solver.solve().x)


@pytest.mark.parametrize("which", ["A", "P"])
def test_duplicate_entries_are_refused_and_left_as_given(which: str) -> None:
    """Two stored entries at one (row, column) are refused by name, before any solve (they
    crashed with an IndexError, and the caller's matrix lost one of them)."""
    prob = small_soc()
    if which == "A":  # small_soc's A with its entry (0, 0) = 1 stored as 0.5 + 0.5
        M = sp.csc_matrix(
            (np.array([0.5, 0.5, -1, -1, -1, -1, -1.0]), np.array([0, 0, 1, 3, 0, 1, 4]),
             np.array([0, 4, 7])), shape=(5, 2)
        )  # fmt: skip
        assert np.array_equal(M.toarray(), prob.A.toarray())
        prob = ConicProblem(P=None, q=prob.q, A=M, b=prob.b, cones=prob.cones)
    else:  # P = I with its entry (0, 0) stored as 0.5 + 0.5
        M = sp.csc_matrix(
            (np.array([0.5, 0.5, 1.0]), np.array([0, 0, 1]), np.array([0, 2, 3])), shape=(2, 2)
        )
        prob = ConicProblem(P=M, q=prob.q, A=prob.A, b=prob.b, cones=prob.cones)
    kept = (M.indices.copy(), M.data.copy(), M.indptr.copy())
    with pytest.raises(csocp.InvalidProblemError, match="duplicate entries"):
        csocp.Solver(prob)
    after = (M.indices, M.data, M.indptr)
    assert all(np.array_equal(a, b) for a, b in zip(after, kept, strict=True))


# ---- the Solver and the sessions own what they were set up with (26 Nov) --------------------


def _copy(prob: ConicProblem) -> ConicProblem:
    P = None if prob.P is None else prob.P.copy()
    return ConicProblem(
        P=P, q=prob.q.copy(), A=prob.A.copy(), b=prob.b.copy(), cones=list(prob.cones)
    )


def _sorted_csc(M: sp.spmatrix) -> sp.csc_matrix:
    C = sp.csc_matrix(M, copy=True)
    C.sort_indices()
    return C


def _reference(P, q, A, b, cones) -> ConicProblem:
    """The problem with canonical CSC copies of its matrices (what Clarabel is given)."""
    P = None if P is None else _sorted_csc(P)
    return ConicProblem(P=P, q=np.asarray(q), A=_sorted_csc(A), b=np.asarray(b), cones=list(cones))


def test_a_solver_keeps_its_sizes_and_numbers_when_the_caller_changes_its_problem() -> None:
    """The caller reuses its problem object after the set-up (longer q and b, new A values,
    other cones): the Solver answers the problem it was set up with, as a fresh solve of a
    copy does (it read n and m from the caller's object at each solve)."""
    base = random_feasible(3, n=10, with_P=True)
    prob = _copy(base)
    solver = csocp.Solver(prob)
    prob.q, prob.b = np.r_[prob.q, 1.0, 2.0], np.r_[prob.b, 3.0]
    prob.A.data *= 3.0
    prob.cones.reverse()
    sol, fresh = solver.solve(), csocp.solve(base)
    assert sol.status == fresh.status == "solved"
    assert sol.x.shape == (base.n,) and sol.z.shape == sol.s.shape == (base.m,)
    np.testing.assert_array_equal(sol.x, fresh.x)
    assert solver.warm_start(fresh) == 0  # a solution of the set-up's sizes is taken


def test_a_caller_shortening_its_q_after_set_up_is_not_written_past() -> None:
    """q shortened to one entry after the set-up: the solve wrote n doubles into an array of
    one (a segmentation fault at exit); it must return the set-up's n entries."""
    code = (
        "from guidance import csocp\n"
        "from socp_problems import random_feasible\n"
        "prob = random_feasible(3, n=40, with_P=True)\n"
        "solver = csocp.Solver(prob)\n"
        "prob.q = prob.q[:1]\n"
        "sol = solver.solve()\n"
        "print(sol.status, sol.x.shape[0])\n"
    )
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(TESTS), os.environ.get("PYTHONPATH", "")])
    )
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.split() == ["solved", "40"]


def _non_psd(prob: ConicProblem) -> ConicProblem:
    bad = _copy(prob)
    bad.P.data = -bad.P.data  # negative diagonal
    return bad


def _nan_q(prob: ConicProblem) -> ConicProblem:
    bad = _copy(prob)
    bad.q[-1] = np.nan
    return bad


@pytest.mark.parametrize("spoil", [_nan_q, _non_psd])
def test_a_session_solves_the_next_problem_after_a_refused_one(spoil) -> None:
    """A problem whose set-up the runtime refuses (NaN in q, an indefinite P) is answered
    invalid_input; the next valid problem of the same pattern is solved, as a fresh solve and
    Clarabel do (the session kept the refused set-up and refused every later problem)."""
    good = random_feasible(3, n=10, with_P=True)
    bad = spoil(good)
    fresh, ref = csocp.solve(good), solve_clarabel(good)
    session = csocp.Session()
    for prob in (bad, good, bad, good):
        sol = session.solve(prob)
        if prob is bad:
            assert sol.status == "invalid_input" == csocp.solve(bad).status
            continue
        assert sol.status == fresh.status == "solved" and ref.ok
        np.testing.assert_allclose(sol.x, fresh.x, rtol=0, atol=1e-7)
        assert abs(sol.obj - ref.obj) <= 1e-6 * max(1.0, abs(ref.obj))


def _shuffled_coo(M: sp.spmatrix, rng: np.random.Generator) -> sp.coo_matrix:
    C = sp.coo_matrix(M)
    k = rng.permutation(C.nnz)
    return sp.coo_matrix((C.data[k], (C.row[k], C.col[k])), shape=C.shape)


def _assert_same_optimum(sol, ref) -> None:
    """Both solved (to full or reduced accuracy), the same optimal value and point (x to the
    1e-4 that gap-based stopping leaves on these strongly convex problems)."""
    assert sol.ok and ref.ok, (sol.status, ref.status)
    assert abs(sol.obj - ref.obj) <= 1e-6 * max(1.0, abs(ref.obj))
    np.testing.assert_allclose(sol.x, ref.x, rtol=0, atol=1e-4)


def _strongly_convex(seed: int) -> ConicProblem:
    """random_feasible(seed, n=10) with P + I: one well-determined optimal x."""
    prob = random_feasible(seed, n=10, with_P=True)
    prob.P = sp.csc_matrix(sp.triu(prob.P + sp.eye(prob.n), format="csc"))
    return prob


def _reversed_rows(M: sp.spmatrix) -> sp.csc_matrix:
    """M as CSC with the rows of every column stored in descending order (unsorted)."""
    C = sp.csc_matrix(M)
    order = np.concatenate(
        [np.arange(lo, hi)[::-1] for lo, hi in zip(C.indptr[:-1], C.indptr[1:], strict=True)]
    )
    R = sp.csc_matrix((C.data[order], C.indices[order], C.indptr.copy()), C.shape)
    assert not R.has_sorted_indices
    return R


def _in_format(M: sp.spmatrix, fmt: str, rng: np.random.Generator) -> sp.spmatrix:
    if fmt == "csr":
        return sp.csr_matrix(M)
    if fmt == "coo":
        return _shuffled_coo(M, rng)
    if fmt == "csc-unsorted":
        return _reversed_rows(M)
    return sp.lil_matrix(M)


def _entry_positions(M: sp.spmatrix) -> tuple[np.ndarray, np.ndarray]:
    """Row and column of each value in the caller's value order (see _rescaled)."""
    if M.format == "coo":
        return M.row, M.col
    C = M if M.format in ("csc", "csr") else sp.csc_matrix(M)
    major = np.repeat(np.arange(C.shape[C.format == "csr"]), np.diff(C.indptr))
    return (C.indices, major) if C.format == "csc" else (major, C.indices)


def _rescaled(M: sp.spmatrix, w: np.ndarray) -> tuple[sp.spmatrix, np.ndarray]:
    """M with its values times w (in the caller's value order), and those values: M.data for
    CSC, CSR and COO, csc_matrix(M).data for other formats."""
    if M.format in ("csc", "csr", "coo"):
        M2 = M.copy()
        M2.data = M.data * w
        return M2, M2.data
    C = sp.csc_matrix(M)
    M2 = sp.csc_matrix((C.data * w, C.indices, C.indptr), C.shape)
    return M2, M2.data


def _new_values(A: sp.spmatrix, P: sp.spmatrix):
    """A and P with new values (each entry its own factor; P as D P D, still semidefinite),
    and those values in the caller's order."""
    A2, A_values = _rescaled(A, np.linspace(0.7, 1.3, A.nnz))
    d = np.linspace(0.5, 2.0, P.shape[0])
    rows, cols = _entry_positions(P)
    P2, P_values = _rescaled(P, d[rows] * d[cols])
    return A2, A_values, P2, P_values


@pytest.mark.parametrize("fmt", ["csr", "coo", "csc-unsorted", "lil"])
def test_update_takes_values_in_the_callers_order_for_every_format(fmt: str) -> None:
    """update(A_values=, P_values=) takes the values in the caller's order (A.data for CSC,
    CSR and COO, csc_matrix(A).data otherwise): the answer is Clarabel's on the new matrices
    (it read CSR and COO values as if in CSC order: another problem, or P 'not PSD')."""
    rng = np.random.default_rng(5)
    base = _strongly_convex(3)
    A1, P1 = _in_format(base.A, fmt, rng), _in_format(base.P, fmt, rng)
    solver = csocp.Solver(ConicProblem(P=P1, q=base.q, A=A1, b=base.b, cones=base.cones))
    _assert_same_optimum(solver.solve(), solve_clarabel(base))
    A2, A_values, P2, P_values = _new_values(A1, P1)
    assert solver.update(A_values=A_values, P_values=P_values) == 0, solver.message
    sol = solver.solve()
    _assert_same_optimum(sol, solve_clarabel(_reference(P2, base.q, A2, base.b, base.cones)))


def test_coo_duplicates_are_refused() -> None:
    """A COO matrix with two stored entries at one position is refused, as CSC and CSR ones
    are (README); it was summed."""
    base = random_feasible(3, n=10, with_P=True)
    C = sp.coo_matrix(base.A)
    halves = np.r_[C.data[:-1], C.data[-1] / 2, C.data[-1] / 2]
    A = sp.coo_matrix((halves, (np.r_[C.row, C.row[-1]], np.r_[C.col, C.col[-1]])), C.shape)
    prob = ConicProblem(P=base.P, q=base.q, A=A, b=base.b, cones=base.cones)
    with pytest.raises(csocp.InvalidProblemError, match="duplicate entries"):
        csocp.Solver(prob)
    assert csocp.solve(prob).status == "invalid_input"


@pytest.mark.parametrize("fmt", ["csr", "coo", "csc-unsorted"])
@pytest.mark.parametrize("backend", ["clarabel", "c"])
def test_sessions_take_new_values_in_any_format_and_storage_order(backend: str, fmt: str) -> None:
    """A session's second problem (same pattern, new values) stored as CSR, shuffled COO or
    CSC with unsorted rows (P too) is solved as Clarabel solves it afresh (the Clarabel
    session passed the values in the caller's storage order, not Clarabel's sorted CSC)."""
    rng = np.random.default_rng(2)
    base = _strongly_convex(3)
    A1, P1 = _in_format(base.A, fmt, rng), _in_format(base.P, "csc-unsorted", rng)
    A2, _, P2, _ = _new_values(A1, P1)
    session = conic_session(backend)
    for P, A in ((P1, A1), (P2, A2)):
        sol = session.solve(ConicProblem(P=P, q=base.q, A=A, b=base.b, cones=base.cones))
        _assert_same_optimum(sol, solve_clarabel(_reference(P, base.q, A, base.b, base.cones)))


def _sort_rows_in_place(prob: ConicProblem) -> None:
    prob.A.sort_indices()


def _cones_edited_in_place(prob: ConicProblem) -> None:
    prob.cones[0] = prob.cones[1] = ("nonneg", 1)
    prob.cones[4] = ("nonneg", 2)


def _A_reassigned(prob: ConicProblem) -> None:
    C = sp.coo_matrix(prob.A)
    prob.A = sp.csc_matrix((C.data, ((C.row + 1) % prob.m, C.col)), shape=C.shape)


@pytest.mark.parametrize("mutate", [_sort_rows_in_place, _cones_edited_in_place, _A_reassigned])
@pytest.mark.parametrize("backend", ["clarabel", "c"])
def test_sessions_compare_with_a_snapshot_not_the_callers_object(backend: str, mutate) -> None:
    """The caller changes its own problem object between two solves (sorts A's rows in place,
    edits its cones list, assigns another A): the session answers the changed problem, as
    Clarabel does afresh (it compared the new problem with the same object: always equal)."""
    base = random_feasible(3, n=10, with_P=True)
    assert base.cones[:2] == [("zero", 1), ("zero", 1)] and base.cones[4] == ("zero", 2)
    prob = _copy(base)
    prob.A = _reversed_rows(prob.A)
    session = conic_session(backend)
    assert session.solve(prob).status == "solved"
    mutate(prob)
    sol = session.solve(prob)
    ref = solve_clarabel(_reference(prob.P, prob.q, prob.A, prob.b, prob.cones))
    assert sol.ok == ref.ok
    if ref.ok:
        assert abs(sol.obj - ref.obj) <= 1e-6 * max(1.0, abs(ref.obj))
    else:
        assert sol.status == ref.status


def test_same_pattern_requires_equal_sizes() -> None:
    prob = random_feasible(3, n=10, with_P=True)
    longer_q = ConicProblem(P=prob.P, q=np.r_[prob.q, 0.0], A=prob.A, b=prob.b, cones=prob.cones)
    longer_b = ConicProblem(P=prob.P, q=prob.q, A=prob.A, b=np.r_[prob.b, 0.0], cones=prob.cones)
    assert same_pattern(prob, _copy(prob))
    assert not same_pattern(prob, longer_q) and not same_pattern(longer_q, prob)
    assert not same_pattern(prob, longer_b)


_PROB = random_feasible(3, n=10, with_P=True)
_BAD_UPDATES = {
    "q short": {"q": _PROB.q[:-1]},
    "q long": {"q": np.r_[_PROB.q, 0.0]},
    "q scalar": {"q": 1.0},
    "q column": {"q": _PROB.q[:, None]},
    "b short": {"b": _PROB.b[:-1]},
    "b long": {"b": np.r_[_PROB.b, 1.0]},
    "A_values short": {"A_values": _PROB.A.data[:-1]},
    "A_values twice": {"A_values": np.tile(_PROB.A.data, 2)},
    "A_values dense": {"A_values": _PROB.A.toarray()},
    "A_values sparse": {"A_values": _PROB.A},
    "P_values short": {"P_values": _PROB.P.data[:-1]},
}


@pytest.mark.parametrize("case", list(_BAD_UPDATES))
def test_update_refuses_arrays_that_do_not_fit_and_changes_nothing(case: str) -> None:
    """An array of the wrong shape raises InvalidProblemError naming the argument, before
    anything is changed: the next solve is the set-up's again (it raised IndexError or
    ValueError after overwriting q, or took the array: a scalar q broadcast, a longer b cut)."""
    bad = _BAD_UPDATES[case]
    name = next(iter(bad))
    other = {"A_values": 2.0 * _PROB.A.data} if name == "q" else {"q": 2.0 * _PROB.q}
    solver = csocp.Solver(_PROB)
    before = solver.solve()
    with pytest.raises(csocp.InvalidProblemError, match=name):
        solver.update(**other, **bad)
    after = solver.solve()
    assert after.status == before.status == "solved"
    np.testing.assert_array_equal(after.x, before.x)


def test_update_refuses_P_values_without_P() -> None:
    prob = random_feasible(3, n=10, with_P=False)
    solver = csocp.Solver(prob)
    with pytest.raises(csocp.InvalidProblemError, match="P_values"):
        solver.update(P_values=np.ones(7))


@pytest.mark.parametrize("value", [2**32 + 3, -(2**31) - 1])
def test_integer_setting_outside_c_int_is_refused(value: int) -> None:
    """ctypes truncated max_iter = 2**32 + 3 to 3 without a word."""
    prob = random_feasible(3, n=10, with_P=True)
    with pytest.raises(csocp.InvalidProblemError, match="max_iter"):
        csocp.Solver(prob, max_iter=value)
    sol = csocp.solve(prob, max_iter=value)
    assert sol.status == "invalid_input" and "max_iter" in sol.info["message"]


def test_fractional_cone_dimension_is_refused() -> None:
    """('soc', 3.9) was read as ('soc', 3) and the problem solved."""
    A = sp.csc_matrix(np.vstack([-np.eye(3), -np.eye(3)]))
    prob = ConicProblem(
        P=sp.csc_matrix(np.diag([1.0, 2.0, 3.0])),
        q=np.array([1.0, -1.0, 2.0]),
        A=A,
        b=np.r_[1.0, 0, 0, 0, 0, 0],
        cones=[("soc", 3.9), ("nonneg", 3)],
    )
    sol = csocp.solve(prob)
    assert sol.status == "invalid_input" and "whole number" in sol.info["message"]
    ref = solve_clarabel(ConicProblem(prob.P, prob.q, A, prob.b, [("soc", 3), ("nonneg", 3)]))
    prob.cones[0] = ("soc", 3.0)  # a whole number, as a float: accepted
    sol = csocp.solve(prob)
    assert sol.status == ref.status == "solved"
    assert abs(sol.obj - ref.obj) <= 1e-6 * max(1.0, abs(ref.obj))


def test_message_is_ok_again_after_a_successful_update() -> None:
    prob = random_feasible(3, n=10, with_P=True)
    solver = csocp.Solver(prob)
    assert solver.message == "ok"
    assert solver.update(q=np.full(prob.n, np.nan)) != 0
    assert "NaN" in solver.message
    assert solver.update(q=prob.q) == 0
    assert solver.message == "ok"
    assert solver.solve().status == "solved"


def test_q_and_b_may_be_lists() -> None:
    prob = random_feasible(3, n=10, with_P=True)
    listed = ConicProblem(P=prob.P, q=list(prob.q), A=prob.A, b=list(prob.b), cones=prob.cones)
    assert (listed.n, listed.m) == (prob.n, prob.m)
    sol, ref = csocp.solve(listed), solve_clarabel(prob)
    assert sol.status == ref.status == "solved"
    assert abs(sol.obj - ref.obj) <= 1e-6 * max(1.0, abs(ref.obj))


@pytest.mark.parametrize("backend", ["clarabel", "c"])
def test_a_session_solve_takes_a_lower_iteration_limit_and_the_next_gets_its_own_back(
    backend: str,
) -> None:
    """session.solve(max_iter=k) stops that solve within k IPM iterations (what SCvx's
    iteration budget gives a subproblem); the next solve without it has the session's limit
    again and the unlimited answer."""
    prob = random_feasible(5, n=30)
    session = conic_session(backend, 1e-9, 200)
    session.solve(prob)  # set-up (Clarabel's fresh set-up and its updates can differ)
    full = session.solve(prob)
    assert full.status == "solved" and full.iterations > 4
    capped = session.solve(prob, max_iter=3)
    assert capped.status in ("max_iterations", "solved_inaccurate")
    assert capped.iterations <= 3
    again = session.solve(prob)
    assert again.status == "solved" and again.iterations == full.iterations
    np.testing.assert_array_equal(again.x, full.x)


def test_a_limit_above_the_setup_one_is_refused_by_name() -> None:
    """The set-up's limit fixes the iteration log's size: a higher one is refused (the solve
    answers invalid_input with the reason), and the solver keeps its limit."""
    solver = csocp.Solver(random_feasible(7, n=30), max_iter=50)
    assert solver.limit_iterations(51) != 0
    assert "max_iter 51: 1 to the set-up's 50" in solver.message
    assert solver.limit_iterations(0) != 0
    assert solver.solve().status == "solved"
    for session in (csocp.Session(max_iter=50), conic_session("clarabel", 1e-9, 50)):
        for limit in (51, 0):  # both sessions answer it alike
            sol = session.solve(random_feasible(7, n=30), max_iter=limit)
            assert sol.status == "invalid_input" and f"max_iter {limit}" in sol.info["message"]
        assert session.solve(random_feasible(7, n=30), max_iter=50).status == "solved"


def test_a_refused_limit_does_not_become_a_later_solves_reason() -> None:
    """A refused limit_iterations changes nothing in the workspace: a later solve refused for
    damage says why as a solver that never had the refusal does (the workspace's reason).
    Before, solve answered with the stale "max_iter 51" message of the refused limit."""
    prob = random_feasible(3, n=10, with_P=True)
    answers = []
    for refused_before in (False, True):
        solver = csocp.Solver(prob, max_iter=50)
        if refused_before:
            assert solver.limit_iterations(51) != 0 and solver.limit_iterations(None) == 0
        arena = solver.arena
        at = (-arena.ctypes.data) % 16 + 8  # the workspace struct's sizes: its checksum fails
        arena[at] ^= 0x10
        sol = solver.solve()
        arena[at] ^= 0x10
        assert sol.status == "invalid_input"
        answers.append(sol.info["message"])
    assert answers[1] == answers[0] and answers[0].startswith("workspace damaged")


def test_check_workspace_says_why_the_workspace_is_refused() -> None:
    """Solver.check_workspace binds tscvx_check_workspace: (0, "") for a ready workspace; a
    bit flipped in the workspace struct (the arena is the solver's array) is refused with the
    reason (the set-up mark, or the set-up checksum of its sizes, settings and pointers),
    which a solve's invalid_input answer carries too; restored, ready again and the same
    answer; a refused update and a failed set-up say so."""
    prob = random_feasible(3, n=10, with_P=True)
    solver = csocp.Solver(prob)
    assert solver.check_workspace() == (0, "")
    first = solver.solve()
    assert first.status == "solved"
    arena = solver.arena
    start = (-arena.ctypes.data) % 16  # the struct at the arena's first 16-byte aligned byte
    reasons = set()
    for offset in range(start, start + 64):
        arena[offset] ^= 0x10
        status, why = solver.check_workspace()
        sol = solver.solve()
        arena[offset] ^= 0x10
        if status != 0:
            assert status == csocp.SETUP_NOT_READY
            assert sol.status == "invalid_input" and sol.info["message"] == why
            reasons.add(why.split(":")[0])
        assert solver.check_workspace() == (0, "")
    assert reasons == {"no set-up mark", "workspace damaged"}
    again = solver.solve()
    assert again.status == "solved" and np.array_equal(again.x, first.x)
    assert solver.update(q=np.full(prob.n, np.nan)) != 0
    status, why = solver.check_workspace()
    assert status == csocp.SETUP_NOT_READY and "last data update was refused" in why
    assert solver.update(q=prob.q) == 0 and solver.check_workspace() == (0, "")
    refused = csocp.Solver(prob, max_iter=0)  # no workspace: the set-up's status and message
    assert not refused.ready and refused.setup_status != 0
    assert refused.check_workspace() == (refused.setup_status, refused.message)


def test_a_refused_update_names_the_array_and_entry_at_fault() -> None:
    """update() said only "NaN or infinity in the problem data" (set-up names the entry) and,
    on a damaged workspace, not what tscvx_check_workspace finds; now both say which."""
    prob = random_feasible(3, n=10, with_P=True)
    solver = csocp.Solver(prob)
    q = prob.q.copy()
    q[4] = np.inf
    assert solver.update(q=q) == 7  # TSCVX_SETUP_NONFINITE_DATA
    assert "(c[4] = inf;" in solver.message
    assert "(c[4] = inf;" in solver.solve().info["message"]  # the reason a solve is refused
    assert solver.update(q=prob.q) == 0 and solver.message == "ok"
    arena = solver.arena
    arena[(-arena.ctypes.data) % 16 + 20] ^= 0x10  # a bit of the workspace struct's head
    assert solver.update(q=prob.q) == csocp.SETUP_NOT_READY
    _, why = solver.check_workspace()
    assert why.startswith("workspace damaged") and solver.message.endswith(f": {why}")


def test_a_refused_update_leaves_the_solvers_copies_as_the_workspace_holds_them() -> None:
    """Review of 28 Nov: update() wrote the numbers into the solver's copies before the C
    runtime looked at them, and kept them when it refused them. tscvx_update_data takes none
    of a non-finite update or of a P failing the cheap test: after a NaN in b and a valid q,
    the workspace solved with the set-up's b while the copies held the NaN, and the next
    refusal (an infinite A entry) was blamed on that NaN ("h[6] = nan"). A P that passes the
    cheap test but not the factorization is stored (refused until replaced): the copies hold
    it."""
    prob = random_feasible(3, n=10, with_P=True)
    solver = csocp.Solver(prob)
    set_up = [a.copy() for a in (solver._c, solver._beq, solver._h, solver._P.data)]
    first = solver.solve()
    b = prob.b.copy()
    b[solver.split.g_rows[6]] = np.nan
    assert solver.update(b=b) == csocp.SETUP_NONFINITE_DATA and "(h[6] = nan;" in solver.message
    assert solver.update(q=prob.q) == 0
    again = solver.solve()  # the workspace's b is the set-up's (to rounding: tscvx_socp.h)
    assert again.status == "solved"
    np.testing.assert_allclose(again.x, first.x, rtol=0, atol=1e-9)
    held = (solver._c, solver._beq, solver._h, solver._P.data)
    assert all(np.array_equal(a, b) for a, b in zip(held, set_up, strict=True))
    A = prob.A.data.copy()
    A[3] = np.inf
    assert solver.update(A_values=A) == csocp.SETUP_NONFINITE_DATA
    assert "(Gx[4] = inf;" in solver.message and "h[6]" not in solver.message
    assert np.isfinite(solver._G.data).all() and np.isfinite(solver._Aeq.data).all()
    # P: a negative diagonal entry fails the cheap test (nothing stored); the off-diagonal
    # entries negated pass it but make P indefinite (stored, refused by the factorization)
    P = sp.csc_matrix(prob.P)
    diagonal = P.indices == np.repeat(np.arange(prob.n), np.diff(P.indptr))
    negative = P.data.copy()
    negative[np.flatnonzero(diagonal)[0]] = -1.0
    assert solver.update(P_values=negative) == csocp.SETUP_P_NOT_PSD
    assert "(P: a negative diagonal entry" in solver.message
    assert np.array_equal(solver._P.data, set_up[3])
    indefinite = np.where(diagonal, P.data, -P.data)
    assert solver.update(P_values=indefinite) == csocp.SETUP_P_NOT_PSD
    assert np.array_equal(solver._P.data, indefinite)
    assert solver.update(q=prob.q) == csocp.SETUP_P_NOT_PSD  # still the stored P, refused
    assert solver.update(P_values=P.data) == 0 and solver.solve().status == "solved"
