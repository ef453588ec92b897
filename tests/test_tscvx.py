"""T-SCvx with oracle predictors: warm start and reduced subproblems keep the full answer."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from guidance.catalog import SCENARIOS
from guidance.errors import InputError
from guidance.params import NC, SCvxSettings
from guidance.scvx import IterationRecord, SCvxResult, SCvxSolver, format_log, solve_scvx
from guidance.tscvx import solve_tscvx
from guidance.verify import audit


@pytest.fixture(scope="module")
def reference() -> SCvxResult:
    return solve_scvx(SCENARIOS["north"])


def _masks_of(reference: SCvxResult) -> Callable[[int], np.ndarray]:
    """The reference's own tight set of succession k (its last one beyond its iterations)."""
    return lambda k: reference.masks[min(k, len(reference.masks)) - 1]


def test_oracle_warm_start_and_masks_converge_fast(reference: SCvxResult) -> None:
    scenario = SCENARIOS["north"]
    final = reference.final_mask

    r = solve_tscvx(
        scenario,
        lambda s: (reference.x, reference.u, reference.t_f),
        lambda s, k: final,
    )
    assert r.status == "solved", r.reason
    assert r.iterations <= 3
    assert abs(r.m_f - reference.m_f) <= 1e-3
    a = audit(r.x, r.u, r.t_f, scenario.params)
    assert a.max_path_violation <= 1e-6 and a.landing_position_error <= 1e-3


def test_dropped_tight_constraints_are_put_back(reference: SCvxResult) -> None:
    """A mask keeping nothing but T_min would let thrust exceed T_max: the guard restores it."""
    scenario = SCENARIOS["north"]
    empty = np.zeros(NC * scenario.params.N)
    r = solve_tscvx(
        scenario, lambda s: (reference.x, reference.u, reference.t_f), lambda s, k: empty
    )
    assert r.status == "solved", r.reason
    a = audit(r.x, r.u, r.t_f, scenario.params)
    assert a.max_path_violation <= 1e-6
    assert abs(r.m_f - reference.m_f) <= 1e-3
    # the log tells a guard rejection (constraints put back) from a rho one
    guarded = [i for i, h in enumerate(r.history) if h.restored]
    assert guarded, "the empty mask must have been repaired"
    for i in guarded:
        h = r.history[i]
        assert not h.accepted and r.history[i + 1].eta == _after_guard(h, SCvxSettings())
        assert format_log(r.history)[i + 1].endswith(f"rej, {h.restored} put back")
    assert all(h.restored == 0 for h in r.history if h.accepted)


def _after_guard(h: IterationRecord, st: SCvxSettings) -> float:
    """The radius after guard rejection h: the same when rho accepted the step, contracted
    by alpha when rho rejected it too (step 5 of Algorithm 2)."""
    return h.eta if h.rho >= st.rho0 else max(h.eta / st.alpha, st.eta_lb)


@pytest.mark.parametrize("where", ["python", "c"])
def test_a_guard_rejection_of_a_step_rho_rejects_contracts_the_radius(where: str) -> None:
    """A candidate that violates a dropped constraint AND makes J worse (rho < rho0) is
    rejected twice over: the constraint goes back and the radius contracts, as Algorithm 2
    rejects it. Until 28 Nov the guard kept the radius whatever rho said, and the retry was
    mostly rejected again at it: on the default landing with SCvx's own tight masks (which
    change with k and leave out what a rejected, longer step meets) 33 subproblems and 409 IPM
    iterations, now 27 and 341 (SCvx: 21 and 267); over 20 sampled landings 30.2 subproblems
    against 24.9, one landing out of iterations, now none (docs/tscvx.md)."""
    scenario = SCENARIOS["default"]
    cguidance = pytest.importorskip("guidance.cguidance")
    if not cguidance.LIB_PATH.exists():
        pytest.skip("run `make lib` first")
    mask = _masks_of(cguidance.solve_c(scenario))  # SCvx's own tight sets
    st = SCvxSettings()
    if where == "c":
        r = cguidance.solve_c(scenario, st, masks=mask)
    else:
        r = SCvxSolver(scenario, st, backend="c").solve(masks=mask)
    assert r.status == "solved", r.reason
    guarded = [i for i, h in enumerate(r.history) if h.restored]
    assert any(r.history[i].rho < st.rho0 for i in guarded)
    assert any(r.history[i].rho >= st.rho0 for i in guarded)
    for i in guarded:
        assert r.history[i + 1].eta == pytest.approx(_after_guard(r.history[i], st), rel=1e-12)
    assert r.subproblems_solved <= 28


