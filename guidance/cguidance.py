"""ctypes bindings to the flight guidance library (c_runtime/include/tscvx_guidance.h).

``solve_c`` runs the WHOLE SCvx / T-SCvx solve in C (guess, discretization, subproblems, SOCP,
penalty, trust region, labelling) and returns the same :class:`guidance.scvx.SCvxResult` as
the Python reference. The workspace (one arena) is set up once per (N, terminal condition,
settings) and reused.

    from guidance.cguidance import solve_c
    res = solve_c(scenario)                       # SCvx
    res = solve_c(scenario, masks=list_of_masks)  # T-SCvx masks (7N entries each)

``solve_tscvx_c`` is the complete on-board T-SCvx call (pdg_solve_tscvx): the networks run in
the C library too (guidance.nn.flight weight blobs, not onnxruntime), the solution network's
prediction is projected onto the boundary conditions and convex path constraints in C (the
same projection as guidance.guess.project_guess), SCvx starts from the reduced radius 0.01 and,
with ``masks=True``, the constraint network gives the mask of every iteration.

    res = solve_tscvx_c(scenario)               # warm start + masks (paper Algorithm 2)
    res = solve_tscvx_c(scenario, masks=False)  # warm start only
"""

from __future__ import annotations

import ctypes as ct
import dataclasses
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from functools import lru_cache
from pathlib import Path
from typing import TypeVar

import numpy as np

# one library (TSCVX_GNC_LIB); its path and error re-exported for the callers that name them here
from guidance.cgnc import LIB_PATH, LibraryNotBuiltError, open_library  # noqa: F401
from guidance.csocp import SOLVE_STATUS
from guidance.errors import InputError, describe
from guidance.guess import checked_guess
from guidance.model import param_vector, pattern_index
from guidance.nn.conventions import (
    CONSTRAINT,
    ONNX_SUFFIX,
    SOLUTION,
    TNN_SUFFIX,
    network_file,
)
from guidance.params import (
    N_MAX,
    N_MIN,
    NC,
    NU,
    NX,
    InitialState,
    Params,
    Scenario,
    SCvxSettings,
)
from guidance.paths import BUILD_DIR
from guidance.scenario import ScenarioError
from guidance.scvx import (
    POLISH_OUTCOMES,
    STATUSES,
    IterationRecord,
    Polish,
    SCvxResult,
    check_masks_argument,
    mask_bits,
    mask_table,
)
from guidance.tscvx import REDUCED_ETA_INIT

MESSAGE_LEN = 256
STATUS_NAMES = (*STATUSES, "invalid_input")  # pdg_status: a solve's ends, then the refusal
PDG_INVALID_INPUT = STATUS_NAMES.index("invalid_input")  # pdg_status (tscvx_guidance.h)
SOCP_STATUS_NAMES = SOLVE_STATUS  # one table of the SOCP runtime's statuses (csocp)

_d = ct.c_double
_i = ct.c_int
_dp = ct.POINTER(ct.c_double)
_ip = ct.POINTER(ct.c_int)
_ucp = ct.POINTER(ct.c_ubyte)


class _Params(ct.Structure):
    _fields_ = [
        ("g_I", _d * 3), ("J_B", _d * 3), ("r_T_B", _d * 3), ("r_cp_B", _d * 3),
        ("alpha_mdot", _d), ("beta_mdot", _d), ("aero_coeff", _d), ("m_dry", _d),
        ("T_min", _d), ("T_max", _d), ("gimbal_max_deg", _d), ("tilt_max_deg", _d),
        ("glideslope_deg", _d), ("omega_max_deg", _d), ("r_f", _d * 3), ("v_f", _d * 3),
        ("q_f", _d * 4), ("omega_f", _d * 3), ("final_roll_free", _i), ("N", _i),
    ]  # fmt: skip


class _Scenario(ct.Structure):
    _fields_ = [("r0", _d * 3), ("v0", _d * 3), ("q0", _d * 4), ("w0", _d * 3), ("m0", _d),
                ("params", _Params)]  # fmt: skip


SETTING_FIELDS = (
    "lam", "rho0", "rho1", "rho2", "alpha", "beta", "eta_init", "eta_lb", "eta_ub",
    "iter_max", "max_subproblems", "step_tol", "cost_tol", "vc_tol", "defect_tol",
    "rk4_substeps",
    "tight_tol", "socp_tol", "socp_max_iter", "socp_max_iter_total", "socp_warm_start",
    "tau_r_update", "prox_u", "polish",
)  # fmt: skip
_INT_SETTINGS = {
    "iter_max", "max_subproblems", "rk4_substeps", "socp_max_iter", "socp_max_iter_total",
    "socp_warm_start", "tau_r_update", "polish",
}  # fmt: skip


class _Settings(ct.Structure):
    _fields_ = [(f, _i if f in _INT_SETTINGS else _d) for f in SETTING_FIELDS]


MASK_FN = ct.CFUNCTYPE(_i, ct.c_void_p, _i, _ucp, _i)
_CLOCK = ct.CFUNCTYPE(ct.c_double)(time.perf_counter)  # subproblem times of the log


