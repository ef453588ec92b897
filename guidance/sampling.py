"""The landings of the training data: sampled base scenarios and their parameters theta.

Base sample ``i`` of a run is drawn from its own generator seeded by ``(seed, i)`` over
:class:`SamplingRanges` (positive east/north only), redrawn until
:func:`guidance.scenario.validate` accepts it. A dataset of n samples is therefore the prefix
of any larger one with the same seed and ranges. The packed dataset holds each base sample
turned about the up axis by 0, 45, ..., 315 degrees (ROTATION_DEG, rotate_theta).

theta (16) = r0 (3), v0 (3), q0 (4), w0 (3, rad/U_T), m0, glideslope_deg, tilt_max_deg.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from guidance.params import NX, InitialState, Params, Scenario
from guidance.scenario import ScenarioError, validate

N_THETA = 16
THETA_NAMES = (
    "r0_1",
    "r0_2",
    "r0_3",
    "v0_1",
    "v0_2",
    "v0_3",
    "q0_0",
    "q0_1",
    "q0_2",
    "q0_3",
    "w0_1",
    "w0_2",
    "w0_3",
    "m0",
    "glideslope_deg",
    "tilt_max_deg",
)
N_ROTATIONS = 8
ROTATION_DEG = tuple(45.0 * j for j in range(N_ROTATIONS))
MAX_DRAWS = 1000


@dataclass(frozen=True)
class SamplingRanges:
    """Uniform ranges of the base samples (the paper's Table 5 made physical).

    The paper samples r0 up to 10 and 13.8 U_L, |v0| up to 2.8 U_L/U_T and m0 down to 0.003;
    with this vehicle (I_sp = 30, m_dry = 2, m0 <= 3) most such starts cannot land. These
    ranges keep the draws mostly feasible around the default landing (r0 = (4, 4, 0),
    v0 = (0, -1, -2), m0 = 3, about 76 % of the propellant burnt). Draws below the glideslope,
    beyond the tilt limit or the rate limit are redrawn (``validate``).
    """

    altitude: tuple[float, float] = (2.0, 6.0)  # r0_1, U_L
    horizontal: tuple[float, float] = (0.0, 4.0)  # r0_2, r0_3 (positive east/north), U_L
    v_up: tuple[float, float] = (-1.2, 0.0)  # v0_1, U_L/U_T
    v_horizontal: tuple[float, float] = (-1.5, 0.5)  # v0_2, v0_3, U_L/U_T
    m0: tuple[float, float] = (2.6, 3.0)  # U_M, within (m_dry, 3]
    glideslope_deg: tuple[float, float] = (5.0, 40.0)
    tilt_max_deg: tuple[float, float] = (45.0, 90.0)
    tilt0_deg: tuple[float, float] = (0.0, 30.0)  # initial tilt (capped by tilt_max)
    omega0: tuple[float, float] = (-0.4, 0.4)  # w0_2, w0_3 in rad/U_T; w0_1 = 0 (no roll rate)

    def to_json_dict(self) -> dict[str, list[float]]:
        return {f.name: list(getattr(self, f.name)) for f in dataclasses.fields(self)}

    @classmethod
    def from_json_dict(cls, d: dict[str, Any]) -> SamplingRanges:
        return cls(**{k: tuple(v) for k, v in d.items()})


def _quaternion_from(roll: float, tilt: float, tilt_axis: float) -> np.ndarray:
    """q_B<-I of a vehicle turned by ``roll`` about the up axis then tilted by ``tilt``.

    The tilt axis is horizontal at angle ``tilt_axis`` from east. Scalar first; the result has
    |(q2, q3)| = sin(tilt / 2), so its tilt from vertical is exactly ``tilt``.
    """
    # C_IB = R_tilt(axis a) R_roll(e1); q_I<-B = q_tilt (x) q_roll; q_B<-I is its conjugate.
    a = np.array([0.0, math.cos(tilt_axis), math.sin(tilt_axis)])
    qt = np.concatenate([[math.cos(tilt / 2)], math.sin(tilt / 2) * a])
    qr = np.array([math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0])
    w1, x1, y1, z1 = qt
    w2, x2, y2, z2 = qr
    q_ib = np.array(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )
    q = q_ib * np.array([1.0, -1.0, -1.0, -1.0])
    return q / np.linalg.norm(q)


def draw_scenario(
    rng: np.random.Generator, ranges: SamplingRanges, params: Params | None = None
) -> tuple[Scenario, int]:
    """One physical base scenario and the number of rejected draws before it."""
    base = params or Params()
    for rejected in range(MAX_DRAWS):
        u = rng.uniform
        gs = u(*ranges.glideslope_deg)
        tilt_max = u(*ranges.tilt_max_deg)
        r0 = (u(*ranges.altitude), u(*ranges.horizontal), u(*ranges.horizontal))
        v0 = (u(*ranges.v_up), u(*ranges.v_horizontal), u(*ranges.v_horizontal))
        tilt0 = math.radians(min(u(*ranges.tilt0_deg), tilt_max))
        q0 = _quaternion_from(u(-math.pi, math.pi), tilt0, u(0.0, 2 * math.pi))
        w0 = (0.0, u(*ranges.omega0), u(*ranges.omega0))
        m0 = u(*ranges.m0)
        scenario = Scenario(
            InitialState(r0=r0, v0=v0, q0=tuple(q0), w0=w0, m0=m0),
            base.replace(glideslope_deg=gs, tilt_max_deg=tilt_max),
        )
        try:
            validate(scenario)
        except ScenarioError:
            continue
        return scenario, rejected
    raise RuntimeError(f"no valid scenario in {MAX_DRAWS} draws: check the sampling ranges")


def base_scenario(seed: int, i: int, ranges: SamplingRanges, params: Params | None = None):
    """Base sample ``i`` of the run with ``seed`` (deterministic, independent of the others)."""
    return draw_scenario(np.random.default_rng([seed, i]), ranges, params)


def theta_of(scenario: Scenario) -> np.ndarray:
    s, p = scenario.initial, scenario.params
    return np.concatenate(
        [s.r0, s.v0, s.q0, s.w0, [s.m0, p.glideslope_deg, p.tilt_max_deg]]
    ).astype(np.float64)


def scenario_of(theta: np.ndarray, params: Params | None = None) -> Scenario:
    """Inverse of :func:`theta_of` (other parameters from ``params``)."""
    t = [float(v) for v in theta]
    base = params or Params()
    initial = InitialState(
        r0=tuple(t[0:3]),  # type: ignore[arg-type]
        v0=tuple(t[3:6]),  # type: ignore[arg-type]
        q0=tuple(t[6:10]),  # type: ignore[arg-type]
        w0=tuple(t[10:13]),  # type: ignore[arg-type]
        m0=t[13],
    )
    return Scenario(initial, base.replace(glideslope_deg=t[14], tilt_max_deg=t[15]))


def rotate_theta(theta: np.ndarray, psi: float) -> np.ndarray:
    from guidance.symmetry import rotate_states

    out = np.array(theta, dtype=np.float64)
    x0 = np.zeros(NX)
    x0[:13] = theta[:13]
    out[:10] = rotate_states(x0, psi)[:10]
    return out
