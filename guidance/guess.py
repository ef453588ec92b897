"""Initial guess for SCvx: a dynamically consistent cubic landing profile (no optimization).

The position is the cubic Hermite curve matching r0, v0 at t = 0 and r_f, v_f at t_f, so that
r' = v holds exactly. The thrust is whatever that curve needs, T_I = m (r'' - g) + c_A |v| v
(drag in the inertial frame is -c_A |v| v whatever the attitude), limited to [T_min, T_max].
Body axis 1 points along T_I (zero gimbal) with zero roll; over the first quarter of the
flight the attitude blends from q0 into that profile. The angular rate is the least-squares
solution of q' = 1/2 Omega(omega) q, and the mass integrates m' = -alpha |T| - beta.
t_f is chosen on a grid as the cheapest profile whose thrust stays within T_max.
"""

from __future__ import annotations

import numpy as np

from guidance.errors import InputError
from guidance.model import dcm_bi_numpy
from guidance.params import (
    I_HORIZONTAL,
    I_UP,
    IM,
    IQ,
    IR,
    IV,
    IW,
    NU,
    NX,
    U_AXIAL,
    U_LATERAL,
    Scenario,
)
from guidance.verify import checked_trajectory

BLEND_FRACTION = 0.25
TF_GRID = np.geomspace(0.5, 20.0, 60)


