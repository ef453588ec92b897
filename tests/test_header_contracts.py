"""The public C headers as a flight-software team reads them: every settings and vehicle field
documents its range (and a vehicle field its unit), the check functions enforce exactly the
documented range (the bound itself as documented, just beyond it refused with a message
naming the field), and a status is returned for the conditions its enum comment names.

The reference is the header text itself (c_runtime/include/*.h): each test reads the comment
of a field or status and probes the C library at the bounds the comment states."""

from __future__ import annotations

import ctypes
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from c_library import nan_output_net

from guidance import cguidance, csocp
from guidance.params import NU, NX, Scenario

INCLUDE = Path(__file__).resolve().parents[1] / "c_runtime" / "include"
SOCP_H = (INCLUDE / "tscvx_socp.h").read_text()
GUIDANCE_H = (INCLUDE / "tscvx_guidance.h").read_text()


def struct_comments(header: str, name: str) -> dict[str, str]:
    """Each field of ``typedef struct {...} name;`` with its comment: the one after it on
    its line, else the one on the lines just before it ("" without either)."""
    end = header.index(f"}} {name};")
    body = header[header.rindex("typedef struct {", 0, end) + len("typedef struct {") : end]
    out: dict[str, str] = {}
    pending, last, last_end = "", [], 0
    for m in re.finditer(r"/\*.*?\*/|[^;/]+;", body, re.S):
        text = m.group(0)
        if text.startswith("/*"):
            comment = " ".join(text[2:-2].replace("*", " ").split())
            if last and "\n" not in body[last_end : m.start()]:
                for f in last:
                    out[f] = comment  # trailing: the declaration's own
            else:
                pending = comment
            continue
        decl = " ".join(text[:-1].split())
        names = [re.sub(r"\[.*?\]", "", n).strip().lstrip("*") for n in decl.split(",")]
        names[0] = names[0].split()[-1]
        last, last_end = names, m.end()
        for f in names:
            out[f] = pending
        pending = ""
    return out


def enum_comments(header: str, name: str) -> dict[str, str]:
    """Each enumerator of ``typedef enum {...} name;`` with its comment."""
    end = header.index(f"}} {name};")
    body = header[header.rindex("typedef enum {", 0, end) : end]
    return {
        m.group(1): " ".join(m.group(2).replace("*", " ").split())
        for m in re.finditer(r"(\w+)(?: = \d+)?,\s*/\*(.*?)\*/", body, re.S)
    }


# ---- settings: the documented range, enforced at its bounds ---------------------------------


@dataclass(frozen=True)
class Bound:
    """One end of a documented range: ``value`` accepted (closed) or refused (open); just
    beyond it refused, naming ``named`` (the field itself by default)."""

    value: float
    closed: bool
    named: str = ""


@dataclass(frozen=True)
class Documented:
    """What the header says of a field (``texts`` all in its comment) and its bounds."""

    texts: tuple[str, ...]
    lo: Bound | None = None
    hi: Bound | None = None
    integer: bool = False
    also: dict[str, float] = field(default_factory=dict)  # other fields set for the probes


def _open(v: float) -> Bound:
    return Bound(v, False)


def _closed(v: float, named: str = "") -> Bound:
    return Bound(v, True, named)


UNIT = (_open(0.0), _open(1.0))
SOCP_SETTINGS: dict[str, Documented] = {
    "max_iter": Documented(("1..500",), _closed(1), _closed(500), integer=True),
    **{
        t: Documented(("(0, 1)",), *UNIT)
        for t in ("tol_gap_abs", "tol_gap_rel", "tol_feas", "tol_infeas")
    },
    **{
        t: Documented(("> 0",), _open(0.0))
        for t in ("tol_gap_abs_inacc", "tol_gap_rel_inacc", "tol_feas_inacc")
    },
    "step_fraction": Documented(("(0, 1)",), *UNIT),
    "static_reg": Documented(("(0, 1)",), *UNIT),
    "refine_iters": Documented(("0..20",), _closed(0), _closed(20), integer=True),
    "ruiz_iters": Documented(("0..50",), _closed(0), _closed(50), integer=True),
    "soc_dense_max": Documented((">= 1",), _closed(1), integer=True),
    "kkt_backend": Documented(
        ("TSCVX_KKT_AUTO", "TSCVX_KKT_BANDED", "TSCVX_KKT_STATIC", "TSCVX_KKT_LDL"),
        _closed(0),
        _closed(3),
        integer=True,
    ),
}

