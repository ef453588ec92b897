"""The JSON files the commands write and read back (run records, training reports, the models
folder's metrics): one checked reader; and ``load_json``, the one place a JSON file's text is
read and parsed (scenario files too), so that every JSON file is read alike.

A file that cannot be read, is not JSON, or is not the object its writer makes (a damaged or
hand-edited one, or another program's) raises InputError naming the file, what is wrong with
it and what to do, instead of a traceback from deep inside the command or a silent wrong
answer.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from guidance.errors import DuplicateKeyError, InputError, unique_keys

# What a required entry may hold: a Python type of a JSON value, or a tuple of them. ``object``
# takes any value; ``int`` and ``float`` take no true/false (bool is an int in Python).
JsonType = type | tuple[type, ...]
NUMBER: tuple[type, ...] = (int, float)
ANY: type = object

_NAMES = {dict: "an object", list: "a list", str: "a string", int: "an integer", float: "a number"}
_NAMES |= {bool: "true/false", type(None): "null"}


def load_json(path: Path, parse_constant: Callable[[str], Any] | None = None) -> Any:
    """The JSON value in the file ``path``: UTF-8 text, a byte order mark at its start ignored
    (RFC 8259 lets a parser ignore one; Windows editors write it, and such a scenario file was
    refused as "not valid JSON"), a key given twice refused (errors.unique_keys).
    ``parse_constant``: as json.loads's (NaN, Infinity). Raises what the caller words for its
    file: OSError, UnicodeDecodeError, DuplicateKeyError, ValueError (no JSON, an integer of
    more than 4,300 digits) or RecursionError (nesting)."""
    text = path.read_text(encoding="utf-8-sig")
    return json.loads(text, parse_constant=parse_constant, object_pairs_hook=unique_keys)


def read_json_object(
    path: str | Path, what: str, fix: str, required: Mapping[str, JsonType] | None = None
) -> dict[str, Any]:
    """The JSON object in ``path``, which holds ``what`` (e.g. "the metrics `guidance export`
    writes"), with each entry of ``required`` present and of its type. A key ``a.b`` is the
    entry ``b`` of the object ``a``; ``a.*.b`` the entry ``b`` of every object in ``a``.

    InputError otherwise: "PATH: not WHAT (PROBLEM); FIX", where ``fix`` says what to do (re-run
    the command that writes the file, delete the folder, ...)."""
    path = Path(path)

    def fail(problem: str) -> InputError:
        return InputError(f"{path}: not {what} ({problem}); {fix}")

    try:
        data = load_json(path)
    except OSError as exc:
        raise InputError(f"{path}: cannot read it ({exc.strerror or exc}); {fix}") from None
    except UnicodeDecodeError as exc:
        raise fail(f"not UTF-8 text ({exc.reason})") from None
    except DuplicateKeyError as exc:
        raise fail(f"key {exc.key!r} given twice") from None
    except (ValueError, RecursionError) as exc:  # JSONDecodeError, a huge integer, nesting
        raise fail(f"not valid JSON ({exc})") from None
    if not isinstance(data, dict):
        raise fail(f"{_name(data)}, not a JSON object")
    problems = missing_or_mistyped(data, required or {})
    if problems:
        raise fail(", ".join(problems))
    return data


def missing_or_mistyped(data: dict[str, Any], required: Mapping[str, JsonType]) -> list[str]:
    """What ``data`` lacks of ``required`` (keys as in :func:`read_json_object`), one phrase
    each ("no 'macs'", "'macs' is a string, not an integer"); empty when nothing."""
    problems: list[str] = []
    for key, types in required.items():
        problems += _check(data, key.split("."), types, "")
    return list(dict.fromkeys(problems))  # an object missing is named once, not per entry


def _check(value: Any, parts: list[str], types: JsonType, where: str) -> list[str]:
    if not parts:
        wanted = types if isinstance(types, tuple) else (types,)
        if isinstance(value, wanted) and not (isinstance(value, bool) and bool not in wanted):
            return []
        names = " or ".join(_NAMES.get(t, t.__name__) for t in wanted)
        return [f"'{where}' is {_name(value)}, not {names}"]
    if not isinstance(value, dict):
        return [f"'{where}' is {_name(value)}, not an object"]
    head, rest = parts[0], parts[1:]
    keys = list(value) if head == "*" else [head]
    problems: list[str] = []
    for k in keys:
        inner = f"{where}.{k}" if where else k
        if k not in value:
            problems.append(f"no '{inner}'")
        else:
            problems += _check(value[k], rest, types, inner)
    return problems


def _name(value: Any) -> str:
    return next((n for t, n in _NAMES.items() if type(value) is t), type(value).__name__)
