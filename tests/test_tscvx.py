"""T-SCvx with oracle predictors: warm start and reduced subproblems keep the full answer."""

from __future__ import annotations

import numpy as np
import pytest

from guidance.catalog import SCENARIOS
from guidance.params import NC, SCvxSettings
from guidance.scvx import SCvxResult, SCvxSolver, format_log, solve_scvx
from guidance.tscvx import solve_tscvx
from guidance.verify import audit


@pytest.fixture(scope="module")
def reference() -> SCvxResult:
    return solve_scvx(SCENARIOS["north"])


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
    # the log tells a guard rejection (same radius, constraints put back) from a rho one
    guarded = [i for i, h in enumerate(r.history) if h.restored]
    assert guarded, "the empty mask must have been repaired"
    for i in guarded:
        h = r.history[i]
        assert not h.accepted and r.history[i + 1].eta == h.eta
        assert format_log(r.history)[i + 1].endswith(f"rej, {h.restored} put back")
    assert all(h.restored == 0 for h in r.history if h.accepted)


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
    scenario = SCENARIOS["north"]

    def mask(k: int) -> np.ndarray:
        return reference.masks[min(k, len(reference.masks)) - 1]

    py = solve_tscvx(scenario, None, lambda s, k: mask(k))
    c = cguidance.solve_c(scenario, masks=mask)
    assert py.status == c.status == "solved"
    assert abs(py.iterations - c.iterations) <= 1
    assert abs(py.m_f - c.m_f) <= 1e-3  # the stopping rule leaves ~1e-4 of drift
    for r in (py, c):
        assert audit(r.x, r.u, r.t_f, scenario.params).max_path_violation <= 1e-6


@pytest.mark.parametrize("where", ["python", "c"])
def test_full_masks_with_the_eq13_radius_are_plain_scvx(where: str) -> None:
    """Masks that keep every constraint change nothing but the trust radius: with
    tau_r_update off (Eq. 13) the solve is plain SCvx's, step for step; with Algorithm 2's
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
    eq13 = solve(SCvxSettings(tau_r_update=False), True)
    paper = solve(SCvxSettings(), True)
    radii = [[h.eta for h in r.history] for r in (plain, eq13, paper)]
    assert radii[1] == radii[0]
    assert eq13.m_f == plain.m_f and eq13.iterations == plain.iterations
    assert radii[2] != radii[0]


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
    from guidance.dataset import SamplingRanges, base_scenario, theta_of
    from guidance.scenario import validate

    landings = bench_tscvx.sample_landings(2)
    trained = {tuple(theta_of(base_scenario(0, i, SamplingRanges())[0])) for i in range(4)}
    for s in landings:
        validate(s)
        assert tuple(theta_of(s)) not in trained
    variants = bench_tscvx.run(1, backend="c", progress=False)
    assert [v.name for v in variants] == [
        "SCvx", "T-SCvx warm start", "T-SCvx (Algorithm 2)", "Alg. 2, Eq. 13 radius"]  # fmt: skip
    for v in variants:
        r = v.results[0]
        assert r.status == "solved", (v.name, r.reason)
        a = audit(r.x, r.u, r.t_f, landings[0].params)
        assert a.max_path_violation <= 1e-6 and a.landing_position_error <= 1e-3, v.name
    lines = bench_tscvx.report(variants, "c")
    assert len(lines) == 2 + len(variants) + 1