LAM_MAX, ALPHA_MIN, PROX_U_MAX = 1e8, 1.1, 0.03
INT_RANGE: dict[str, tuple[int, int, str]] = {
    "iter_max": (1, 100, "1..100"),
    "max_subproblems": (1, 500, "1..500"),
    "rk4_substeps": (1, 64, "1..64"),
    "socp_max_iter": (1, 500, "1..500"),
    "socp_max_iter_total": (1, 500000, "1..500000"),
    "socp_warm_start": (0, 1, "(0 or 1)"),
    "tau_r_update": (0, 1, "(0 or 1)"),
    "polish": (0, 1, "0 or 1"),
}
PDG_SETTINGS: dict[str, Documented] = {
    **{
        n: Documented((text,), _closed(lo), _closed(hi), integer=True)
        for n, (lo, hi, text) in INT_RANGE.items()
    },
    "lam": Documented(("(0, PDG_LAM_MAX]",), _open(0.0), _closed(LAM_MAX)),
    # the thresholds' chain: each probed against its neighbours' defaults (0, 0.1, 0.7)
    "rho0": Documented(("0 <= rho0 <= rho1 <= rho2",), _closed(0.0)),
    "rho1": Documented(("0 <= rho0 <= rho1 <= rho2",), _closed(0.0), _closed(0.7, "rho2")),
    "rho2": Documented(("0 <= rho0 <= rho1 <= rho2",), _closed(0.1)),
    "alpha": Documented((">= PDG_ALPHA_MIN",), _closed(ALPHA_MIN)),
    "beta": Documented((">= 1",), _closed(1.0)),
    # the radii's chain against the defaults eta_lb = 0.001, eta_ub = 10
    "eta_init": Documented(("[eta_lb, eta_ub]",), _closed(0.001), _closed(10.0)),
    "eta_lb": Documented(("0 < eta_lb <= eta_ub",), _open(0.0)),
    "eta_ub": Documented(("0 < eta_lb <= eta_ub",), _closed(0.001), also={"eta_init": 0.001}),
    **{
        t: Documented((">= 0",), _closed(0.0))
        for t in ("step_tol", "cost_tol", "vc_tol", "defect_tol", "tight_tol")
    },
    "socp_tol": Documented(("(0, 1)",), *UNIT),
    "prox_u": Documented(("w >= 0", "at most PDG_PROX_U_MAX"), _closed(0.0), _closed(PROX_U_MAX)),
}


def _beyond(b: Bound, integer: bool, down: bool) -> list[tuple[float, bool]]:
    """(value, accepted) at a bound: the bound itself, and the next value beyond it."""
    step = -1 if down else 1
    if integer:
        return [(b.value, True), (b.value + step, False)]
    toward = -math.inf if down else math.inf
    inside = [] if b.closed else [(math.nextafter(b.value, -toward), True)]
    return [(b.value, b.closed), (math.nextafter(b.value, toward), False), *inside]


def _probes(doc: Documented) -> list[tuple[float, bool, str]]:
    out = []
    for b, down in ((doc.lo, True), (doc.hi, False)):
        if b is not None:
            out += [(v, ok, b.named) for v, ok in _beyond(b, doc.integer, down)]
    return out


