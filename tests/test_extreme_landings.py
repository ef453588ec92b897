"""Landings at the edges of what validation accepts (no fuel to spare, an engine too weak or
too strong, a vehicle that is nearly weightless to torque, drag that overflows the model):
each ends with a status and its reason, never an exception or a numpy warning, and the C
library gives the Python reference's status.

Infeasible ones are not compared further: their subproblems are ill-posed, and the loops part
ways within the conic solvers' tolerances (at N = 3, 49 RK4 steps per interval, the first
candidate's penalty differs by 4e-5 relative between Clarabel and the C runtime, by 3e-9
between the Python loop on the C runtime and the C loop, whose patterns differ by the C
loop's explicit zeros), then stop after 20, 14 and 13 iterations (27 Nov)."""

from __future__ import annotations

import warnings

import pytest

from guidance import cguidance
from guidance.errors import InputError
from guidance.guess import initial_guess
from guidance.params import InitialState, Params, Scenario
from guidance.scenario import MAGNITUDE_MAX, ScenarioError, validate
from guidance.scvx import SCvxSolver
from guidance.verify import audit

# name -> (scenario, the status the 23 Nov probe found with Clarabel and with the C library)
CASES = {
    "no fuel to spare": (Scenario(InitialState(m0=2.0 + 1e-9)), "infeasible"),
    "thrown upwards": (Scenario(InitialState(v0=(1000.0, 0.0, 0.0))), "solver_error"),
    "drag overflows the model": (Scenario(params=Params(aero_coeff=1e3)), "solver_error"),
    "three nodes": (Scenario(params=Params(N=3)), "infeasible"),
    "weak engine": (Scenario(params=Params(T_max=1e-3, T_min=1e-4)), "infeasible"),
    "tiny inertia": (Scenario(params=Params(J_B=(1e-9, 1e-8, 1e-8))), "solved"),
    # at the edge of validation's envelope of magnitudes (scenario.MAGNITUDE_MAX)
    "far above the pad": (Scenario(InitialState(r0=(MAGNITUDE_MAX, 0.0, 0.0))), "solver_error"),
    "thrown sideways": (Scenario(InitialState(v0=(0.0, MAGNITUDE_MAX, 0.0))), "solver_error"),
    "heavy": (Scenario(InitialState(m0=MAGNITUDE_MAX)), "infeasible"),
}
EDGE = ("far above the pad", "thrown sideways", "heavy")


@pytest.mark.parametrize("name", list(CASES))
def test_an_extreme_landing_ends_with_a_status_in_python_and_in_c(name: str) -> None:
    scenario, expected = CASES[name]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reference = SCvxSolver(scenario).solve()  # Clarabel
        python_c = SCvxSolver(scenario, backend="c").solve()
        c = cguidance.solve_c(scenario)
    assert reference.status == python_c.status == c.status == expected, (
        reference.reason, c.reason)  # fmt: skip
    if expected == "solver_error":  # decided at the first subproblem or before it
        assert c.reason == python_c.reason == reference.reason
    if expected == "solved":
        assert audit(c.x, c.u, c.t_f, scenario.params).max_path_violation <= 1e-6


@pytest.mark.parametrize("backend", ["clarabel", "c"])
def test_tscvx_without_propellant_is_an_infeasible_landing(backend: str) -> None:
    """T-SCvx from the networks' warm start (trust radius 0.01) on the landing with no fuel
    to spare: an infeasible landing, as SCvx says. With the mass scaled by the propellant
    itself (1e-9) both conic solvers certified the first reduced subproblem infeasible, which
    stopped the solve with a solver error (subproblem.MASS_SCALE_FLOOR)."""
    from guidance.api import solve

    scenario = CASES["no fuel to spare"][0]
    result = solve(scenario, method="tscvx", backend=backend)
    assert result.status == "infeasible", result.reason


@pytest.mark.parametrize("name", EDGE)
def test_tscvx_at_the_envelope_edge_ends_with_the_same_status(name: str) -> None:
    """The networks' warm start far outside their training data still ends in a status,
    the same in the Python loop and in C."""
    from guidance.api import solve

    scenario, _ = CASES[name]
    validate(scenario)  # inside the envelope
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reference = solve(scenario, method="tscvx", backend="clarabel")
        c = solve(scenario, method="tscvx", backend="c")
    assert reference.status == c.status != "solved", (reference.reason, c.reason)


def test_the_reference_loop_refuses_what_the_c_loop_refuses() -> None:
    """r0 = 1e9 overflows the cubic guess. The reference's own loop took any scenario until
    26 Nov (it ended this one with a solver_error status, after numpy warnings) while the C
    loop refused it by name; both now check the scenario as a scenario file is checked."""
    scenario = Scenario(InitialState(r0=(1e9, 0.0, 0.0)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ScenarioError, match="r0") as ref:
            SCvxSolver(scenario)
        with pytest.raises(ScenarioError, match="r0") as c:
            cguidance.solve_c(scenario)
    assert str(ref.value) == str(c.value)


@pytest.mark.parametrize("broken", ["x", "t_f"])
def test_a_non_finite_guess_is_refused(broken: str) -> None:
    scenario = Scenario()
    x, u, t_f = initial_guess(scenario)
    if broken == "x":
        x[5, 3] = float("nan")
    else:
        t_f = float("inf")
    with pytest.raises(InputError, match="guess: x, u and t_f must be finite"):
        SCvxSolver(scenario).solve(guess=(x, u, t_f))
