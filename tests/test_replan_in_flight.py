"""In-flight re-planning (``guidance.guess.plan_remainder``, the C library's
``pdg_plan_remainder``, ``guidance solve --guess PLAN --at T``): the remainder of a plan from
time T starts the solve of the landing from the state at T.

- the remainder's thrust is the plan's first-order hold at the new node times, its states lie
  within the interpolation error of the plan flown open loop (scipy), and it is projected
  onto the new landing's boundary conditions;
- the C library computes it to the bit;
- from the state at T, reached by flying the plan open loop (scipy), the remainder re-plans
  the landing in fewer subproblems than the cubic guess, to the plan's final mass and
  touchdown time (the principle of optimality, within SCvx's convergence tolerances);
- bad input is refused with the reason.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from c_library import needs_c_library

from guidance import cguidance
from guidance.cli import main
from guidance.errors import InputError
from guidance.guess import plan_remainder
from guidance.params import InitialState, Scenario
from guidance.paths import BUILD_DIR
from guidance.scenario import scenario_to_dict
from guidance.scvx import SCvxResult
from guidance.trajectory_io import read_trajectory
from guidance.verify import T_F_RANGE, VALUE_LIMIT, audit, propagate

pytestmark = needs_c_library

SCN = Scenario()
NODE = 15  # re-plan at the plan's node 15 of 49: t = 15 t_f / 49


@pytest.fixture(scope="module")
def plan() -> SCvxResult:
    return cguidance.solve_c(SCN)


def state_at_node(plan: SCvxResult, k: int) -> tuple[Scenario, float]:
    """The landing from the plan's state at node k, flown there open loop (scipy), and t."""
    x = propagate(plan.x[0], plan.u, plan.t_f, SCN.params)[k]
    q = x[6:10] / np.linalg.norm(x[6:10])
    # the vehicle makes no roll torque: a roll rate of rounding noise could never be undone
    w = (0.0, float(x[11]), float(x[12]))
    init = InitialState(tuple(x[0:3]), tuple(x[3:6]), tuple(q), w, float(x[13]))
    return Scenario(init, SCN.params), plan.t_f * k / (SCN.params.N - 1)


def test_the_remainder_is_the_plan_from_t(plan: SCvxResult) -> None:
    here, t1 = state_at_node(plan, NODE)
    x, u, t_f = plan_remainder(here, plan.x, plan.u, plan.t_f, t1)
    N = SCN.params.N
    assert t_f == pytest.approx(plan.t_f - t1, rel=1e-15)
    t_new = t1 + np.linspace(0.0, t_f, N)
    t_old = np.linspace(0.0, plan.t_f, N)
    for i in range(3):  # the first-order hold, evaluated independently (np.interp)
        np.testing.assert_allclose(u[:, i], np.interp(t_new, t_old, plan.u[:, i]), atol=1e-12)
    np.testing.assert_array_equal(x[0], here.x0)  # projected: node 0 is the new start
    flown = propagate(plan.x[0], plan.u, plan.t_f, SCN.params, rtol=1e-10)
    dense = np.array([np.interp(t_new, t_old, flown[:, i]) for i in range(14)]).T
    # linear interpolation between nodes 0.14 U_T apart: within a few 1e-3 of the flown states
    assert np.abs(x[1:-1, :6] - dense[1:-1, :6]).max() < 5e-3


@pytest.mark.parametrize("t1_fraction", [0.0, 0.37, 0.99])
def test_the_c_library_computes_it_to_the_bit(plan: SCvxResult, t1_fraction: float) -> None:
    t1 = t1_fraction * plan.t_f
    a = plan_remainder(SCN, plan.x, plan.u, plan.t_f, t1)
    b = cguidance.plan_remainder_c(SCN, plan.x, plan.u, plan.t_f, t1)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert a[2] == b[2]