def _check_socp(values: dict[str, float]) -> tuple[int, str]:
    lib = csocp.load_library()
    st = csocp._Settings()
    lib.tscvx_default_settings(ctypes.byref(st))
    for k, v in values.items():
        setattr(st, k, int(v) if dict(csocp._SETTING_FIELDS)[k] is ctypes.c_int else v)
    msg = ctypes.create_string_buffer(csocp.MESSAGE_LEN)
    return lib.tscvx_check_settings(ctypes.byref(st), msg), msg.value.decode()


def _check_pdg(values: dict[str, float]) -> tuple[int, str]:
    st = cguidance.c_settings()
    for k, v in values.items():
        setattr(st, k, int(v) if k in cguidance._INT_SETTINGS else v)
    msg = ctypes.create_string_buffer(cguidance.MESSAGE_LEN)
    msg.value = b"stale"
    status = cguidance.library().pdg_check_settings(ctypes.byref(st), msg)
    return status, msg.value.decode() if status else ""


@dataclass(frozen=True)
class SettingsContract:
    header: str
    struct: str
    table: dict[str, Documented]
    check: Callable[[dict[str, float]], tuple[int, str]]
    prefix: str  # how a refusal names field f: prefix.format(f)


CONTRACTS = {
    "tscvx_settings": SettingsContract(SOCP_H, "tscvx_settings", SOCP_SETTINGS, _check_socp,
                                       "{} must"),
    "pdg_settings": SettingsContract(GUIDANCE_H, "pdg_settings", PDG_SETTINGS, _check_pdg,
                                     "settings.{}: must"),
}  # fmt: skip


@pytest.mark.parametrize("which", sorted(CONTRACTS))
def test_every_setting_documents_the_range_its_check_enforces(which: str) -> None:
    """Each field's comment states its range (soc_dense_max, the _inacc tolerances, socp_tol,
    step_tol, vc_tol, defect_tol and tight_tol stated none, though their checks refuse
    values), and the check takes the bound as documented and refuses just beyond it, naming
    the field."""
    c = CONTRACTS[which]
    comments = struct_comments(c.header, c.struct)
    assert set(comments) == set(c.table), "a field without its documented range in this test"
    wrong = []
    for name, doc in c.table.items():
        missing = [t for t in doc.texts if t not in comments[name]]
        if missing:
            wrong.append(f"{name}: the header says {comments[name]!r}, not {missing}")
        for value, accepted, named in _probes(doc):
            status, msg = c.check({**doc.also, name: value})
            if accepted and status != 0:
                wrong.append(f"{name} = {value!r} documented in range, refused: {msg}")
            if not accepted and not (
                status != 0 and msg.startswith(c.prefix.format(named or name))
            ):
                wrong.append(f"{name} = {value!r} out of range: status {status}, {msg!r}")
    assert not wrong, "\n".join(wrong)


# ---- the vehicle and the initial state: unit and range of every field -----------------------

U_ACC, U_LEN, U_VEL = "U_L / U_T^2", "U_L", "U_L / U_T"
PARAMS_TEXTS: dict[str, tuple[str, ...]] = {
    "g_I": (U_ACC, "g_I[0] < 0", "g_I[1] = g_I[2] = 0"),
    "J_B": ("U_M U_L^2", ">= PDG_INERTIA_MIN"),
    "r_T_B": (U_LEN, "r_T_B[0] < 0"),
    "r_cp_B": (U_LEN,),
    "alpha_mdot": ("U_T / U_L", "> 0"),
    "beta_mdot": ("U_M / U_T", ">= 0"),
    "aero_coeff": ("U_M / U_L", "> 0"),
    "m_dry": ("U_M", "> 0"),
    "T_min": ("U_M U_L / U_T^2", "0 < T_min < T_max"),
    "T_max": ("U_M U_L / U_T^2", "0 < T_min < T_max"),
    "gimbal_max_deg": ("deg", "(0, 90)"),
    "tilt_max_deg": ("deg", "(0, 180]"),
    "glideslope_deg": ("deg", "[0, 90)"),
    "omega_max_deg": ("deg / U_T", ">= PDG_OMEGA_MAX_DEG_MIN"),
    "r_f": (U_LEN, "r_f[0] >= 0", "inside the glideslope cone"),
    "v_f": (U_VEL, "from inside the glideslope cone"),
    "q_f": ("unit quaternion", "upright", "tilt_max_deg"),
    "omega_f": ("rad / U_T", "omega_max_deg"),
    "final_roll_free": ("(0 or 1)",),
    "N": ("[PDG_N_MIN, PDG_N_MAX]",),
}
SCENARIO_TEXTS: dict[str, tuple[str, ...]] = {
    "r0": (U_LEN, "inside the glideslope cone"),
    "v0": (U_VEL,),
    "q0": ("unit quaternion", "tilt_max_deg"),
    "w0": ("rad / U_T", "omega_max_deg", "w0[0] = omega_f[0]"),
    "m0": ("U_M", "> m_dry"),
    "params": (),
}