class _Options(ct.Structure):
    _fields_ = [
        ("guess_x", _dp), ("guess_u", _dp), ("guess_t_f", _d), ("masks", _ucp),
        ("n_masks", _i), ("mask_fn", MASK_FN), ("mask_ctx", ct.c_void_p),
        ("clock_s", ct.CFUNCTYPE(ct.c_double)),
    ]  # fmt: skip


class _Result(ct.Structure):
    _fields_ = [
        ("status", _i), ("message", ct.c_char * MESSAGE_LEN), ("x", _dp), ("u", _dp),
        ("t_f", _d), ("iterations", _i), ("subproblems_solved", _i), ("max_defect", _d),
        ("max_violation", _d), ("socp_iterations", _i), ("polish", _i),
        ("polish_iterations", _i), ("defect_before_polish", _d), ("m_f_before_polish", _d),
    ]  # fmt: skip


class _TscvxOptions(ct.Structure):
    _fields_ = [("solution", ct.c_void_p), ("constraint", ct.c_void_p), ("eta_init", _d),
                ("clock_s", ct.CFUNCTYPE(ct.c_double))]  # fmt: skip


class _TscvxReport(ct.Structure):
    _fields_ = [("warm_started", _i), ("masks_predicted", _i), ("mask_failures", _i),
                ("eta_init", _d)]  # fmt: skip


class _LogRow(ct.Structure):
    _fields_ = [
        ("k", _i), ("J", _d), ("dJ", _d), ("dL", _d), ("rho", _d), ("eta", _d),
        ("vc_norm1", _d), ("n_tight", _i), ("subproblem_time_s", _d), ("accepted", _i),
        ("solver_status", _i), ("solver_iterations", _i), ("restored", _i),
    ]  # fmt: skip


@lru_cache(maxsize=1)
def library() -> ct.CDLL:
    lib = open_library()
    sz = ct.c_size_t
    lib.pdg_default_settings.argtypes = [ct.POINTER(_Settings)]
    lib.pdg_default_scenario.argtypes = [ct.POINTER(_Scenario)]
    lib.pdg_workspace_size.argtypes = [ct.POINTER(_Params), ct.POINTER(_Settings), ct.c_void_p,
                                       sz, ct.POINTER(sz)]  # fmt: skip
    lib.pdg_setup.argtypes = [ct.POINTER(ct.c_void_p), ct.c_void_p, sz, ct.POINTER(_Params),
                              ct.POINTER(_Settings)]  # fmt: skip
    lib.pdg_solve.argtypes = [ct.c_void_p, ct.POINTER(_Scenario), ct.POINTER(_Options),
                              ct.POINTER(_Result)]  # fmt: skip
    lib.pdg_validate_scenario.argtypes = [ct.POINTER(_Scenario), ct.c_char_p]
    lib.pdg_check_settings.argtypes = [ct.POINTER(_Settings), ct.c_char_p]
    lib.pdg_check_vehicle.argtypes = [ct.POINTER(_Params), ct.c_char_p]
    lib.pdg_get_log.argtypes = [ct.c_void_p, _i, ct.POINTER(_LogRow)]
    lib.pdg_get_mask.argtypes = [ct.c_void_p, _i, _ucp]
    lib.pdg_log_length.argtypes = [ct.c_void_p, ct.POINTER(_i)]
    lib.pdg_arena_high_water.argtypes = [ct.c_void_p, ct.POINTER(sz)]
    lib.pdg_setup_status_message.argtypes = [_i]
    lib.pdg_setup_status_message.restype = ct.c_char_p
    lib.pdg_polish_message.argtypes = [_i]
    lib.pdg_polish_message.restype = ct.c_char_p
    lib.pdg_problem_size.argtypes = [ct.c_void_p, _ip, _ip, _ip, _ip, _ip]
    lib.pdg_debug_assemble.argtypes = [ct.c_void_p, ct.POINTER(_Scenario), _dp, _dp, _d, _d,
                                       _dp, _dp, _dp, _dp, _dp, _ip, _ip, _ip, _ip,
                                       ct.c_char_p]  # fmt: skip
    lib.pdg_debug_guess.argtypes = [ct.c_void_p, ct.POINTER(_Scenario), _dp, _dp, _dp,
                                    ct.c_char_p]  # fmt: skip
    lib.pdg_solve_tscvx.argtypes = [ct.c_void_p, ct.POINTER(_Scenario),
                                    ct.POINTER(_TscvxOptions), ct.POINTER(_Result),
                                    ct.POINTER(_TscvxReport)]  # fmt: skip
    lib.pdg_tscvx_guess.argtypes = [ct.c_void_p, ct.POINTER(_Scenario), ct.c_void_p, _dp, _dp,
                                    _dp, ct.c_char_p]  # fmt: skip
    lib.pdg_theta_of.argtypes = [ct.POINTER(_Scenario), _dp]
    lib.pdg_plan_remainder.argtypes = [ct.POINTER(_Scenario), _dp, _dp, _d, _d, _dp, _dp, _dp,
                                       ct.c_char_p]  # fmt: skip
    lib.pdg_scenario_at_state.argtypes = [ct.POINTER(_Scenario), _dp, ct.POINTER(_Scenario),
                                          ct.c_char_p]  # fmt: skip
    return lib


