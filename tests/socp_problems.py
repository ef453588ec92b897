"""Seeded SOCP families (Clarabel form) for cross-checking the flight runtime.

Feasible problems are built from a strictly feasible primal point (x0, s0) and a strictly
feasible dual point z0, so an optimum exists; infeasible and unbounded problems carry a known
certificate by construction.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from guidance.conic import ConicProblem


def cone_interior(rng: np.random.Generator, cones, scale: float = 1.0) -> np.ndarray:
    """A point in the interior of K (zero cones get 0)."""
    parts = []
    for kind, dim in cones:
        if kind == "zero":
            parts.append(np.zeros(dim))
        elif kind == "nonneg":
            parts.append(rng.uniform(0.1, 2.0, dim) * scale)
        else:
            u = rng.standard_normal(dim - 1)
            t = np.linalg.norm(u) + rng.uniform(0.1, 2.0)
            parts.append(np.concatenate([[t], u]) * scale)
    return np.concatenate(parts) if parts else np.zeros(0)


def dual_interior(rng: np.random.Generator, cones) -> np.ndarray:
    """A point in the interior of K* (zero cones get free values)."""
    z = cone_interior(rng, cones)
    row = 0
    for kind, dim in cones:
        if kind == "zero":
            z[row : row + dim] = rng.standard_normal(dim)
        row += dim
    return z


def random_cones(rng: np.random.Generator, m_target: int, soc_max: int = 8) -> list:
    cones = []
    rows = 0
    while rows < m_target:
        kind = rng.choice(["zero", "nonneg", "soc", "soc"])
        dim = int(rng.integers(1, soc_max + 1)) if kind == "soc" else int(rng.integers(1, 6))
        cones.append((str(kind), dim))
        rows += dim
    # keep the equality rows a minority so that A_eq keeps full row rank
    nzero = sum(d for k, d in cones if k == "zero")
    if nzero > rows // 3:
        cones = [("nonneg", d) if k == "zero" else (k, d) for k, d in cones]
        cones.insert(0, ("zero", max(1, rows // 4)))
    return cones


def random_feasible(
    seed: int,
    n: int | None = None,
    with_P: bool | None = None,
    density: float | None = None,
    soc_max: int = 8,
) -> ConicProblem:
    """A random SOCP with a strictly feasible primal and dual (hence an optimum)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 60)) if n is None else n
    with_P = bool(rng.integers(0, 2)) if with_P is None else with_P
    m_target = int(rng.integers(n // 2 + 1, 2 * n + 2))
    cones = random_cones(rng, m_target, soc_max)
    nzero = sum(d for k, d in cones if k == "zero")
    if nzero >= n:  # keep equalities fewer than variables
        cones = [("nonneg", d) if k == "zero" else (k, d) for k, d in cones]
    m = sum(d for _, d in cones)
    density = float(rng.uniform(0.05, 0.4)) if density is None else density
    A = sp.random(m, n, density=density, random_state=rng, data_rvs=rng.standard_normal)
    A = sp.csc_matrix(
        A + sp.csc_matrix((np.ones(min(m, n)), (np.arange(min(m, n)),) * 2), shape=(m, n))
    )
    x0 = rng.standard_normal(n)
    s0 = cone_interior(rng, cones)
    b = A @ x0 + s0
    z0 = dual_interior(rng, cones)
    if with_P:
        r = int(rng.integers(1, n + 1))
        F = sp.random(r, n, density=0.3, random_state=rng, data_rvs=rng.standard_normal)
        P = sp.csc_matrix(F.T @ F + 1e-3 * sp.eye(n))
        xp = rng.standard_normal(n)
        q = -(P @ xp) - A.T @ z0
        Pu = sp.csc_matrix(sp.triu(P))
    else:
        Pu = None
        q = -(A.T @ z0)
    return ConicProblem(P=Pu, q=np.asarray(q).ravel(), A=A, b=np.asarray(b).ravel(), cones=cones)


def random_primal_infeasible(seed: int) -> ConicProblem:
    """Feasible random data plus an infeasible block: |x_S| <= 1 (SOC) and x_S[0] >= 2, or
    a'x <= b1 and -a'x <= b2 with b1 + b2 < 0 (nonneg rows)."""
    rng = np.random.default_rng(seed)
    base = random_feasible(seed + 100_000, n=int(rng.integers(4, 40)))
    n = base.n
    extra_rows, extra_b, extra_cones = [], [], []
    if seed % 2 == 0:
        k = int(rng.integers(2, min(5, n) + 1))
        idx = rng.choice(n, size=k, replace=False)
        # SOC: (1, x_S) in Q  <=>  [0; -x_S] x + s = [1; 0]
        rows = np.zeros((k + 1, n))
        rows[np.arange(1, k + 1), idx] = -1.0
        extra_rows.append(rows)
        extra_b.append(np.concatenate([[1.0], np.zeros(k)]))
        extra_cones.append(("soc", k + 1))
        # x_S[0] >= 2  <=>  x_S[0] - s = ... : -x + s = -2
        row = np.zeros((1, n))
        row[0, idx[0]] = -1.0
        extra_rows.append(row)
        extra_b.append(np.array([-2.0]))
        extra_cones.append(("nonneg", 1))
    else:
        a = sp.random(1, n, density=0.5, random_state=rng).toarray() + 0.1
        b1 = rng.uniform(-1, 1)
        extra_rows.append(np.vstack([a, -a]))
        extra_b.append(np.array([b1, -b1 - rng.uniform(0.5, 2.0)]))
        extra_cones.append(("nonneg", 2))
    A = sp.vstack([base.A] + [sp.csc_matrix(r) for r in extra_rows], format="csc")
    b = np.concatenate([base.b, *extra_b])
    return ConicProblem(P=base.P, q=base.q, A=A, b=b, cones=base.cones + extra_cones)


def random_dual_infeasible(seed: int) -> ConicProblem:
    """A feasible problem with a recession direction d: A d = 0 (all rows), P d = 0,
    q'd < 0 -- the objective is unbounded below."""
    rng = np.random.default_rng(seed)
    base = random_feasible(seed + 200_000, n=int(rng.integers(4, 40)))
    n = base.n
    A = base.A.toarray()
    S = rng.choice(n, size=min(3, n), replace=False)
    d = np.zeros(n)
    d[S] = rng.uniform(0.5, 1.5, len(S))
    k = S[0]
    others = [j for j in S if j != k]
    A[:, k] = -(A[:, others] @ d[others]) / d[k]
    P = None
    if base.P is not None:
        F = rng.standard_normal((max(1, n // 2), n))
        F[:, k] = -(F[:, others] @ d[others]) / d[k]
        P = sp.csc_matrix(sp.triu(sp.csc_matrix(F.T @ F)))
    q = base.q.copy()
    q -= (q @ d + rng.uniform(0.5, 2.0)) * d / (d @ d)  # now q'd < 0
    b = A @ rng.standard_normal(n) + cone_interior(rng, base.cones)  # primal stays feasible
    return ConicProblem(P=P, q=q, A=sp.csc_matrix(A), b=b, cones=base.cones)


def badly_scaled(seed: int) -> ConicProblem:
    """A random feasible problem with rows and columns scaled over several decades."""
    rng = np.random.default_rng(seed)
    prob = random_feasible(seed + 300_000)
    n, m = prob.n, prob.m
    col = 10.0 ** rng.uniform(-3, 3, n)
    row = np.empty(m)
    r = 0
    for kind, dim in prob.cones:  # one factor per cone keeps SOCs invariant
        if kind == "soc":
            row[r : r + dim] = 10.0 ** rng.uniform(-3, 3)
        else:
            row[r : r + dim] = 10.0 ** rng.uniform(-3, 3, dim)
        r += dim
    A = sp.csc_matrix(sp.diags(row) @ prob.A @ sp.diags(col))
    b = row * prob.b
    obj_scale = 10.0 ** rng.uniform(-2, 2)
    q = obj_scale * col * prob.q
    P = None
    if prob.P is not None:
        P = sp.csc_matrix(sp.triu(obj_scale * sp.diags(col) @ prob.P @ sp.diags(col)))
    return ConicProblem(P=P, q=q, A=A, b=b, cones=prob.cones)