@pytest.mark.parametrize(
    ("struct", "texts"), [("pdg_params", PARAMS_TEXTS), ("pdg_scenario", SCENARIO_TEXTS)]
)
def test_every_vehicle_and_state_field_documents_its_unit_and_range(
    struct: str, texts: dict[str, tuple[str, ...]]
) -> None:
    """pdg_params gave units for omega_max_deg alone and ranges for g_I and N alone (m_dry,
    T_min and T_max had no comment at all); the flight team had to read pdg_scenario.c to
    learn that r_T_B[0] must be negative or that omega_f is in rad / U_T."""
    comments = struct_comments(GUIDANCE_H, struct)
    assert set(comments) == set(texts)
    missing = {f: [t for t in ts if t not in comments[f]] for f, ts in texts.items()}
    assert not any(missing.values()), {f: (comments[f], m) for f, m in missing.items() if m}


MAG = 1e4  # PDG_MAGNITUDE_MAX


def below(v: float) -> float:
    return math.nextafter(v, -math.inf)


def above(v: float) -> float:
    return math.nextafter(v, math.inf)


# (field, index or None, value, accepted, the field the refusal names): the bounds the header
# documents, everything else the default vehicle
Probe = tuple[str, int | None, float, bool, str]


def ok(name: str, index: int | None, value: float) -> Probe:
    return (name, index, value, True, "")


def no(name: str, index: int | None, value: float, named: str = "") -> Probe:
    return (name, index, value, False, named or name)


TINY = 5e-324
VEHICLE_PROBES: list[Probe] = [
    ok("g_I", 0, -TINY), no("g_I", 0, 0.0), no("g_I", 1, TINY),
    ok("J_B", 0, 1e-9), no("J_B", 0, below(1e-9)),
    ok("r_T_B", 0, -TINY), no("r_T_B", 0, 0.0),
    ok("r_cp_B", 0, MAG), no("r_cp_B", 0, above(MAG)),
    ok("alpha_mdot", None, TINY), no("alpha_mdot", None, 0.0),
    ok("beta_mdot", None, 0.0), no("beta_mdot", None, -TINY),
    ok("aero_coeff", None, TINY), no("aero_coeff", None, 0.0),
    ok("m_dry", None, TINY), no("m_dry", None, 0.0),
    ok("T_min", None, TINY), no("T_min", None, 0.0),
    ok("T_min", None, below(5.0)), no("T_min", None, 5.0),
    ok("T_max", None, above(0.3)), no("T_max", None, 0.3, "T_min"),  # T_min < T_max
    ok("gimbal_max_deg", None, TINY), no("gimbal_max_deg", None, 0.0),
    ok("gimbal_max_deg", None, below(90.0)), no("gimbal_max_deg", None, 90.0),
    ok("tilt_max_deg", None, 180.0), no("tilt_max_deg", None, above(180.0)),
    no("tilt_max_deg", None, 0.0),
    ok("glideslope_deg", None, 0.0), no("glideslope_deg", None, -TINY),
    ok("glideslope_deg", None, below(90.0)), no("glideslope_deg", None, 90.0),
    ok("omega_max_deg", None, 1e-3), no("omega_max_deg", None, below(1e-3)),
    no("r_f", 0, -TINY), no("r_f", 1, 0.5),
    no("v_f", 0, 0.1),
    ok("q_f", 0, 1.0 + 5e-7), no("q_f", 0, 1.0 + 2e-6), no("q_f", 2, 1e-3),
    # rad / U_T: 1.5 is below omega_max_deg = 90 deg / U_T = 1.5708 rad / U_T, 2 above it
    ok("omega_f", 2, 1.5), no("omega_f", 2, 2.0),
    ok("final_roll_free", None, 0), no("final_roll_free", None, 2),
    ok("N", None, 3), no("N", None, 2), ok("N", None, 400), no("N", None, 401),
]  # fmt: skip


