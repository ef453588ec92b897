"""The 6-DoF landing model in CasADi: dynamics, Jacobians, path constraints, FOH discretization.

Every function takes the physical parameters as a numeric input vector ``p`` (see
:func:`param_vector`) instead of baking them in, so the same expressions serve every scenario
and can be generated once as C (``codegen/``).

Equations (DESIGN.md; paper Eq. (4)), with sigma = t_f and normalized time tau in [0, 1]:
    dm/dt = -alpha |T_B| - beta
    dr/dt = v
    dv/dt = C_IB(q) (T_B + A_B) / m + g_I,        A_B = -c_A |v_B| v_B,  v_B = C_BI(q) v_I
    dq/dt = 1/2 Omega(omega) q
    J domega/dt = r_T x T_B + r_cp x A_B - omega x (J omega)
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from guidance.errors import ModelEvaluationError
from guidance.params import I_HORIZONTAL, I_TILT, I_UP, IM, IQ, IV, IW, NU, NX, U_AXIAL, Params

# Parameter vector layout for the CasADi functions.
P_NAMES = (
    "g1",  # gravity along e1 (negative)
    "J1", "J2", "J3",
    "rT1", "rT2", "rT3",
    "rcp1", "rcp2", "rcp3",
    "alpha_mdot",
    "beta_mdot",
    "aero_coeff",
)  # fmt: skip
NP = len(P_NAMES)


def param_vector(params: Params) -> np.ndarray:
    return np.array(
        [
            params.g_I[0],
            *params.J_B,
            *params.r_T_B,
            *params.r_cp_B,
            params.alpha_mdot,
            params.beta_mdot,
            params.aero_coeff,
        ],
        dtype=float,
    )


def _dcm_entries(q0, q1, q2, q3):
    """C_B<-I(q), scalar-first, in its homogeneous form.

    On unit quaternions this is DESIGN.md's matrix (1 - 2(q2^2 + q3^2) = q0^2 + q1^2 - q2^2 -
    q3^2). Off the unit sphere, where SCvx iterates and linearizations live, the homogeneous
    form stays a scaled rotation, so the Jacobians commute with rotations about the up axis
    (the other form does not, and a rotated scenario would then take a different path).
    """
    s0, s1, s2, s3 = q0 * q0, q1 * q1, q2 * q2, q3 * q3
    return (
        (s0 + s1 - s2 - s3, 2 * (q1 * q2 + q0 * q3), 2 * (q1 * q3 - q0 * q2)),
        (2 * (q1 * q2 - q0 * q3), s0 - s1 + s2 - s3, 2 * (q2 * q3 + q0 * q1)),
        (2 * (q1 * q3 + q0 * q2), 2 * (q2 * q3 - q0 * q1), s0 - s1 - s2 + s3),
    )


def dcm_bi(q: ca.SX) -> ca.SX:
    """C_B<-I(q) for a scalar-first quaternion (DESIGN.md), see _dcm_entries."""
    rows = _dcm_entries(q[0], q[1], q[2], q[3])
    return ca.vertcat(*(ca.horzcat(*row) for row in rows))


def omega_matrix(w: ca.SX) -> ca.SX:
    w1, w2, w3 = w[0], w[1], w[2]
    return ca.vertcat(
        ca.horzcat(0, -w1, -w2, -w3),
        ca.horzcat(w1, 0, w3, -w2),
        ca.horzcat(w2, -w3, 0, w1),
        ca.horzcat(w3, w2, -w1, 0),
    )


# |v| is floored at sqrt of this (1e-150) so that its derivative at v = 0 is 0, not 0 * inf.
NORM_FLOOR_SQ = 1e-300


def _norm(v: ca.SX) -> ca.SX:
    """|v|, exactly, for |v| >= 1e-150. A smooth norm would change the model; this one only
    fixes v = 0, where |v| is not differentiable: there the drag |v_B| v_B (a landing that
    starts or passes at rest) has derivative 0, which the floor gives, where the plain norm gave
    0 * inf = NaN and failed the model evaluation."""
    return ca.sqrt(ca.fmax(ca.sumsqr(v), NORM_FLOOR_SQ))


def dynamics_expr(x: ca.SX, u: ca.SX, p: ca.SX) -> ca.SX:
    """Time derivative f(x, u; p) of the state (physical time)."""
    v, q, w, m = x[IV], x[IQ], x[IW], x[IM]
    g_I = ca.vertcat(p[0], 0, 0)
    J = ca.vertcat(p[1], p[2], p[3])
    r_T, r_cp = p[4:7], p[7:10]
    alpha, beta, c_A = p[10], p[11], p[12]
    C_BI = dcm_bi(q)
    v_B = C_BI @ v
    A_B = -c_A * _norm(v_B) * v_B
    m_dot = -alpha * _norm(u) - beta
    v_dot = (C_BI.T @ (u + A_B)) / m + g_I
    q_dot = 0.5 * omega_matrix(w) @ q
    Jw = J * w
    w_dot = (ca.cross(r_T, u) + ca.cross(r_cp, A_B) - ca.cross(w, Jw)) / J
    return ca.vertcat(v, v_dot, q_dot, w_dot, m_dot)


def _with_jacobians(
    name: str, expr: ca.SX, args: list[ca.SX], arg_names: list[str], out_names: list[str]
) -> tuple[ca.Function, ca.Function]:
    """ca.Functions `name`(x, u, c) -> expr and `name`_jac -> (d expr/dx, d expr/du)."""
    x, u = args[0], args[1]
    value = ca.Function(name, args, [expr], arg_names, out_names[:1])
    jac = ca.Function(
        name + "_jac", args, [ca.jacobian(expr, x), ca.jacobian(expr, u)], arg_names, out_names[1:]
    )
    return value, jac


@lru_cache(maxsize=1)
def dynamics_functions() -> tuple[ca.Function, ca.Function]:
    """f(x, u, p) and its Jacobians (A, B) = (df/dx, df/du)."""
    x, u, p = ca.SX.sym("x", NX), ca.SX.sym("u", NU), ca.SX.sym("p", NP)
    return _with_jacobians(
        "tscvx_dynamics", dynamics_expr(x, u, p), [x, u, p], ["x", "u", "p"], ["f", "A", "B"]
    )


# ---- path constraints: h(x, u) <= 0 in each constraint's own units, order of DESIGN.md -------
CONSTRAINT_PARAM_NAMES = ("m_dry", "tan_gs", "tilt_q_max", "omega_max", "T_max", "cos_gimbal",
                          "T_min")  # fmt: skip


def constraint_param_vector(params: Params) -> np.ndarray:
    return np.array(
        [
            params.m_dry,
            params.tan_glideslope,
            params.tilt_q_max,
            params.omega_max,
            params.T_max,
            params.cos_gimbal,
            params.T_min,
        ]
    )


def path_constraints_expr(x: ca.SX, u: ca.SX, c: ca.SX) -> ca.SX:
    w, m = x[IW], x[IM]
    T = _norm(u)
    return ca.vertcat(
        c[0] - m,
        c[1] * _norm(x[I_HORIZONTAL]) - x[I_UP],
        _norm(x[I_TILT]) - c[2],
        _norm(w) - c[3],
        T - c[4],
        c[5] * T - u[U_AXIAL],
        c[6] - T,
    )


@lru_cache(maxsize=1)
def constraint_functions() -> tuple[ca.Function, ca.Function]:
    """h(x, u, c) (7 values, <= 0 when met) and its Jacobians (dh/dx, dh/du)."""
    x, u, c = ca.SX.sym("x", NX), ca.SX.sym("u", NU), ca.SX.sym("c", len(CONSTRAINT_PARAM_NAMES))
    return _with_jacobians(
        "tscvx_path_constraints",
        path_constraints_expr(x, u, c),
        [x, u, c],
        ["x", "u", "c"],
        ["h", "H_x", "H_u"],
    )


# ---- first-order-hold discretization -----------------------------------------------------
# Augmented state of one interval, packed: x (14), Phi_A (14x14), Phi_m (14x3), Phi_p (14x3),
# Phi_s (14); matrices column-major as CasADi stores them.
N_AUG = NX + NX * NX + 2 * NX * NU + NX


def _unpack_aug(P: ca.SX) -> tuple[ca.SX, ...]:
    i = 0
    out = []
    for rows, cols in ((NX, 1), (NX, NX), (NX, NU), (NX, NU), (NX, 1)):
        out.append(ca.reshape(P[i : i + rows * cols], rows, cols))
        i += rows * cols
    return tuple(out)


def _pack_aug(parts: tuple[ca.SX, ...]) -> ca.SX:
    return ca.vertcat(*(ca.vec(m) for m in parts))


@lru_cache(maxsize=1)
def foh_step_function() -> ca.Function:
    """One classic RK4 step, from s to s + h, of the augmented FOH system (the
    discretization behind the linearized dynamics, paper Eq. (10)):

        x'     = sigma f(x, u(s)),              u(s) = l_m(s) u_k + l_p(s) u_k1
        Phi_A' = sigma A Phi_A                  Phi_A(0) = I
        Phi_m' = sigma A Phi_m + sigma B l_m    Phi_m(0) = 0
        Phi_p' = sigma A Phi_p + sigma B l_p    Phi_p(0) = 0
        Phi_s' = sigma A Phi_s + f              Phi_s(0) = 0

    with l_m = 1 - s/dtau, l_p = s/dtau and A, B the Jacobians of f. The flight library calls
    the generated C of this function in a bounded loop; Python composes it symbolically.
    """
    P = ca.SX.sym("P", N_AUG)
    s, h = ca.SX.sym("s"), ca.SX.sym("h")
    uk, uk1 = ca.SX.sym("u_k", NU), ca.SX.sym("u_k1", NU)
    sigma, dtau, p = ca.SX.sym("sigma"), ca.SX.sym("dtau"), ca.SX.sym("p", NP)
    xs, us = ca.SX.sym("xs", NX), ca.SX.sym("us", NU)
    f = dynamics_expr(xs, us, p)
    fAB = ca.Function("fAB", [xs, us, p], [f, ca.jacobian(f, xs), ca.jacobian(f, us)])

    def rhs(t: ca.SX, state: tuple[ca.SX, ...]) -> tuple[ca.SX, ...]:
        x, PA, Pm, Pp, Ps = state
        lp = t / dtau
        lm = 1 - lp
        fx, A, B = fAB(x, lm * uk + lp * uk1, p)
        SA = sigma * A
        return (
            sigma * fx,
            SA @ PA,
            SA @ Pm + sigma * B * lm,
            SA @ Pp + sigma * B * lp,
            SA @ Ps + fx,
        )

    def axpy(a: tuple[ca.SX, ...], c: ca.SX, b: tuple[ca.SX, ...]) -> tuple[ca.SX, ...]:
        return tuple(ai + c * bi for ai, bi in zip(a, b, strict=True))

    y = _unpack_aug(P)
    k1 = rhs(s, y)
    k2 = rhs(s + h / 2, axpy(y, h / 2, k1))
    k3 = rhs(s + h / 2, axpy(y, h / 2, k2))
    k4 = rhs(s + h, axpy(y, h, k3))
    y_next = tuple(
        a + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
        for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4, strict=True)
    )
    return ca.Function(
        "tscvx_foh_step",
        [P, s, h, uk, uk1, sigma, dtau, p],
        [_pack_aug(y_next)],
        ["P", "s", "h", "u_k", "u_k1", "sigma", "dtau", "p"],
        ["P_next"],
    )


# The parameters whose value zero removes entries from A_k's structural pattern, in groups
# that act together: the centre of pressure r_cp_B (the aerodynamic torque r_cp x A_B; one or
# two components zero remove none). Any other parameter zero removes no entry of A_k's
# pattern, or cannot be zero (J, aero_coeff: the scenario check wants them positive);
# test_model checks both claims.
PATTERN_PARAM_GROUPS = ((7, 8, 9),)
N_PATTERNS = 1 << len(PATTERN_PARAM_GROUPS)


def pattern_index(p: np.ndarray) -> int:
    """Which of the N_PATTERNS patterns of A_k holds for the parameter vector p: bit g is set
    when every parameter of group g is exactly zero."""
    return sum(
        1 << g for g, group in enumerate(PATTERN_PARAM_GROUPS) if all(p[i] == 0.0 for i in group)
    )


@lru_cache(maxsize=N_PATTERNS)
def transition_pattern(index: int = 0) -> np.ndarray:
    """The structural nonzeros of A_k = Phi_A (NX x NX bool, row-major) for every parameter
    vector of pattern_index ``index`` (0: every parameter vector): pattern_with_zeros of the
    index's zero parameters. The subproblem leaves the other entries out of its pattern: 49
    of 196 per interval in general, 89 with r_cp_B = 0."""
    return pattern_with_zeros(
        frozenset(
            i for g, group in enumerate(PATTERN_PARAM_GROUPS) if index >> g & 1 for i in group
        )
    )


@lru_cache(maxsize=32)
def pattern_with_zeros(zero: frozenset[int]) -> np.ndarray:
    """The entries of A_k = Phi_A that can be nonzero when the parameters ``zero`` are 0.
    Phi_A' = sigma A(x(t)) Phi_A from Phi_A(0) = I, and A = df/dx has a structural pattern S
    (nothing depends on the position; the mass rate on the mass only; built here with the
    zero parameters as constant zeros, which CasADi folds away), so entry (i, j) can be
    nonzero only if j reaches i in the graph of S plus self-loops: the transitive closure.
    The integration keeps every other entry an exact 0.0 (each of its terms has an exact zero
    factor) as long as the numbers are finite, which the discretization checks."""
    x, u, p = ca.SX.sym("x", NX), ca.SX.sym("u", NU), ca.SX.sym("p", NP)
    p_const = ca.vertcat(*(0 if i in zero else p[i] for i in range(NP)))
    rows, cols = ca.jacobian(dynamics_expr(x, u, p_const), x).sparsity().get_triplet()
    step = np.eye(NX, dtype=np.int64)
    step[rows, cols] = 1
    reach = step.copy()
    for _ in range(NX):  # paths of length <= NX cover every pair a path joins
        reach = np.minimum(reach @ step, 1)
    return reach.astype(bool)


def vehicle_pattern(params: Params) -> np.ndarray:
    """A_k's structural nonzeros for this vehicle (transition_pattern of its pattern_index)."""
    return transition_pattern(pattern_index(param_vector(params)))


