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
from typing import Any, Literal, Protocol

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
        return int(np.shape(self.q)[0])

    @property
    def m(self) -> int:
        return int(np.shape(self.b)[0])


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


def invalid_solution(n: int, m: int, message: str) -> ConicSolution:
    """The answer to a problem (or call) refused as invalid input: NaN point, the reason in
    ``info["message"]``."""
    nan = float("nan")
    return ConicSolution(
        status="invalid_input",
        x=np.full(n, nan),
        s=np.full(m, nan),
        z=np.full(m, nan),
        obj=nan,
        iterations=0,
        solve_time_s=0.0,
        info={"message": message},  # type: ignore[dict-item]
    )


def _clarabel_solution(sol: Any, elapsed: float) -> ConicSolution:
    status: Status = _CLARABEL_STATUS.get(str(sol.status), "numerical_error")
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


def clarabel_solver(prob: ConicProblem, settings: Any) -> Any:
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


def canonical_csc(M: object) -> sp.csc_matrix:
    """A canonical CSC copy of ``M`` (rows sorted in each column, duplicates summed): the
    order in which Clarabel takes the values of A and P. ``M`` itself is left as it is."""
    C = sp.csc_matrix(M, copy=True)
    C.sum_duplicates()
    return C


def csc_key(M: object) -> tuple[tuple[int, int], np.ndarray, np.ndarray]:
    """Copies of the shape, indptr and indices of a canonical CSC pattern (anything with those
    attributes)."""
    shape = tuple(int(d) for d in M.shape)  # type: ignore[attr-defined]
    return shape, np.array(M.indptr), np.array(M.indices)  # type: ignore[attr-defined,return-value]


@dataclass(frozen=True, eq=False)
class Pattern:
    """A private snapshot of what a session compares the next problem with: the sizes, the
    cones (a tuple copy) and the canonical CSC pattern of A and P (copies), so that a caller
    who changes or reuses its problem object afterwards changes nothing here."""

    n: int
    m: int
    cones: tuple[tuple[ConeKind, int], ...]
    A: tuple[tuple[int, int], np.ndarray, np.ndarray]
    P: tuple[tuple[int, int], np.ndarray, np.ndarray] | None

    @classmethod
    def with_keys(cls, prob: ConicProblem, A: tuple, P: tuple | None) -> Pattern:
        """``prob``'s snapshot with the csc_key of its A and P (given: the caller has them)."""
        cones = tuple((kind, dim) for kind, dim in prob.cones)
        return cls(n=prob.n, m=prob.m, cones=cones, A=A, P=P)

    @classmethod
    def of(cls, prob: ConicProblem) -> Pattern:
        P = None if prob.P is None else csc_key(canonical_csc(prob.P))
        return cls.with_keys(prob, csc_key(canonical_csc(prob.A)), P)

    def matches(self, other: Pattern | None) -> bool:
        if other is None or (self.n, self.m, self.cones) != (other.n, other.m, other.cones):
            return False
        pairs = [(self.A, other.A)]
        if self.P is not None and other.P is not None:
            pairs.append((self.P, other.P))
        elif self.P is not None or other.P is not None:
            return False
        return all(
            k1[0] == k2[0] and np.array_equal(k1[1], k2[1]) and np.array_equal(k1[2], k2[2])
            for k1, k2 in pairs
        )


def same_pattern(a: ConicProblem, b: ConicProblem) -> bool:
    """Whether b has a's sizes (len(q), len(b)), cones and the sparsity pattern of its A and P
    (numbers and storage order aside)."""
    return Pattern.of(a).matches(Pattern.of(b))


class ClarabelSession:
    """Clarabel for a sequence of problems (what SCvx solves).

    The first solve sets Clarabel up (ordering, symbolic factorization); later solves of the
    same sparsity pattern only write the new numbers of P, q, A and b into it, and a problem
    of another pattern gets a new set-up (before 26 Nov its numbers were written into the old
    pattern: the wrong problem, solved without a word). The pattern is compared with a private
    snapshot (:class:`Pattern`), and the numbers are written in canonical CSC order whatever
    the format or storage order of the caller's matrices.
    """

    warm_starts = False  # Clarabel has no warm start: the reference starts cold

    def __init__(self, tol: float = 1e-9, max_iter: int = 200) -> None:
        self.tol, self.max_iter = tol, max_iter
        self._solver: Any = None  # a clarabel.DefaultSolver once set up
        self._pattern: Pattern | None = None
        self._limit = max_iter  # the set-up solver's iteration limit now

    def solve(
        self, prob: ConicProblem, warm: ConicSolution | None = None, max_iter: int | None = None
    ) -> ConicSolution:
        """``warm`` is ignored (``warm_starts``); ``max_iter``, 1 to the session's, limits this
        solve's iterations (None: the session's; another: invalid_input)."""
        del warm
        A = canonical_csc(prob.A)
        P = None if prob.P is None else canonical_csc(prob.P)
        pattern = Pattern.with_keys(prob, csc_key(A), None if P is None else csc_key(P))
        if self._solver is None or not pattern.matches(self._pattern):
            self._solver, self._pattern = None, None
            settings = _clarabel_settings(self.tol, self.max_iter, False)
            canonical = ConicProblem(P=P, q=prob.q, A=A, b=prob.b, cones=list(pattern.cones))
            self._solver, self._pattern = clarabel_solver(canonical, settings), pattern
            self._limit = self.max_iter
        else:
            new = {"q": prob.q, "A": A.data, "b": prob.b}
            if P is not None:
                new["P"] = P.data
            self._solver.update(**new)
        limit = self.max_iter if max_iter is None else max_iter
        if not 1 <= limit <= self.max_iter:  # as the C session answers it
            return invalid_solution(
                prob.n, prob.m, f"max_iter {limit}: 1 to the session's {self.max_iter}"
            )
        if limit != self._limit:
            settings = _clarabel_settings(self.tol, limit, False)
            self._solver.update(settings=settings)
            self._limit = limit
        t0 = time.perf_counter()
        sol = self._solver.solve()
        return _clarabel_solution(sol, time.perf_counter() - t0)


class Session(Protocol):
    warm_starts: bool  # whether solve starts from ``warm`` (else it is ignored)

    def solve(
        self, prob: ConicProblem, warm: ConicSolution | None = None, max_iter: int | None = None
    ) -> ConicSolution: ...


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