def _fill(arr: ct.Array, values: Sequence[float] | np.ndarray, field: str) -> None:
    """A fixed-size C array from a sequence of exactly its length (the C library checks the
    numbers themselves; a short or long sequence cannot reach it)."""
    if len(values) != len(arr):
        raise ScenarioError(field, f"expected a list of {len(arr)} numbers, got {list(values)}")
    for i, v in enumerate(values):
        arr[i] = float(v)


def c_params(p: Params) -> _Params:
    cp = _Params()
    for f in dataclasses.fields(Params):
        v = getattr(p, f.name)
        if isinstance(v, tuple | list | np.ndarray):  # a vector (a Params may hold arrays)
            _fill(getattr(cp, f.name), np.asarray(v, dtype=float).reshape(-1), f.name)
        elif f.name in ("final_roll_free", "N"):
            setattr(cp, f.name, int(v))
        else:
            setattr(cp, f.name, float(v))
    return cp


def c_scenario(scenario: Scenario) -> _Scenario:
    s = scenario.initial
    out = _Scenario()
    for name in ("r0", "v0", "q0", "w0"):
        _fill(getattr(out, name), getattr(s, name), name)
    out.m0 = float(s.m0)
    out.params = c_params(scenario.params)
    return out


def c_settings(settings: SCvxSettings | None = None, **socp: float | int) -> _Settings:
    st = _Settings()
    library().pdg_default_settings(ct.byref(st))
    if settings is not None:
        for f in dataclasses.fields(SCvxSettings):
            if f.name in SETTING_FIELDS:
                v = getattr(settings, f.name)
                setattr(st, f.name, int(v) if f.name in _INT_SETTINGS else float(v))
    for k, v in socp.items():
        if k not in SETTING_FIELDS:  # setattr would make a Python attribute, silently unused
            raise TypeError(f"unknown setting {k!r} (the settings are {', '.join(SETTING_FIELDS)})")
        setattr(st, k, v)
    return st


class Workspace:
    """One arena holding the whole guidance workspace for a vehicle (its N, terminal condition
    and A_k pattern, model.vehicle_pattern) and settings."""

    def __init__(self, vehicle: Params, settings: _Settings) -> None:
        lib = library()
        self.lib, self.N, self.settings = lib, vehicle.N, settings
        cv = c_params(vehicle)
        msg = ct.create_string_buffer(MESSAGE_LEN)
        if lib.pdg_check_settings(ct.byref(settings), msg) != 0:
            raise InputError(msg.value.decode())
        if lib.pdg_check_vehicle(ct.byref(cv), msg) != 0:  # the scenario's params, as a solve would
            raise _refusal(msg.value.decode())
        need = ct.c_size_t(0)
        scratch = None
        for _ in range(4):  # bounded: pattern size, then analysis size, then exact size
            buf = (ct.c_char * max(need.value, 1))() if need.value else None
            st = lib.pdg_workspace_size(ct.byref(cv), ct.byref(settings), buf, need.value,
                                        ct.byref(need))  # fmt: skip
            scratch = buf
            if st == 0:
                break
            if st != 4:  # PDG_SETUP_SCRATCH_TOO_SMALL
                raise RuntimeError(lib.pdg_setup_status_message(st).decode())
        del scratch
        self.arena_bytes = need.value
        self.arena = (ct.c_char * self.arena_bytes)()
        self.ws = ct.c_void_p()
        st = lib.pdg_setup(ct.byref(self.ws), self.arena, self.arena_bytes, ct.byref(cv),
                           ct.byref(settings))  # fmt: skip
        if st != 0:
            raise RuntimeError(f"pdg_setup: {lib.pdg_setup_status_message(st).decode()}")

    @property
    def high_water(self) -> int:
        bytes_ = ct.c_size_t()
        _read_ok(self.lib, "pdg_arena_high_water",
                 self.lib.pdg_arena_high_water(self.ws, ct.byref(bytes_)))  # fmt: skip
        return bytes_.value

    def log_length(self) -> int:
        rows = _i()
        _read_ok(self.lib, "pdg_log_length", self.lib.pdg_log_length(self.ws, ct.byref(rows)))
        return rows.value

    def problem_size(self) -> dict[str, int]:
        vals = [_i() for _ in range(5)]
        if self.lib.pdg_problem_size(self.ws, *[ct.byref(v) for v in vals]) != 0:
            raise RuntimeError("pdg_problem_size: the workspace is not set up")
        return dict(zip(("n", "p", "m", "nnz_A", "nnz_G"), [v.value for v in vals], strict=True))


def _read_ok(lib: ct.CDLL, call: str, status: int) -> None:
    """Raises for a record read the library refused (a workspace not set up, a bad index)."""
    if status != 0:
        raise RuntimeError(f"{call}: {lib.pdg_setup_status_message(status).decode()}")


# A guidance workspace or a network is used by one C call at a time, and ctypes releases the
# GIL during the call: each thread keeps its own (solves in threads run in parallel). Each
# thread keeps the CACHE_SIZE last used of each kind: a sweep over settings or model files
# would otherwise keep every workspace (2.5 MB each at N = 50) or network (9 MB) it made.
_PER_THREAD = threading.local()
CACHE_SIZE = 4
_T = TypeVar("_T")