def test_node_0_is_the_start_as_given_not_renormalized(plan: SCvxResult) -> None:
    """A start whose q0 is off unit length within the input tolerance (1e-6) is the
    subproblem's boundary condition as given: the remainder's node 0 must be that state to
    the bit, in Python and C alike (both normalized node 0's q again, moving it off by up to
    the tolerance; on a unit q0, by an ulp)."""
    here, t1 = state_at_node(plan, NODE)
    q = tuple(c * (1.0 + 5e-7) for c in here.initial.q0)
    init = InitialState(here.initial.r0, here.initial.v0, q, here.initial.w0, here.initial.m0)
    start = Scenario(init, SCN.params)
    x, _, _ = plan_remainder(start, plan.x, plan.u, plan.t_f, t1)
    cx, _, _ = cguidance.plan_remainder_c(start, plan.x, plan.u, plan.t_f, t1)
    np.testing.assert_array_equal(x[0], start.x0)
    np.testing.assert_array_equal(cx[0], start.x0)
    # the other nodes' attitudes are still made unit
    np.testing.assert_allclose(np.linalg.norm(x[1:, 6:10], axis=1), 1.0, atol=1e-15)


def test_the_remainder_replans_to_the_plan(plan: SCvxResult) -> None:
    """Measured 27 Nov: 9 subproblems (22 from the cubic guess), final mass 2.238491 against
    the plan's 2.238336, touchdown 6.8740 against 6.8749."""
    here, t1 = state_at_node(plan, NODE)
    guess = plan_remainder(here, plan.x, plan.u, plan.t_f, t1)
    replan, cold = cguidance.solve_c(here, guess=guess), cguidance.solve_c(here)
    assert replan.status == cold.status == "solved", (replan.reason, cold.reason)
    assert replan.subproblems_solved < cold.subproblems_solved
    assert abs(replan.m_f - plan.m_f) <= 2e-4 * plan.m_f
    assert abs(t1 + replan.t_f - plan.t_f) <= 2e-3 * plan.t_f
    a = audit(replan.x, replan.u, replan.t_f, SCN.params)
    assert a.landing_position_error <= 1e-3 and a.max_path_violation <= 1e-6


