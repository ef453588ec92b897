"""Python bindings (ctypes) to the flight SOCP runtime ``build/libtscvx.so``.

Takes a :class:`~guidance.conic.ConicProblem` in Clarabel's form

    minimize 1/2 x'Px + q'x   s.t.  A x + s = b,  s in K  (cones: zero, nonneg, soc)

and maps it to the C form (``c_runtime/include/tscvx_socp.h``): the zero-cone rows become the
equality constraints ``A_eq x = b_eq``, the nonnegative rows (first) and the second-order cones
(in order) the cone rows ``G x + s = h``. Results come back in Clarabel's row order.

    sol = solve(prob)                                   # one-shot
    S = Solver(prob, max_iter=50); S.solve()             # set up once ...
    S.update(q=q2, A_values=A2.data, b=b2); S.solve()    # ... new numbers, same sparsity
    session = Session(); session.solve(prob_k)           # SCvx: re-setup only on new patterns

A Solver (and a Session) holds one C workspace. Its calls take turns: threads sharing one
are served one call at a time (unguarded, two solves at once corrupted the workspace and
crashed), while solvers in different threads run in parallel (the C call releases the GIL).

Statuses: solved, solved_inaccurate, primal_infeasible (z holds the certificate, b'z = -1),
dual_infeasible (x, s hold the certificate, q'x = -1), max_iterations, numerical_error,
invalid_input (``info["message"]`` says why). ``solve(prob, log=True)`` adds the iteration log
(``info["log"]``: iter, pcost, dcost, gap, pres, dres, mu, step per iteration). Settings are
the fields of ``tscvx_settings`` (e.g. ``max_iter``, ``tol_feas``, ``soc_dense_max``,
``kkt_backend``: ``KKT_AUTO`` (default), ``KKT_BANDED``, ``KKT_STATIC`` or ``KKT_LDL``;
``info["kkt_backend"]`` names the method that ran).
"""

from __future__ import annotations

import ctypes as ct
import functools
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import numpy as np
import scipy.sparse as sp

from guidance.conic import ConeKind, ConicProblem, ConicSolution, Status, same_pattern

_LIB_ENV = "TSCVX_LIB"
_LIB_DEFAULT = Path(__file__).resolve().parents[1] / "build" / "libtscvx.so"

c_int = ct.c_int
c_double = ct.c_double
P_int = ct.POINTER(ct.c_int)
P_double = ct.POINTER(ct.c_double)


class LibraryNotBuiltError(RuntimeError):
    """The shared library is missing: run ``make lib``."""


MESSAGE_LEN = 160  # TSCVX_MESSAGE_LEN (tscvx_socp.h)


class _Data(ct.Structure):
    _fields_ = [
        ("n", c_int),
        ("p", c_int),
        ("m", c_int),
        ("Pp", P_int),
        ("Pi", P_int),
        ("Px", P_double),
        ("c", P_double),
        ("Ap", P_int),
        ("Ai", P_int),
        ("Ax", P_double),
        ("b", P_double),
        ("Gp", P_int),
        ("Gi", P_int),
        ("Gx", P_double),
        ("h", P_double),
        ("l", c_int),
        ("nsoc", c_int),
        ("q", P_int),
    ]


_SETTING_FIELDS = [
    ("max_iter", c_int),
    ("tol_gap_abs", c_double),
    ("tol_gap_rel", c_double),
    ("tol_feas", c_double),
    ("tol_infeas", c_double),
    ("tol_gap_abs_inacc", c_double),
    ("tol_gap_rel_inacc", c_double),
    ("tol_feas_inacc", c_double),
    ("step_fraction", c_double),
    ("static_reg", c_double),
    ("refine_iters", c_int),
    ("ruiz_iters", c_int),
    ("soc_dense_max", c_int),
    ("kkt_backend", c_int),
]

# tscvx_settings.kkt_backend: AUTO (default) takes the banded method when the problem has stage
# structure (each cone couples a few variables, the equalities neighbouring stages), else the
# sparse LDL' of the whole KKT matrix: the runtime's static-pattern LDL' (the same factor as
# SuiteSparse LDL without its per-factorization symbolic work) or SuiteSparse LDL itself.
KKT_AUTO, KKT_LDL, KKT_STATIC, KKT_BANDED = 0, 1, 2, 3
KKT_NAMES = {KKT_LDL: "ldl", KKT_STATIC: "static", KKT_BANDED: "banded"}