def _thread_cached(kind: str, key: tuple, make: Callable[[], _T]) -> _T:
    """This thread's object of ``kind`` for ``key``, made by ``make`` when not kept."""
    cache = getattr(_PER_THREAD, kind, None)
    if cache is None:
        cache = OrderedDict()
        setattr(_PER_THREAD, kind, cache)
    if key in cache:
        cache.move_to_end(key)
    else:
        cache[key] = make()
        while len(cache) > CACHE_SIZE:
            cache.popitem(last=False)  # callers still holding it keep it alive
    return cache[key]


def workspace(scenario: Scenario, settings: SCvxSettings | None = None,
              **socp: float | int) -> Workspace:  # fmt: skip
    """This thread's workspace for the scenario's vehicle and the settings (made once)."""
    st = c_settings(settings, **socp)
    p = scenario.params
    key = (p.N, p.final_roll_free, pattern_index(param_vector(p)), bytes(st))
    return _thread_cached("workspaces", key, lambda: Workspace(p, st))


def validate_c(scenario: Scenario) -> str | None:
    """The C validation's message for a scenario, or None when it is accepted."""
    msg = ct.create_string_buffer(MESSAGE_LEN)
    bad = library().pdg_validate_scenario(ct.byref(c_scenario(scenario)), msg)
    return msg.value.decode() if bad else None


def _dptr(a: np.ndarray) -> ct._Pointer[ct.c_double]:
    return a.ctypes.data_as(_dp)


def _refusal(message: str) -> InputError:
    """The C library's refusal as the Python reference raises it: a ScenarioError naming the
    field when the message names one ("scenario field 'X': why")."""
    if message.startswith("scenario field '"):
        return ScenarioError(message.split("'")[1], message.split("': ", 1)[1])
    return InputError(message)


def _result_buffers(N: int) -> tuple[np.ndarray, np.ndarray, _Result]:
    """x, u and the pdg_result that points at them. NaN stays where the solve stops before
    its first subproblem: C then leaves x, u untouched (and t_f NaN)."""
    x, u = np.full((N, NX), np.nan), np.full((N, NU), np.nan)
    res = _Result()
    res.x, res.u = _dptr(x), _dptr(u)
    return x, u, res


def solve_c(
    scenario: Scenario,
    settings: SCvxSettings | None = None,
    guess: tuple[np.ndarray, np.ndarray, float] | None = None,
    masks: Callable[[int], np.ndarray | None] | Sequence[np.ndarray] | None = None,
    **socp: float | int,
) -> SCvxResult:
    """The whole SCvx / T-SCvx solve in the C library. Bad input raises ScenarioError (the
    C validation's message, naming the field) like the Python reference. Masks hold 0/1 bits
    only (guidance.scvx.mask_bits: probabilities are refused, not read nonzero = keep)."""
    lib = library()
    N = scenario.params.N
    if not N_MIN <= N <= N_MAX:
        raise ScenarioError("N", f"must lie in [{N_MIN}, {N_MAX}], got {N}")
    check_masks_argument(masks)  # True or a number: refused by name, before the solve
    ran_with = _ran_with(settings, socp)  # a bad setting refused before the solve
    ws = workspace(scenario, settings, **socp)
    cs = c_scenario(scenario)
    opt = _Options()
    keep: list[object] = []  # what opt points at, alive until the call returns
    if guess is not None:
        keep += _point_at_guess(opt, guess, N)
    callback_errors: list[BaseException] = []
    if masks is not None:
        keep.append(_point_at_masks(opt, masks, N, callback_errors))
    opt.clock_s = _CLOCK
    x, u, res = _result_buffers(N)
    t_start = time.perf_counter()  # the guidance call only (set-up is a one-time init)
    status = lib.pdg_solve(ws.ws, ct.byref(cs), ct.byref(opt), ct.byref(res))
    solve_time = time.perf_counter() - t_start
    if callback_errors:  # the callback's own exception; one of ours as itself
        raise _callback_error(callback_errors[0])
    return _collect(ws, status, res, x, u, solve_time, ran_with)


def _point_at_guess(
    opt: _Options, guess: tuple[np.ndarray, np.ndarray, float], N: int
) -> list[np.ndarray]:
    """Points opt at the guess; returns the arrays it points at."""
    x, u, t_f = checked_guess(guess, N)  # the Python loop's check
    gx, gu = np.ascontiguousarray(x), np.ascontiguousarray(u)
    opt.guess_x, opt.guess_u, opt.guess_t_f = _dptr(gx), _dptr(gu), t_f
    return [gx, gu]


def _point_at_masks(
    opt: _Options,
    masks: Callable[[int], np.ndarray | None] | Sequence[np.ndarray],
    N: int,
    errors: list[BaseException],
) -> object:
    """Points opt at the masks, a callback (its exceptions collected in ``errors``) or a table
    of rows of 7N; returns what it points at."""
    if callable(masks):
        cb = _mask_callback(masks, N, errors)
        opt.mask_fn = cb
        return cb
    table = np.ascontiguousarray(np.stack(mask_table(masks, N)), dtype=np.uint8)
    opt.masks = table.ctypes.data_as(_ucp)
    opt.n_masks = len(table)
    return table


def _callback_error(exc: BaseException) -> BaseException:
    """What solve_c raises for an exception inside the mask callback: an InputError, Ctrl-C
    or an exit as it is; any other exception as an InputError with its message (the C loop
    stopped on it)."""
    if isinstance(exc, InputError) or not isinstance(exc, Exception):
        return exc
    return InputError(str(exc) or type(exc).__name__)


