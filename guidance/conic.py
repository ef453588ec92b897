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
from typing import Literal, Protocol

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


def _clarabel_settings(tol: float, max_iter: int, verbose: bool) -> object:
    import clarabel

    settings = clarabel.DefaultSettings()
    settings.verbose = verbose
    settings.tol_gap_abs = tol
    settings.tol_gap_rel = tol
    settings.tol_feas = tol
    settings.max_iter = max_iter
    # Clarabel's own iterative refinement (1e-13 relative, 1e-12 absolute): with the 1e-10 that
    # this reference used until 22 Nov, the subproblems with the proximal term (a quadratic
    # objective) end "AlmostSolved" at a 6e-8 gap on the default landing's first subproblem.
    # Presolve may drop rows, which would forbid updating the numbers in place.
    settings.presolve_enable = False
    return settings


def _clarabel_solution(sol: object, elapsed: float) -> ConicSolution:
    status = _CLARABEL_STATUS.get(str(sol.status), "numerical_error")  # type: ignore[attr-defined]
    return ConicSolution(
        status=status,
        x=np.asarray(sol.x),  # type: ignore[attr-defined]
        s=np.asarray(sol.s),  # type: ignore[attr-defined]
        z=np.asarray(sol.z),  # type: ignore[attr-defined]
        obj=float(sol.obj_val),  # type: ignore[attr-defined]
        iterations=int(sol.iterations),  # type: ignore[attr-defined]
        solve_time_s=elapsed,
        info={"solve_time_internal_s": float(sol.solve_time)},  # type: ignore[attr-defined]
    )


def clarabel_solver(prob: ConicProblem, settings: object) -> object:
    """A Clarabel solver set up for ``prob`` (set-up only: the caller times ``solve()``)."""
    import clarabel

    P = prob.P if prob.P is not None else sp.csc_matrix((prob.n, prob.n))
    return clarabel.DefaultSolver(
        sp.csc_matrix(P),
        prob.q,
        sp.csc_matrix(prob.A),
        prob.b,
        clarabel_cones(prob.cones),
        settings,
    )


def solve_clarabel(
    prob: ConicProblem, *, tol: float = 1e-9, max_iter: int = 200, verbose: bool = False
) -> ConicSolution:
    """Solve with Clarabel (the ground reference). Time counts Clarabel's own solve only."""
    solver = clarabel_solver(prob, _clarabel_settings(tol, max_iter, verbose))
    t0 = time.perf_counter()
    sol = solver.solve()
    return _clarabel_solution(sol, time.perf_counter() - t0)


def same_pattern(a: ConicProblem, b: ConicProblem) -> bool:
    """Whether b has a's cones and the sparsity pattern of its A and P (numbers aside)."""
    if a.cones != b.cones or a.A.shape != b.A.shape or (a.P is None) != (b.P is None):
        return False
    pairs = [(a.A, b.A)] if a.P is None else [(a.A, b.A), (a.P, b.P)]
    for M1, M2 in pairs:
        C1, C2 = sp.csc_matrix(M1), sp.csc_matrix(M2)
        if not (np.array_equal(C1.indptr, C2.indptr) and np.array_equal(C1.indices, C2.indices)):
            return False
    return True


class ClarabelSession:
    """Clarabel for a sequence of problems (what SCvx solves).

    The first solve sets Clarabel up (ordering, symbolic factorization); later solves of the
    same sparsity pattern only write the new numbers of P, q, A and b into it, and a problem
    of another pattern gets a new set-up (before 26 Nov its numbers were written into the old
    pattern: the wrong problem, solved without a word).
    """

    def __init__(self, tol: float = 1e-9, max_iter: int = 200) -> None:
        self.tol, self.max_iter = tol, max_iter
        self._solver: object | None = None
        self._prob: ConicProblem | None = None

    def solve(self, prob: ConicProblem, warm: ConicSolution | None = None) -> ConicSolution:
        """``warm`` is ignored: Clarabel has no warm start (the reference starts cold)."""
        del warm
        if self._solver is None or self._prob is None or not same_pattern(self._prob, prob):
            settings = _clarabel_settings(self.tol, self.max_iter, False)
            self._solver = clarabel_solver(prob, settings)
        else:
            new = {"q": prob.q, "A": prob.A.data, "b": prob.b}
            if prob.P is not None:
                new["P"] = sp.csc_matrix(prob.P).data
            self._solver.update(**new)  # type: ignore[attr-defined]
        self._prob = prob
        t0 = time.perf_counter()
        sol = self._solver.solve()  # type: ignore[attr-defined]
        return _clarabel_solution(sol, time.perf_counter() - t0)


class Session(Protocol):
    def solve(self, prob: ConicProblem, warm: ConicSolution | None = None) -> ConicSolution: ...


def session(backend: str, tol: float = 1e-9, max_iter: int = 200) -> Session:
    """A solver for a sequence of problems sharing one sparsity pattern, stopping at the same
    gap and feasibility tolerance ``tol`` whichever the backend."""
    if backend == "clarabel":
        return ClarabelSession(tol, max_iter)
    if backend == "c":
        from guidance import csocp

        return csocp.Session(tol_gap_abs=tol, tol_gap_rel=tol, tol_feas=tol, max_iter=max_iter)
    raise ValueError(f"unknown conic backend {backend!r} (use 'clarabel' or 'c')")


def solve(prob: ConicProblem, backend: str = "clarabel") -> ConicSolution:
    """Solve with the named backend: ``clarabel`` (reference) or ``c`` (flight runtime)."""
    if backend == "clarabel":
        return solve_clarabel(prob)
    if backend == "c":
        from guidance import csocp

        return csocp.solve(prob)
    raise ValueError(f"unknown conic backend {backend!r} (use 'clarabel' or 'c')")
