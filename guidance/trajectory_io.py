"""Trajectory .npz files (DESIGN.md contract) and their provenance.

Text entries (``status``, ``reason``, ``method``, ``backend``, ``polish``) hold no NUL
character: numpy stores them as fixed-width strings padded with NULs, so a trailing NUL would
be read back as padding, by this reader and any other, and lost. A text with one is refused
on writing, and a file with one in its text is refused on reading. ``status`` is one of the
solvers' (scvx.STATUSES), on writing and reading. The JSON entries refuse a key given twice
(``json`` would keep the last and say nothing).
"""

from __future__ import annotations

import dataclasses
import json
import math
import zipfile
from pathlib import Path

import numpy as np

from guidance.atomic import atomic_write
from guidance.errors import (
    UNREADABLE_NPZ,
    DuplicateKeyError,
    InputError,
    describe,
    npz_damage,
    unique_keys,
)
from guidance.params import (
    NU,
    NX,
    PARAM_NAMES,
    Params,
    Scenario,
    SCvxSettings,
    rk4_steps_per_interval,
)
from guidance.provenance import provenance
from guidance.scenario import checked, scenario_to_dict
from guidance.scvx import STATUSES, SCvxResult

REQUIRED_KEYS = ("t_f", "x", "u", "status", "iterations", "solve_time_s", "params")
# The contract's scalars: the dtype kinds each may have and what it is. A count is an integer;
# a time any real number (an integer time is exact), and none of them true/false.
SCALAR_KEYS = {
    "t_f": ("iuf", "one real number >= 0 (a scalar, U_T; DESIGN.md)"),
    "iterations": ("iu", "one integer >= 0 (a scalar; DESIGN.md)"),
    "solve_time_s": ("iuf", "one real number >= 0 (a scalar, seconds; DESIGN.md)"),
}
JSON_KEYS = ("params", "scenario", "settings", "provenance")


def write_trajectory(
    path: str | Path,
    result: SCvxResult,
    params: Params,
    scenario: Scenario,
    method: str,
    backend: str,
    inputs: dict[str, Path] | None = None,
) -> None:
    """Writes the contract keys plus the iteration masks, reason, what became of the polish
    (scvx.POLISH_OUTCOMES), scenario (every parameter), the SCvx settings the solve ran with
    (``result.settings``, when known) and provenance (with the absolute path and sha256 of
    each file in ``inputs``, such as the networks of a T-SCvx solve). A text with a NUL
    character, a status none of scvx.STATUSES, params other than the scenario's, x or u not
    of params.N rows, or a result without a trajectory (no file the readers take) raise
    InputError before anything is written."""
    path = Path(path)
    text = {
        "status": result.status,
        "reason": result.reason,
        "method": method,
        "backend": backend,
        "polish": result.polish.outcome,
    }
    for key, value in text.items():
        _check_no_nul(path, key, value)
    _check_status(path, result.status)
    scenario = _check_contract(path, result, params, scenario)
    params = scenario.params  # equal to the given ones, as the numbers JSON takes
    with atomic_write(path) as f:
        np.savez(
            f,
            t_f=np.float64(result.t_f),
            x=result.x,
            u=result.u,
            status=np.str_(result.status),
            iterations=np.int64(result.iterations),
            solve_time_s=np.float64(result.solve_time_s),
            params=np.str_(json.dumps(params.to_json_dict())),
            reason=np.str_(result.reason),
            polish=np.str_(result.polish.outcome),
            masks=result.masks,
            scenario=np.str_(json.dumps(scenario_to_dict(scenario))),
            method=np.str_(method),
            backend=np.str_(backend),
            provenance=np.str_(json.dumps(provenance(inputs))),
            # numpy's stubs read ** as possibly its allow_pickle flag
            **({} if result.settings is None else _settings_entries(result.settings, params.N)),  # type: ignore[arg-type]
        )


def _check_contract(path: Path, result: SCvxResult, params: Params, scenario: Scenario) -> Scenario:
    """What the readers require of a file, checked before writing one: a scenario that passes
    the scenario file's checks (returned with its numbers as floats: a numpy float32 is no
    JSON number), the parameters it has, x and u of their N, and a trajectory (a solve that
    stopped before its first subproblem has none: t_f and x are NaN). InputError names what
    is wrong."""
    scenario = checked(scenario)
    differ = [
        name
        for name in PARAM_NAMES
        if not np.array_equal(getattr(scenario.params, name), getattr(params, name))
    ]
    if differ:
        raise InputError(f"{path}: params and scenario disagree on {', '.join(differ)}")
    for name, value, cols in (("x", result.x, NX), ("u", result.u, NU)):
        shape = np.shape(value)
        if shape != (params.N, cols):
            raise InputError(f"{path}: {name} is {shape}, the params ask for ({params.N}, {cols})")
    t_f = float(result.t_f)
    finite = np.isfinite(result.x).all() and np.isfinite(result.u).all()
    if not (math.isfinite(t_f) and t_f > 0.0 and finite):
        raise InputError(
            f"{path}: no trajectory to write (status {result.status}, t_f = {t_f:g}, x and u "
            f"{'finite' if finite else 'not finite'}): {result.reason}"
        )
    return scenario