def _mask_callback(
    fn: Callable[[int], np.ndarray | None], N: int, errors: list[BaseException]
) -> object:
    """fn as the C library's mask callback: None answers 0 (the full problem), a mask 1."""

    def _cb(ctx, k, out, n):
        # An exception cannot cross the C call: ctypes would print and drop it, and hand C an
        # undefined answer. Any one (Ctrl-C too) is kept and -1 answered, which stops the
        # solve; solve_c raises it after the call.
        try:
            m = fn(int(k))
            if m is None:
                return 0
            bits = np.ascontiguousarray(mask_bits(m, N, int(k)), np.uint8)
            ct.memmove(out, bits.ctypes.data, n)
            return 1
        except BaseException as exc:
            errors.append(exc)
            return -1

    return MASK_FN(_cb)


def _ran_with(settings: SCvxSettings | None, socp: dict[str, float | int]) -> SCvxSettings:
    """The SCvxSettings of a C call: the given ones with any per-call override of a field,
    and the discretization that runs (the C loop's generated C, whatever the setting)."""
    names = {f.name for f in dataclasses.fields(SCvxSettings)}
    ran = {k: v for k, v in socp.items() if k in names} | {"discretization": "c"}
    return (settings or SCvxSettings()).replace(**ran)


def _collect(
    ws: Workspace,
    status: int,
    res: _Result,
    x: np.ndarray,
    u: np.ndarray,
    solve_time: float,
    settings: SCvxSettings,
) -> SCvxResult:
    """The SCvxResult of a finished C call (log and masks read from the workspace)."""
    lib = ws.lib
    N = ws.N
    message = res.message.decode()
    if status == PDG_INVALID_INPUT:
        raise _refusal(message)
    history = []
    row = _LogRow()
    for i in range(ws.log_length()):
        _read_ok(lib, "pdg_get_log", lib.pdg_get_log(ws.ws, i, ct.byref(row)))
        history.append(
            IterationRecord(
                row.k,
                row.J,
                row.dJ,
                row.dL,
                row.rho,
                row.eta,
                row.vc_norm1,
                row.n_tight,
                row.subproblem_time_s,
                bool(row.accepted),
                SOCP_STATUS_NAMES[row.solver_status]
                if 0 <= row.solver_status < len(SOCP_STATUS_NAMES)
                else "numerical_error",
                row.solver_iterations,
                row.restored,
            )
        )
    mask_log = np.zeros((res.iterations, NC * N), np.uint8)
    for k in range(res.iterations):
        _read_ok(lib, "pdg_get_mask", lib.pdg_get_mask(ws.ws, k, mask_log[k].ctypes.data_as(_ucp)))
    return SCvxResult(
        status=STATUS_NAMES[status],
        reason=message,
        x=x,
        u=u,
        t_f=float(res.t_f),
        iterations=int(res.iterations),
        subproblems_solved=int(res.subproblems_solved),
        solve_time_s=solve_time,
        history=history,
        masks=mask_log,
        max_defect=float(res.max_defect),
        max_violation=float(res.max_violation),
        settings=settings,
        polish=Polish(
            POLISH_OUTCOMES[res.polish],
            int(res.polish_iterations),
            float(res.defect_before_polish),
            float(res.m_f_before_polish),
        ),
    )


# ---- T-SCvx on board (pdg_solve_tscvx) -----------------------------------------------------

BUILD_MODELS_DIR = BUILD_DIR / "models"  # `make lib`'s .tnn
NET_KINDS = (SOLUTION, CONSTRAINT)  # the C call's order: the warm start's, then the masks'


class FlightNetsError(InputError):
    """The C library refused the networks for this problem; the message says why."""


class FlightStatusError(RuntimeError):
    """A C call that returns no SCvxResult (tscvx_guess_c, c_assemble) ended in a status that
    is not a refusal, e.g. PDG_SOLVER_ERROR for a solution network whose prediction is not
    finite, or a model not finite at the iterate c_assemble was given: ``status`` its name
    as SCvxResult.status gives it ("solver_error"), ``reason`` (and the message) the
    library's, as SCvxResult.reason."""

    def __init__(self, status: str, reason: str) -> None:
        super().__init__(f"{status}: {reason}")
        self.status, self.reason = status, reason


def _status_error(status: int, message: str) -> FlightStatusError:
    """The FlightStatusError of a pdg_status that is not a refusal, with the library's reason."""
    name = STATUS_NAMES[status] if 0 < status < len(STATUS_NAMES) else str(status)
    return FlightStatusError(name, message)


def net_source(models_dir: Path, kind: str) -> Path:
    """``{kind}.tnn`` in the folder, else ``{kind}.onnx`` (converted to the flight blob)."""
    names = [network_file(kind, suffix) for suffix in (TNN_SUFFIX, ONNX_SUFFIX)]
    for name in names:
        path = Path(models_dir) / name
        if path.is_file():
            return path
    raise FlightNetsError(f"no {' or '.join(names)} in {models_dir} (run `make lib`)")


