"""Rotations about the up axis e1: the symmetry behind the paper's data augmentation.

With the roll-free terminal condition every constraint and the dynamics are invariant under
a rotation of the inertial frame about e1 (J2 = J3 and the engine on the body axis make
gravity, drag and torques commute with it). Rotating a scenario therefore rotates its optimal
solution: r and v rotate, the attitude turns with the frame, and body-frame quantities
(omega_B, T_B) and the mass are unchanged.
"""

from __future__ import annotations

import math

import numpy as np

from guidance.params import IQ, IR, IV, InitialState, Scenario


def rotation_about_up(psi: float) -> np.ndarray:
    """R(psi) acting on inertial vectors (e1 up, e2 east, e3 north)."""
    c, s = math.cos(psi), math.sin(psi)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rotate_quaternions(q: np.ndarray, psi: float) -> np.ndarray:
    """q' with C_B<-I(q') = C_B<-I(q) R(psi)^T, i.e. q' = (cos psi/2, sin psi/2, 0, 0) (x) q."""
    q = np.asarray(q, dtype=float)
    c, s = math.cos(psi / 2.0), math.sin(psi / 2.0)
    q0, q1, q2, q3 = (q[..., i] for i in range(4))
    return np.stack([q0 * c - q1 * s, q1 * c + q0 * s, q2 * c - q3 * s, q3 * c + q2 * s], -1)


def rotate_states(x: np.ndarray, psi: float) -> np.ndarray:
    R = rotation_about_up(psi)
    x = np.array(x, dtype=float)
    x[..., IR] = x[..., IR] @ R.T
    x[..., IV] = x[..., IV] @ R.T
    x[..., IQ] = rotate_quaternions(x[..., IQ], psi)
    return x


def rotate_scenario(scenario: Scenario, psi: float) -> Scenario:
    x0 = rotate_states(scenario.x0, psi)
    s = scenario.initial
    initial = InitialState(r0=tuple(x0[IR]), v0=tuple(x0[IV]), q0=tuple(x0[IQ]), w0=s.w0, m0=s.m0)
    return Scenario(initial, scenario.params)