@lru_cache(maxsize=8)
def discretization_function(substeps: int) -> ca.Function:
    """FOH discretization of one interval of normalized length dtau (paper Eq. (10)).

    ``substeps`` RK4 steps of :func:`foh_step_function` from the initial augmented state;
    returns x(dtau), A_k = Phi_A, B-_k = Phi_m, B+_k = Phi_p, Sigma_k = Phi_s and the defect term
        z_k = x(dtau) - A_k x_k - B-_k u_k - B+_k u_k1 - Sigma_k sigma,
    so that x_{k+1} ~ A_k x_k + B-_k u_k + B+_k u_k1 + Sigma_k sigma + z_k.
    """
    xk, uk, uk1 = ca.SX.sym("x_k", NX), ca.SX.sym("u_k", NU), ca.SX.sym("u_k1", NU)
    sigma, dtau, p = ca.SX.sym("sigma"), ca.SX.sym("dtau"), ca.SX.sym("p", NP)
    step = foh_step_function()
    P = _pack_aug((xk, ca.SX.eye(NX), ca.SX.zeros(NX, NU), ca.SX.zeros(NX, NU), ca.SX.zeros(NX, 1)))
    h = dtau / substeps
    for i in range(substeps):
        P = step(P, i * h, h, uk, uk1, sigma, dtau, p)
    x_next, A_k, Bm_k, Bp_k, S_k = _unpack_aug(P)
    z_k = x_next - A_k @ xk - Bm_k @ uk - Bp_k @ uk1 - S_k * sigma
    return ca.Function(
        "tscvx_foh_interval",
        [xk, uk, uk1, sigma, dtau, p],
        [x_next, A_k, Bm_k, Bp_k, S_k, z_k],
        ["x_k", "u_k", "u_k1", "sigma", "dtau", "p"],
        ["x_next", "A", "Bm", "Bp", "Sigma", "z"],
    )


