"""Scenario JSON loading and validation (DESIGN.md, "File contracts").

Every rejection raises :class:`ScenarioError` naming the offending field; the CLI turns it
into exit code 2 before anything is written or solved.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from guidance.errors import DuplicateKeyError, InputError
from guidance.json_files import load_json
from guidance.params import (
    N_MAX,
    N_MIN,
    PARAM_NAMES,
    VECTOR_PARAM_SIZES,
    InitialState,
    Params,
    Scenario,
)

STATE_KEYS = {"r0": 3, "v0": 3, "q0": 4, "w0": 3}
SCALAR_STATE_KEYS = ("m0",)
UNIT_QUATERNION_TOL = 1e-6
# Largest magnitude of any number in a scenario (C: PDG_MAGNITUDE_MAX). Table 1's landing and
# vehicle are O(1) in its nondimensional units; at 1e4 every loop still ends with a status, and
# the same one on every backend. Far beyond it the initial guess and the networks' float32
# inputs overflow (r0 = 1e9 raised inside numpy), so such input is refused, not solved.
MAGNITUDE_MAX = 1e4
# Floors of two scales the solve divides by (C: PDG_INERTIA_MIN, PDG_OMEGA_MAX_DEG_MIN). The
# rotational dynamics divide by J_B: at 1e-11 the first subproblem failed numerically on every
# backend (1e-300: the same), while the catalog's smallest vehicle, J_B = (1e-9, 1e-8, 1e-8)
# (tests/test_extreme_landings.py), solves. The scaled rates are omega / omega_max: below
# 1e-3 deg/U_T (a rate limit that turns the vehicle by under 0.01 deg in a landing) Clarabel
# failed numerically where the C runtime called the landing infeasible (1e-5), and at 1e-300
# every backend failed at the first subproblem.
INERTIA_MIN = 1e-9
OMEGA_MAX_DEG_MIN = 1e-3
INT_PARAMS = {"N"}
BOOL_PARAMS = {"final_roll_free"}
# The keys DESIGN.md's scenario format always has; a missing one is an error, not a default.
REQUIRED_KEYS = (*STATE_KEYS, *SCALAR_STATE_KEYS, "glideslope_deg", "tilt_max_deg")


class ScenarioError(InputError):
    """A scenario that must not be solved. ``field`` names the offending key."""

    def __init__(self, field: str, message: str) -> None:
        where = "scenario file" if field == "<file>" else f"scenario field '{field}'"
        super().__init__(f"{where}: {message}")
        self.field = field
        self.reason = message


def _shown(value: Any) -> str:
    """A value as the user wrote it in JSON (true, not Python's True)."""
    try:
        return json.dumps(value)
    except (TypeError, ValueError):
        return repr(value)


def _finite(field: str, v: int | float) -> float:
    """v as a finite float; an integer too large for a float is refused like infinity."""
    try:
        f = float(v)
    except OverflowError:
        raise ScenarioError(
            field, f"must be finite, got an integer of {len(str(v))} digits"
        ) from None
    if not math.isfinite(f):
        raise ScenarioError(field, f"must be finite, got {v!r}")
    return f


def _finite_vector(field: str, value: Any, size: int) -> tuple[float, ...]:
    if not isinstance(value, list | tuple) or len(value) != size:
        raise ScenarioError(field, f"expected a list of {size} numbers, got {_shown(value)}")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise ScenarioError(field, f"expected numbers, got {_shown(v)}")
        out.append(_finite(field, v))
    return tuple(out)


def _finite_scalar(field: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ScenarioError(field, f"expected a number, got {_shown(value)}")
    return _finite(field, value)


def _parse_param(name: str, value: Any) -> Any:
    if name in VECTOR_PARAM_SIZES:
        return _finite_vector(name, value, VECTOR_PARAM_SIZES[name])
    if name in BOOL_PARAMS:
        if not isinstance(value, bool):
            raise ScenarioError(name, f"expected true or false, got {_shown(value)}")
        return value
    if name in INT_PARAMS:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ScenarioError(name, f"expected an integer, got {_shown(value)}")
        return value
    return _finite_scalar(name, value)


def scenario_from_dict(data: dict[str, Any]) -> Scenario:
    """Build and validate a scenario from the JSON contract's dictionary."""
    if not isinstance(data, dict):
        raise ScenarioError("<root>", "a scenario is a JSON object")
    allowed = set(STATE_KEYS) | set(SCALAR_STATE_KEYS) | set(PARAM_NAMES)
    for key in data:
        if key not in allowed:
            raise ScenarioError(key, f"unknown key (allowed: {', '.join(sorted(allowed))})")
    for key in REQUIRED_KEYS:
        if key not in data:
            raise ScenarioError(
                key, f"missing (a scenario gives all of {', '.join(REQUIRED_KEYS)})"
            )
    initial_kwargs: dict[str, Any] = {}
    for key, size in STATE_KEYS.items():
        if key in data:
            initial_kwargs[key] = _finite_vector(key, data[key], size)
    if "m0" in data:
        initial_kwargs["m0"] = _finite_scalar("m0", data["m0"])
    param_kwargs = {k: _parse_param(k, v) for k, v in data.items() if k in PARAM_NAMES}
    scenario = Scenario(InitialState(**initial_kwargs), Params(**param_kwargs))
    validate(scenario)
    return scenario


def _plain(value: Any) -> Any:
    """numpy arrays and scalars as the JSON types they stand for (a Scenario built in Python
    may hold them); everything else as it is, for the contract's checks to judge."""
    if isinstance(value, np.ndarray | list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def checked(scenario: Any) -> Scenario:
    """A scenario built in Python, checked as a scenario file is (types, sizes, finite
    values, physics) and with its numbers as floats; ScenarioError names the field."""
    if not isinstance(scenario, Scenario):
        raise InputError(f"scenario: expected a guidance.Scenario, got {type(scenario).__name__}")
    s = scenario.initial
    data = {"r0": s.r0, "v0": s.v0, "q0": s.q0, "w0": s.w0, "m0": s.m0}
    data |= {name: getattr(scenario.params, name) for name in PARAM_NAMES}
    return scenario_from_dict({k: _plain(v) for k, v in data.items()})


def params_from_dict(data: dict[str, Any]) -> Params:
    """Build and validate the parameters from a trajectory file's ``params`` dictionary (every
    field given by name, as ``Params.to_json_dict`` writes them)."""
    if not isinstance(data, dict):
        raise ScenarioError("<root>", "the parameters are a JSON object")
    unknown = sorted(set(data) - set(PARAM_NAMES))
    if unknown:
        raise ScenarioError(unknown[0], "unknown parameter")
    params = Params(**{k: _parse_param(k, v) for k, v in data.items()})
    _validate_params(params)
    return params


def load_scenario(path: str | Path) -> Scenario:
    return scenario_from_dict(read_scenario_data(path))


def read_scenario_data(path: str | Path) -> dict[str, Any]:
    """A scenario file's JSON object, read once (a pipe can be read only once), not yet
    checked as a scenario (scenario_from_dict does that)."""
    path = Path(path)
    try:
        data = load_json(path, parse_constant=_reject_constant)
    except OSError as exc:
        raise ScenarioError("<file>", f"cannot read {path}: {exc.strerror}") from exc
    except UnicodeDecodeError as exc:  # e.g. UTF-16, as some shells redirect
        raise ScenarioError("<file>", f"{path} is not UTF-8 text ({exc.reason})") from None
    except DuplicateKeyError as exc:
        raise ScenarioError(exc.key, "given twice") from None
    except (ValueError, RecursionError) as exc:  # JSONDecodeError, a 4,300-digit integer, nesting
        raise ScenarioError("<file>", f"{path} is not valid JSON: {exc}") from None
    return data


def _reject_constant(name: str) -> float:
    # json accepts NaN/Infinity literals; return them so the field check names the field.
    return float(name.replace("Infinity", "inf"))


def scenario_to_dict(scenario: Scenario, changed_only: bool = False) -> dict[str, Any]:
    """The JSON contract form, with every parameter: a file carries the parameters it was
    made with, not today's defaults (a file that left one out was read with the default of
    the day it is read). ``changed_only``: only those that differ from the defaults (for
    display)."""
    s = scenario.initial
    out: dict[str, Any] = {
        "r0": list(s.r0),
        "v0": list(s.v0),
        "q0": list(s.q0),
        "w0": list(s.w0),
        "m0": s.m0,
        "glideslope_deg": scenario.params.glideslope_deg,
        "tilt_max_deg": scenario.params.tilt_max_deg,
    }
    default = Params().to_json_dict()
    for key, value in scenario.params.to_json_dict().items():
        if key not in out and not (changed_only and value == default[key]):
            out[key] = value
    return out


def _norm(v: Any) -> float:
    """|v| as the C library's validation computes it (squares summed in order, then sqrt), so
    that both take the same side of every limit, to the last bit."""
    total = 0.0
    for x in np.ravel(np.asarray(v, float)):
        total += float(x) * float(x)
    return math.sqrt(total)


def validate(scenario: Scenario) -> None:
    """Reject parameters and initial states that cannot give a meaningful landing."""
    p = scenario.params
    _validate_finite(scenario.initial)  # every field first, as the C library
    _validate_finite(p)
    _validate_magnitudes(scenario.initial)
    _validate_params(p)
    s = scenario.initial
    q0 = np.asarray(s.q0)
    if abs(_norm(q0) - 1.0) > UNIT_QUATERNION_TOL:
        raise ScenarioError("q0", f"must be a unit quaternion, |q0| = {_norm(q0):.9g}")
    if s.m0 <= p.m_dry:
        raise ScenarioError("m0", f"m0 = {s.m0:g} must exceed the dry mass m_dry = {p.m_dry:g}")
    r0 = np.asarray(s.r0)
    horizontal = float(_norm(r0[1:]))
    gs = math.radians(p.glideslope_deg)
    # tan(gs) |(r2, r3)| <= r1 written as sin(gs) |h| <= cos(gs) r1 (valid up to 90 deg).
    if math.sin(gs) * horizontal > math.cos(gs) * r0[0] + 1e-12:
        raise ScenarioError(
            "r0",
            f"start is below the {p.glideslope_deg:g} deg glideslope cone "
            f"(altitude {r0[0]:g}, horizontal distance {horizontal:g})",
        )
    tilt_q = float(_norm(q0[2:4]))
    if tilt_q > p.tilt_q_max + 1e-12:
        raise ScenarioError(
            "q0",
            f"initial tilt {_tilt_deg(tilt_q):.3f} deg exceeds tilt_max_deg = {p.tilt_max_deg:g}",
        )
    w0 = np.asarray(s.w0)
    if _norm(w0) > p.omega_max + 1e-12:
        raise ScenarioError(
            "w0",
            f"|w0| = {math.degrees(_norm(w0)):.3f} deg/U_T exceeds "
            f"omega_max_deg = {p.omega_max_deg:g}",
        )
    if p.roll_decoupled and w0[0] != p.omega_f[0]:
        raise ScenarioError(  # named after the field moved from its default 0
            "omega_f" if p.omega_f[0] != 0.0 else "w0",
            "the engine cannot make roll torque (J2 = J3, r_T on the body axis), so the roll "
            f"rate is constant: w0[0] = {w0[0]:g} cannot reach omega_f[0] = {p.omega_f[0]:g}",
        )


def _real_fields(part: InitialState | Params) -> Iterator[tuple[str, np.ndarray]]:
    """Each field of real numbers (not N or final_roll_free) with its values, in field order."""
    for f in dataclasses.fields(part):
        if not isinstance(f.default, bool | int):
            yield f.name, np.ravel(np.asarray(getattr(part, f.name), dtype=float))


def _validate_finite(part: InitialState | Params) -> None:
    """Every real number finite (what a scenario file's parsing checks; validate() runs it
    too, for a Scenario built in Python)."""
    for name, values in _real_fields(part):
        if not np.all(np.isfinite(values)):
            got = values.tolist() if values.size > 1 else float(values[0])
            raise ScenarioError(name, f"must be finite, got {_shown(got)}")


def _validate_magnitudes(part: InitialState | Params) -> None:
    """Every real number within MAGNITUDE_MAX, in the fields' order (the C library's)."""
    for name, values in _real_fields(part):
        largest = float(np.max(np.abs(values)))
        if largest > MAGNITUDE_MAX:
            raise ScenarioError(
                name,
                f"magnitude {largest:g} is beyond the library's envelope "
                f"(|value| <= {MAGNITUDE_MAX:g} in nondimensional units)",
            )


def _validate_params(p: Params) -> None:
    _validate_magnitudes(p)
    for field, broken, message in _param_rules(p):
        if broken:
            value = getattr(p, field)
            raise ScenarioError(field, message.format_map({**vars(p), "value": value}))
    _validate_terminal(p)


def _param_rules(p: Params) -> Iterator[tuple[str, bool, str]]:
    """(field, whether the rule is broken, message) of each rule on the parameters, in the C
    library's order (check_params in pdg_scenario.c): a generator, each rule judged only after
    the earlier ones passed. The message is a template over the fields and ``value``, the
    named field's."""
    for name in ("alpha_mdot", "aero_coeff", "m_dry", "T_min", "T_max", "omega_max_deg"):
        yield name, getattr(p, name) <= 0.0, "must be positive, got {value!r}"
    yield "beta_mdot", p.beta_mdot < 0.0, "must be non-negative, got {value!r}"
    yield "J_B", any(j <= 0.0 for j in p.J_B), "inertia diagonal must be positive, got {J_B}"
    yield (
        "J_B",
        any(j < INERTIA_MIN for j in p.J_B),
        f"inertia diagonal must be at least {INERTIA_MIN:g}, got {{J_B}}",
    )
    yield (
        "omega_max_deg",
        p.omega_max_deg < OMEGA_MAX_DEG_MIN,
        f"must be at least {OMEGA_MAX_DEG_MIN:g} deg/U_T, got {{value:g}}",
    )
    yield "T_min", p.T_min >= p.T_max, "T_min = {T_min:g} must be below T_max = {T_max:g}"
    yield (  # the gimbal's lever arm; the guess divides by it
        "r_T_B",
        not p.r_T_B[0] < 0.0,
        "r_T_B[0] = {r_T_B[0]!r}: the engine sits below the centre of mass on the body axis "
        "(r_T_B[0] < 0, DESIGN.md: -0.01)",
    )
    yield "gimbal_max_deg", not 0.0 < p.gimbal_max_deg < 90.0, "must lie in (0, 90) degrees"
    yield "tilt_max_deg", not 0.0 < p.tilt_max_deg <= 180.0, "must lie in (0, 180] degrees"
    yield "glideslope_deg", not 0.0 <= p.glideslope_deg < 90.0, "must lie in [0, 90) degrees"
    yield "q_f", abs(_norm(p.q_f) - 1.0) > UNIT_QUATERNION_TOL, "must be a unit quaternion"
    yield (
        "g_I",
        p.g_I[0] >= 0.0 or p.g_I[1] != 0.0 or p.g_I[2] != 0.0,
        "gravity must point along -e1 (e1 is up)",
    )
    yield "N", not N_MIN <= p.N <= N_MAX, f"must lie in [{N_MIN}, {N_MAX}], got {{N}}"
    yield "r_f", p.r_f[0] < 0.0, "landing point must not be below the surface"


def _validate_terminal(p: Params) -> None:
    """The terminal state must meet the path constraints it is held to at the last node."""
    r_f = np.asarray(p.r_f)
    gs = math.radians(p.glideslope_deg)
    horizontal = float(_norm(r_f[1:]))
    if math.sin(gs) * horizontal > math.cos(gs) * r_f[0] + 1e-12:
        raise ScenarioError(
            "r_f", f"landing point is outside the {p.glideslope_deg:g} deg glideslope cone"
        )
    if _arrives_from_outside_the_cone(r_f, horizontal, p.v_f, gs):
        raise ScenarioError(
            "v_f",
            f"v_f = ({p.v_f[0]:g}, {p.v_f[1]:g}, {p.v_f[2]:g}) reaches r_f, on the "
            f"{p.glideslope_deg:g} deg glideslope cone, from outside the cone (e1 is up): at "
            "r_f = 0, v_f[0] <= -tan(glideslope) |(v_f[1], v_f[2])|",
        )
    if _norm(p.omega_f) > p.omega_max + 1e-12:
        raise ScenarioError(
            "omega_f",
            f"|omega_f| = {math.degrees(_norm(p.omega_f)):.3f} deg/U_T exceeds "
            f"omega_max_deg = {p.omega_max_deg:g}",
        )
    tilt_q = float(_norm(p.q_f[2:4]))
    if p.final_roll_free and tilt_q > 1e-12:
        raise ScenarioError(
            "q_f",
            f"a roll-free landing ends upright (q2 = q3 = 0), but q_f is tilted "
            f"{_tilt_deg(tilt_q):.3f} deg; set final_roll_free to false to pin it",
        )
    if not p.final_roll_free and tilt_q > p.tilt_q_max + 1e-12:
        raise ScenarioError(
            "q_f",
            f"pinned final tilt {_tilt_deg(tilt_q):.3f} deg exceeds tilt_max_deg = "
            f"{p.tilt_max_deg:g}",
        )


def _arrives_from_outside_the_cone(
    r_f: np.ndarray, horizontal: float, v_f: tuple[float, ...], gs: float
) -> bool:
    """Whether the vehicle would reach r_f (inside the glideslope cone) with velocity v_f only
    from outside the cone: r_f on the cone's boundary (g(r_f) = 0 to 1e-12, with g(r) =
    sin(gs) |(r2, r3)| - cos(gs) r1 <= 0 inside) and g growing backwards along -v_f. Then the
    path constraint holds at the last nodes and is broken between them: at r_f = 0, v_f =
    (0.1, 0, 0) "solved" 4e-3 below the surface inside the last interval (C library, 27 Nov).
    The C library's check_terminal computes the same, in the same order."""
    sin_gs, cos_gs = math.sin(gs), math.cos(gs)
    if sin_gs * horizontal - cos_gs * float(r_f[0]) < -1e-12:
        return False  # inside the cone: any final velocity keeps the path near r_f in it
    vh = (float(v_f[1]), float(v_f[2]))
    if horizontal > 0.0:  # d|r_h| along -v_h: -(r_h . v_h) / |r_h|
        away = -(float(r_f[1]) * vh[0] + float(r_f[2]) * vh[1]) / horizontal
    else:  # at the axis |r_h| grows along any horizontal motion
        away = _norm(vh)
    return sin_gs * away + cos_gs * float(v_f[0]) > 1e-12


def _tilt_deg(tilt_q: float) -> float:
    """Tilt of body axis 1 from up for |(q2, q3)| = tilt_q: cos(tilt) = 1 - 2 tilt_q^2."""
    return math.degrees(math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * tilt_q**2))))
