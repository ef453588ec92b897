"""Figures of a landing: 3-D path with the plume (minus the thrust) and the constrained time
histories."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from guidance.atomic import atomic_write
from guidance.model import dcm_bi_numpy
from guidance.params import I_TILT, IM, IQ, IR, IW, U_AXIAL, Params


def landing_figure(
    x: np.ndarray, u: np.ndarray, t_f: float, p: Params, path: str | Path, title: str = ""
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    N = x.shape[0]
    t = np.linspace(0.0, t_f, N)
    C_IB = np.transpose(dcm_bi_numpy(x[:, IQ]), (0, 2, 1))
    T_I = np.einsum("kij,kj->ki", C_IB, u)
    Tn = np.linalg.norm(u, axis=1)
    gimbal = np.degrees(np.arccos(np.clip(u[:, U_AXIAL] / np.maximum(Tn, 1e-12), -1, 1)))
    tilt = np.degrees(np.arccos(np.clip(1 - 2 * np.sum(x[:, I_TILT] ** 2, axis=1), -1, 1)))
    wn = np.degrees(np.linalg.norm(x[:, IW], axis=1))

    fig = plt.figure(figsize=(13, 7.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    r = x[:, IR]
    # plot east, north, up so that "up" is the vertical axis of the figure
    ax.plot(r[:, 1], r[:, 2], r[:, 0], "k-", lw=1.5, label="trajectory")
    scale = 0.35 * max(np.ptp(r, axis=0).max(), 1.0) / max(p.T_max, 1e-9)
    for k in range(N):
        tail = r[k] - scale * T_I[k]  # the plume points away from the thrust direction
        ax.plot([r[k, 1], tail[1]], [r[k, 2], tail[2]], [r[k, 0], tail[0]], "r-", lw=0.8)
    # glideslope cone at the landing site
    h = np.linspace(0.0, r[:, 0].max(), 12)
    ang = np.linspace(0.0, 2 * np.pi, 48)
    rad = h / max(p.tan_glideslope, 1e-9)
    ax.plot_wireframe(
        np.outer(rad, np.cos(ang)),
        np.outer(rad, np.sin(ang)),
        np.outer(h, np.ones_like(ang)),
        color="0.8",
        lw=0.3,
    )
    lim = np.abs(r[:, 1:]).max() * 1.1 + 0.1
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_zlim(0.0, r[:, 0].max() * 1.05 + 0.1)
    ax.set_xlabel("east [U_L]")
    ax.set_ylabel("north [U_L]")
    ax.set_zlabel("up [U_L]")
    ax.set_title("trajectory, plume = -thrust (red) and glideslope cone")

    panels = [
        ("|T| [U_M U_L/U_T^2]", Tn, [(p.T_min, "T_min"), (p.T_max, "T_max")]),
        ("gimbal angle [deg]", gimbal, [(p.gimbal_max_deg, "delta_max")]),
        ("tilt angle [deg]", tilt, [(p.tilt_max_deg, "theta_max")]),
        ("|omega| [deg/U_T]", wn, [(p.omega_max_deg, "omega_max")]),
        ("mass [U_M]", x[:, IM], [(p.m_dry, "m_dry")]),
    ]
    for i, (label, y, limits) in enumerate(panels):
        a = fig.add_subplot(5, 2, 2 * (i + 1))
        a.plot(t, y, "b.-", ms=3, lw=1)
        for value, name in limits:
            a.axhline(value, color="r", ls="--", lw=0.8)
            a.text(t[-1], value, f" {name}", color="r", va="center", fontsize=7)
        a.set_ylabel(label, fontsize=8)
        a.grid(alpha=0.3)
        if i == len(panels) - 1:
            a.set_xlabel("time [U_T]")
    fig.suptitle(title or "6-DoF powered descent")
    fig.tight_layout()
    with atomic_write(path) as f:  # a file object: the format comes from the name
        fig.savefig(f, dpi=110, format=Path(path).suffix.lstrip(".").lower() or None)
    plt.close(fig)