def test_guard_rejections_are_logged_alike_in_c() -> None:
    """The flight library's log counts the constraints its guard put back as Python's does."""
    cguidance = pytest.importorskip("guidance.cguidance")
    if not cguidance.LIB_PATH.exists():
        pytest.skip("run `make lib` first")
    scenario = SCENARIOS["north"]
    empty = np.zeros(NC * scenario.params.N)
    c = cguidance.solve_c(scenario, masks=lambda k: empty)
    py = SCvxSolver(scenario, backend="c").solve(masks=lambda k: empty)
    assert [h.restored for h in c.history] == [h.restored for h in py.history]
    assert any(h.restored for h in c.history)


def test_reference_masks_without_warm_start_match_in_c_and_python(
    reference: SCvxResult,
) -> None:
    """The reduced subproblems and the guard behave the same in the flight library."""
    cguidance = pytest.importorskip("guidance.cguidance")
    if not cguidance.LIB_PATH.exists():
        pytest.skip("run `make lib` first")
    scenario, mask = SCENARIOS["north"], _masks_of(reference)
    py = solve_tscvx(scenario, None, lambda s, k: mask(k))
    c = cguidance.solve_c(scenario, masks=mask)
    assert py.status == c.status == "solved"
    assert abs(py.iterations - c.iterations) <= 1
    assert abs(py.m_f - c.m_f) <= 1e-3  # the stopping rule leaves ~1e-4 of drift
    for r in (py, c):
        assert audit(r.x, r.u, r.t_f, scenario.params).max_path_violation <= 1e-6


def test_the_python_loop_warm_starts_across_mask_changes_as_the_c_loop(
    reference: SCvxResult,
) -> None:
    """The C loop keeps one KKT pattern for every mask (dropped rows empty) and starts each
    subproblem's IPM from the last answer; the Python loop's masked templates leave the rows
    out, and until 28 Nov the runtime refused the last answer of another size: every
    subproblem after a mask change started cold (north, these masks: 289 IPM iterations
    against the C loop's 266; Algorithm 2 on the default landing with the networks, 394
    against 351). It now carries the answer over (subproblem.carry_solution)."""
    cguidance = pytest.importorskip("guidance.cguidance")
    if not cguidance.LIB_PATH.exists():
        pytest.skip("run `make lib` first")
    scenario, mask = SCENARIOS["north"], _masks_of(reference)
    c = cguidance.solve_c(scenario, masks=mask)
    py = SCvxSolver(scenario, backend="c").solve(masks=mask)
    assert (py.status, py.subproblems_solved) == (c.status, c.subproblems_solved)
    assert len({tuple(mask(k)) for k in range(1, c.iterations + 1)}) >= 5  # masks change
    # the same subproblems from the same starts: within the last bits' IPM iteration or two
    assert abs(py.ipm_iterations - c.ipm_iterations) <= 0.02 * c.ipm_iterations