def _set(obj: ctypes.Structure, name: str, index: int | None, value: float) -> None:
    if index is None:
        setattr(obj, name, type(getattr(obj, name))(value))
    else:
        getattr(obj, name)[index] = value


@pytest.mark.parametrize(("name", "index", "value", "accepted", "named"), VEHICLE_PROBES)
def test_the_vehicle_check_enforces_the_documented_bounds(
    name: str, index: int | None, value: float, accepted: bool, named: str
) -> None:
    """pdg_check_vehicle at each documented bound (the rest the default vehicle): the bound
    as documented, just beyond it refused naming the field."""
    lib = cguidance.library()
    p = cguidance._Params()
    lib.pdg_default_params(ctypes.byref(p))
    _set(p, name, index, value)
    msg = ctypes.create_string_buffer(cguidance.MESSAGE_LEN)
    status = lib.pdg_check_vehicle(ctypes.byref(p), msg)
    if accepted:
        assert status == 0, msg.value
    else:
        assert status != 0 and msg.value.decode().startswith(f"scenario field '{named}':")


@pytest.mark.parametrize(
    ("name", "index", "value", "accepted"),
    [("m0", None, 2.0, False), ("m0", None, above(2.0), True),
     ("q0", 0, 1.0 + 2e-6, False), ("r0", 1, 20.0, False),
     ("w0", 2, 1.5, True), ("w0", 2, 2.0, False), ("w0", 0, 1e-3, False)],
)  # fmt: skip
def test_the_scenario_check_enforces_the_documented_state_bounds(
    name: str, index: int | None, value: float, accepted: bool
) -> None:
    """pdg_validate_scenario at the initial state's documented bounds (m0 > m_dry = 2; w0 in
    rad / U_T against omega_max_deg = 90 deg / U_T; a roll rate the engine cannot change)."""
    s = cguidance._Scenario()
    cguidance.library().pdg_default_scenario(ctypes.byref(s))
    _set(s, name, index, value)
    msg = ctypes.create_string_buffer(cguidance.MESSAGE_LEN)
    status = cguidance.library().pdg_validate_scenario(ctypes.byref(s), msg)
    if accepted:
        assert status == 0, msg.value
    else:
        assert status != 0 and msg.value.decode().startswith(f"scenario field '{name}':")


# ---- statuses: returned for the conditions their comments name -------------------------------


def _data(n: int, p: int, m: int, l: int, q: list[int]) -> tuple[csocp._Data, list[np.ndarray]]:
    """A problem of these sizes with G = the first m rows of I (columns permitting), A = 0."""
    c, b, h = np.zeros(max(n, 1)), np.zeros(max(p, 1)), np.ones(max(m, 1))
    ncol = max(n, 0)
    Gp = np.array([min(j, max(m, 0)) for j in range(ncol + 1)], np.int32)
    Gi = np.arange(max(m, 1), dtype=np.int32)
    Gx, Ap, qq = np.ones(max(m, 1)), np.zeros(ncol + 1, np.int32), np.array(q or [1], np.int32)
    d = csocp._Data()
    d.n, d.p, d.m, d.l, d.nsoc = n, p, m, l, len(q)
    d.c, d.b, d.h = csocp._dptr(c), csocp._dptr(b), csocp._dptr(h)
    d.Ap, d.Ai, d.Ax = csocp._iptr(Ap), csocp._iptr(Gi), csocp._dptr(Gx)
    d.Gp, d.Gi, d.Gx = csocp._iptr(Gp), csocp._iptr(Gi), csocp._dptr(Gx)
    d.q = csocp._iptr(qq)
    return d, [c, b, h, Gp, Gi, Gx, Ap, qq]


