"""Conic programs in Clarabel's form and the reference (Clarabel) backend.

    minimize    1/2 x'Px + q'x
    subject to  A x + s = b,   s in K = K_1 x ... x K_p

with K_i one of: the zero cone (equalities), the nonnegative orthant, or a second-order cone
{(t, y): |y|_2 <= t}. Every backend (Clarabel here, the flight C runtime in ``guidance.csocp``)
takes a :class:`ConicProblem` and returns a :class:`ConicSolution`, so the SCvx loop switches
backends with one option.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import scipy.sparse as sp

ConeKind = Literal["zero", "nonneg", "soc"]
Status = Literal[
    "solved",
    "solved_inaccurate",
    "primal_infeasible",
    "dual_infeasible",
    "max_iterations",
    "numerical_error",
    "invalid_input",
]


@dataclass
class ConicProblem:
    """Problem data. ``P`` is upper-triangular CSC (or None for an LP/SOCP without it)."""

    P: sp.csc_matrix | None
    q: np.ndarray
    A: sp.csc_matrix
    b: np.ndarray
    cones: list[tuple[ConeKind, int]]

    @property
    def n(self) -> int:
        return int(self.q.shape[0])

    @property
    def m(self) -> int:
        return int(self.b.shape[0])


@dataclass
class ConicSolution:
    status: Status
    x: np.ndarray  # primal variables (n)
    s: np.ndarray  # slacks (m)
    z: np.ndarray  # duals (m)
    obj: float
    iterations: int
    solve_time_s: float
    info: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.status in ("solved", "solved_inaccurate")


_CLARABEL_STATUS: dict[str, Status] = {
    "Solved": "solved",
    "AlmostSolved": "solved_inaccurate",
    "PrimalInfeasible": "primal_infeasible",
    "AlmostPrimalInfeasible": "primal_infeasible",
    "DualInfeasible": "dual_infeasible",
    "AlmostDualInfeasible": "dual_infeasible",
    "MaxIterations": "max_iterations",
    "MaxTime": "max_iterations",
    "NumericalError": "numerical_error",
    "InsufficientProgress": "numerical_error",
}


def clarabel_cones(cones: list[tuple[ConeKind, int]]) -> list[object]:
    import clarabel

    make = {
        "zero": clarabel.ZeroConeT,
        "nonneg": clarabel.NonnegativeConeT,
        "soc": clarabel.SecondOrderConeT,
    }
    return [make[kind](dim) for kind, dim in cones]


def solve_clarabel(
    prob: ConicProblem, *, tol: float = 1e-9, max_iter: int = 200, verbose: bool = False
) -> ConicSolution:
    """Solve with Clarabel (the ground reference). Time counts Clarabel's own solve only."""
    import clarabel

    settings = clarabel.DefaultSettings()
    settings.verbose = verbose
    settings.tol_gap_abs = tol
    settings.tol_gap_rel = tol
    settings.tol_feas = tol
    settings.max_iter = max_iter
    P = prob.P if prob.P is not None else sp.csc_matrix((prob.n, prob.n))
    solver = clarabel.DefaultSolver(
        sp.csc_matrix(P),
        prob.q,
        sp.csc_matrix(prob.A),
        prob.b,
        clarabel_cones(prob.cones),
        settings,
    )
    t0 = time.perf_counter()
    sol = solver.solve()
    elapsed = time.perf_counter() - t0
    status = _CLARABEL_STATUS.get(str(sol.status), "numerical_error")
    return ConicSolution(
        status=status,
        x=np.asarray(sol.x),
        s=np.asarray(sol.s),
        z=np.asarray(sol.z),
        obj=float(sol.obj_val),
        iterations=int(sol.iterations),
        solve_time_s=elapsed,
        info={"solve_time_internal_s": float(sol.solve_time)},
    )


def solve(prob: ConicProblem, backend: str = "clarabel") -> ConicSolution:
    """Solve with the named backend: ``clarabel`` (reference) or ``c`` (flight runtime)."""
    if backend == "clarabel":
        return solve_clarabel(prob)
    if backend == "c":
        from guidance import csocp

        return csocp.solve(prob)
    raise ValueError(f"unknown conic backend {backend!r} (use 'clarabel' or 'c')")
