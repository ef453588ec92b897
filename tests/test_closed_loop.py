"""Closed-loop flight with in-flight re-planning (``guidance.closed_loop``,
``guidance closed-loop``):

- a plan flown without a disturbance is the open-loop check's flight (``verify.propagate``),
  whole or in pieces that end between nodes;
- the disturbances act as modelled: without aerodynamics an acceleration bias b moves the
  vehicle by exactly b t^2 / 2, and a thrust error e burns exactly (1 + e) times the thrust's
  propellant;
- without a disturbance the re-plans keep the vehicle on its plan to the pad;
- through a thrust error, re-planning lands many times nearer the pad than the plan flown
  open loop; a re-plan that fails (the engine too weak for the last burn) leaves the vehicle
  on its plan;
- bad settings are refused with the reason; the command line prints the figures and JSON.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from c_library import needs_c_library

from guidance import cguidance
from guidance.cli import main
from guidance.closed_loop import (
    ROLL_NOISE,
    ClosedLoop,
    Disturbance,
    Navigation,
    ReplanSettings,
    _fly,
    fly_closed_loop,
    state_scenario,
)
from guidance.errors import InputError
from guidance.params import IM, IR, IV, Scenario
from guidance.provenance import code_version
from guidance.scvx import SCvxResult
from guidance.verify import propagate

pytestmark = needs_c_library

SCN = Scenario()
SETTINGS = ReplanSettings(period=1.0, lock=0.5)  # 6 re-plans of the default landing


@pytest.fixture(scope="module")
def plan() -> SCvxResult:
    return cguidance.solve_c(SCN)


def test_a_plan_flown_undisturbed_is_the_open_loop_check(plan: SCvxResult) -> None:
    reference = propagate(SCN.x0, plan.u, plan.t_f, SCN.params)[-1]
    whole, _ = _fly(SCN.x0, plan.u, plan.t_f, 0.0, plan.t_f, SCN, Disturbance())
    np.testing.assert_allclose(whole, reference, rtol=0, atol=1e-8)
    x, t = SCN.x0, 0.0
    for t_next in (0.37 * plan.t_f, 0.8123 * plan.t_f, plan.t_f):  # ends between nodes
        x, _ = _fly(x, plan.u, plan.t_f, t, t_next, SCN, Disturbance())
        t = t_next
    np.testing.assert_allclose(x, reference, rtol=0, atol=1e-8)


def test_the_disturbances_act_as_modelled(plan: SCvxResult) -> None:
    no_aero = Scenario(SCN.initial, SCN.params.replace(aero_coeff=0.0))
    T = 0.6 * plan.t_f
    nominal, _ = _fly(SCN.x0, plan.u, plan.t_f, 0.0, T, no_aero, Disturbance())
    b = np.array([0.01, -0.02, 0.03])
    biased, _ = _fly(SCN.x0, plan.u, plan.t_f, 0.0, T, no_aero, Disturbance(accel_bias=tuple(b)))
    np.testing.assert_allclose(biased[IR] - nominal[IR], 0.5 * b * T**2, rtol=0, atol=1e-8)
    np.testing.assert_allclose(biased[IV] - nominal[IV], b * T, rtol=0, atol=1e-8)
    # mass: m(T) = m0 - (1 + e) alpha int |u| - beta T
    e, beta = 0.03, SCN.params.beta_mdot
    strong, _ = _fly(SCN.x0, plan.u, plan.t_f, 0.0, T, SCN, Disturbance(thrust_error=e))
    burned = SCN.x0[IM] - nominal[IM] - beta * T
    assert SCN.x0[IM] - strong[IM] - beta * T == pytest.approx((1 + e) * burned, abs=1e-8)


def _landed(res: ClosedLoop) -> None:
    """Each re-plan's record holds together: kept ones solved, with a touchdown after it."""
    for r in res.replans:
        assert r.kept == (r.outcome == "solved")
        assert (r.touchdown > r.t) if r.kept else np.isnan(r.touchdown)


def test_undisturbed_replans_keep_the_vehicle_on_its_plan(plan: SCvxResult) -> None:
    res = fly_closed_loop(SCN, Disturbance(), SETTINGS, plan)
    _landed(res)
    assert len(res.replans) == 6 and all(r.kept for r in res.replans)
    assert res.closed.position_error < 1e-5 and res.closed.velocity_error < 1e-5
    # the principle of optimality, within SCvx's tolerances
    assert res.closed.m_f == pytest.approx(plan.m_f, abs=5e-4)
    assert res.closed.touchdown == pytest.approx(plan.t_f, abs=0.02)
    assert res.open.position_error < 1e-3  # guidance verify's landing tolerance


def test_replanning_corrects_a_thrust_error(plan: SCvxResult) -> None:
    res = fly_closed_loop(SCN, Disturbance(thrust_error=0.02), SETTINGS, plan)
    _landed(res)
    assert all(r.kept for r in res.replans)
    assert res.open.position_error > 0.3  # 2 % more thrust for a whole landing
    assert res.closed.position_error < res.open.position_error / 10
    assert res.closed.velocity_error < res.open.velocity_error / 2


