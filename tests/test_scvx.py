"""Reference SCvx end to end: convergence, open-loop landing, symmetry, infeasibility, files."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from guidance import cgnc
from guidance.catalog import SCENARIOS
from guidance.cli import main
from guidance.params import NC, InitialState, Scenario, SCvxSettings
from guidance.provenance import file_digest
from guidance.scvx import SCvxResult, solve_scvx
from guidance.symmetry import rotate_scenario, rotate_states
from guidance.trajectory_io import read_trajectory
from guidance.verify import audit


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_converges_and_lands_open_loop(catalog_solved: dict[str, SCvxResult], name: str) -> None:
    r = catalog_solved[name]
    p = SCENARIOS[name].params
    assert r.status == "solved", r.reason
    assert r.iterations <= 20
    assert r.history[-1].vc_norm1 <= 1e-6  # virtual control and buffers of the last step
    a = audit(r.x, r.u, r.t_f, p)  # scipy integration of the numpy dynamics from x0
    assert a.landing_position_error <= 1e-3
    assert a.landing_velocity_error <= 1e-3
    assert a.max_path_violation <= 1e-6
    assert r.masks.shape == (r.iterations, NC * p.N)


def test_default_landing_burns_about_three_quarters(catalog_solved: dict[str, SCvxResult]) -> None:
    fuel = 3.0 - catalog_solved["default"].m_f
    assert 0.6 < fuel < 0.9  # DESIGN.md: about three quarters of the unit of propellant


def test_rotation_about_up_axis_rotates_the_solution(catalog_solved: dict[str, SCvxResult]) -> None:
    base = catalog_solved["default"]
    for j in range(1, 8):
        psi = j * math.pi / 4
        r = solve_scvx(rotate_scenario(SCENARIOS["default"], psi))
        assert r.status == "solved"
        assert abs(r.m_f - base.m_f) <= 1e-5
        # The fuel fixes the optimum sharply; some directions of it (gimbal and rate profiles)
        # are nearly flat, where solver round-off of 1e-9 moves the answer by up to 1e-3.
        np.testing.assert_allclose(r.x, rotate_states(base.x, psi), atol=1e-3)
        np.testing.assert_allclose(r.u, base.u, atol=5e-3)  # thrust is O(1..5)
        np.testing.assert_array_equal(r.final_mask, base.final_mask)


def test_far_and_fast_start_is_infeasible_with_a_reason() -> None:
    far = Scenario(InitialState(r0=(8.0, 8.0, 0.0), v0=(0.0, -2.0, -2.0), m0=2.4))
    r = solve_scvx(far)
    assert r.status == "infeasible"
    assert "virtual control" in r.reason or "defect" in r.reason
    assert "mass at the floor" in r.reason


def test_pinned_final_attitude_lands_with_q_f() -> None:
    scenario = SCENARIOS["north"]
    pinned = Scenario(scenario.initial, scenario.params.replace(final_roll_free=False))
    r = solve_scvx(pinned)
    assert r.status == "solved", r.reason
    np.testing.assert_allclose(r.x[-1, 6:10], pinned.params.q_f, atol=1e-8)
    assert audit(r.x, r.u, r.t_f, pinned.params).landing_position_error <= 1e-3


def test_cli_writes_the_trajectory_contract(tmp_path: Path) -> None:
    out, fig = tmp_path / "traj.npz", tmp_path / "figures" / "traj.png"  # folder made for it
    assert main(["solve", "--out", str(out), "--plot", str(fig)]) == 0
    data = read_trajectory(out)
    assert data["x"].shape == (50, 14) and data["u"].shape == (50, 3)
    assert str(data["status"]) == "solved"
    assert float(data["t_f"]) > 0 and int(data["iterations"]) <= 20
    params = data["params"]
    for key in (
        "g_I",
        "J_B",
        "r_T_B",
        "r_cp_B",
        "alpha_mdot",
        "beta_mdot",
        "aero_coeff",
        "m_dry",
        "T_min",
        "T_max",
        "gimbal_max_deg",
        "tilt_max_deg",
        "glideslope_deg",
        "omega_max_deg",
        "r_f",
        "v_f",
        "q_f",
        "omega_f",
        "final_roll_free",
        "N",
    ):
        assert key in params
    assert data["scenario"]["m0"] == 3.0
    # the defaults, with the IPM warm start off (Clarabel starts every subproblem cold) and
    # the discretization that ran, not "auto" (audit of 28 Nov: the file did not say which)
    engine = "c" if cgnc.available() else "casadi"
    ran = SCvxSettings(socp_warm_start=False, discretization=engine)
    assert data["settings"] == dataclasses.asdict(ran)
    prov = data["provenance"]
    assert prov["generator"].startswith("guidance ") and "clarabel" in prov["packages"]
    # SCvx reads no model file; the build of the generated C that discretized is named
    lib = cgnc.LIB_PATH
    if engine == "c":
        built = {"c_discretization": {"path": str(lib), "sha256": file_digest(lib)}}
        assert prov["files"] == built
    else:
        assert "files" not in prov
    assert fig.stat().st_size > 10_000


def test_cli_prox_u_reaches_the_solve(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`--prox-u 0` solves with the paper's objective, says so, and the file records it."""
    out = tmp_path / "paper.npz"
    assert main(["solve", "--prox-u", "0", "--out", str(out)]) == 0
    assert "subproblem objective: paper's linear" in capsys.readouterr().out
    data = read_trajectory(out)
    assert data["settings"]["prox_u"] == 0.0
    paper = solve_scvx(SCENARIOS["default"], SCvxSettings(prox_u=0.0))
    assert int(data["iterations"]) == paper.iterations
    assert float(data["x"][-1, 13]) == pytest.approx(paper.m_f, rel=1e-12)