def flight_net(models_dir: Path | str, kind: str):
    """One network of ``models_dir`` loaded in the C library (guidance.nn.flight.FlightNet),
    cached (per thread) by file and modification time. An ONNX file is converted to the flight
    blob (guidance.nn.flight.tnn_bytes: the bytes `make lib` writes to build/models)."""
    from guidance.nn.flight import FlightNet, FlightNetError, tnn_bytes

    path = net_source(Path(models_dir), kind)
    stat = path.stat()
    key = (str(path.resolve()), stat.st_mtime_ns, stat.st_size)

    def load() -> FlightNet:
        try:
            blob = tnn_bytes(path) if path.suffix == ONNX_SUFFIX else path.read_bytes()
        except OSError as exc:  # the CLI prints an InputError; an OSError was a traceback
            raise FlightNetsError(f"model {path}: cannot read it ({exc.strerror or exc})") from None
        except InputError as exc:  # an ONNX file unreadable or not a T-SCvx export
            raise FlightNetsError(f"model {path}: {exc}") from exc
        try:
            return FlightNet(blob)
        except FlightNetError as exc:
            raise FlightNetsError(f"model {path}: refused by the C library: {exc}") from exc

    return _thread_cached("nets", key, load)


_TRAINED: dict[tuple, dict] = {}


def check_trained_params(models_dir: Path | str, kind: str, params: Params) -> None:
    """For an ONNX source, the checks of guidance.nn.infer: the grid (N) the model was trained
    on, then every other problem parameter that is not a network input, named in the ONNX
    file's terms. (The C library checks the same against the values the .tnn blob records,
    for .tnn files and converted ONNX alike; this names them before the conversion.)"""
    import json

    from guidance.nn.infer import META_KEY, _params_diff, grid_mismatch

    path = net_source(Path(models_dir), kind)
    if path.suffix != ONNX_SUFFIX:
        return
    stat = path.stat()
    key = (str(path.resolve()), stat.st_mtime_ns, stat.st_size)
    if key not in _TRAINED:
        from guidance.nn.flight import load_onnx

        props = {p.key: p.value for p in load_onnx(path, load_external_data=False).metadata_props}
        if META_KEY not in props:  # an empty file parses as an empty model
            raise FlightNetsError(f"model {path}: not a T-SCvx model export (no metadata)")
        try:
            _TRAINED[key] = dict(json.loads(props[META_KEY]))
        except (json.JSONDecodeError, TypeError, ValueError) as exc:
            raise FlightNetsError(
                f"model {path}: its '{META_KEY}' metadata is unreadable ({exc})"
            ) from None
    grid = grid_mismatch(kind, _TRAINED[key].get("N"), params.N)
    if grid:
        raise FlightNetsError(f"model {path}: {grid}")
    diff = _params_diff(_TRAINED[key].get("params", {}), params)
    if diff:
        raise FlightNetsError(
            f"model {path}: trained for other problem parameters: " + "; ".join(diff)
        )


@contextmanager
def _holding(*nets: object) -> Iterator[None]:
    """The locks of the given FlightNets, always in this order; None and a network given
    twice (one network in both roles) skipped."""
    with ExitStack() as stack:
        held: list[object] = []
        for net in nets:
            if net is not None and all(net is not h for h in held):
                stack.enter_context(net.lock)  # type: ignore[attr-defined]
                held.append(net)
        yield


def _nets(models_dir: Path | str | None, masks: bool, params: Params | None = None) -> tuple:
    d = Path(models_dir) if models_dir is not None else BUILD_MODELS_DIR
    kinds = NET_KINDS if masks else NET_KINDS[:1]
    if params is not None:
        for kind in kinds:
            check_trained_params(d, kind, params)
    nets = tuple(flight_net(d, kind) if kind in kinds else None for kind in NET_KINDS)
    if params is not None:  # a .tnn's grid, named by its file
        for kind, net in zip(NET_KINDS, nets, strict=True):
            _check_grid(f"model {net_source(d, kind)}", kind, net, params.N)
    return nets


def _check_grid(where: str, kind: str, net: object, N: int) -> None:
    """A FlightNet (or None) trained on the problem's grid, refused in the words of
    guidance.nn.infer.grid_mismatch (onnxruntime's refusal too), before the C library's
    own check of the same."""
    from guidance.nn.infer import grid_mismatch

    grid = None if net is None else grid_mismatch(kind, net.info.N, N)  # type: ignore[attr-defined]
    if grid:
        raise FlightNetsError(f"{where}: {grid}")