# (condition as the header words it, sizes n, p, m, l, q)
DATA_CONDITIONS: list[tuple[str, tuple[int, int, int, int, list[int]]]] = [
    ("n <= 0", (0, 0, 0, 0, [])),
    ("p < 0", (2, -1, 2, 2, [])),
    ("m < 0", (2, 0, -1, 0, [])),
    ("l < 0", (2, 0, 2, -1, [3])),
    ("a cone dimension < 1", (2, 0, 2, 2, [0])),
    ("l + sum(q) != m", (2, 0, 2, 1, [])),  # fewer rows than G has
    ("l + sum(q) != m", (2, 0, 2, 1, [2])),  # more
]


@pytest.mark.parametrize(("condition", "sizes"), DATA_CONDITIONS)
def test_a_data_refusal_is_the_status_whose_comment_names_it(
    condition: str, sizes: tuple[int, int, int, int, list[int]]
) -> None:
    """tscvx_socp.h listed "l + sum(q) != m" under TSCVX_SETUP_BAD_DIMENSIONS, but the data
    check (and the message) return TSCVX_SETUP_BAD_CONES for it."""
    comments = enum_comments(SOCP_H, "tscvx_setup_status")  # every status but OK, in order
    names = ["TSCVX_SETUP_OK", *comments]
    d, _keep = _data(*sizes)
    msg = ctypes.create_string_buffer(csocp.MESSAGE_LEN)
    status = csocp.load_library().tscvx_check_data(ctypes.byref(d), msg)
    documented = [n for n, text in comments.items() if condition in text]
    assert len(documented) == 1, (condition, documented)
    assert names[status] == documented[0], (condition, names[status], msg.value)


# ---- a failed warm-start inference: what pdg_result and pdg_tscvx_guess say of it ------------

NETS = cguidance.BUILD_MODELS_DIR


def _function_comment(header: str, name: str) -> str:
    """The comment just before a function's declaration."""
    at = header.index(f" {name}(")
    return " ".join(header[header.rindex("/*", 0, at) : at].replace("*", " ").split())


@pytest.mark.skipif(not (NETS / "solution.tnn").exists(), reason="`make lib` writes the nets")
def test_a_solution_network_that_fails_returns_what_the_header_says() -> None:
    """pdg_solve_tscvx with a solution network whose prediction is not finite returns
    PDG_SOLVER_ERROR with t_f NaN and x, u untouched, and pdg_tscvx_guess PDG_SOLVER_ERROR
    with its outputs untouched; the header listed neither (PDG_SOLVER_ERROR's comment said
    x and u then hold the last accepted iterate, t_f's comment left the case out, and
    pdg_tscvx_guess named PDG_INVALID_INPUT alone)."""
    lib, net = cguidance.library(), nan_output_net()
    scn = Scenario()
    ws, cs = cguidance.workspace(scn), cguidance.c_scenario(scn)
    N = scn.params.N
    x, u = np.full((N, NX), 7.0), np.full((N, NU), 7.0)
    res = cguidance._Result()
    res.x, res.u = cguidance._dptr(x), cguidance._dptr(u)
    opt = cguidance._TscvxOptions()
    opt.solution = net._net
    status = lib.pdg_solve_tscvx(ws.ws, ctypes.byref(cs), ctypes.byref(opt), ctypes.byref(res),
                                 None)  # fmt: skip
    assert status == 3 and res.message.startswith(b"solution network: ")  # PDG_SOLVER_ERROR
    assert math.isnan(res.t_f) and (x == 7.0).all() and (u == 7.0).all()
    assert ws.log_length() == 0
    assert "solution network" in enum_comments(GUIDANCE_H, "pdg_status")["PDG_SOLVER_ERROR"]
    assert "solution network" in struct_comments(GUIDANCE_H, "pdg_result")["t_f"]

    t_f = ctypes.c_double(7.0)
    msg = ctypes.create_string_buffer(cguidance.MESSAGE_LEN)
    status = lib.pdg_tscvx_guess(ws.ws, ctypes.byref(cs), net._net, cguidance._dptr(x),
                                 cguidance._dptr(u), ctypes.byref(t_f), msg)  # fmt: skip
    assert status == 3 and msg.value.startswith(b"solution network: ")
    assert t_f.value == 7.0 and (x == 7.0).all() and (u == 7.0).all()
    assert "PDG_SOLVER_ERROR" in _function_comment(GUIDANCE_H, "pdg_tscvx_guess")


