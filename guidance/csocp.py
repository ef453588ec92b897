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

``A_values`` and ``P_values`` are in the caller's value order: ``A.data`` itself for CSC, CSR
and COO (whatever the storage order), ``scipy.sparse.csc_matrix(A).data`` for other formats.
A Solver keeps its own copies of the sizes, pattern and numbers it was set up with.

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
import operator
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import scipy.sparse as sp

from guidance.conic import (
    ConeKind,
    ConicProblem,
    ConicSolution,
    Pattern,
    Status,
    csc_key,
    invalid_solution,
)
from guidance.errors import LibraryNotBuiltError
from guidance.paths import BUILD_DIR

_LIB_ENV = "TSCVX_LIB"
_LIB_DEFAULT = BUILD_DIR / "libtscvx.so"

c_int = ct.c_int
c_double = ct.c_double
P_int = ct.POINTER(ct.c_int)
P_double = ct.POINTER(ct.c_double)


MESSAGE_LEN = 160  # TSCVX_MESSAGE_LEN (tscvx_socp.h)
SETUP_NONFINITE_DATA = 7  # TSCVX_SETUP_NONFINITE_DATA (tscvx_socp.h)
SETUP_NOT_READY = 11  # TSCVX_SETUP_NOT_READY (tscvx_socp.h)
SETUP_P_NOT_PSD = 14  # TSCVX_SETUP_P_NOT_PSD (tscvx_socp.h)


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