def solve_tscvx_c(
    scenario: Scenario,
    settings: SCvxSettings | None = None,
    models_dir: Path | str | None = None,
    masks: bool = True,
    eta_init: float = REDUCED_ETA_INIT,
    nets: tuple | None = None,
    **socp: float | int,
) -> SCvxResult:
    """The complete on-board T-SCvx call (pdg_solve_tscvx): both networks, the projection of
    the prediction and the SCvx loop all in C. ``models_dir`` holds {solution,constraint}.tnn
    or .onnx (default build/models); ``nets`` = (solution, constraint or None) FlightNets
    instead. ``masks=False``: warm start only. Networks of the wrong kind or size raise
    FlightNetsError with the C library's message; bad scenarios raise ScenarioError."""
    lib = library()
    N = scenario.params.N
    if not N_MIN <= N <= N_MAX:
        raise ScenarioError("N", f"must lie in [{N_MIN}, {N_MAX}], got {N}")
    _check_tscvx_arguments(masks, nets)
    ran_with = _ran_with(settings, socp)  # a bad setting refused before the solve
    if nets is not None:
        for kind, net in zip(NET_KINDS, nets, strict=True):
            _check_grid("nets", kind, net if kind == SOLUTION or masks else None, N)
    sol, con = nets if nets is not None else _nets(models_dir, masks, scenario.params)
    ws = workspace(scenario, settings, **socp)
    cs = c_scenario(scenario)
    opt = _TscvxOptions()
    opt.solution = sol._net if sol is not None else None
    opt.constraint = con._net if (con is not None and masks) else None
    opt.eta_init = float(eta_init)
    opt.clock_s = _CLOCK
    x, u, res = _result_buffers(N)
    rep = _TscvxReport()
    with _holding(sol, con if masks else None):  # the call runs them: no other user meanwhile
        t_start = time.perf_counter()  # the whole guidance call, network inference included
        status = lib.pdg_solve_tscvx(ws.ws, ct.byref(cs), ct.byref(opt), ct.byref(res),
                                     ct.byref(rep))  # fmt: skip
        solve_time = time.perf_counter() - t_start
    if status == PDG_INVALID_INPUT and res.message.startswith(b"nets: "):
        raise FlightNetsError(res.message.decode())
    if rep.eta_init > 0:  # 0: no solve started (a refusal, or the warm start's inference failed)
        ran_with = ran_with.replace(eta_init=float(rep.eta_init))
    out = _collect(ws, status, res, x, u, solve_time, ran_with)
    out.tscvx_report = {  # type: ignore[attr-defined]
        "warm_started": bool(rep.warm_started),
        "masks_predicted": int(rep.masks_predicted),
        "mask_failures": int(rep.mask_failures),
        "eta_init": float(rep.eta_init),
    }
    return out


def _check_tscvx_arguments(masks: object, nets: object) -> None:
    """masks is a bool here (the constraint network's masks or none): a table or function
    of masks would be truthy and silently replaced by the network's, an array ambiguous.
    nets is None or a pair of FlightNets (None allowed), not file names."""
    if not isinstance(masks, (bool, np.bool_)):
        raise InputError(
            "masks: True (the constraint network's masks) or False (warm start only), got "
            f"{type(masks).__name__}; masks of your own go to solve_c(..., masks=...)"
        )
    if nets is None:
        return
    if not isinstance(nets, (tuple, list)) or len(nets) != 2:
        raise InputError(f"nets: expected (solution, constraint) FlightNets, got {describe(nets)}")
    for role, net in zip(NET_KINDS, nets, strict=True):
        _check_net(f"nets: the {role} network", net)


def _check_net(what: str, net: object) -> None:
    """A FlightNet or None (a path or a blob is loaded with flight_net / FlightNet first)."""
    from guidance.nn.flight import FlightNet

    if net is not None and not isinstance(net, FlightNet):
        raise InputError(f"{what}: expected a FlightNet or None, got {describe(net)}")


def tscvx_guess_c(
    scenario: Scenario, models_dir: Path | str | None = None, net=None
) -> tuple[np.ndarray, np.ndarray, float]:
    """The projected warm start computed on board (pdg_tscvx_guess). A refusal raises
    FlightNetsError (the networks) or InputError (a ScenarioError naming the field, as
    solve_tscvx_c's); a failed inference (PDG_SOLVER_ERROR)
    FlightStatusError with status "solver_error" and the library's reason."""
    N = scenario.params.N
    if not N_MIN <= N <= N_MAX:  # as solve_tscvx_c: the range before any network's grid
        raise ScenarioError("N", f"must lie in [{N_MIN}, {N_MAX}], got {N}")
    _check_net("net", net)
    _check_grid("net", SOLUTION, net, N)
    sol = net if net is not None else _nets(models_dir, False, scenario.params)[0]
    ws = workspace(scenario)
    x, u, tf = np.zeros((N, NX)), np.zeros((N, NU)), ct.c_double(0.0)
    msg = ct.create_string_buffer(MESSAGE_LEN)
    with _holding(sol):
        st = library().pdg_tscvx_guess(ws.ws, ct.byref(c_scenario(scenario)), sol._net,
                                       _dptr(x), _dptr(u), ct.byref(tf), msg)  # fmt: skip
    text = msg.value.decode()
    if st == PDG_INVALID_INPUT:  # a bad scenario as every C call raises it: the field named
        raise FlightNetsError(text) if text.startswith("nets: ") else _refusal(text)
    if st != 0:
        raise _status_error(st, text)
    return x, u, tf.value


def plan_remainder_c(
    scenario: Scenario, x: np.ndarray, u: np.ndarray, t_f: float, t1: float
) -> tuple[np.ndarray, np.ndarray, float]:
    """The remainder of a plan from t1 as the scenario's guess, on board (pdg_plan_remainder;
    guidance.guess.plan_remainder in Python). InputError with the library's message."""
    N = scenario.params.N
    xx = np.ascontiguousarray(x, dtype=float)
    uu = np.ascontiguousarray(u, dtype=float)
    if xx.shape != (N, NX) or uu.shape != (N, NU):
        raise InputError(f"plan remainder: x, u must be {N} x {NX} and {N} x {NU}")
    gx, gu, tf = np.zeros((N, NX)), np.zeros((N, NU)), ct.c_double(0.0)
    msg = ct.create_string_buffer(MESSAGE_LEN)
    st = library().pdg_plan_remainder(ct.byref(c_scenario(scenario)), _dptr(xx), _dptr(uu),
                                      float(t_f), float(t1), _dptr(gx), _dptr(gu),
                                      ct.byref(tf), msg)  # fmt: skip
    if st != 0:
        raise InputError(msg.value.decode())
    return gx, gu, tf.value