def test_proximal_term_is_on_the_thrust_only() -> None:
    """SCvxSettings.prox_u adds (w/2)|u_hat - u_hat_ref|^2 to the subproblem and nothing else:
    P = w on the thrust columns, q shifted by -w u_hat_ref there, the constraints unchanged;
    prox_u = 0 is the paper's objective (no P)."""
    from guidance.guess import initial_guess
    from guidance.model import discretize
    from guidance.subproblem import Scaling, SubproblemTemplate, physical, scaled

    scn = SCENARIOS["tilted"]
    x, u, tf = initial_guess(scn)
    sc = Scaling.for_scenario(scn, tf)
    tpl = SubproblemTemplate(scn.params.N, scn.params.final_roll_free)
    z = scaled(x, u, tf, tpl.lay, sc)
    z += np.random.default_rng(0).normal(scale=0.1, size=z.size)  # u_ref not the guess's
    disc = discretize(*physical(z, tpl.lay, sc), scn.params, 2)
    paper = tpl.assemble(disc, z, 0.5, 500.0, scn, sc, 0.0)
    w = 0.03
    prox = tpl.assemble(disc, z, 0.5, 500.0, scn, sc, w)
    assert paper.P is None
    thrust = np.zeros(tpl.lay.n, bool)
    thrust[tpl.lay.iu : tpl.lay.isig] = True
    np.testing.assert_array_equal(prox.P.toarray(), np.diag(np.where(thrust, w, 0.0)))
    np.testing.assert_array_equal(prox.q - paper.q, np.where(thrust, -w * z, 0.0))
    assert (prox.A != paper.A).nnz == 0
    np.testing.assert_array_equal(prox.b, paper.b)
    # the objective difference is the proximal term up to a constant: zero at u_hat_ref
    for v in (z, z + 0.2):
        quad = 0.5 * v @ (prox.P @ v) + prox.q @ v - paper.q @ v
        assert quad + 0.5 * w * (z[thrust] ** 2).sum() == pytest.approx(
            0.5 * w * ((v - z)[thrust] ** 2).sum(), rel=1e-9
        )


def test_a_rejection_skips_the_radii_that_hold_the_step() -> None:
    """After a rejection only the radius changes. A radius that still holds the rejected step
    gives the same step back, so SCvx goes straight to the first radius of Eq. (15)'s sequence
    that cuts into the step. The flight SOCP runtime solves them (cross-checked against
    Clarabel in test_socp_*): Clarabel ends the radius-1 solve "AlmostSolved" 2.4e-8 above
    the optimum, even at tol 1e-11, and the proximal term (weight w) fixes the thrust only to
    about sqrt(2 gap / w): 2e-4 off the step."""
    from guidance.conic import solve
    from guidance.guess import initial_guess
    from guidance.model import discretize
    from guidance.params import rk4_steps_per_interval
    from guidance.scvx import RETRY_MARGIN, _retry_radius
    from guidance.subproblem import Scaling, SubproblemTemplate, physical, scaled

    scn, st = SCENARIOS["default"], SCvxSettings()
    x, u, tf = initial_guess(scn)
    sc = Scaling.for_scenario(scn, tf)
    tpl = SubproblemTemplate(scn.params.N, scn.params.final_roll_free)
    z = scaled(x, u, tf, tpl.lay, sc)
    steps = rk4_steps_per_interval(st.rk4_substeps, scn.params.N)  # what SCvx uses
    disc = discretize(*physical(z, tpl.lay, sc), scn.params, steps)

    def step(eta: float) -> tuple[np.ndarray, float]:
        sol = solve(tpl.assemble(disc, z, eta, st.lam, scn, sc, st.prox_u), backend="c")
        assert sol.status == "solved"
        return (sol.x - z)[: tpl.lay.n_traj], sol.obj

    d, obj = step(st.eta_init)
    s = tpl.trust_norm(d)
    assert s < st.eta_init / st.alpha  # the first step fits in half the initial radius
    eta = _retry_radius(st.eta_init, s, st)
    assert eta <= RETRY_MARGIN * s < st.alpha * eta
    # every skipped radius gives the rejected step back; the first radius not skipped gives
    # another step
    skipped = st.eta_init / st.alpha
    while skipped > eta:
        d_skip, obj_skip = step(skipped)
        np.testing.assert_allclose(d_skip, d, atol=1e-4)
        assert obj_skip == pytest.approx(obj, rel=1e-7)
        skipped /= st.alpha
    assert np.abs(step(eta)[0] - d).max() > 0.1
    r = solve_scvx(scn)
    assert not r.history[0].accepted and r.history[1].eta == eta


def test_retry_radius_follows_the_sequence_and_its_bounds() -> None:
    from guidance.params import ALPHA_MIN
    from guidance.scvx import RETRY_SKIP_MAX, _retry_radius

    st = SCvxSettings()  # alpha = 2, eta_lb = 1e-3
    assert _retry_radius(2.0, 1.5, st) == 1.0  # the step is cut at once: Eq. (15)
    assert _retry_radius(2.0, 0.3, st) == 0.25  # 1 and 0.5 hold the step: skipped
    assert _retry_radius(2.0, 0.2502, st) == 0.25  # within the margin: not skipped
    assert _retry_radius(2.0, 0.0, st) == st.eta_lb
    # at most RETRY_SKIP_MAX radii are skipped: at the smallest factor, with no step and no
    # floor in reach, the retry radius is eta / ALPHA_MIN^(1 + RETRY_SKIP_MAX)
    slow = dataclasses.replace(st, alpha=ALPHA_MIN, eta_lb=1e-30)
    assert _retry_radius(2.0, 0.0, slow) == pytest.approx(2.0 / ALPHA_MIN ** (1 + RETRY_SKIP_MAX))
