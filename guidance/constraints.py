"""Path constraints evaluated in numpy, their scales, and the tight-constraint labelling.

h[k, c] <= 0 means constraint c is met at node k; c follows DESIGN.md's table (mask order).
The CasADi form of the same functions is in ``guidance.model`` (used for code generation);
a test checks the two agree.
"""

from __future__ import annotations

import numpy as np

from guidance.params import I_HORIZONTAL, I_TILT, I_UP, IM, IW, U_AXIAL, Params

TIGHT_DUAL_TOL = 1e-5  # a constraint whose multiplier exceeds this is tight (scaled problem)


def path_constraint_values(x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """h (N, 7) in each constraint's own units (mass, length, quaternion, rad/U_T, thrust)."""
    T = np.linalg.norm(u, axis=1)
    return np.stack(
        [
            p.m_dry - x[:, IM],
            p.tan_glideslope * np.linalg.norm(x[:, I_HORIZONTAL], axis=1) - x[:, I_UP],
            np.linalg.norm(x[:, I_TILT], axis=1) - p.tilt_q_max,
            np.linalg.norm(x[:, IW], axis=1) - p.omega_max,
            T - p.T_max,
            p.cos_gimbal * T - u[:, U_AXIAL],
            p.T_min - T,
        ],
        axis=1,
    )


def constraint_scales(p: Params, Sx: np.ndarray, Su: float) -> np.ndarray:
    """The unit of each constraint used for penalties and the tightness threshold (7,)."""
    return np.array([Sx[IM], Sx[I_UP], 1.0, p.omega_max, Su, Su, Su])


def tight_mask(
    h: np.ndarray,
    scales: np.ndarray,
    duals: np.ndarray | None = None,
    slack_tol: float = 1e-6,
) -> np.ndarray:
    """Tight-constraint mask (7N, node-major bit 7k + c) of a subproblem solution.

    Rule: constraint c at node k is tight when its slack -h[k, c], in the constraint's own
    units, is at most ``slack_tol * max(1, scale_c)`` (this includes violated constraints),
    or when its multiplier in the subproblem (``duals[k, c]``, NaN where the constraint was not
    in the subproblem) is at least TIGHT_DUAL_TOL: an interior-point solution leaves active
    constraints with slacks of the order of the solver tolerance, and the multiplier is what
    tells them from inactive ones.
    """
    tight = -h <= slack_tol * np.maximum(1.0, scales)[None, :]
    if duals is not None:
        tight |= np.nan_to_num(duals, nan=0.0) >= TIGHT_DUAL_TOL
    return tight.reshape(-1).astype(np.uint8)


def max_violation(h: np.ndarray) -> float:
    return float(max(0.0, h.max()))