@pytest.mark.parametrize("where", ["python", "c"])
def test_full_masks_with_the_algorithm_1_radius_are_plain_scvx(where: str) -> None:
    """Masks that keep every constraint change nothing but the trust radius: with
    tau_r_update off (Eq. (15)) the solve is plain SCvx's, step for step; with Algorithm 2's
    update (tau_r = 0: a poor accepted step no longer shrinks the radius) it is not."""
    scenario = SCENARIOS["default"]
    ones = np.ones(NC * scenario.params.N, dtype=bool)
    if where == "c":
        cguidance = pytest.importorskip("guidance.cguidance")
        if not cguidance.LIB_PATH.exists():
            pytest.skip("run `make lib` first")

        def solve(st: SCvxSettings, masked: bool) -> SCvxResult:
            return cguidance.solve_c(scenario, st, masks=(lambda k: ones) if masked else None)
    else:

        def solve(st: SCvxSettings, masked: bool) -> SCvxResult:
            return SCvxSolver(scenario, st).solve(masks=(lambda k: ones) if masked else None)

    plain = solve(SCvxSettings(), False)
    alg1 = solve(SCvxSettings(tau_r_update=False), True)
    paper = solve(SCvxSettings(), True)
    radii = [[h.eta for h in r.history] for r in (plain, alg1, paper)]
    assert radii[1] == radii[0]
    assert alg1.m_f == plain.m_f and alg1.iterations == plain.iterations
    assert radii[2] != radii[0]
    # T_min is always kept (its buffer is penalized), so a mask without its bits is the full
    # one too: the guard must not "put back" a T_min the subproblem never dropped
    ones.reshape(-1, NC)[:, 6] = False
    no_tmin = solve(SCvxSettings(tau_r_update=False), True)
    assert [h.eta for h in no_tmin.history] == radii[0] and no_tmin.m_f == plain.m_f


def _alternating_masks(N: int):
    """Masks that change every succession but drop only the mass bound at early nodes (never
    near m_dry, so the guard never acts): tau_r = 15/7N between successive successions."""

    def mask(k: int) -> np.ndarray:
        m = np.ones((N, NC), dtype=bool)
        m[: (25 if k % 2 == 0 else 10), 0] = False
        return m.reshape(-1)

    return mask


@pytest.mark.parametrize("where", ["python", "c"])
def test_tau_r_compares_the_predictions_of_successive_successions(where: str) -> None:
    """Algorithm 2, steps 4-5: after an accepted step at succession k the radius is updated
    with alpha^tau_r / beta^(1 - tau_r), tau_r the fraction of bits in which the predicted masks
    of successions k and k-1 differ. A retry of k does not reset it to 0 (the masks compared
    are still those of k and k-1), so the rule is re-derived here from the masks alone."""
    scenario = SCENARIOS["default"]
    N, st = scenario.params.N, SCvxSettings()
    mask = _alternating_masks(N)
    if where == "c":
        cguidance = pytest.importorskip("guidance.cguidance")
        if not cguidance.LIB_PATH.exists():
            pytest.skip("run `make lib` first")
        r = cguidance.solve_c(scenario, st, masks=mask)
    else:
        r = SCvxSolver(scenario, st).solve(masks=mask)
    assert r.status == "solved", r.reason
    hist = r.history
    after_rejection = 0
    for i, h in enumerate(hist[:-1]):
        if not h.accepted:
            assert not h.restored  # the mass bound is never violated at early nodes
            continue
        tau = 0.0 if h.k == 1 else float(np.mean(mask(h.k) != mask(h.k - 1)))
        rho = h.rho if h.dL > 0 else 1.0
        if rho < st.rho1:
            want = h.eta / st.alpha**tau
        elif rho >= st.rho2:
            want = h.eta * st.beta ** (1.0 - tau)
        else:
            want = h.eta
        want = min(max(want, st.eta_lb), st.eta_ub)
        assert hist[i + 1].eta == pytest.approx(want, rel=1e-12), (i, h)
        after_rejection += i > 0 and not hist[i - 1].accepted and want != h.eta
    assert after_rejection > 0, "no accepted step after a rejection changed the radius"


def test_speed_up_interval_covers_the_ratio_and_narrows_with_landings() -> None:
    from guidance.bench_tscvx import ratio_interval

    rng = np.random.default_rng(3)
    base = rng.uniform(0.3, 0.5, 400)
    fast = base / 1.5 * rng.uniform(0.8, 1.2, 400)  # true speed-up about 1.5
    lo16, hi16 = ratio_interval(base[:16], fast[:16])
    lo400, hi400 = ratio_interval(base, fast)
    assert lo400 <= base.mean() / fast.mean() <= hi400
    assert 1.4 < lo400 < hi400 < 1.6
    assert hi400 - lo400 < (hi16 - lo16) / 2
    assert ratio_interval(base, base) == (1.0, 1.0)