@lru_cache(maxsize=8)
def _mapped_discretization(substeps: int, intervals: int) -> ca.Function:
    return discretization_function(substeps).map(intervals, "serial")


def discretize(
    x: np.ndarray,
    u: np.ndarray,
    sigma: float,
    params: Params,
    substeps: int,
    engine: str = "casadi",
) -> dict[str, np.ndarray]:
    """FOH discretization of all N-1 intervals about (x, u, sigma); arrays are interval-major.

    ``engine``: "casadi" evaluates the CasADi function; "c" the generated C of the same
    expressions (build/libtscvx_gnc.so, equal to 1e-10 and about ten times faster).

    Returns x_next (N-1, 14), A (N-1, 14, 14), Bm (N-1, 14, 3), Bp (N-1, 14, 3),
    Sigma (N-1, 14), z (N-1, 14). Raises ModelEvaluationError if any of them is not finite,
    or if A has a nonzero outside :func:`vehicle_pattern` (which the subproblem drops; the C
    engine checks both itself).
    """
    if engine == "c":
        from guidance import cgnc

        return cgnc.discretize_all(x, u, sigma, param_vector(params), substeps)
    N = x.shape[0]
    fun = _mapped_discretization(substeps, N - 1)
    out = fun(x[:-1].T, u[:-1].T, u[1:].T, sigma, 1.0 / (N - 1), param_vector(params))
    xn, A, Bm, Bp, S, z = (np.asarray(o) for o in out)
    if not all(np.isfinite(o).all() for o in (xn, A, Bm, Bp, S, z)):
        raise ModelEvaluationError("the FOH discretization is not finite")
    A = A.reshape(NX, N - 1, NX).transpose(1, 0, 2)
    if np.any(A[:, ~vehicle_pattern(params)]):
        raise ModelEvaluationError("the FOH discretization left its structural pattern")
    return {
        "x_next": xn.T,
        # CasADi stacks the mapped matrix outputs side by side (column-major blocks).
        "A": A,
        "Bm": Bm.reshape(NX, N - 1, NU).transpose(1, 0, 2),
        "Bp": Bp.reshape(NX, N - 1, NU).transpose(1, 0, 2),
        "Sigma": S.T,
        "z": z.T,
    }


def dcm_bi_numpy(q: np.ndarray) -> np.ndarray:
    """C_B<-I for a batch of quaternions (..., 4) -> (..., 3, 3), same formula as dcm_bi."""
    rows = _dcm_entries(*(q[..., i] for i in range(4)))
    return np.stack([np.stack(row, -1) for row in rows], axis=-2)
