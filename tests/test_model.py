"""CasADi model against an independent numpy implementation, finite differences and scipy."""

from __future__ import annotations

import numpy as np
import pytest

from guidance.constraints import path_constraint_values
from guidance.model import (
    constraint_functions,
    constraint_param_vector,
    discretization_function,
    dynamics_functions,
    param_vector,
)
from guidance.params import Params, SCvxSettings, rk4_steps_per_interval
from guidance.verify import dynamics_numpy, integrate_interval

P = Params()


def random_state(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    return np.concatenate(
        [
            rng.uniform(0.5, 5, 1),
            rng.normal(size=2),
            rng.normal(size=3),
            q / np.linalg.norm(q),
            0.5 * rng.normal(size=3),
            rng.uniform(2.0, 3.0, 1),
        ]
    )


@pytest.fixture(scope="module")
def samples() -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(7)
    return [(random_state(rng), rng.normal(size=3) * 2 + np.array([3, 0, 0])) for _ in range(20)]


def tangent(x: np.ndarray) -> np.ndarray:
    """Projector onto the directions that keep |q| = 1 (identity on the other states).

    The model writes C_B<-I(q) in its homogeneous form, equal to DESIGN.md's on unit
    quaternions; the two differ only in the radial direction of q, which the dynamics never
    take (|q| is conserved), so Jacobians are compared on the tangent space.
    """
    P = np.eye(14)
    q = x[6:10] / np.linalg.norm(x[6:10])
    P[6:10, 6:10] -= np.outer(q, q)
    return P


def test_dynamics_match_numpy(samples) -> None:
    f, _ = dynamics_functions()
    for x, u in samples:
        got = np.asarray(f(x, u, param_vector(P))).ravel()
        np.testing.assert_allclose(got, dynamics_numpy(x, u, P), rtol=1e-12, atol=1e-12)


def test_jacobians_match_finite_differences(samples) -> None:
    _, jac = dynamics_functions()
    eps = 1e-6
    for x, u in samples:
        A, B = (np.asarray(m) for m in jac(x, u, param_vector(P)))
        A_fd = np.column_stack(
            [
                (dynamics_numpy(x + eps * e, u, P) - dynamics_numpy(x - eps * e, u, P)) / (2 * eps)
                for e in np.eye(14)
            ]
        )
        B_fd = np.column_stack(
            [
                (dynamics_numpy(x, u + eps * e, P) - dynamics_numpy(x, u - eps * e, P)) / (2 * eps)
                for e in np.eye(3)
            ]
        )
        np.testing.assert_allclose(A @ tangent(x), A_fd @ tangent(x), atol=1e-7)
        np.testing.assert_allclose(B, B_fd, atol=1e-7)


def test_jacobians_at_rest_are_finite_and_the_limit(samples) -> None:
    """At v = 0 the drag |v_B| v_B is not differentiable term by term (|v| is not), but it is
    C1 with derivative 0: the Jacobians must be finite and match finite differences, or a
    landing that starts at rest fails its first model evaluation."""
    _, jac = dynamics_functions()
    eps = 1e-7
    for x, u in samples[:5]:
        x = x.copy()
        x[3:6] = 0.0
        A, B = (np.asarray(m) for m in jac(x, u, param_vector(P)))
        assert np.isfinite(A).all() and np.isfinite(B).all()
        A_fd = np.column_stack(
            [
                (dynamics_numpy(x + eps * e, u, P) - dynamics_numpy(x - eps * e, u, P)) / (2 * eps)
                for e in np.eye(14)
            ]
        )
        np.testing.assert_allclose(A @ tangent(x), A_fd @ tangent(x), atol=1e-7)


def test_path_constraints_match_numpy(samples) -> None:
    h, _ = constraint_functions()
    c = constraint_param_vector(P)
    for x, u in samples:
        got = np.asarray(h(x, u, c)).ravel()
        want = path_constraint_values(x[None], u[None], P)[0]
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def _integrate(x0: np.ndarray, uk: np.ndarray, uk1: np.ndarray, t1: float) -> np.ndarray:
    """scipy at 1e-12 of the plain-numpy dynamics (guidance.verify), not of CasADi."""
    return integrate_interval(x0, uk, uk1, t1, P, rtol=1e-12)


def test_discretization_matches_solve_ivp(samples) -> None:
    """x_next and the sensitivities of the FOH map agree with scipy integration (1e-6)."""
    F = discretization_function(rk4_steps_per_interval(SCvxSettings().rk4_substeps, 50))  # SCvx's
    p = param_vector(P)
    sigma, dtau = 6.0, 1.0 / 49
    t1 = sigma * dtau
    for x, u in samples[:6]:
        uk1 = u + np.array([0.3, -0.2, 0.1])
        xn, A, Bm, Bp, S, z = (np.asarray(o) for o in F(x, u, uk1, sigma, dtau, p))
        ref = _integrate(x, u, uk1, t1)
        assert np.abs(xn.ravel() - ref).max() <= 1e-6 * max(1.0, np.abs(ref).max())
        # sensitivities against central differences of the scipy integration
        eps = 1e-5
        A_fd = np.column_stack(
            [
                (_integrate(x + eps * e, u, uk1, t1) - _integrate(x - eps * e, u, uk1, t1))
                / (2 * eps)
                for e in np.eye(14)
            ]
        )
        Bp_fd = np.column_stack(
            [
                (_integrate(x, u, uk1 + eps * e, t1) - _integrate(x, u, uk1 - eps * e, t1))
                / (2 * eps)
                for e in np.eye(3)
            ]
        )
        np.testing.assert_allclose(A @ tangent(x), A_fd @ tangent(x), atol=1e-6)
        np.testing.assert_allclose(Bp, Bp_fd, atol=1e-6)
        # the affine model reproduces the propagation at the linearization point
        lin = A @ x + Bm @ u + Bp @ uk1 + S.ravel() * sigma + z.ravel()
        np.testing.assert_allclose(lin, xn.ravel(), atol=1e-12)


def test_foh_interval_sensitivities_match_scipy(samples) -> None:
    """discretize (Python engine) on a 3-node grid against scipy: the first interval's end state
    (interval length sigma / (N - 1) in physical time), A_k, B-_k, B+_k and Sigma_k against
    central differences of a 1e-12 integration under the FOH thrust between u_k and u_k1."""
    from guidance.model import discretize

    x, u = samples[0]
    uk1 = u + np.array([0.4, -0.3, 0.2])
    N, sigma = 3, 0.3  # interval of 0.15 time units
    xs = np.vstack([x, x, x])
    us = np.vstack([u, uk1, u])
    d = discretize(xs, us, sigma, P, substeps=16, engine="casadi")
    t1 = sigma / (N - 1)
    ref = _integrate(x, u, uk1, t1)
    np.testing.assert_allclose(d["x_next"][0], ref, atol=1e-9)
    # an interval of sigma / N would end elsewhere: the check above tells them apart
    assert np.abs(_integrate(x, u, uk1, sigma / N) - ref).max() > 1e-3
    eps = 1e-5

    def fd(fun, n: int) -> np.ndarray:
        return np.column_stack([(fun(eps * e) - fun(-eps * e)) / (2 * eps) for e in np.eye(n)])

    A_fd = fd(lambda dx: _integrate(x + dx, u, uk1, t1), 14)
    Bm_fd = fd(lambda du: _integrate(x, u + du, uk1, t1), 3)
    Bp_fd = fd(lambda du: _integrate(x, u, uk1 + du, t1), 3)
    S_fd = fd(lambda ds: _integrate(x, u, uk1, (sigma + ds[0]) / (N - 1)), 1).ravel()
    np.testing.assert_allclose(d["A"][0] @ tangent(x), A_fd @ tangent(x), atol=1e-7)
    np.testing.assert_allclose(d["Bm"][0], Bm_fd, atol=1e-7)
    np.testing.assert_allclose(d["Bp"][0], Bp_fd, atol=1e-7)
    np.testing.assert_allclose(d["Sigma"][0], S_fd, atol=1e-7)
    # B-_k and B+_k weigh the two ends differently (the hold is not symmetric in time)
    assert np.abs(d["Bm"][0] - d["Bp"][0]).max() > 1e-4


def _generic_params(r_cp_zero: bool) -> np.ndarray:
    """A parameter vector without the default vehicle's special values (J2 = J3 and r_cp_B = 0
    zero further entries), with r_cp_B zero if asked."""
    p = param_vector(P)
    p[1:4] = (0.001, 0.012, 0.008)
    p[7:10] = 0.0 if r_cp_zero else (0.05, 0.02, -0.03)
    return p


@pytest.mark.parametrize("index", [0, 1])
def test_transition_pattern_is_the_support_of_a_k(index: int) -> None:
    """Each pattern of A_k is its support: the entries off it are exact zeros, and each entry
    on it is nonzero somewhere (numbers without special values), for the vectors of its
    pattern_index."""
    from guidance.model import pattern_index, transition_pattern

    p = _generic_params(r_cp_zero=index == 1)
    assert pattern_index(p) == index
    pattern = transition_pattern(index)
    F = discretization_function(2)
    rng = np.random.default_rng(5)
    support = np.zeros_like(pattern)
    for _ in range(8):
        x, u = random_state(rng), rng.normal(size=3) + np.array([3.0, 0.0, 0.0])
        A = np.asarray(F(x, u, u + 0.1 * rng.normal(size=3), 6.0, 1 / 49, p)[1])
        assert np.all(A[~pattern] == 0.0)
        support |= A != 0.0
    np.testing.assert_array_equal(support, pattern)


def test_only_the_pattern_groups_change_the_pattern() -> None:
    """PATTERN_PARAM_GROUPS is complete: no other parameter that may be zero (J and aero_coeff
    must be positive), and no part of r_cp_B, removes an entry of the general pattern."""
    from guidance.model import N_PATTERNS, NP, pattern_with_zeros, transition_pattern

    general = transition_pattern(0)
    # Nothing depends on the position (each position row: its own entry and the 11 others),
    # the mass rate on the mass only: 3 x 12 + 10 x 11 + 1.
    assert general.sum() == 3 * 12 + 10 * 11 + 1 == 147
    for i in set(range(NP)) - {1, 2, 3, 7, 8, 9, 12}:
        np.testing.assert_array_equal(pattern_with_zeros(frozenset({i})), general)
    for part in ({7}, {8}, {9}, {7, 8}, {7, 9}, {8, 9}):
        np.testing.assert_array_equal(pattern_with_zeros(frozenset(part)), general)
    # r_cp_B = 0, no aerodynamic torque: the attitude no longer sees the velocity or the mass,
    # so the quaternion rows reach q and w only (4 x 7), the rate rows w only (3 x 3).
    assert N_PATTERNS == 2 and transition_pattern(1).sum() == 3 * 12 + 3 * 11 + 4 * 7 + 3 * 3 + 1