class _Settings(ct.Structure):
    _fields_ = _SETTING_FIELDS


class _Info(ct.Structure):
    _fields_ = [
        ("status", c_int),
        ("iterations", c_int),
        ("pcost", c_double),
        ("dcost", c_double),
        ("gap_abs", c_double),
        ("gap_rel", c_double),
        ("pres", c_double),
        ("dres", c_double),
        ("mu", c_double),
        ("kkt_backend", c_int),
        ("kkt_dim", c_int),
        ("kkt_nnz", c_int),
        ("factor_nnz", c_int),
        ("factorizations", c_int),
        ("arena_used", ct.c_size_t),
        ("arena_high_water", ct.c_size_t),
        ("ruiz_passes", c_int),
        ("warm_started", c_int),
        ("restart_iterations", c_int),
    ]


class _IterLog(ct.Structure):
    _fields_ = [
        ("iter", c_int),
        ("pcost", c_double),
        ("dcost", c_double),
        ("gap", c_double),
        ("pres", c_double),
        ("dres", c_double),
        ("mu", c_double),
        ("step", c_double),
    ]


# C solve status -> ConicSolution status (index = enum value)
SOLVE_STATUS: tuple[Status, ...] = (
    "numerical_error",  # UNSOLVED (never returned by solve)
    "solved",
    "solved_inaccurate",
    "primal_infeasible",
    "dual_infeasible",
    "max_iterations",
    "numerical_error",
    "invalid_input",
)

_lib_cache: ct.CDLL | None = None


def library_path() -> Path:
    return Path(os.environ.get(_LIB_ENV, str(_LIB_DEFAULT)))


def load_library() -> ct.CDLL:
    """Load ``libtscvx.so`` once; a clear error if it was not built."""
    global _lib_cache
    if _lib_cache is not None:
        return _lib_cache
    path = library_path()
    if not path.exists():
        raise LibraryNotBuiltError(
            f"flight SOCP library not found at {path}: run `make lib` (or set {_LIB_ENV})"
        )
    lib = ct.CDLL(str(path))
    ws_p = ct.c_void_p
    sigs = {
        "tscvx_default_settings": (c_int, [ct.POINTER(_Settings)]),
        "tscvx_scratch_size": (
            c_int,
            [ct.POINTER(_Data), ct.POINTER(_Settings), ct.POINTER(ct.c_size_t)],
        ),
        "tscvx_workspace_size": (
            c_int,
            [
                ct.POINTER(_Data),
                ct.POINTER(_Settings),
                ct.c_void_p,
                ct.c_size_t,
                ct.POINTER(ct.c_size_t),
            ],
        ),
        "tscvx_setup": (
            c_int,
            [
                ct.POINTER(ws_p),
                ct.c_void_p,
                ct.c_size_t,
                ct.POINTER(_Data),
                ct.POINTER(_Settings),
            ],
        ),
        "tscvx_update_data": (c_int, [ws_p] + [P_double] * 6),
        "tscvx_update_settings": (c_int, [ws_p, ct.POINTER(_Settings)]),
        "tscvx_warm_start": (c_int, [ws_p] + [P_double] * 4),
        "tscvx_solve": (c_int, [ws_p]),
        "tscvx_get_solution": (c_int, [ws_p, P_double, P_double, P_double, P_double]),
        "tscvx_get_info": (c_int, [ws_p, ct.POINTER(_Info)]),
        "tscvx_get_iter_log": (c_int, [ws_p, c_int, ct.POINTER(_IterLog)]),
        "tscvx_setup_status_message": (ct.c_char_p, [c_int]),
        "tscvx_check_data": (c_int, [ct.POINTER(_Data), ct.c_char_p]),
        "tscvx_solve_status_message": (ct.c_char_p, [c_int]),
    }
    for name, (res, args) in sigs.items():
        fn = getattr(lib, name)
        fn.restype = res
        fn.argtypes = args
    _lib_cache = lib
    return lib


def _iptr(a: np.ndarray | None):
    return None if a is None else a.ctypes.data_as(P_int)


def _dptr(a: np.ndarray | None):
    return None if a is None else a.ctypes.data_as(P_double)