def _settings_entries(settings: SCvxSettings, N: int) -> dict[str, np.generic]:
    """The settings the solve ran with, and the RK4 steps its intervals took (rk4_substeps is
    the least; a grid coarser than N = 50 takes more)."""
    steps = rk4_steps_per_interval(settings.rk4_substeps, N)
    return {
        "settings": np.str_(json.dumps(dataclasses.asdict(settings))),
        "rk4_steps_per_interval": np.int64(steps),
    }


def read_trajectory(path: str | Path) -> dict[str, object]:
    """The file's arrays, its JSON entries decoded to dictionaries. A file that is not a
    trajectory file raises InputError saying why."""
    if Path(path).is_dir():
        raise InputError(f"{path}: is a folder, not a trajectory file")
    if not Path(path).is_file():
        raise InputError(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise InputError(f"{path}: not a trajectory file (not an .npz archive)")
    out = _load(path)
    missing = [k for k in REQUIRED_KEYS if k not in out]
    if missing:
        raise InputError(f"{path}: not a trajectory file, missing {', '.join(missing)}")
    status = out["status"]
    if not (isinstance(status, np.ndarray) and status.shape == () and status.dtype.kind == "U"):
        raise InputError(f"{path}: status must be a text entry (DESIGN.md), got {status!r}")
    for key, (kinds, what) in SCALAR_KEYS.items():
        _check_scalar(path, key, out[key], kinds, what)
    for key, value in out.items():
        if isinstance(value, np.ndarray) and value.dtype.kind == "U":  # the text entries
            for item in value.ravel().tolist():
                _check_no_nul(path, key, item)
    _check_status(path, str(status))  # after the NUL check, which says more of such a text
    return out


def _check_status(path: str | Path, status: str) -> None:
    """A status the solvers end with (scvx.STATUSES); any other text is no answer of theirs
    ("converged", "SOLVED", a typo), which a reader would report as if it were one."""
    if status not in STATUSES:
        raise InputError(
            f"{path}: status {status!r} is none the solvers write (one of {', '.join(STATUSES)})"
        )


def _check_scalar(path: str | Path, key: str, value: object, kinds: str, what: str) -> None:
    """One of the contract's scalar entries: one finite number >= 0 of its kind, not an array
    (iterations = "3" or NaN, t_f = [4.2] were read as trajectory files)."""
    if isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in kinds:
        number = float(value)
        if math.isfinite(number) and number >= 0.0:
            return
    raise InputError(f"{path}: {key}: expected {what}, got {value!r}")


def _load(path: str | Path) -> dict[str, object]:
    try:
        with np.load(path, allow_pickle=False) as data:
            out: dict[str, object] = {k: data[k] for k in data.files}
        for key in JSON_KEYS:  # decoded to dictionaries
            if key in out:
                out[key] = _decode_json(path, key, out[key])
    except InputError:
        raise  # already names the file and says what is wrong
    except UNREADABLE_NPZ as exc:
        raise InputError(f"{path}: not a readable trajectory file: {npz_damage(exc)}") from exc
    return out


def _check_no_nul(path: str | Path, key: str, text: str) -> None:
    if "\x00" in text:
        raise InputError(
            f"{path}: {key} {text!r} holds a NUL character (a trajectory file's text cannot: "
            ".npz strings are NUL-padded, a trailing NUL would be lost)"
        )


def _decode_json(path: str | Path, entry: str, value: object) -> object:
    """A JSON entry (one text); a key given twice in any of its objects is refused, not the
    last kept. An entry that is no JSON text is said to be one, not a damaged archive."""
    unreadable = f"{path}: not a readable trajectory file: its {entry} entry"
    if not (isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind == "U"):
        raise InputError(f"{unreadable} must be a JSON text, got {describe(value)}")
    try:
        return json.loads(str(value), object_pairs_hook=unique_keys)
    except DuplicateKeyError as exc:
        raise InputError(f"{path}: {entry}: key {exc.key!r} given twice") from None
    except RecursionError:
        raise InputError(f"{unreadable} is JSON nested too deeply to read") from None
    except ValueError as exc:  # JSONDecodeError, an integer of more than 4,300 digits
        raise InputError(f"{unreadable} is not valid JSON ({exc})") from None