def test_a_failed_replan_leaves_the_vehicle_on_its_plan(plan: SCvxResult) -> None:
    """2 % too little thrust: late in the last, full-thrust burn no landing is left."""
    res = fly_closed_loop(SCN, Disturbance(thrust_error=-0.02), ReplanSettings(), plan)
    _landed(res)
    failed = [r for r in res.replans if not r.kept]
    assert failed and all(r.t > 4.0 for r in failed)
    assert {r.outcome for r in failed} <= {"infeasible", "max_iterations"}
    last_kept = [r for r in res.replans if r.kept][-1]
    assert res.closed.touchdown == last_kept.touchdown  # flown to that plan's end
    assert res.closed.position_error < res.open.position_error / 3


@pytest.mark.parametrize(
    ("make", "reason"),
    [
        (lambda: Disturbance(thrust_error=float("nan")), "thrust_error"),
        (lambda: Disturbance(thrust_error=0.6), "thrust_error"),
        (lambda: Disturbance(accel_bias=(0.0, 2.0, 0.0)), "accel_bias"),
        (lambda: Disturbance(accel_bias=(0.0, 0.0)), "accel_bias"),
        (lambda: ReplanSettings(period=0.0), "period"),
        (lambda: Navigation(position_sigma=-0.01), "position_sigma"),
        (lambda: Navigation(velocity_sigma=float("nan")), "velocity_sigma"),
        (lambda: Navigation(velocity_sigma=2.0), "velocity_sigma"),
        (lambda: Navigation(seed=-1), "seed"),
        (lambda: ReplanSettings(lock=float("inf")), "lock"),
    ],
)
def test_bad_settings_are_refused(make, reason: str) -> None:
    with pytest.raises(InputError, match=reason):
        make()


def test_a_roll_rate_beyond_rounding_is_refused() -> None:
    x = SCN.x0.copy()
    x[10] = 1e-6
    with pytest.raises(InputError, match="roll rate"):
        state_scenario(x, SCN)
    x[10] = 3e-14  # the integration's rounding: zeroed
    assert state_scenario(x, SCN).initial.w0[0] == 0.0


def test_the_flight_library_makes_the_same_landing_from_a_state(plan: SCvxResult) -> None:
    """pdg_scenario_at_state, what a re-plan on board starts from, against state_scenario on
    the plan's states with a measured quaternion off unit length: the same landing to the
    last bits, and the same roll-rate limit (ROLL_NOISE against PDG_ROLL_NOISE)."""
    for k in (0, 12, 31, 45):
        x = plan.x[k].copy()
        x[6:10] *= 1.0 + 1e-4 * (k - 20)
        x[10] = 3e-11 * (k - 20)
        want, got = state_scenario(x, SCN), cguidance.scenario_at_state_c(x, SCN)
        np.testing.assert_allclose(got.x0, want.x0, rtol=1e-15, atol=0)
        assert got.params == want.params
    x = plan.x[12].copy()
    x[10] = ROLL_NOISE
    assert cguidance.scenario_at_state_c(x, SCN).x0[10] == 0.0
    x[10] = np.nextafter(ROLL_NOISE, 1.0)
    with pytest.raises(InputError, match="roll rate"):
        cguidance.scenario_at_state_c(x, SCN)
    with pytest.raises(InputError, match="roll rate"):
        state_scenario(x, SCN)
    x[10], x[13] = 0.0, SCN.params.m_dry * 0.9  # refused by the scenario's own check
    with pytest.raises(InputError, match="m0"):
        cguidance.scenario_at_state_c(x, SCN)