class InvalidProblemError(ValueError):
    """The problem data do not describe a valid conic program (message says why)."""


@dataclass
class _Split:
    """How Clarabel's (A, b, cones) maps to the C form (A_eq, b_eq, G, h, l, q)."""

    eq_rows: np.ndarray  # original rows of the zero cones (in order)
    g_rows: np.ndarray  # original rows of G: nonneg rows first, then the SOC rows
    l: int
    soc: np.ndarray  # SOC dimensions
    A_src: np.ndarray  # for each A_eq entry, its index in the original A.data
    G_src: np.ndarray  # for each G entry, its index in the original A.data
    P_src: np.ndarray | None  # for each canonical P entry, its index in the original P.data


def _csc_int(M: sp.csc_matrix) -> sp.csc_matrix:
    M = sp.csc_matrix(M, copy=True)
    M.indptr = M.indptr.astype(np.int32)
    M.indices = M.indices.astype(np.int32)
    return M


def _pattern_of(M: sp.spmatrix) -> sp.csc_matrix:
    """Copy of M's stored pattern whose values are 1 + the index into M.data (canonical CSC).
    M itself is left as it is: its index arrays are copied before the sort (sp.csc_matrix
    of a CSC matrix shares them, and sorting them in place would reorder the caller's rows
    under its values)."""
    M = sp.csc_matrix(M)
    index = np.arange(1, M.nnz + 1, dtype=float)
    T = sp.csc_matrix((index, M.indices.copy(), M.indptr.copy()), M.shape)
    T.sum_duplicates()  # sorts; duplicates (if any) merge: refused below
    if T.nnz != M.nnz:
        raise InvalidProblemError("duplicate entries in a sparse matrix")
    return T


def _split(prob: ConicProblem) -> _Split:
    n, m = prob.n, prob.m
    A = prob.A
    if not sp.issparse(A) or A.shape != (m, n):
        raise InvalidProblemError(
            f"A must be a sparse {m} x {n} matrix (len(b) x len(q)), got shape {A.shape}"
        )
    eq, nonneg, soc_rows, soc = _cone_rows(prob.cones, m)
    eq_rows = np.array(eq, dtype=np.int64)
    g_rows = np.array(nonneg + soc_rows, dtype=np.int64)
    T = _pattern_of(A)
    P_src = None
    if prob.P is not None:
        if not sp.issparse(prob.P) or prob.P.shape != (n, n):
            raise InvalidProblemError(f"P must be a sparse {n} x {n} matrix")
        P_src = _pattern_of(prob.P).data.astype(np.int64) - 1
    return _Split(
        eq_rows=eq_rows,
        g_rows=g_rows,
        l=len(nonneg),
        soc=np.array(soc, dtype=np.int32),
        A_src=_sources_of_rows(T, eq_rows),
        G_src=_sources_of_rows(T, g_rows),
        P_src=P_src,
    )


def _cone_rows(
    cones: list[tuple[ConeKind, int]], m: int
) -> tuple[list[int], list[int], list[int], list[int]]:
    """The rows of the zero, nonneg and SOC cones and the SOC dimensions; the cones must cover
    the m rows exactly."""
    eq: list[int] = []
    nonneg: list[int] = []
    soc_rows: list[int] = []
    soc: list[int] = []
    row = 0
    for kind, dim in cones:
        dim = int(dim)
        if dim < 1:
            raise InvalidProblemError(f"cone ({kind}, {dim}): dimension must be >= 1")
        if row + dim > m:
            raise InvalidProblemError(
                f"cones cover more rows ({row + dim}) than A and b have ({m})"
            )
        rows = list(range(row, row + dim))
        if kind == "zero":
            eq += rows
        elif kind == "nonneg":
            nonneg += rows
        elif kind == "soc":
            soc_rows += rows
            soc.append(dim)
        else:
            raise InvalidProblemError(f"unknown cone kind {kind!r}")
        row += dim
    if row != m:
        raise InvalidProblemError(f"cones cover {row} rows but A and b have {m}")
    return eq, nonneg, soc_rows, soc


