"""Named test and benchmark scenarios: the default landing and ten varied ones."""

from __future__ import annotations

import math

from guidance.params import InitialState, Params, Scenario


def _q_tilt(deg: float, axis: str = "y") -> tuple[float, float, float, float]:
    """Attitude tilted by `deg` about inertial e2 ('y') or e3 ('z')."""
    h = math.radians(deg) / 2.0
    return (
        (math.cos(h), 0.0, math.sin(h), 0.0)
        if axis == "y"
        else (math.cos(h), 0.0, 0.0, math.sin(h))
    )


SCENARIOS: dict[str, Scenario] = {
    "default": Scenario(),
    "north": Scenario(InitialState(r0=(4.0, 0.0, 3.0), v0=(-0.5, 0.0, -1.0))),
    "overhead": Scenario(InitialState(r0=(4.0, 0.5, 0.5), v0=(-1.0, 0.0, 0.0))),
    "crossing": Scenario(InitialState(r0=(4.0, 2.0, 2.0), v0=(0.0, 1.0, -0.5))),
    "low_fast": Scenario(InitialState(r0=(2.5, 2.0, 0.0), v0=(-0.5, -1.5, 0.0))),
    "high": Scenario(InitialState(r0=(6.0, 1.0, 1.0), v0=(-0.5, 0.0, 0.0))),
    "tilted": Scenario(InitialState(r0=(4.0, 3.0, 1.0), v0=(0.0, -1.0, -1.0), q0=_q_tilt(20))),
    "tilted_z": Scenario(
        InitialState(r0=(4.0, 1.0, 3.0), v0=(0.0, -0.5, -1.5), q0=_q_tilt(-15, "z"))
    ),
    "spinning": Scenario(
        InitialState(r0=(4.0, 2.0, 2.0), v0=(0.0, -1.0, 0.0), w0=(0.0, 0.3, -0.2))
    ),
    "light": Scenario(InitialState(r0=(3.5, 2.0, 1.0), v0=(-0.3, -0.5, -0.5), m0=2.6)),
    "steep_cone": Scenario(
        InitialState(r0=(5.0, 2.0, 1.0), v0=(0.0, -0.5, -0.5)), Params(glideslope_deg=40.0)
    ),
}
