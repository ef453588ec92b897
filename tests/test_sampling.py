"""guidance.sampling: the base landings are physical and reproducible, and their
rotations are the rotated scenarios'."""

from __future__ import annotations

import math

import numpy as np

from guidance.sampling import (
    ROTATION_DEG,
    SamplingRanges,
    base_scenario,
    rotate_theta,
    scenario_of,
    theta_of,
)
from guidance.scenario import validate
from guidance.symmetry import rotate_scenario


def test_base_samples_are_physical_and_reproducible() -> None:
    ranges = SamplingRanges()
    for i in range(60):
        s, _ = base_scenario(3, i, ranges)
        validate(s)  # glideslope, tilt, rate, roll rate, mass
        t = theta_of(s)
        assert t[1] >= 0 and t[2] >= 0  # positive east / north only
        assert t[10] == 0.0  # no roll rate
        assert 2.0 < t[13] <= 3.0
        assert ranges.glideslope_deg[0] <= t[14] <= ranges.glideslope_deg[1]
        assert abs(np.linalg.norm(t[6:10]) - 1.0) < 1e-12
        np.testing.assert_array_equal(theta_of(scenario_of(t)), t)
    a, _ = base_scenario(3, 7, ranges)
    b, _ = base_scenario(3, 7, ranges)
    assert a == b


def test_rotate_theta_matches_rotate_scenario() -> None:
    s, _ = base_scenario(0, 1, SamplingRanges())
    for deg in ROTATION_DEG:
        psi = math.radians(deg)
        np.testing.assert_allclose(
            rotate_theta(theta_of(s), psi), theta_of(rotate_scenario(s, psi))
        )
