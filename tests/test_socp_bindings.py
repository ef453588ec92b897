"""ctypes bindings of the flight SOCP runtime: bad input, updates, iteration log, errors."""

from __future__ import annotations

import threading

import numpy as np
import pytest
import scipy.sparse as sp
from socp_problems import random_feasible

from guidance import csocp
from guidance.conic import ConicProblem, solve_clarabel
from guidance.conic import session as conic_session


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
    sol = csocp.solve(prob, log=True)
    log = sol.info["log"]
    assert len(log) == sol.iterations + 1
    assert [row["iter"] for row in log] == list(range(sol.iterations + 1))
    assert set(log[0]) == {"iter", "pcost", "dcost", "gap", "pres", "dres", "mu", "step"}
    assert log[-1]["pcost"] == pytest.approx(sol.obj)
    assert log[-1]["mu"] < log[0]["mu"]
    assert sol.info["arena_high_water"] <= sol.info["arena_used"] + 10 * 2**20


def test_max_iterations_status() -> None:
    sol = csocp.solve(random_feasible(5), max_iter=2)
    assert sol.status == "max_iterations"
    assert sol.iterations == 2


def test_unknown_setting_is_an_error() -> None:
    with pytest.raises(TypeError):
        csocp.Solver(small_soc(), tolerance=1)


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
