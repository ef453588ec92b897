"""The open-loop audit (guidance.verify) must detect bad trajectories, not only pass good ones.

References: an interval-by-interval scipy integration of the CasADi model (guidance.model)
under a first-order-hold thrust written here, and hand-derived constraint values.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from guidance.catalog import SCENARIOS
from guidance.model import dynamics_functions, param_vector
from guidance.params import IQ, IR, IV, IW
from guidance.verify import audit, engine_landing_error, propagate, propagate_sampled

SCN = SCENARIOS["default"]
P = SCN.params


@pytest.fixture(scope="module")
def landing(default_solved) -> tuple[np.ndarray, np.ndarray, float]:
    _, r = default_solved
    return r.x, r.u, r.t_f


def reference_propagation(x0: np.ndarray, u: np.ndarray, t_f: float) -> np.ndarray:
    """States at the N node times: scipy DOP853 at rtol = atol = 1e-12 of the CasADi dynamics,
    restarted at every node so the kinks of the first-order hold never fall inside a step."""
    f, _ = dynamics_functions()
    pv = param_vector(P)
    N = u.shape[0]
    dt = t_f / (N - 1)
    out = [np.asarray(x0, float)]
    for k in range(N - 1):
        uk, uk1 = u[k], u[k + 1]

        def rhs(t: float, x: np.ndarray, uk=uk, uk1=uk1) -> np.ndarray:
            s = t / dt
            return np.asarray(f(x, (1 - s) * uk + s * uk1, pv)).ravel()

        sol = solve_ivp(rhs, (0.0, dt), out[-1], rtol=1e-12, atol=1e-12, method="DOP853")
        out.append(sol.y[:, -1])
    return np.array(out)


@pytest.mark.parametrize(("stride", "tol"), [(49, 1e-8), (7, 5e-8), (1, 1e-8)])
def test_propagate_matches_tight_reference(landing, stride: int, tol: float) -> None:
    """propagate at its default tolerance agrees with a 1e-12 integration to ~1e-8.

    The thrust is sampled every ``stride`` nodes (2, 8 and all 50 nodes over the same t_f):
    with few long hold intervals a loose integration tolerance shows (rtol 1e-3 is 1e-3 to
    3e-2 off); on the 50-node grid an integration that steps across the hold's kinks is
    1.5e-7 off.
    """
    x, u, t_f = landing
    us = u[::stride]
    got = propagate(x[0], us, t_f, P)
    ref = reference_propagation(x[0], us, t_f)
    assert got.shape == ref.shape == (us.shape[0], 14)
    assert np.abs(got - ref).max() < tol


def test_audit_landing_error_uses_propagation(landing) -> None:
    """Perturbing the thrust while keeping the node states must show up in the landing error,
    which is |r(t_f) - r_f| of the open-loop propagation (not of the node states), and in the
    touchdown attitude and rate (`guidance verify`'s "final attitude" and "final rate"): the
    reference landing ends upright at rest (both ~1e-14 .. 3e-6), so no other test sees a
    rate figure that is wrong, or stuck at 0, on a finite flight."""
    x, u, t_f = landing
    u_bad = u.copy()
    u_bad[:, 1] += 0.2  # a lateral thrust bias, node states untouched
    a = audit(x, u_bad, t_f, P)
    ref = reference_propagation(x[0], u_bad, t_f)
    want_r = np.linalg.norm(ref[-1, IR] - np.array(P.r_f))
    want_v = np.linalg.norm(ref[-1, IV] - np.array(P.v_f))
    assert want_r > 0.1  # the perturbation is large: the node states still land exactly
    assert np.linalg.norm(x[-1, IR] - np.array(P.r_f)) < 1e-6
    assert a.landing_position_error == pytest.approx(want_r, rel=1e-6)
    assert a.landing_velocity_error == pytest.approx(want_v, rel=1e-6)
    assert a.max_node_deviation == pytest.approx(np.abs(ref - x).max(), rel=1e-6)
    # the bias torques the vehicle (thrust offset from the centre of mass): it lands turning
    # (1.37 rad/U_T) and tilted (|(q2, q3)| 0.89) though the node states end upright at rest
    want_w = np.linalg.norm(ref[-1, IW] - np.array(P.omega_f))
    want_q = np.linalg.norm(ref[-1, IQ][2:4])  # roll-free: |(q2, q3)|
    assert want_w > 0.1 and want_q > 0.1
    assert np.linalg.norm(x[-1, IW] - np.array(P.omega_f)) < 1e-9
    assert a.final_rate_error == pytest.approx(want_w, rel=1e-6)
    assert a.final_attitude_error == pytest.approx(want_q, rel=1e-6)
    # the unperturbed landing passes
    good = audit(x, u, t_f, P)
    assert good.landing_position_error < 1e-3


def test_audit_reports_thrust_below_minimum(landing) -> None:
    """|T| = T_min - 0.1 at one node: max_path_violation (h in thrust units) = 0.1."""
    x, u, t_f = landing
    u_bad = u.copy()
    k = 20
    u_bad[k] *= (P.T_min - 0.1) / np.linalg.norm(u[k])  # same direction: gimbal still met
    a = audit(x, u_bad, t_f, P)
    assert a.max_path_violation == pytest.approx(0.1, abs=1e-6)


@pytest.mark.parametrize(("lo", "hi", "held"), [(0.1, 0.9, "T_min"), (1.1, 3.0, "T_max")])
def test_engine_flies_its_limit_where_the_command_passes_it(
    landing, lo: float, hi: float, held: str
) -> None:
    """A command along the thrust axis below T_min (above T_max) everywhere is flown at T_min
    (T_max): the same states as the constant command at the limit, which the CasADi
    reference integrates without any limiting."""
    x, u, t_f = landing
    limit = getattr(P, held)
    command = np.zeros_like(u)
    command[:, 0] = np.linspace(lo, hi, u.shape[0]) * limit
    constant = np.zeros_like(u)
    constant[:, 0] = limit
    got = propagate_sampled(x[0], command, t_f, P, 0, engine=True).nodes
    assert np.abs(got - reference_propagation(x[0], constant, t_f)).max() < 1e-8
    assert np.abs(propagate(x[0], command, t_f, P) - got).max() > 1e-2  # the command differs


def test_engine_landing_error_is_the_plans_when_the_thrust_stays_in_range(landing) -> None:
    x, u, t_f = landing
    plan = audit(x, u, t_f, P, between=8)
    assert plan.path_between_nodes[6] < 0.0  # the reference landing keeps T_min in between
    r, v = engine_landing_error(x, u, t_f, P)
    assert r == pytest.approx(plan.landing_position_error, rel=1e-9)
    assert v == pytest.approx(plan.landing_velocity_error, rel=1e-9)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"x": "short"}, r"x is \(49, 14\), the params ask for \(50, 14\)"),
        ({"t_f": 0.0}, "t_f = 0: holds no trajectory"),
        ({"t_f": float("nan")}, "t_f = nan: holds no trajectory"),  # used to hang
        ({"between": -1}, "between: expected an integer >= 0"),
        ({"between": 2.5}, "between: expected an integer >= 0"),
    ],
)
def test_audit_refuses_what_it_cannot_check(landing, change: dict, message: str) -> None:
    from guidance.errors import InputError

    x, u, t_f = landing
    args = {"x": x, "u": u, "t_f": t_f, "between": 0, **change}
    if isinstance(args["x"], str):  # "short"
        args["x"] = x[:-1]
    with pytest.raises(InputError, match=message):
        audit(args["x"], args["u"], args["t_f"], P, between=args["between"])