def test_the_command_line(capsys) -> None:
    assert main(["closed-loop", "--period", "1.5", "--thrust-error", "0.01", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["disturbance"]["thrust_error"] == 0.01 and out["settings"]["period"] == 1.5
    assert out["provenance"]["generator"] == code_version()
    assert out["closed"]["position_error"] < out["open"]["position_error"]
    assert [r["t"] for r in out["replans"]] == [1.5, 3.0, 4.5, 6.0]  # 0.87 U_T left at 6
    assert main(["closed-loop", "--thrust-error", "0.9"]) == 2
    assert "thrust_error" in capsys.readouterr().err
    noisy = ["closed-loop", "--period", "2", "--thrust-error", "0", "--nav-error", "0.01", "0",
             "--seed", "3", "--json"]  # fmt: skip
    assert main(noisy) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["navigation"] == {"position_sigma": 0.01, "velocity_sigma": 0.0, "seed": 3}
    known = [r["knowledge_error"] for r in out["replans"]]
    assert all(dr > 0.0 and dv == 0.0 for dr, dv in known)
    assert main(noisy) == 0  # the same seed, the same flight
    again = json.loads(capsys.readouterr().out)
    assert {**again, "provenance": None} == {**out, "provenance": None}
    assert main([*noisy[:-2], "4", "--json"]) == 0
    assert [r["knowledge_error"] for r in json.loads(capsys.readouterr().out)["replans"]] != known
    assert main(["closed-loop", "--nav-error", "0.01", "-1"]) == 2
    assert "velocity_sigma" in capsys.readouterr().err


def test_a_flight_that_cannot_be_integrated_exits_1(monkeypatch, capsys) -> None:
    from guidance import closed_loop

    def broken(*args: object, **kwargs: object) -> None:
        raise closed_loop.PropagationError("the state is no longer finite")

    monkeypatch.setattr(closed_loop, "fly_interval", broken)
    assert main(["closed-loop"]) == 1
    assert "the flight stopped at t = 0.0000 of the plan" in capsys.readouterr().err


def test_replans_start_from_what_navigation_knows(plan: SCvxResult) -> None:
    """Without aerodynamics (a solve needs them positive: 1e-9, the drag 1e-9 of g) the thrust
    accelerates the true vehicle as the estimated one (the same attitude and mass), so after
    the last kept re-plan, from an estimate off by (e_r, e_v), the vehicle lands off by
    exactly -(e_r + e_v T) and -e_v, T the time flown on that plan: within the plan's own
    miss. The errors are the seeded draws, one pair per re-plan."""
    no_aero = Scenario(SCN.initial, SCN.params.replace(aero_coeff=1e-9))
    nav = Navigation(position_sigma=0.01, velocity_sigma=0.01, seed=7)
    res = fly_closed_loop(no_aero, Disturbance(), SETTINGS, nav=nav)
    _landed(res)
    rng = np.random.default_rng(7)
    draws = [(rng.normal(0, 0.01, 3), rng.normal(0, 0.01, 3)) for _ in res.replans]
    for r, (e_r, e_v) in zip(res.replans, draws, strict=True):
        assert r.knowledge_error == pytest.approx((np.linalg.norm(e_r), np.linalg.norm(e_v)))
    last = max(i for i, r in enumerate(res.replans) if r.kept)
    e_r, e_v = draws[last]
    T = res.closed.touchdown - res.replans[last].t
    assert res.closed.velocity_error == pytest.approx(np.linalg.norm(e_v), abs=5e-4)
    assert res.closed.position_error == pytest.approx(np.linalg.norm(e_r + e_v * T), abs=5e-4)
    assert res.closed.position_error > 5e-3  # far above the plan's own miss
    # perfect navigation: the same flight as without it, to the bit
    again = fly_closed_loop(no_aero, Disturbance(), SETTINGS, nav=Navigation())
    perfect = fly_closed_loop(no_aero, Disturbance(), SETTINGS)
    assert again.closed == perfect.closed
    assert all(r.knowledge_error == (0.0, 0.0) for r in perfect.replans)


def test_the_report_says_what_was_flown() -> None:
    from guidance.closed_loop import Flight, Replan, report

    def flight(error: float) -> Flight:
        return Flight(6.0, error, 0.0, 0.0, 0.0, 2.2, -1.0)

    replan = Replan(0.5, (0.012, 0.0034), "infeasible", False, 13, np.nan, np.nan)
    res = ClosedLoop("solved", 2.24, flight(0.02), flight(0.004), [replan])
    text = report(res, Disturbance(), SETTINGS, Navigation(0.01, 0.002, 5))
    assert "navigation: position error 0.01 U_L, velocity error 0.002 U_L/U_T" in text
    assert "seed 5" in text and "re-plans: 1, 0 kept" in text
    assert "   0.50    1.20e-02    3.40e-03  infeasible" in text
    assert text.endswith("landing error: closed loop 5.0x larger than open loop")
    res.closed, res.open = flight(0.004), flight(0.02)
    text = report(res, Disturbance(), SETTINGS)
    assert "navigation: perfect" in text
    assert text.endswith("landing error: closed loop 5.0x smaller than open loop")


def test_the_worst_path_value_names_its_constraint() -> None:
    """Review of 27 Nov: "max path" was the largest value over all seven constraints, in their
    mixed units, without saying which; the flight names it (open loop through a 2 % thrust
    error, the glideslope; closed loop, the commanded thrust dipping below T_min)."""
    from guidance.closed_loop import Flight, _landing, report

    first = np.full((3, 7), -1.0)
    first[1, 4] = 0.5  # thrust_max
    worst = np.full((2, 7), -1.0)
    worst[0, 1] = 0.7  # glideslope, the largest
    f = _landing(SCN.x0, 1.0, SCN, [first, np.empty((0, 7)), worst])
    assert f.max_path_value == 0.7 and f.max_path_constraint == "glideslope"
    none = _landing(SCN.x0, 1.0, SCN, [])
    assert none.max_path_value == -np.inf and none.max_path_constraint == ""
    flown = Flight(6.0, 0.01, 0.0, 0.0, 0.0, 2.2, 2.15e-3, "thrust_min")
    text = report(ClosedLoop("solved", 2.24, flown, flown, []), Disturbance(), SETTINGS)
    assert "max path (constraint)" in text and "2.15e-03 thrust_min" in text