def test_replan_from_the_command_line(plan: SCvxResult, tmp_path: Path, capsys) -> None:
    here, t1 = state_at_node(plan, NODE)
    plan_file, scn_file, out = tmp_path / "plan.npz", tmp_path / "here.json", tmp_path / "r.npz"
    assert main(["solve", "--backend", "c", "--out", str(plan_file)]) == 0
    scn_file.write_text(json.dumps(scenario_to_dict(here)))
    args = ["solve", str(scn_file), "--backend", "c", "--guess", str(plan_file)]
    assert main([*args, "--at", repr(t1), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"its remainder from t = {t1:g} U_T" in printed
    data = read_trajectory(out)
    # the re-plan's t_f counts from t1; the touchdown is on the plan's clock, near the plan's
    t_f = float(data["t_f"])  # type: ignore[arg-type]
    assert f"{t_f:.6f} U_T from the re-plan (touchdown at t = {t1 + t_f:.6f}" in printed
    assert abs(t1 + t_f - plan.t_f) <= 2e-3 * plan.t_f
    assert f"initial_guess from t = {t1:g}" in data["provenance"]["files"]  # type: ignore[index]
    assert main([*args, "--at", "99"]) == 2
    assert "is not within the plan's [0, " in capsys.readouterr().err
    assert main(["solve", str(scn_file), "--at", "1"]) == 2
    assert "--at: applies with --guess only" in capsys.readouterr().err


def test_the_plain_c_example_replans(plan: SCvxResult) -> None:
    """build/pdg_example (no Python) solves the default landing, then re-plans from its node
    16 with pdg_plan_remainder: both solved, the plan's final mass printed as the library
    gives it, the re-plan's within 2e-4 of it in fewer subproblems."""
    import re
    import subprocess

    example = BUILD_DIR / "pdg_example"  # not beside the library: `make coverage` moves that
    run = subprocess.run([str(example)], capture_output=True, text=True, check=False, timeout=120)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr
    summary = re.search(r"subproblems (\d+), t_f [\d.]+, m_f ([\d.]+)", run.stdout)
    assert summary and float(summary.group(2)) == pytest.approx(plan.m_f, abs=1e-6)
    line = re.search(
        r"re-plan at .*: solved \(.*\), (\d+) subproblems, .* m_f ([\d.]+)", run.stdout
    )
    assert line, run.stdout[-600:]
    assert int(line.group(1)) < int(summary.group(1))
    assert float(line.group(2)) == pytest.approx(plan.m_f, rel=2e-4)


@pytest.mark.parametrize("t1", [-0.1, float("nan"), 1e9])
def test_a_time_off_the_plan_is_refused(plan: SCvxResult, t1: float) -> None:
    with pytest.raises(InputError, match="not within the plan's"):
        plan_remainder(SCN, plan.x, plan.u, plan.t_f, t1)
    with pytest.raises(InputError, match="not within the plan's"):
        cguidance.plan_remainder_c(SCN, plan.x, plan.u, plan.t_f, t1)


def test_a_plan_that_is_no_trajectory_is_refused(plan: SCvxResult) -> None:
    x = plan.x.copy()
    x[3, 2] = np.nan
    with pytest.raises(InputError, match="guess: x"):
        plan_remainder(SCN, x, plan.u, plan.t_f, 1.0)
    with pytest.raises(InputError, match="must be finite"):
        cguidance.plan_remainder_c(SCN, x, plan.u, plan.t_f, 1.0)
    with pytest.raises(InputError, match="x, u must be"):
        cguidance.plan_remainder_c(SCN, plan.x[:-1], plan.u, plan.t_f, 1.0)


def _edge_plans(plan: SCvxResult) -> dict[str, tuple[np.ndarray, np.ndarray, float, bool]]:
    """Plans at and just beyond the trajectory file's limits (verify.VALUE_LIMIT, T_F_RANGE),
    each with whether it is taken."""
    x_at, x_beyond = plan.x.copy(), plan.x.copy()
    x_at[7, 0], x_beyond[7, 0] = VALUE_LIMIT, np.nextafter(VALUE_LIMIT, np.inf)
    u_beyond = plan.u.copy()
    u_beyond[3, 1] = -2 * VALUE_LIMIT
    lo, hi = T_F_RANGE
    return {
        "x at the value limit": (x_at, plan.u, plan.t_f, True),
        "x beyond it": (x_beyond, plan.u, plan.t_f, False),
        "u beyond it": (plan.x, u_beyond, plan.t_f, False),
        "t_f at its least": (plan.x, plan.u, lo, True),
        "t_f below it": (plan.x, plan.u, np.nextafter(lo, 0.0), False),
        "t_f at its most": (plan.x, plan.u, hi, True),
        "t_f beyond it": (plan.x, plan.u, np.nextafter(hi, np.inf), False),
    }


EDGE_CASES = ["x at the value limit", "x beyond it", "u beyond it", "t_f at its least",
              "t_f below it", "t_f at its most", "t_f beyond it"]  # fmt: skip


@pytest.mark.parametrize("case", EDGE_CASES)
def test_a_plan_out_of_range_is_refused_alike(plan: SCvxResult, case: str) -> None:
    """Python and the C library take and refuse the same plans, at the limits a trajectory
    file is checked against (C: PDG_PLAN_VALUE_MAX, PDG_PLAN_T_F_MIN/MAX)."""
    x, u, t_f, taken = _edge_plans(plan)[case]
    t1 = 0.5 * t_f
    if taken:
        gx, gu, gt_f = plan_remainder(SCN, x, u, t_f, t1)
        cx, cu, ct_f = cguidance.plan_remainder_c(SCN, x, u, t_f, t1)
        assert np.array_equal(gx, cx) and np.array_equal(gu, cu) and gt_f == ct_f
        return
    with pytest.raises(InputError, match=r"beyond|t_f = "):
        plan_remainder(SCN, x, u, t_f, t1)
    with pytest.raises(InputError, match=r"beyond|t_f = "):
        cguidance.plan_remainder_c(SCN, x, u, t_f, t1)