# ---- the guidance layer's messages -----------------------------------------------------------


def test_the_guidance_checks_clear_the_message_of_what_they_accept() -> None:
    """pdg_check_settings, pdg_check_vehicle and pdg_validate_scenario left `message` as it
    was for input they accept (a caller printing it printed the last refusal, or garbage),
    where tscvx_check_settings writes ""; for NULL they wrote nothing."""
    lib = cguidance.library()
    st, scn = cguidance.c_settings(), cguidance.c_scenario(Scenario())
    calls = {
        "pdg_check_settings": lambda m: lib.pdg_check_settings(ctypes.byref(st), m),
        "pdg_check_vehicle": lambda m: lib.pdg_check_vehicle(ctypes.byref(scn.params), m),
        "pdg_validate_scenario": lambda m: lib.pdg_validate_scenario(ctypes.byref(scn), m),
    }
    for name, call in calls.items():
        msg = ctypes.create_string_buffer(b"stale", cguidance.MESSAGE_LEN)
        assert call(msg) == 0 and msg.value == b"", (name, msg.value)
    msg = ctypes.create_string_buffer(b"stale", cguidance.MESSAGE_LEN)
    assert lib.pdg_check_settings(None, msg) == 1 and msg.value == b"settings is NULL"
    assert lib.pdg_check_vehicle(None, msg) == 1 and msg.value == b"vehicle is NULL"


def test_a_damaged_guidance_workspace_is_refused_with_a_message_that_says_so() -> None:
    """A bit flipped in a set-up workspace's N: every call refuses it (PDG_SETUP_NOT_READY,
    PDG_INVALID_INPUT) as the header says, but the status message and the solve's message
    said "workspace not set up", which it was; they now name the damage and what to do."""
    lib = cguidance.library()
    w = cguidance.Workspace(Scenario().params, cguidance.c_settings())
    addr = ctypes.addressof(w.arena)
    n_at = (-addr) % 16 + 4  # the aligned workspace: unsigned magic, then int N
    w.arena[n_at] = bytes([w.arena[n_at][0] ^ 1])
    rows = ctypes.c_int(-1)
    status = lib.pdg_log_length(w.ws, ctypes.byref(rows))
    assert status == 7 and rows.value == -1  # PDG_SETUP_NOT_READY, output untouched
    assert b"damaged" in lib.pdg_setup_status_message(status)
    assert "damaged" in enum_comments(GUIDANCE_H, "pdg_setup_status")["PDG_SETUP_NOT_READY"]
    _x, _u, res = cguidance._result_buffers(Scenario().params.N)  # alive while res points
    cs = cguidance.c_scenario(Scenario())
    assert lib.pdg_solve(w.ws, ctypes.byref(cs), None, ctypes.byref(res)) == 4
    assert b"damaged" in res.message and math.isnan(res.t_f)