def test_tscvx_benchmark_landings_are_fresh_and_each_variant_is_audited() -> None:
    """`guidance bench --tscvx-landings`: valid landings that no dataset seed draws, each variant
    solved with the shipped networks and checked open loop like the reference."""
    from guidance import bench_tscvx
    from guidance.sampling import SamplingRanges, base_scenario, theta_of
    from guidance.scenario import validate

    landings = bench_tscvx.sample_landings(2)
    trained = {tuple(theta_of(base_scenario(0, i, SamplingRanges())[0])) for i in range(4)}
    for s in landings:
        validate(s)
        assert tuple(theta_of(s)) not in trained
    variants = bench_tscvx.run(1, backend="c", progress=False)
    assert [v.name for v in variants] == [
        "SCvx", "T-SCvx warm start", "T-SCvx (Algorithm 2)", "Alg. 2, Alg. 1 radius"]  # fmt: skip
    for v in variants:
        r = v.results[0]
        assert r.status == "solved", (v.name, r.reason)
        a = audit(r.x, r.u, r.t_f, landings[0].params)
        assert a.max_path_violation <= 1e-6 and a.landing_position_error <= 1e-3, v.name
    lines = bench_tscvx.report(variants, "c")
    assert len(lines) == 2 + len(variants) + 1


def test_a_predicted_start_takes_the_reduced_radius_not_the_settings_one(
    reference: SCvxResult,
) -> None:
    """Algorithm 2 / Table 1: a predicted solution starts at eta_reduced,init = 0.01 (or the
    eta_init argument), whatever the settings' full-problem eta_init."""
    scenario = SCENARIOS["north"]
    st = SCvxSettings(eta_init=1.0, iter_max=1)

    def predict(s):  # type: ignore[no-untyped-def]
        return reference.x, reference.u, reference.t_f

    assert solve_tscvx(scenario, predict, None, settings=st).history[0].eta == 0.01
    assert solve_tscvx(scenario, predict, None, st, eta_init=0.05).history[0].eta == 0.05


def test_without_a_predicted_solution_the_settings_radius_starts() -> None:
    st = SCvxSettings(eta_init=1.0, iter_max=1)
    r = solve_tscvx(SCENARIOS["north"], None, None, settings=st)
    assert r.history[0].eta == 1.0


def test_a_prediction_off_the_boundary_conditions_is_projected(reference: SCvxResult) -> None:
    """A warm start 1 above the true altitude at every node misses x(0) = x0 and r(t_f) = r_f
    by 1, far beyond the 0.01 radius: unprojected, the first subproblem would be infeasible."""
    scenario = SCENARIOS["north"]
    x = reference.x.copy()
    x[:, 0] += 1.0
    r = solve_tscvx(scenario, lambda s: (x, reference.u, reference.t_f), None)
    assert r.history[0].solver_status == "solved"
    assert r.status == "solved", r.reason
    np.testing.assert_allclose(r.x[0], scenario.x0, atol=1e-9)
    a = audit(r.x, r.u, r.t_f, scenario.params)
    assert a.max_path_violation <= 1e-6 and a.landing_position_error <= 1e-3


def test_mask_probabilities_are_refused() -> None:
    scenario = SCENARIOS["north"]
    probs = np.full(NC * scenario.params.N, 0.7)
    with pytest.raises(InputError, match="0/1 bits"):
        solve_tscvx(scenario, None, lambda s, k: probs)


@pytest.mark.parametrize("backend", ["clarabel", "c-socp"])
def test_a_non_finite_prediction_ends_with_the_flight_librarys_status(
    reference: SCvxResult, backend: str
) -> None:
    """A warm start with an overflow in it (NaN) stops before the first subproblem with
    pdg_solve_tscvx's status and reason, not an exception from inside the discretization."""
    u = reference.u.copy()
    u[7, 1] = np.nan
    r = solve_tscvx(SCENARIOS["north"], lambda s: (reference.x, u, reference.t_f), None,
                    backend=backend)  # fmt: skip
    assert (r.status, r.subproblems_solved) == ("solver_error", 0)
    assert r.reason == (
        "solution network: the network output is not finite (overflow inside the network)"
    )
    assert np.isnan(r.t_f) and np.isnan(r.x).all()