_SETTING_FIELDS: list[tuple[str, Any]] = [
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
        "tscvx_check_settings": (c_int, [ct.POINTER(_Settings), ct.c_char_p]),
        "tscvx_solve_status_message": (ct.c_char_p, [c_int]),
        "tscvx_check_workspace": (c_int, [ws_p, ct.c_char_p]),
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
    """The problem data (or a setting) do not describe a valid conic program (message says
    why)."""


# ---- the caller's value order and the canonical pattern ------------------------------------
#
# The values of a sparse matrix are numbered in "the caller's value order": ``M.data`` itself
# for CSC, CSR and COO (entry k of M.data is value k, whatever the storage order), and
# ``scipy.sparse.csc_matrix(M).data`` for any other format (BSR, DIA, LIL, DOK). Set-up takes
# the initial values in that order, and update() takes new ones in it. Inside, every matrix is
# canonical CSC (rows sorted in each column); two stored entries at one position are refused.


@dataclass(frozen=True)
class _Numbered:
    """A sparse matrix's stored entries in canonical CSC, each with the index of its value in
    the caller's value order."""

    shape: tuple[int, int]
    indptr: np.ndarray  # canonical CSC (int32)
    indices: np.ndarray  # canonical CSC (int32)
    order: np.ndarray  # for each canonical entry, its index in the caller's values

    @property
    def nnz(self) -> int:
        return len(self.order)


def _positions(M: sp.spmatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row, column and value of each stored entry of M, in the caller's value order."""
    if M.format == "coo":
        return np.asarray(M.row), np.asarray(M.col), np.asarray(M.data)
    if M.format in ("csc", "csr"):
        major = np.repeat(np.arange(len(M.indptr) - 1), np.diff(M.indptr))
        if M.format == "csc":
            return np.asarray(M.indices), major, np.asarray(M.data)
        return major, np.asarray(M.indices), np.asarray(M.data)
    return _positions(sp.csc_matrix(M))


def _caller_values(M: sp.spmatrix) -> np.ndarray:
    """M's values in the caller's value order (a float copy)."""
    return np.array(_positions(M)[2], dtype=float)


def _numbered(M: Any, name: str) -> _Numbered:
    """M's entries numbered in the caller's value order and placed in canonical CSC; M itself
    is left as it is (nothing is sorted in place)."""
    if not sp.issparse(M):
        raise InvalidProblemError(f"{name} must be a scipy sparse matrix, got {type(M).__name__}")
    rows, cols, _ = _positions(M)
    rows, cols = rows.astype(np.int64), cols.astype(np.int64)
    order = np.lexsort((rows, cols))
    r, c = rows[order], cols[order]
    twice = np.flatnonzero((np.diff(r) == 0) & (np.diff(c) == 0))
    if len(twice):
        at = f"({r[twice[0]]}, {c[twice[0]]})"
        raise InvalidProblemError(
            f"duplicate entries in a sparse matrix ({name} stores {at} twice)"
        )
    indptr = np.searchsorted(c, np.arange(M.shape[1] + 1))
    return _Numbered(tuple(M.shape), indptr.astype(np.int32), r.astype(np.int32), order)


@dataclass(frozen=True)
class _Block:
    """Some rows of A (or all of P) as the C runtime takes them: the canonical CSC pattern and,
    for each entry, the index of its value in the caller's value order."""

    shape: tuple[int, int]
    indptr: np.ndarray
    indices: np.ndarray
    src: np.ndarray

    @staticmethod
    def rows_of(num: _Numbered, rows: np.ndarray) -> _Block:
        index = np.arange(1, num.nnz + 1, dtype=np.int64)  # 1 + canonical index (never 0)
        T = sp.csc_matrix((index, num.indices, num.indptr), num.shape)
        sub = sp.csc_matrix(T[rows, :]) if len(rows) else sp.csc_matrix((0, num.shape[1]))
        sub.sort_indices()
        src = num.order[sub.data.astype(np.int64) - 1]
        return _Block(sub.shape, sub.indptr.astype(np.int32), sub.indices.astype(np.int32), src)

    @staticmethod
    def whole(num: _Numbered) -> _Block:
        return _Block(num.shape, num.indptr, num.indices, num.order)

    def matrix(self, values: np.ndarray) -> sp.csc_matrix:
        """The block with these values (the caller's value order), int32 indices."""
        M = sp.csc_matrix((values[self.src], self.indices.copy(), self.indptr.copy()), self.shape)
        M.indptr = M.indptr.astype(np.int32)
        M.indices = M.indices.astype(np.int32)
        return M


@dataclass
class _Split:
    """How Clarabel's (A, b, cones) maps to the C form (A_eq, b_eq, G, h, l, q)."""

    eq_rows: np.ndarray  # original rows of the zero cones (in order)
    g_rows: np.ndarray  # original rows of G: nonneg rows first, then the SOC rows
    l: int
    soc: np.ndarray  # SOC dimensions
    A: _Numbered  # A's entries
    Aeq: _Block  # the zero-cone rows of A
    G: _Block  # the other rows
    P: _Numbered | None


def _split(prob: ConicProblem) -> _Split:
    n, m = prob.n, prob.m
    A = prob.A
    if not sp.issparse(A) or A.shape != (m, n):
        raise InvalidProblemError(
            f"A must be a sparse {m} x {n} matrix (len(b) x len(q)), got shape {np.shape(A)}"
        )
    eq, nonneg, soc_rows, soc = _cone_rows(prob.cones, m)
    eq_rows = np.array(eq, dtype=np.int64)
    g_rows = np.array(nonneg + soc_rows, dtype=np.int64)
    A_num = _numbered(A, "A")
    P_num = None
    if prob.P is not None:
        if not sp.issparse(prob.P) or prob.P.shape != (n, n):
            raise InvalidProblemError(f"P must be a sparse {n} x {n} matrix")
        P_num = _numbered(prob.P, "P")
    return _Split(
        eq_rows=eq_rows,
        g_rows=g_rows,
        l=len(nonneg),
        soc=np.array(soc, dtype=np.int32),
        A=A_num,
        Aeq=_Block.rows_of(A_num, eq_rows),
        G=_Block.rows_of(A_num, g_rows),
        P=P_num,
    )


def _cone_dim(kind: object, dim: object) -> int:
    """A cone's dimension: a whole number >= 1."""
    try:
        d = int(dim)  # type: ignore[call-overload]
        whole = d == dim
    except (TypeError, ValueError):
        whole = False
    if not whole:
        raise InvalidProblemError(f"cone ({kind}, {dim!r}): dimension must be a whole number")
    if d < 1:
        raise InvalidProblemError(f"cone ({kind}, {d}): dimension must be >= 1")
    return d


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
        dim = _cone_dim(kind, dim)
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


_C_INT_MIN, _C_INT_MAX = -(2**31), 2**31 - 1


def _settings_struct(lib: ct.CDLL, settings: dict[str, float | int]) -> _Settings:
    """The C settings: the defaults with these changes. An unknown name raises TypeError (as
    does a fraction for an integer setting); an integer outside the C int range (which ctypes
    would truncate without a word) raises InvalidProblemError."""
    st = _Settings()
    lib.tscvx_default_settings(ct.byref(st))
    fields = dict(_SETTING_FIELDS)
    for key, val in settings.items():
        if key not in fields:
            raise TypeError(f"unknown setting {key!r}")
        # operator.index refuses a float for an int field (TypeError) instead of truncating it
        if fields[key] is c_int and not _C_INT_MIN <= operator.index(val) <= _C_INT_MAX:  # type: ignore[arg-type]
            raise InvalidProblemError(f"setting {key} = {val} is outside the C int range")
        setattr(st, key, val)
    return st


def _checked_vector(name: str, value: object, length: int) -> np.ndarray:
    """``value`` as a new float vector of exactly ``length`` entries, or InvalidProblemError
    naming the argument."""
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidProblemError(f"{name} must be a vector of {length} numbers ({err})") from err
    if v.shape != (length,):
        raise InvalidProblemError(
            f"{name} must be a vector of length {length}, got an array of shape {v.shape}"
        )
    return v


def _flat(v: object) -> np.ndarray:
    """A problem's q or b as the set-up reads it."""
    return np.asarray(v, dtype=float).reshape(-1)


class Solver:
    """A set-up workspace: one arena, fixed sparsity, repeated solves.

    It keeps its own copies of everything it was set up with (sizes, pattern, numbers): the
    caller may change or reuse its problem object afterwards."""

    def __init__(self, prob: ConicProblem, **settings: float | int):
        self._lock = threading.RLock()
        self.lib = load_library()
        self._settings = _settings_struct(self.lib, settings)
        self._setup_max_iter = int(self._settings.max_iter)
        self.prob = prob  # the caller's object, kept for the caller: never read after set-up
        self.n, self.m = n, m = prob.n, prob.m
        q, b = _flat(prob.q), _flat(prob.b)
        if q.shape[0] != n or b.shape[0] != m:
            raise InvalidProblemError("q and b must be vectors of length n and m")
        self.split = sp_ = _split(prob)
        # canonical CSC structure (sorted rows), values taken in the caller's value order
        a = _caller_values(prob.A)
        self._Aeq, self._G = sp_.Aeq.matrix(a), sp_.G.matrix(a)
        self._P = None if sp_.P is None else _Block.whole(sp_.P).matrix(_caller_values(prob.P))
        self._c = q.copy()
        self._beq = np.ascontiguousarray(b[sp_.eq_rows], dtype=float)
        self._h = np.ascontiguousarray(b[sp_.g_rows], dtype=float)
        self._soc = np.ascontiguousarray(sp_.soc, dtype=np.int32)
        self._data = self._make_data()
        self._set_up()

    def _set_up(self) -> None:
        """The C set-up: arena size, arena, workspace; on failure, not ready with a message."""
        self.ws = ct.c_void_p()
        self.message = self._data_message = "ok"
        self.arena = np.zeros(0, dtype=np.uint8)
        data, settings = ct.byref(self._data), ct.byref(self._settings)
        need = ct.c_size_t(0)
        st = self.lib.tscvx_scratch_size(data, settings, ct.byref(need))
        if st == 0:
            scratch = np.zeros(need.value, dtype=np.uint8)
            scratch_p = scratch.ctypes.data_as(ct.c_void_p)
            st = self.lib.tscvx_workspace_size(
                data, settings, scratch_p, need.value, ct.byref(need)
            )
            del scratch
        if st == 0:
            self.arena = np.zeros(need.value, dtype=np.uint8)
            arena_p = self.arena.ctypes.data_as(ct.c_void_p)
            st = self.lib.tscvx_setup(ct.byref(self.ws), arena_p, need.value, data, settings)
        self.setup_status = int(st)
        if st != 0:
            self.message = self._data_message = self._setup_message(st)
            self.ws = ct.c_void_p()

    def _setup_message(self, st: int) -> str:
        message = self.lib.tscvx_setup_status_message(st).decode()
        detail = ct.create_string_buffer(MESSAGE_LEN)  # the setting, or array and entry, at fault
        if self.lib.tscvx_check_settings(ct.byref(self._settings), detail) == st and detail.value:
            return f"{message}: {detail.value.decode()}"
        if self.lib.tscvx_check_data(ct.byref(self._data), detail) == st and detail.value:
            message += f" ({detail.value.decode()}; in the C runtime's terms: c is q, "
            message += "A and b the zero-cone rows, G and h the other rows)"
        return message

    def _update_message(self, st: int) -> str:
        """Why tscvx_update_data refused: the array and entry at fault, as set-up says it (the
        solver's copies hold every number the workspace would now have), or, for a workspace
        not ready (damaged before or during the update), tscvx_check_workspace's reason."""
        message = self._setup_message(st)
        why = ct.create_string_buffer(MESSAGE_LEN)
        if st == SETUP_NOT_READY and self.lib.tscvx_check_workspace(self.ws, why) and why.value:
            message += f": {why.value.decode()}"
        return message

    def _make_data(self) -> _Data:
        d = _Data()
        d.n, d.p, d.m = self.n, self._Aeq.shape[0], self._G.shape[0]
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

    def _checked_update(
        self, q: object, A_values: object, b: object, P_values: object
    ) -> dict[str, np.ndarray]:
        """The given arrays, each checked against the set-up's sizes (InvalidProblemError
        naming the first one that does not fit)."""
        sizes = {"q": self.n, "A_values": self.split.A.nnz, "b": self.m}
        if self.split.P is not None:
            sizes["P_values"] = self.split.P.nnz
        elif P_values is not None:
            raise InvalidProblemError("P_values given, but the problem was set up without P")
        given = {"q": q, "A_values": A_values, "b": b, "P_values": P_values}
        return {
            name: _checked_vector(name, value, sizes[name])
            for name, value in given.items()
            if value is not None
        }

    @_one_at_a_time
    def update(
        self,
        q: np.ndarray | None = None,
        A_values: np.ndarray | None = None,
        b: np.ndarray | None = None,
        P_values: np.ndarray | None = None,
    ) -> int:
        """New numbers, same sparsity: q and b of lengths n and m, A_values / P_values in the
        caller's value order of the set-up's A / P (``A.data`` for CSC, CSR and COO, else
        ``csc_matrix(A).data``). An array that does not fit raises InvalidProblemError before
        anything changes. Returns the C setup status (0 = ok); ``message`` says why it refused
        (the array and entry at fault, or what tscvx_check_workspace finds). The solver's
        copies then hold what the workspace holds: the numbers sent when it stored them, the
        ones before when it refused them unread (``_workspace_took``)."""
        new = self._checked_update(q, A_values, b, P_values)
        if not self.ready:
            return self.setup_status
        kept = [(a, a.copy()) for a in self._copies_of(new)]
        if "q" in new:
            self._c[:] = new["q"]
        if "A_values" in new:
            self._Aeq.data[:] = new["A_values"][self.split.Aeq.src]
            self._G.data[:] = new["A_values"][self.split.G.src]
        if "b" in new:
            self._beq[:] = new["b"][self.split.eq_rows]
            self._h[:] = new["b"][self.split.g_rows]
        if "P_values" in new and self._P is not None:
            self._P.data[:] = new["P_values"][self.split.P.order]  # type: ignore[union-attr]
        st = self._send(new)
        # the message names the entry at fault in the numbers sent; then the copies go back
        # to what the workspace holds when it took none of them
        self.message = "ok" if st == 0 else self._update_message(st)
        if not self._workspace_took(st):
            for copy, old in kept:
                copy[:] = old
        self._data_message = self.message  # why a solve is refused until the next update
        return st

    def _copies_of(self, new: dict[str, np.ndarray]) -> list[np.ndarray]:
        """The solver's copies that an update with these arrays writes."""
        copies = [self._c] if "q" in new else []
        copies += [self._Aeq.data, self._G.data] if "A_values" in new else []
        copies += [self._beq, self._h] if "b" in new else []
        if "P_values" in new and self._P is not None:
            copies.append(self._P.data)
        return copies

    def _workspace_took(self, st: int) -> bool:
        """Whether tscvx_update_data, returning ``st``, stored the numbers sent (the copies
        hold them). It stores none when it refuses them at its start: a number not finite, a
        P failing the cheap semidefiniteness test (the one tscvx_check_data makes, which the
        copies now holding the numbers sent fail again), or a workspace damaged before the
        call. It stores them when it takes them, when P's factorization refuses P (stored,
        and refused until an update replaces it), and when its end check finds damage done
        during the call."""
        if st == 0:
            return True
        if st == SETUP_P_NOT_PSD:
            return int(self.lib.tscvx_check_data(ct.byref(self._data), None)) != SETUP_P_NOT_PSD
        if st == SETUP_NOT_READY:
            why = ct.create_string_buffer(MESSAGE_LEN)
            self.lib.tscvx_check_workspace(self.ws, why)
            return "during a data update" in why.value.decode()
        return False

    def _send(self, new: dict[str, np.ndarray]) -> int:
        """tscvx_update_data with the arrays that changed (NULL: unchanged)."""
        A, P = "A_values" in new, "P_values" in new
        arrays = (
            self._P.data if P and self._P is not None else None,
            self._c if "q" in new else None,
            self._Aeq.data if A else None,
            self._beq if "b" in new else None,
            self._G.data if A else None,
            self._h if "b" in new else None,
        )
        return int(self.lib.tscvx_update_data(self.ws, *(_dptr(a) for a in arrays)))

    @_one_at_a_time
    def limit_iterations(self, max_iter: int | None) -> int:
        """The next solves' IPM iteration limit: ``max_iter`` (1 to the set-up's limit, which
        fixes the log's size) or, with None, the set-up's (tscvx_update_settings). Returns
        the C setup status (0 = ok)."""
        if not self.ready:
            return self.setup_status
        limit = self._setup_max_iter if max_iter is None else max_iter
        if limit == self._settings.max_iter:
            return 0
        settings = _Settings.from_buffer_copy(self._settings)
        settings.max_iter = limit
        st = int(self.lib.tscvx_update_settings(self.ws, ct.byref(settings)))
        if st == 0:
            self._settings = settings
        else:
            message = self.lib.tscvx_setup_status_message(st).decode()
            self.message = f"{message} (max_iter {limit}: 1 to the set-up's {self._setup_max_iter})"
        return st

    @_one_at_a_time
    def warm_start(self, sol: ConicSolution) -> int:
        """Start the next solve from ``sol`` (Clarabel's form, e.g. the last solve's answer),
        centred into the cones (tscvx_warm_start). Returns the C setup status (0 = ok);
        a solution of another size is refused (-1) and the next solve starts cold."""
        if not self.ready:
            return self.setup_status
        n, m = self.n, self.m
        if sol.x.shape != (n,) or sol.z.shape != (m,) or sol.s.shape != (m,):
            self.lib.tscvx_warm_start(self.ws, None, None, None, None)  # refused: drops any point
            return -1
        x, y, z, s = c_point(self.split, sol)
        return int(self.lib.tscvx_warm_start(self.ws, _dptr(x), _dptr(y), _dptr(z), _dptr(s)))

    @_one_at_a_time
    def check_workspace(self) -> tuple[int, str]:
        """Whether the C calls would take this solver's workspace (tscvx_check_workspace):
        the C setup status (0 = ready, SETUP_NOT_READY = refused) and why ("" when ready):
        no set-up mark, the workspace damaged (its set-up checksum does not match; "during a
        solve" when a solve's end check found it), or the last data update refused. A solver
        whose set-up failed has no workspace: its set-up status and message."""
        if not self.ready:
            return self.setup_status, self.message
        why = ct.create_string_buffer(MESSAGE_LEN)
        st = int(self.lib.tscvx_check_workspace(self.ws, why))
        return st, why.value.decode()

    @_one_at_a_time
    def info(self) -> dict[str, float]:
        inf = _Info()
        if self.ready:
            self.lib.tscvx_get_info(self.ws, ct.byref(inf))
        return {name: float(getattr(inf, name)) for name, *_ in _Info._fields_}

    @_one_at_a_time
    def iteration_log(self) -> list[dict[str, float]]:
        rows: list[dict[str, float]] = []
        if not self.ready:
            return rows
        inf = _Info()
        self.lib.tscvx_get_info(self.ws, ct.byref(inf))
        row = _IterLog()
        for k in range(inf.iterations + 1):
            if self.lib.tscvx_get_iter_log(self.ws, k, ct.byref(row)) != 0:
                break
            rows.append({name: getattr(row, name) for name, *_ in _IterLog._fields_})
        return rows

    @_one_at_a_time
    def solve(self, log: bool = False) -> ConicSolution:
        n, m = self.n, self.m
        if not self.ready:
            return invalid_solution(n, m, self.message)
        t0 = time.perf_counter()
        st = int(self.lib.tscvx_solve(self.ws))
        elapsed = time.perf_counter() - t0
        status = SOLVE_STATUS[st] if 0 <= st < len(SOLVE_STATUS) else "numerical_error"
        if status == "invalid_input":  # a refused update's message, else the workspace's why
            # (not self.message: a refused limit_iterations, which changed nothing, wrote it)
            why = self.check_workspace()[1] if self._data_message == "ok" else ""
            return invalid_solution(n, m, why or self._data_message)
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
        info["message"] = self.lib.tscvx_solve_status_message(st).decode()
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
    problems of the same pattern only update the numbers (no new symbolic work).

    The pattern is compared with a private snapshot of the set-up problem's (sizes, cones,
    canonical CSC pattern of A and P), so the caller may change or reuse its problem objects
    between solves; the new values are passed in the set-up's value order whatever the new
    matrices' format or storage order. A problem whose set-up is refused (e.g. NaN data or an
    indefinite P) gets its invalid_input answer and is not kept: the next problem is set up
    afresh."""

    warm_starts = True

    def __init__(self, **settings: float | int) -> None:
        self._lock = threading.RLock()
        self.settings = settings
        self.solver: Solver | None = None
        self._pattern: Pattern | None = None
        self.setups = 0

    @_one_at_a_time
    def solve(
        self, prob: ConicProblem, warm: ConicSolution | None = None, max_iter: int | None = None
    ) -> ConicSolution:
        """Solve ``prob``; ``warm``, a solution of a problem of the same size, is where the
        interior-point method starts (Solver.warm_start); ``max_iter``, at most the set-up's,
        limits this solve's IPM iterations (None: the set-up's limit)."""
        try:
            refused = self._load(prob)
        except InvalidProblemError as err:
            return invalid_solution(prob.n, prob.m, str(err))
        if refused is not None:
            return refused
        assert self.solver is not None
        if self.solver.limit_iterations(max_iter) != 0:
            return invalid_solution(prob.n, prob.m, self.solver.message)
        if warm is not None and warm.ok:
            self.solver.warm_start(warm)
        return self.solver.solve()

    def _load(self, prob: ConicProblem) -> ConicSolution | None:
        """Put ``prob`` into a workspace: the current one if ``prob`` has its pattern, else a
        new set-up. Returns None, or the answer to a refused problem."""
        A = _numbered(prob.A, "A")
        P = None if prob.P is None else _numbered(prob.P, "P")
        pattern = Pattern.with_keys(prob, csc_key(A), None if P is None else csc_key(P))
        if self.solver is not None and pattern.matches(self._pattern):
            return self._update(self.solver, prob, A, P)
        self.solver, self._pattern = None, None
        solver = Solver(prob, **self.settings)
        if not solver.ready:
            return solver.solve()  # invalid_input with the set-up's message
        self.solver, self._pattern = solver, pattern
        self.setups += 1
        return None

    @staticmethod
    def _update(
        solver: Solver, prob: ConicProblem, A: _Numbered, P: _Numbered | None
    ) -> ConicSolution | None:
        """``prob``'s numbers into ``solver`` (set up for a problem of the same pattern)."""
        split = solver.split
        P_values = None
        if P is not None and split.P is not None:
            P_values = _reordered(_caller_values(prob.P), P, split.P)
        st = solver.update(
            q=_flat(prob.q),
            A_values=_reordered(_caller_values(prob.A), A, split.A),
            b=_flat(prob.b),
            P_values=P_values,
        )
        return None if st == 0 else invalid_solution(prob.n, prob.m, solver.message)


def _reordered(values: np.ndarray, now: _Numbered, setup: _Numbered) -> np.ndarray:
    """Values in the caller's order of one matrix (numbered ``now``) put in the caller's order
    of another of the same canonical pattern (numbered ``setup``)."""
    out = np.empty(setup.nnz)
    out[setup.order] = values[now.order]
    return out


def solve(prob: ConicProblem, log: bool = False, **settings: float | int) -> ConicSolution:
    """Solve ``prob`` with the flight runtime. Invalid data give status ``invalid_input`` with
    ``info["message"]``; a missing library raises :class:`LibraryNotBuiltError`."""
    load_library()
    try:
        solver = Solver(prob, **settings)
    except InvalidProblemError as err:
        return invalid_solution(prob.n, prob.m, str(err))
    return solver.solve(log=log)