def _hermite(
    r0: np.ndarray, v0: np.ndarray, rf: np.ndarray, vf: np.ndarray, t_f: float, s: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cubic Hermite position, velocity and acceleration at normalized times s (N,)."""
    s = s[:, None]
    h00, h10, h01, h11 = (
        2 * s**3 - 3 * s**2 + 1,
        s**3 - 2 * s**2 + s,
        -2 * s**3 + 3 * s**2,
        s**3 - s**2,
    )
    d00, d10, d01, d11 = 6 * s**2 - 6 * s, 3 * s**2 - 4 * s + 1, -6 * s**2 + 6 * s, 3 * s**2 - 2 * s
    a00, a10, a01, a11 = 12 * s - 6, 6 * s - 4, -12 * s + 6, 6 * s - 2
    m0, m1 = v0 * t_f, vf * t_f
    r = h00 * r0 + h10 * m0 + h01 * rf + h11 * m1
    v = (d00 * r0 + d10 * m0 + d01 * rf + d11 * m1) / t_f
    a = (a00 * r0 + a10 * m0 + a01 * rf + a11 * m1) / t_f**2
    return r, v, a


def _required_thrust(scenario: Scenario, t_f: float, s: np.ndarray) -> tuple[np.ndarray, ...]:
    p, st = scenario.params, scenario.initial
    r, v, a = _hermite(np.array(st.r0), np.array(st.v0), np.array(p.r_f), np.array(p.v_f), t_f, s)
    g = np.array(p.g_I)
    drag = p.aero_coeff * np.linalg.norm(v, axis=1, keepdims=True) * v
    # mass along the profile: integrate m' = -alpha |T| - beta with T computed at the current m
    N = len(s)
    m = np.empty(N)
    T_I = np.empty((N, 3))
    m[0] = st.m0
    dt = t_f * np.diff(s)
    for k in range(N):
        T_I[k] = m[k] * (a[k] - g) + drag[k]
        if k + 1 < N:
            mdot = -p.alpha_mdot * np.linalg.norm(T_I[k]) - p.beta_mdot
            m[k + 1] = m[k] + dt[k] * mdot
    return r, v, T_I, m


def _smoothstep(a: np.ndarray) -> np.ndarray:
    a = np.clip(a, 0.0, 1.0)
    return a * a * (3.0 - 2.0 * a)


def _min_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation matrix of the smallest rotation taking unit vector a to unit vector b."""
    v = np.cross(a, b)
    c = float(a @ b)
    if c < -1.0 + 1e-9:  # opposite: rotate by pi about any axis normal to a
        n = np.cross(a, [0.0, 1.0, 0.0] if abs(a[1]) < 0.9 else [0.0, 0.0, 1.0])
        n /= np.linalg.norm(n)
        return 2.0 * np.outer(n, n) - np.eye(3)
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


def _quaternion_from_dcm_bi(C: np.ndarray) -> np.ndarray:
    """Inverse of dcm_bi_numpy: scalar-first q with C_B<-I(q) = C (Shepperd's method)."""
    tr = np.trace(C)
    cand = np.array([tr, C[0, 0], C[1, 1], C[2, 2]])
    i = int(np.argmax(cand))
    if i == 0:
        q0 = 0.5 * np.sqrt(1.0 + tr)
        q = np.array(
            [
                q0,
                (C[1, 2] - C[2, 1]) / (4 * q0),
                (C[2, 0] - C[0, 2]) / (4 * q0),
                (C[0, 1] - C[1, 0]) / (4 * q0),
            ]
        )
    elif i == 1:
        q1 = 0.5 * np.sqrt(1.0 + 2 * C[0, 0] - tr)
        q = np.array(
            [
                (C[1, 2] - C[2, 1]) / (4 * q1),
                q1,
                (C[0, 1] + C[1, 0]) / (4 * q1),
                (C[0, 2] + C[2, 0]) / (4 * q1),
            ]
        )
    elif i == 2:
        q2 = 0.5 * np.sqrt(1.0 + 2 * C[1, 1] - tr)
        q = np.array(
            [
                (C[2, 0] - C[0, 2]) / (4 * q2),
                (C[0, 1] + C[1, 0]) / (4 * q2),
                q2,
                (C[1, 2] + C[2, 1]) / (4 * q2),
            ]
        )
    else:
        q3 = 0.5 * np.sqrt(1.0 + 2 * C[2, 2] - tr)
        q = np.array(
            [
                (C[0, 1] - C[1, 0]) / (4 * q3),
                (C[0, 2] + C[2, 0]) / (4 * q3),
                (C[1, 2] + C[2, 1]) / (4 * q3),
                q3,
            ]
        )
    return q / np.linalg.norm(q)


def _attitude_along(d: np.ndarray) -> np.ndarray:
    """Zero-roll quaternions q_B<-I whose body axis 1 is the unit vector d (N, 3) in I."""
    c = np.clip(d[:, 0], -1.0, 1.0)
    q0 = np.sqrt(np.maximum((1.0 + c) / 2.0, 1e-6))
    # C_IB e1 = (1 - 2(q2^2 + q3^2), 2 q0 q3, -2 q0 q2) for q1 = 0
    q = np.stack([q0, np.zeros_like(q0), -d[:, 2] / (2 * q0), d[:, 1] / (2 * q0)], axis=1)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _omega_from_quaternions(q: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Least-squares omega_B of q' = 1/2 Omega(omega) q at every node."""
    qdot = np.gradient(q, t, axis=0)
    w = np.zeros((len(q), 3))
    for k, (qk, dk) in enumerate(zip(q, qdot, strict=True)):
        if not (np.all(np.isfinite(qk)) and np.all(np.isfinite(dk))):
            w[k] = np.nan  # an overflowed guess (see initial_guess); lstsq would raise
            continue
        q0, q1, q2, q3 = qk
        # Omega(omega) q = M(q) omega with M from DESIGN.md's Omega
        M = np.array([[-q1, -q2, -q3], [q0, -q3, q2], [q3, q0, -q1], [-q2, q1, q0]])
        w[k] = np.linalg.lstsq(0.5 * M, dk, rcond=None)[0]
    return w


# A landing far beyond validation's envelope (r0 = 1e6 or 1e9 in a Scenario that skipped it)
# overflows here; the discretization then refuses the guess (ModelEvaluationError), so the
# overflow needs no warning of its own.
@np.errstate(over="ignore", invalid="ignore")
def initial_guess(scenario: Scenario) -> tuple[np.ndarray, np.ndarray, float]:
    p, st = scenario.params, scenario.initial
    N = p.N
    s = np.linspace(0.0, 1.0, N)
    best = None
    for t_f in TF_GRID:
        _, _, T_I, m = _required_thrust(scenario, float(t_f), s)
        over = np.linalg.norm(T_I, axis=1).max() > p.T_max
        fuel = st.m0 - m[-1]
        key = (over, fuel if not over else np.linalg.norm(T_I, axis=1).max())
        if best is None or key < best[0]:
            best = (key, float(t_f))
    assert best is not None
    t_f = best[1]
    r, v, T_I, m = _required_thrust(scenario, t_f, s)
    # Desired body axis 1 in I: from the initial one, along the thrust, to upright at the end.
    C_IB0 = dcm_bi_numpy(np.array(st.q0)).T
    b0 = C_IB0[:, 0]
    d = T_I / np.maximum(np.linalg.norm(T_I, axis=1), 1e-9)[:, None]
    w_start = _smoothstep(1.0 - s / BLEND_FRACTION)[:, None]
    w_end = _smoothstep((s - (1.0 - BLEND_FRACTION)) / BLEND_FRACTION)[:, None]
    d = w_start * b0 + w_end * np.array([1.0, 0.0, 0.0]) + (1.0 - w_start - w_end) * d
    d /= np.maximum(np.linalg.norm(d, axis=1), 1e-9)[:, None]
    # Attitude: the smallest rotation taking b0 to d, applied to the initial attitude. This
    # commutes with rotations about the up axis, so a rotated scenario gets the rotated guess.
    q = np.array([_quaternion_from_dcm_bi((_min_rotation(b0, dk) @ C_IB0).T) for dk in d])
    # q and -q are the same attitude, but the iterate must start at the given q0 and stay
    # continuous from there (the sign would otherwise depend on the frame).
    if q[0] @ np.array(st.q0) < 0:
        q[0] = -q[0]
    for k in range(1, N):
        if q[k] @ q[k - 1] < 0:
            q[k] = -q[k]
    if not p.final_roll_free:
        q_f = scenario.x_final_target()[IQ]
        q = (1.0 - w_end) * q + w_end * np.where(q @ q_f < 0, -1.0, 1.0)[:, None] * q_f
        q /= np.linalg.norm(q, axis=1, keepdims=True)
    x = np.zeros((N, NX))
    x[:, IR], x[:, IV], x[:, IQ] = r, v, q
    t = s * t_f
    w = _omega_from_quaternions(q, t)
    w[:, 0] = st.w0[0]  # no roll torque: the roll rate is constant (DESIGN.md)
    x[:, IW] = w
    x[:, IM] = np.maximum(m, p.m_dry)
    u = np.einsum("kij,kj->ki", dcm_bi_numpy(q), T_I)
    # Gimbal that makes the angular rate consistent: r_T x T_B = J w' + w x J w.
    J = np.array(p.J_B)
    torque = J * np.gradient(w, t, axis=0) + np.cross(w, J * w)
    r_T = np.array(p.r_T_B)
    # r_T = (l, 0, 0): r_T x T = (0, -l T3, l T2), so T2 = tau3 / l and T3 = -tau2 / l.
    u[:, 1] = torque[:, 2] / r_T[0]
    u[:, 2] = -torque[:, 1] / r_T[0]
    return project_guess(scenario, x, u, t_f)


def checked_guess(guess: object, N: int) -> tuple[np.ndarray, np.ndarray, float]:
    """A guess (x, u, t_f) as the SCvx loops take it, used as given: x N x 14, u N x 3 and t_f
    one positive number, all finite (the C library's words for the last); InputError
    otherwise. Both loops (this package's and the C library's through guidance.cguidance)
    check a given guess through it."""
    if not isinstance(guess, tuple | list) or len(guess) != 3:
        raise InputError("guess: give (x, u, t_f)")
    arrays = []
    for name, value, cols in (("x", guess[0], NX), ("u", guess[1], NU)):
        a = np.asarray(value)
        if a.dtype.kind not in "iuf" or a.shape != (N, cols):
            raise InputError(
                f"guess: {name} is {a.shape} {a.dtype} values, not {N} x {cols} numbers"
            )
        arrays.append(a.astype(float))
    tf = np.asarray(guess[2])
    if tf.dtype.kind not in "iuf" or tf.size != 1:
        raise InputError(f"guess: t_f must be one number, got {guess[2]!r}")
    x, u, t_f = arrays[0], arrays[1], float(tf.reshape(-1)[0])
    if not (is_finite_guess(x, u, t_f) and t_f > 0.0):
        raise InputError("guess: x, u and t_f must be finite and t_f positive")
    return x, u, t_f


def is_finite_guess(x: np.ndarray, u: np.ndarray, t_f: float) -> bool:
    """No NaN or inf in a guess (x, u, t_f), as pdg_solve checks a given one."""
    return bool(np.isfinite(x).all() and np.isfinite(u).all() and np.isfinite(t_f))


def given_guess(
    scenario: Scenario, x: object, u: object, t_f: object
) -> tuple[np.ndarray, np.ndarray, float]:
    """A guess from outside (a trajectory: a file's, or the caller's, of the scenario's N) as
    SCvx starts from it: checked as a trajectory file's arrays are (shapes, real and finite
    values, t_f in range: ``verify.checked_trajectory``), then projected as the solution
    network's prediction is (``project_guess``), so that a trajectory of a neighbouring landing
    starts this one (re-planning). Bad input raises InputError."""
    try:
        x, u, t_f = checked_trajectory(x, u, t_f, scenario.params)
    except InputError as exc:
        raise InputError(f"guess: {exc}") from None
    return project_guess(scenario, x, u, t_f)


def plan_remainder(
    scenario: Scenario, x: object, u: object, t_f: object, t1: float
) -> tuple[np.ndarray, np.ndarray, float]:
    """In-flight re-planning: the plan (x, u, t_f: an answer on the scenario's N nodes from
    t = 0) from time t1 in [0, t_f) on, as the guess of ``scenario``, the landing from the
    state at t1. N nodes over [t1, t_f]: the states linearly interpolated between the plan's
    nodes, the thrust as its first-order hold (exactly); then projected as every guess is
    (``project_guess``: node 0 becomes the scenario's initial state). The same arithmetic,
    operation for operation, as the C library's pdg_plan_remainder. Bad input raises
    InputError."""
    try:
        x, u, t_f = checked_trajectory(x, u, t_f, scenario.params)
    except InputError as exc:
        raise InputError(f"guess: {exc}") from None
    if not (np.isfinite(t1) and 0.0 <= t1 < t_f):
        raise InputError(f"plan remainder: t1 = {t1:g} is not within the plan's [0, {t_f:g}) U_T")
    N = scenario.params.N
    s = np.append(np.arange(N - 1) * (1.0 / (N - 1)), 1.0)  # node fractions, the last exact
    t = t1 + (t_f - t1) * s
    gx, gu = hold_at(x, t_f, t), hold_at(u, t_f, t)
    return project_guess(scenario, gx, gu, t_f - t1)


def hold_at(values: np.ndarray, t_f: float, t: np.ndarray) -> np.ndarray:
    """values (N x d, on N nodes over [0, t_f]) linearly interpolated at the times t (M,):
    M x d, the first-order hold of a thrust; pdg_plan_remainder's arithmetic."""
    N = values.shape[0]
    h = t_f / (N - 1)
    j = np.minimum((t / h).astype(int), N - 2)  # the plan's interval holding t
    a = np.clip((t - j * h) / h, 0.0, 1.0)[:, None]
    return values[j] + a * (values[j + 1] - values[j])


def project_guess(
    scenario: Scenario, x: np.ndarray, u: np.ndarray, t_f: float
) -> tuple[np.ndarray, np.ndarray, float]:
    """Makes a guess meet the boundary conditions and every convex path constraint exactly.

    The convex subproblem keeps those constraints hard and limits the step by the trust
    radius, so a reference outside them can make the first subproblem infeasible. Dynamics
    defects are left alone: the virtual control absorbs them. Used for the cubic guess and for
    any external warm start (the solution network's prediction).
    """
    p = scenario.params
    x, u = np.array(x, dtype=float), np.array(u, dtype=float)
    x[0] = scenario.x0
    xf = scenario.x_final_target()
    x[-1, IR], x[-1, IV], x[-1, IW] = xf[IR], xf[IV], xf[IW]
    if p.final_roll_free:
        x[-1, 8:10] = 0.0
    else:
        x[-1, IQ] = xf[IQ]
    q = x[:, IQ]
    q /= np.maximum(np.linalg.norm(q, axis=1, keepdims=True), 1e-12)
    tilt = np.linalg.norm(q[:, 2:4], axis=1)
    over = tilt > p.tilt_q_max
    if over.any():  # shrink (q2, q3) onto the tilt limit, keep (q0, q1) direction
        q[over, 2:4] *= (p.tilt_q_max / tilt[over])[:, None]
        rest = np.linalg.norm(q[over, 0:2], axis=1, keepdims=True)
        room = np.sqrt(1.0 - p.tilt_q_max**2)
        q[over, 0:2] = np.where(
            rest > 1e-12, q[over, 0:2] / np.maximum(rest, 1e-12) * room, np.array([room, 0.0])
        )
    x[:, IQ] = q
    wn = np.linalg.norm(x[:, IW], axis=1, keepdims=True)
    x[:, IW] *= np.minimum(1.0, p.omega_max / np.maximum(wn, 1e-12))
    # the mass only falls: within [m_dry, m0] (a prediction above m0 is hundreds of trust
    # radii away in the scaled mass, (m - m_dry) / (m0 - m_dry), when little propellant is left)
    x[:, IM] = np.clip(x[:, IM], p.m_dry, scenario.initial.m0)
    horiz = np.linalg.norm(x[:, I_HORIZONTAL], axis=1)
    x[:, I_UP] = np.maximum(x[:, I_UP], p.tan_glideslope * horiz)
    # Thrust: into the gimbal cone about body axis 1, then into [T_min, T_max].
    un = np.maximum(np.linalg.norm(u, axis=1), 1e-12)
    lateral = np.linalg.norm(u[:, U_LATERAL], axis=1)
    tan_d = np.tan(np.arccos(p.cos_gimbal))
    axial = np.maximum(u[:, U_AXIAL], 0.0)
    too_wide = lateral > tan_d * axial
    # project (axial, lateral) onto the cone boundary where needed
    cone_dir = np.array([p.cos_gimbal, np.sqrt(1 - p.cos_gimbal**2)])
    proj = np.maximum(u[:, U_AXIAL] * cone_dir[0] + lateral * cone_dir[1], 1e-9)
    new_axial = np.where(too_wide, proj * cone_dir[0], u[:, U_AXIAL])
    new_lat = np.where(too_wide, proj * cone_dir[1], lateral)
    scale_lat = np.where(lateral > 1e-12, new_lat / np.maximum(lateral, 1e-12), 0.0)
    u = np.column_stack([new_axial, u[:, 1] * scale_lat, u[:, 2] * scale_lat])
    un = np.maximum(np.linalg.norm(u, axis=1), 1e-12)
    u *= (np.clip(un, p.T_min, p.T_max) / un)[:, None]
    # node 0 is the initial state as given (checked at input): normalizing its q again moved
    # it by an ulp off the subproblem's boundary condition
    x[0] = scenario.x0
    return x, u, float(max(t_f, 1e-2))