# ---- one mask rule at every entry point (review of the T-SCvx entry points, 26 Nov) ---------

SHORT = SCvxSettings(iter_max=2)
MASK_ENTRY_POINTS = [
    "solve_tscvx",
    "solve_c function",
    "solve_c table",
    "SCvxSolver",
]


def _c_library():  # type: ignore[no-untyped-def]
    cguidance = pytest.importorskip("guidance.cguidance")
    if not cguidance.LIB_PATH.exists():
        pytest.skip("run `make lib` first")
    return cguidance


def _loop(where: str, masks: object) -> SCvxResult:
    """Two iterations of the default landing in the C loop (solve_c) or the Python one."""
    scenario = SCENARIOS["default"]
    if where == "SCvxSolver":
        return SCvxSolver(scenario, SHORT).solve(masks=masks)  # type: ignore[arg-type]
    return _c_library().solve_c(scenario, SHORT, masks=masks)


def _masked_solve(where: str, mask: np.ndarray) -> SCvxResult:
    """Two iterations of the default landing with ``mask`` at every one, through one entry
    point."""
    if where == "solve_tscvx":
        return solve_tscvx(SCENARIOS["default"], None, lambda s, k: mask, SHORT)
    return _loop(where, [mask] if where == "solve_c table" else lambda k: mask)


@pytest.mark.parametrize("where", MASK_ENTRY_POINTS)
def test_every_entry_point_takes_0_1_bits_and_refuses_probabilities(where: str) -> None:
    """solve_tscvx refused a network's probabilities while solve_c (and the Python loop) read
    them as nonzero = keep: sigmoid outputs, never exactly 0, kept every constraint without a
    word. One rule now: bools or numbers equal to 0 or 1, anything else refused by value."""
    N = SCENARIOS["default"].params.N
    bits = np.ones((N, NC), bool)
    bits[:20, 0] = False  # the mass bound dropped at early nodes: never put back
    as_bools = _masked_solve(where, bits.reshape(-1))
    as_floats = _masked_solve(where, bits.reshape(-1).astype(float))
    assert as_bools.status == as_floats.status and as_bools.m_f == as_floats.m_f
    probs = np.full(NC * N, 0.7)
    probs[::3] = 0.2
    with pytest.raises(InputError, match=r"mask holds 0\.2 \(350 values not 0 or 1\): give 0/1"):
        _masked_solve(where, probs)
    with_nan = bits.reshape(-1).astype(float)
    with_nan[5] = np.nan  # read as "keep" by nonzero = keep
    with pytest.raises(InputError, match=r"iteration 1's mask holds nan \(1 values"):
        _masked_solve(where, with_nan)


C_AND_PYTHON_LOOPS = ["solve_c", "SCvxSolver"]


@pytest.mark.parametrize("where", C_AND_PYTHON_LOOPS)
def test_a_masks_argument_of_another_type_is_refused_by_name(where: str) -> None:
    """masks=True (meant: the networks' masks) raised TypeError from len() inside the loop;
    a number, a string or a dict likewise or as a misleading shape error. Refused by name."""
    mask = np.ones(NC * SCENARIOS["default"].params.N, bool)
    for bad in (True, np.bool_(True), 5, 0.5, "ones", {1: mask}, np.array(True)):
        with pytest.raises(InputError, match=r"masks: expected a table of masks .* got "):
            _loop(where, bad)


def test_solve_tscvx_refuses_a_predictor_that_is_not_a_function(reference: SCvxResult) -> None:
    """A mask table, True or the predicted (x, u, t_f) itself in place of the function raised
    TypeError ("object is not callable") from inside the solve; refused by name first."""
    scenario = SCENARIOS["north"]
    final = reference.final_mask
    for bad in (True, [final], final):
        with pytest.raises(InputError, match="predict_mask: expected a function"):
            solve_tscvx(scenario, None, bad)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="predict_solution: expected a function"):
        guess = (reference.x, reference.u, reference.t_f)
        solve_tscvx(scenario, guess, None)  # type: ignore[arg-type]