def scenario_at_state_c(x: np.ndarray, scenario: Scenario) -> Scenario:
    """The landing from state x with the scenario's vehicle and targets, on board
    (pdg_scenario_at_state; guidance.closed_loop.state_scenario in Python). InputError (a
    ScenarioError naming the field) with the library's message."""
    xx = np.ascontiguousarray(x, dtype=float)
    if xx.shape != (NX,):
        raise InputError(f"scenario at state: x must hold {NX} numbers, not shape {xx.shape}")
    out, msg = _Scenario(), ct.create_string_buffer(MESSAGE_LEN)
    if library().pdg_scenario_at_state(ct.byref(c_scenario(scenario)), _dptr(xx),
                                       ct.byref(out), msg) != 0:  # fmt: skip
        raise _refusal(msg.value.decode())
    init = InitialState(r0=tuple(out.r0), v0=tuple(out.v0), q0=tuple(out.q0), w0=tuple(out.w0),
                        m0=out.m0)  # fmt: skip
    return Scenario(init, scenario.params)


def theta_c(scenario: Scenario) -> np.ndarray:
    """pdg_theta_of (for tests against guidance.sampling.theta_of)."""
    out = np.zeros(16)
    library().pdg_theta_of(ct.byref(c_scenario(scenario)), _dptr(out))
    return out


def _debug_call_error(status: int, message: str) -> InputError | FlightStatusError:
    """A test hook's failure as the solves' calls raise it: a refusal (PDG_INVALID_INPUT) an
    InputError (a ScenarioError naming the field), any other status a FlightStatusError;
    both with the library's message."""
    if status == PDG_INVALID_INPUT:
        return _refusal(message)
    return _status_error(status, message)


def c_guess(scenario: Scenario) -> tuple[np.ndarray, np.ndarray, float]:
    """The C initial guess (for tests against guidance.guess.initial_guess). A refusal raises
    InputError with the library's message."""
    ws = workspace(scenario)
    N = scenario.params.N
    x, u, tf = np.zeros((N, NX)), np.zeros((N, NU)), ct.c_double(0.0)
    msg = ct.create_string_buffer(MESSAGE_LEN)
    st = library().pdg_debug_guess(ws.ws, ct.byref(c_scenario(scenario)), _dptr(x), _dptr(u),
                                   ct.byref(tf), msg)  # fmt: skip
    if st != 0:
        raise _debug_call_error(st, msg.value.decode())
    return x, u, tf.value


def c_assemble(scenario: Scenario, x: np.ndarray, u: np.ndarray, t_f: float,
               eta: float) -> dict[str, np.ndarray]:  # fmt: skip
    """The C subproblem about (x, u, t_f), scaling with Ss = t_f (for tests). A refusal (x or
    u not finite, t_f or eta not finite and > 0) raises InputError, a failed assembly (the
    model not finite at the iterate: PDG_SOLVER_ERROR) FlightStatusError "solver_error", both
    with the library's message."""
    import scipy.sparse as sp

    ws = workspace(scenario)
    size = ws.problem_size()
    n, p, m, na, ng = (size[k] for k in ("n", "p", "m", "nnz_A", "nnz_G"))
    c, Ax, b, Gx, h = np.zeros(n), np.zeros(na), np.zeros(p), np.zeros(ng), np.zeros(m)
    Ap, Ai = np.zeros(n + 1, np.int32), np.zeros(na, np.int32)
    Gp, Gi = np.zeros(n + 1, np.int32), np.zeros(ng, np.int32)
    xx = np.ascontiguousarray(x, dtype=float)
    uu = np.ascontiguousarray(u, dtype=float)
    if xx.shape != (scenario.params.N, NX) or uu.shape != (scenario.params.N, NU):
        # the C call reads N x 14 and N x 3 numbers whatever it is given
        raise InputError(f"assemble: x, u must be {scenario.params.N} x {NX} and "
                         f"{scenario.params.N} x {NU}")  # fmt: skip
    msg = ct.create_string_buffer(MESSAGE_LEN)
    st = library().pdg_debug_assemble(
        ws.ws, ct.byref(c_scenario(scenario)), _dptr(xx), _dptr(uu), float(t_f), float(eta),
        _dptr(c), _dptr(Ax), _dptr(b), _dptr(Gx), _dptr(h), Ap.ctypes.data_as(_ip),
        Ai.ctypes.data_as(_ip), Gp.ctypes.data_as(_ip), Gi.ctypes.data_as(_ip), msg,
    )  # fmt: skip
    if st != 0:
        raise _debug_call_error(st, msg.value.decode())
    return {
        "c": c,
        "A": sp.csc_matrix((Ax, Ai, Ap), shape=(p, n)),
        "b": b,
        "G": sp.csc_matrix((Gx, Gi, Gp), shape=(m, n)),
        "h": h,
    }
