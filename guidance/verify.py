"""Independent checks of a trajectory: open-loop integration with scipy and constraint audit.

The dynamics here are written again in plain numpy from DESIGN.md (not through CasADi), so
that a landing that passes is checked by code that shares nothing with the solver but the
equations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from guidance.constraints import path_constraint_values
from guidance.errors import InputError
from guidance.params import CONSTRAINT_NAMES, IM, IQ, IR, IV, IW, NU, NX, Params

# What the check propagates: a landing takes a few U_T, and its states and thrust are O(1)
# to O(10) in the nondimensional units; far outside these the propagation does not end.
T_F_RANGE = (1e-6, 1e4)  # U_T
VALUE_LIMIT = 1e9
# Right-hand-side evaluations allowed per interval. A landing needs at most 116 at rtol 1e-10
# (47 the catalog's, 116 the 1e-9-inertia landing of the extreme tests); a thrust or rate far
# outside any landing (u = 1e5, inside VALUE_LIMIT) makes the integrator crawl or fail, and the
# check then ran for more than ten minutes, so such an interval is stopped and reported.
MAX_EVALUATIONS = 20_000
# The path constraints on the state (the others bound the thrust command, which the flight
# takes from the file as it is): what the flown trajectory is judged against.
STATE_CONSTRAINTS = tuple(
    CONSTRAINT_NAMES.index(n) for n in ("mass", "glideslope", "tilt", "omega")
)


class PropagationError(ArithmeticError):
    """The open-loop integration of an interval could not reach its end."""


def _dcm_bi(q: np.ndarray) -> np.ndarray:
    q0, q1, q2, q3 = q
    return np.array(
        [
            [1 - 2 * (q2**2 + q3**2), 2 * (q1 * q2 + q0 * q3), 2 * (q1 * q3 - q0 * q2)],
            [2 * (q1 * q2 - q0 * q3), 1 - 2 * (q1**2 + q3**2), 2 * (q2 * q3 + q0 * q1)],
            [2 * (q1 * q3 + q0 * q2), 2 * (q2 * q3 - q0 * q1), 1 - 2 * (q1**2 + q2**2)],
        ]
    )


def dynamics_numpy(x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """dx/dt of DESIGN.md in plain numpy (physical time)."""
    v, q, w, m = x[IV], x[IQ], x[IW], x[IM]
    J = np.array(p.J_B)
    C_BI = _dcm_bi(q)
    v_B = C_BI @ v
    A_B = -p.aero_coeff * np.linalg.norm(v_B) * v_B
    w1, w2, w3 = w
    Omega = np.array([[0, -w1, -w2, -w3], [w1, 0, w3, -w2], [w2, -w3, 0, w1], [w3, w2, -w1, 0]])
    torque = np.cross(p.r_T_B, u) + np.cross(p.r_cp_B, A_B) - np.cross(w, J * w)
    return np.concatenate(
        [
            v,
            C_BI.T @ (u + A_B) / m + np.array(p.g_I),
            0.5 * Omega @ q,
            torque / J,
            [-p.alpha_mdot * np.linalg.norm(u) - p.beta_mdot],
        ]
    )


def engine_thrust(u: np.ndarray, p: Params) -> np.ndarray:
    """What an engine that can only throttle within [T_min, T_max] gives for the command u
    (same direction; the gimbal cone is convex, so a first-order hold never leaves it)."""
    n = float(np.linalg.norm(u))
    if 0.0 < n < p.T_min:
        return u * (p.T_min / n)
    if n > p.T_max:
        return u * (p.T_max / n)
    return u


def fly_interval(
    x0: np.ndarray,
    u_k: np.ndarray,
    u_k1: np.ndarray,
    dt: float,
    p: Params,
    rtol: float,
    dense: bool,
    engine: bool = False,
    thrust_scale: float = 1.0,
    accel_bias: np.ndarray | None = None,
):  # -> scipy's OdeResult
    """One interval of open-loop flight from x0 under the first-order hold from u_k (t = 0) to
    u_k1 (t = dt); ``engine``: the thrust an engine limited to [T_min, T_max] gives for it
    (``engine_thrust``); the engine's thrust times ``thrust_scale`` and an inertial
    acceleration ``accel_bias`` (3,) the plan does not know of (``closed_loop``).
    PropagationError says why it did not reach dt."""
    du = u_k1 - u_k
    evaluations = 0
    bias = None if accel_bias is None else np.concatenate([np.zeros(3), accel_bias, np.zeros(8)])

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        if evaluations > MAX_EVALUATIONS:  # solve_ivp passes the exception on
            raise PropagationError(f"more than {MAX_EVALUATIONS} evaluations of the dynamics")
        u = u_k + (t / dt) * du
        dx = dynamics_numpy(x, thrust_scale * (engine_thrust(u, p) if engine else u), p)
        return dx if bias is None else dx + bias

    # an overflow shows as a non-finite state below, not as numpy's warnings on the way
    with np.errstate(all="ignore"):
        sol = solve_ivp(
            rhs, (0.0, dt), x0, rtol=rtol, atol=rtol, method="DOP853", dense_output=dense
        )
    if sol.status != 0:
        raise PropagationError(f"the integrator failed ({sol.message.rstrip('.')})")
    if not np.isfinite(sol.y[:, -1]).all():
        raise PropagationError("the state is no longer finite")
    return sol


def integrate_interval(
    x0: np.ndarray, u_k: np.ndarray, u_k1: np.ndarray, dt: float, p: Params, rtol: float
) -> np.ndarray:
    """x(dt) from x0 under the first-order hold from u_k (t = 0) to u_k1 (t = dt);
    PropagationError when the integration cannot reach dt."""
    return fly_interval(x0, u_k, u_k1, dt, p, rtol, False).y[:, -1]


@dataclass
class Propagation:
    nodes: np.ndarray  # (N, 14) propagated states at the node times
    x_between: np.ndarray  # (N - 1, s, 14) at s equally spaced times inside each interval
    u_between: np.ndarray  # (N - 1, s, 3) the first-order-hold thrust there
    # why the integration stopped before t_f ("" when it did not); the states from there
    # on are NaN
    stopped: str = ""


def propagate_sampled(
    x0: np.ndarray,
    u: np.ndarray,
    t_f: float,
    p: Params,
    between: int,
    rtol: float = 1e-10,
    engine: bool = False,
) -> Propagation:
    """Open-loop integration from x0 under the FOH thrust: the states at the N node times and
    at ``between`` times inside each interval (from the integrator's dense output, which
    leaves its steps and so the node states unchanged). ``engine``: the thrust an engine
    limited to [T_min, T_max] gives for the FOH command (``engine_thrust``), not the command.

    Each interval is integrated on its own, the state carried over: the thrust has a kink at
    every node, and a step across one leaves the error estimate blind to it: on the default
    landing, against an interval-wise integration at 1e-13, 1.5e-7 in one go, 1.4e-9 so."""
    N = u.shape[0]
    dt = t_f / (N - 1)
    s = np.arange(1, between + 1) / (between + 1)  # fractions of the interval
    nodes = np.full((N, len(x0)), np.nan)
    xb = np.full((N - 1, between, len(x0)), np.nan)
    ub = u[:-1, None, :] + s[None, :, None] * (u[1:] - u[:-1])[:, None, :]
    nodes[0] = x0
    for k in range(N - 1):
        try:
            sol = fly_interval(nodes[k], u[k], u[k + 1], dt, p, rtol, between > 0, engine)
        except PropagationError as exc:
            return Propagation(nodes, xb, ub, f"interval {k} of {N - 1}: {exc}")
        nodes[k + 1] = sol.y[:, -1]
        if between > 0:
            xb[k] = sol.sol(s * dt).T
    return Propagation(nodes, xb, ub)


def propagate(
    x0: np.ndarray, u: np.ndarray, t_f: float, p: Params, rtol: float = 1e-10
) -> np.ndarray:
    """Open-loop integration from x0 under the FOH thrust; states at the N node times."""
    return propagate_sampled(x0, u, t_f, p, 0, rtol).nodes


def final_attitude_error(q: np.ndarray, p: Params) -> float:
    """Roll-free touchdown: |(q2, q3)| (upright, any roll). Pinned: the distance to q_f or
    -q_f, whichever is nearer (q and -q are the same attitude)."""
    if p.final_roll_free:
        return float(np.linalg.norm(q[2:4]))
    q_f = np.asarray(p.q_f)
    return float(min(np.linalg.norm(q - q_f), np.linalg.norm(q + q_f)))


def _landing_errors(x_final: np.ndarray, p: Params) -> tuple[float, float]:
    """|r(t_f) - r_f| and |v(t_f) - v_f| of a propagated final state."""
    return (
        float(np.linalg.norm(x_final[IR] - np.array(p.r_f))),
        float(np.linalg.norm(x_final[IV] - np.array(p.v_f))),
    )


@dataclass
class Audit:
    landing_position_error: float  # |r(t_f) - r_f| of the open-loop propagation
    landing_velocity_error: float
    max_path_violation: float  # max over nodes and constraints of h (<= 0 when met)
    max_node_deviation: float  # max |x_propagated - x| over nodes
    final_attitude_error: float  # final_attitude_error() of the propagated q(t_f)
    final_rate_error: float  # |omega(t_f) - omega_f|, propagated
    path_at_nodes: np.ndarray  # (7,) max over the nodes of each constraint's h
    # (7,) max of h on the propagated trajectory between the nodes (NaN when not sampled):
    # the method imposes the constraints at the nodes only
    path_between_nodes: np.ndarray
    # max h of the state constraints (STATE_CONSTRAINTS) at the flown trajectory's nodes (the
    # propagated node states; NaN when the propagation stopped). The file's node states
    # meeting the constraints says nothing of the flight, which may leave them by up to the
    # node-deviation tolerance
    max_flown_state_violation: float = float("nan")
    # why the open-loop propagation stopped before t_f ("" when it reached t_f); the
    # propagated figures are then NaN, which fails every check on them
    propagation_stopped: str = ""


def checked_trajectory(
    x: object, u: object, t_f: object, p: Params
) -> tuple[np.ndarray, np.ndarray, float]:
    """x (N x 14), u (N x 3) and t_f as audit needs them; InputError names what is wrong."""
    out = []
    for name, value, cols in (("x", x, NX), ("u", u, NU)):
        a = np.asarray(value)
        if a.dtype.kind not in "iuf":
            raise InputError(f"{name}: expected real numbers, got {a.dtype} values")
        a = a.astype(float)
        if a.shape != (p.N, cols):
            raise InputError(f"{name} is {a.shape}, the params ask for ({p.N}, {cols})")
        if not np.isfinite(a).all():
            raise InputError(f"{name}: holds no trajectory (values not finite)")
        if np.abs(a).max() > VALUE_LIMIT:
            raise InputError(f"{name}: values beyond {VALUE_LIMIT:g}, outside any landing")
        out.append(a)
    tf = np.asarray(t_f)
    if tf.dtype.kind not in "iuf" or tf.size != 1:
        raise InputError(f"t_f: expected one real number, got {t_f!r}")
    t = float(tf.reshape(-1)[0])
    if not T_F_RANGE[0] <= t <= T_F_RANGE[1]:
        raise InputError(
            f"t_f = {t:g}: holds no trajectory the check can fly (t_f within "
            f"[{T_F_RANGE[0]:g}, {T_F_RANGE[1]:g}] U_T)"
        )
    return out[0], out[1], t


def audit(x: np.ndarray, u: np.ndarray, t_f: float, p: Params, between: int = 0) -> Audit:
    """The open-loop check of a trajectory; ``between`` > 0 also samples the path constraints
    at that many times inside each interval. Bad input raises InputError."""
    if isinstance(between, bool) or not isinstance(between, int | np.integer) or between < 0:
        raise InputError(f"between: expected an integer >= 0, got {between!r}")
    x, u, t_f = checked_trajectory(x, u, t_f, p)
    prop = propagate_sampled(x[0], u, t_f, p, int(between))
    xp = prop.nodes
    landing = _landing_errors(xp[-1], p)
    h = path_constraint_values(x, u, p)
    # the flight at the nodes, where the method imposes the constraints (between them it
    # does not: path_between_nodes reports what the flight does there)
    flown = path_constraint_values(xp, u, p)[:, STATE_CONSTRAINTS]
    if between > 0:
        hb = path_constraint_values(
            prop.x_between.reshape(-1, xp.shape[1]), prop.u_between.reshape(-1, u.shape[1]), p
        ).max(axis=0)
    else:
        hb = np.full(h.shape[1], np.nan)
    return Audit(
        landing_position_error=landing[0],
        landing_velocity_error=landing[1],
        max_path_violation=float(h.max()),
        max_node_deviation=float(np.abs(xp - x).max()),
        final_attitude_error=final_attitude_error(xp[-1, IQ], p),
        final_rate_error=float(np.linalg.norm(xp[-1, IW] - np.array(p.omega_f))),
        path_at_nodes=h.max(axis=0),
        path_between_nodes=hb,
        max_flown_state_violation=float(flown.max()),  # NaN from a stopped propagation
        propagation_stopped=prop.stopped,
    )


def engine_landing_error(
    x: np.ndarray, u: np.ndarray, t_f: float, p: Params
) -> tuple[float, float]:
    """|r(t_f) - r_f| and |v(t_f) - v_f| when an engine limited to [T_min, T_max] flies the
    plan: where the first-order hold's norm dips below T_min between the nodes, it gives
    T_min (``engine_thrust``). The cost of the dip, open loop."""
    return _landing_errors(propagate_sampled(x[0], u, t_f, p, 0, engine=True).nodes[-1], p)