def _sources_of_rows(T: sp.csc_matrix, rows: np.ndarray) -> np.ndarray:
    """For each entry of these rows of A (canonical CSC), its index in the original A.data;
    ``T`` is A's _pattern_of."""
    sub = sp.csc_matrix(T[rows, :]) if len(rows) else sp.csc_matrix((0, T.shape[1]))
    sub.sort_indices()
    return sub.data.astype(np.int64) - 1


def c_point(
    split: _Split, sol: ConicSolution
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``sol`` (Clarabel's form) as the runtime's (x, y, z, s): y the zero cones' z."""
    rows_eq, rows_g = split.eq_rows, split.g_rows
    return tuple(  # type: ignore[return-value]
        np.ascontiguousarray(v, dtype=float)
        for v in (sol.x, sol.z[rows_eq], sol.z[rows_g], sol.s[rows_g])
    )


_R = TypeVar("_R")


def _one_at_a_time(method: Callable[..., _R]) -> Callable[..., _R]:
    """The method runs under the object's lock (a re-entrant one: methods call each other)."""

    @functools.wraps(method)
    def serialized(self, *args: object, **kwargs: object) -> _R:
        with self._lock:
            return method(self, *args, **kwargs)

    return serialized


class Solver:
    """A set-up workspace: one arena, fixed sparsity, repeated solves."""

    def __init__(self, prob: ConicProblem, **settings: float | int):
        self._lock = threading.RLock()
        self.lib = load_library()
        self.prob = prob
        n, m = prob.n, prob.m
        q = np.asarray(prob.q, dtype=float).reshape(-1)
        b = np.asarray(prob.b, dtype=float).reshape(-1)
        if q.shape[0] != n or b.shape[0] != m:
            raise InvalidProblemError("q and b must be vectors of length n and m")
        self.split = sp_ = _split(prob)
        A = sp.csc_matrix(prob.A)
        # canonical CSC structure (sorted rows) with values taken through the source maps
        self._Aeq = _csc_int(self._take(A, sp_.A_src, sp_.eq_rows))
        self._G = _csc_int(self._take(A, sp_.G_src, sp_.g_rows))
        if prob.P is not None:
            Pc = _csc_int(_pattern_of(prob.P))
            Pc.data = np.asarray(sp.csc_matrix(prob.P).data, dtype=float)[sp_.P_src]
            self._P = Pc
        else:
            self._P = None
        self._c = q.copy()
        self._beq = np.ascontiguousarray(b[sp_.eq_rows], dtype=float)
        self._h = np.ascontiguousarray(b[sp_.g_rows], dtype=float)
        self._soc = np.ascontiguousarray(sp_.soc, dtype=np.int32)
        self._data = self._make_data()

        self._settings = _Settings()
        self.lib.tscvx_default_settings(ct.byref(self._settings))
        for key, val in settings.items():
            if key not in dict(_SETTING_FIELDS):
                raise TypeError(f"unknown setting {key!r}")
            setattr(self._settings, key, val)

        self.ws = ct.c_void_p()
        self.setup_status = 0
        self.message = "ok"
        need = ct.c_size_t(0)
        st = self.lib.tscvx_scratch_size(
            ct.byref(self._data), ct.byref(self._settings), ct.byref(need)
        )
        if st == 0:
            scratch = np.zeros(need.value, dtype=np.uint8)
            st = self.lib.tscvx_workspace_size(
                ct.byref(self._data),
                ct.byref(self._settings),
                scratch.ctypes.data_as(ct.c_void_p),
                need.value,
                ct.byref(need),
            )
            del scratch
        if st == 0:
            self.arena = np.zeros(need.value, dtype=np.uint8)
            st = self.lib.tscvx_setup(
                ct.byref(self.ws),
                self.arena.ctypes.data_as(ct.c_void_p),
                need.value,
                ct.byref(self._data),
                ct.byref(self._settings),
            )
        else:
            self.arena = np.zeros(0, dtype=np.uint8)
        self.setup_status = int(st)
        if st != 0:
            self.message = self.lib.tscvx_setup_status_message(st).decode()
            detail = ct.create_string_buffer(MESSAGE_LEN)  # the array and entry at fault
            if self.lib.tscvx_check_data(ct.byref(self._data), detail) == st and detail.value:
                self.message += f" ({detail.value.decode()}; in the C runtime's terms: c is q, "
                self.message += "A and b the zero-cone rows, G and h the other rows)"
            self.ws = ct.c_void_p()

    @staticmethod
    def _take(A: sp.csc_matrix, src: np.ndarray, rows: np.ndarray) -> sp.csc_matrix:
        T = _pattern_of(A)
        Ts = sp.csc_matrix(T[rows, :]) if len(rows) else sp.csc_matrix((0, A.shape[1]))
        Ts.sort_indices()
        return sp.csc_matrix(
            (np.asarray(A.data, dtype=float)[src], Ts.indices.copy(), Ts.indptr.copy()),
            Ts.shape,
        )

    def _make_data(self) -> _Data:
        d = _Data()
        n = self.prob.n
        d.n, d.p, d.m = n, self._Aeq.shape[0], self._G.shape[0]
        if self._P is not None:
            d.Pp, d.Pi, d.Px = _iptr(self._P.indptr), _iptr(self._P.indices), _dptr(self._P.data)
        d.c = _dptr(self._c)
        d.Ap, d.Ai, d.Ax = _iptr(self._Aeq.indptr), _iptr(self._Aeq.indices), _dptr(self._Aeq.data)
        d.b = _dptr(self._beq)
        d.Gp, d.Gi, d.Gx = _iptr(self._G.indptr), _iptr(self._G.indices), _dptr(self._G.data)
        d.h = _dptr(self._h)
        d.l = self.split.l
        d.nsoc = len(self._soc)
        d.q = _iptr(self._soc) if len(self._soc) else None
        return d

    @property
    def ready(self) -> bool:
        return bool(self.ws)

    @property
    def arena_bytes(self) -> int:
        return int(self.arena.nbytes)

    @_one_at_a_time
    def update(
        self,
        q: np.ndarray | None = None,
        A_values: np.ndarray | None = None,
        b: np.ndarray | None = None,
        P_values: np.ndarray | None = None,
    ) -> int:
        """New numbers, same sparsity: A_values/P_values in the order of the original
        ``prob.A.data`` / ``prob.P.data``. Returns the C setup status (0 = ok)."""
        if not self.ready:
            return self.setup_status
        Px = c = Ax = beq = Gx = h = None
        if q is not None:
            self._c[:] = np.asarray(q, dtype=float).reshape(-1)
            c = self._c
        if A_values is not None:
            av = np.asarray(A_values, dtype=float).reshape(-1)
            self._Aeq.data[:] = av[self.split.A_src]
            self._G.data[:] = av[self.split.G_src]
            Ax, Gx = self._Aeq.data, self._G.data
        if b is not None:
            bv = np.asarray(b, dtype=float).reshape(-1)
            self._beq[:] = bv[self.split.eq_rows]
            self._h[:] = bv[self.split.g_rows]
            beq, h = self._beq, self._h
        if P_values is not None and self._P is not None:
            self._P.data[:] = np.asarray(P_values, dtype=float).reshape(-1)[self.split.P_src]
            Px = self._P.data
        st = self.lib.tscvx_update_data(
            self.ws, _dptr(Px), _dptr(c), _dptr(Ax), _dptr(beq), _dptr(Gx), _dptr(h)
        )
        if st != 0:
            self.message = self.lib.tscvx_setup_status_message(st).decode()
        return int(st)

    @_one_at_a_time
    def warm_start(self, sol: ConicSolution) -> int:
        """Start the next solve from ``sol`` (Clarabel's form, e.g. the last solve's answer),
        centred into the cones (tscvx_warm_start). Returns the C setup status (0 = ok);
        a solution of another size is refused (-1) and the next solve starts cold."""
        if not self.ready:
            return self.setup_status
        n, m = self.prob.n, self.prob.m
        if sol.x.shape != (n,) or sol.z.shape != (m,) or sol.s.shape != (m,):
            self.lib.tscvx_warm_start(self.ws, None, None, None, None)  # refused: drops any point
            return -1
        x, y, z, s = c_point(self.split, sol)
        return int(self.lib.tscvx_warm_start(self.ws, _dptr(x), _dptr(y), _dptr(z), _dptr(s)))

    @_one_at_a_time
    def info(self) -> dict[str, float]:
        inf = _Info()
        if self.ready:
            self.lib.tscvx_get_info(self.ws, ct.byref(inf))
        return {name: float(getattr(inf, name)) for name, _ in _Info._fields_}

    @_one_at_a_time
    def iteration_log(self) -> list[dict[str, float]]:
        rows = []
        if not self.ready:
            return rows
        inf = _Info()
        self.lib.tscvx_get_info(self.ws, ct.byref(inf))
        row = _IterLog()
        for k in range(inf.iterations + 1):
            if self.lib.tscvx_get_iter_log(self.ws, k, ct.byref(row)) != 0:
                break
            rows.append({name: getattr(row, name) for name, _ in _IterLog._fields_})
        return rows

    @_one_at_a_time
    def solve(self, log: bool = False) -> ConicSolution:
        n, m = self.prob.n, self.prob.m
        if not self.ready:
            return _invalid(n, m, self.message)
        t0 = time.perf_counter()
        st = int(self.lib.tscvx_solve(self.ws))
        elapsed = time.perf_counter() - t0
        status = SOLVE_STATUS[st] if 0 <= st < len(SOLVE_STATUS) else "numerical_error"
        if status == "invalid_input":
            return _invalid(n, m, self.message)
        p, mg = self._Aeq.shape[0], self._G.shape[0]
        # NaN where the runtime keeps no point (TSCVX_SETUP_NO_SOLUTION after a numerical error)
        x, y = np.full(n, np.nan), np.full(p, np.nan)
        zg, sg = np.full(mg, np.nan), np.full(mg, np.nan)
        self.lib.tscvx_get_solution(self.ws, _dptr(x), _dptr(y), _dptr(zg), _dptr(sg))
        z, s = np.zeros(m), np.zeros(m)
        z[self.split.eq_rows] = y
        z[self.split.g_rows] = zg
        s[self.split.g_rows] = sg
        if status == "primal_infeasible":
            s[:] = np.nan
        if status == "dual_infeasible":
            z[:] = np.nan
        info = self.info()
        info["message"] = self.lib.tscvx_solve_status_message(st).decode()  # type: ignore[assignment]
        if log:
            info["log"] = self.iteration_log()  # type: ignore[assignment]
        obj = info["pcost"] if status in ("solved", "solved_inaccurate") else float("nan")
        return ConicSolution(
            status=status,
            x=x,
            s=s,
            z=z,
            obj=float(obj),
            # a warm start that failed and was run again cold counts both runs (as the C loop)
            iterations=int(info["iterations"] + info["restart_iterations"]),
            solve_time_s=elapsed,
            info=info,
        )


class Session:
    """A sequence of problems (what SCvx solves): one workspace per sparsity pattern, later
    problems of the same pattern only update the numbers (no new symbolic work)."""

    def __init__(self, **settings: float | int) -> None:
        self._lock = threading.RLock()
        self.settings = settings
        self.solver: Solver | None = None
        self.setups = 0

    @_one_at_a_time
    def solve(self, prob: ConicProblem, warm: ConicSolution | None = None) -> ConicSolution:
        """Solve ``prob``; ``warm``, a solution of a problem of the same size, is where the
        interior-point method starts (Solver.warm_start)."""
        if self.solver is None or not same_pattern(self.solver.prob, prob):
            try:
                self.solver = Solver(prob, **self.settings)
            except InvalidProblemError as err:
                self.solver = None
                return _invalid(prob.n, prob.m, str(err))
            self.setups += 1
        else:
            st = self.solver.update(
                q=prob.q,
                A_values=sp.csc_matrix(prob.A).data,
                b=prob.b,
                P_values=None if prob.P is None else sp.csc_matrix(prob.P).data,
            )
            self.solver.prob = prob
            if st != 0:
                return _invalid(prob.n, prob.m, self.solver.message)
        if warm is not None and warm.ok:
            self.solver.warm_start(warm)
        return self.solver.solve()


def _invalid(n: int, m: int, message: str) -> ConicSolution:
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


def solve(prob: ConicProblem, log: bool = False, **settings: float | int) -> ConicSolution:
    """Solve ``prob`` with the flight runtime. Invalid data give status ``invalid_input`` with
    ``info["message"]``; a missing library raises :class:`LibraryNotBuiltError`."""
    load_library()
    try:
        solver = Solver(prob, **settings)
    except InvalidProblemError as err:
        return _invalid(prob.n, prob.m, str(err))
    return solver.solve(log=log)
