"""The errors the guidance code raises on purpose.

Bad user input (a scenario, setting, model or data file that must not be used) is an
:class:`InputError` (a ``ValueError``) whose message says what is wrong; the command line prints
it and exits with code 2, before anything is written. A trajectory at which the dynamics cannot
be evaluated is a :class:`ModelEvaluationError`; the SCvx loop turns it into a solver_error
status, as the C library does. A resumable run whose worker process died stops with a
:class:`WorkerDiedError`; the command line prints it and exits with code 1.
(``atomic.check_outputs`` refuses an output file that cannot be written, before the work that
would fill it.)
"""

from __future__ import annotations

import zipfile
import zlib
from typing import Any


class InputError(ValueError):
    """Input that cannot be used as given; the message names it and says why."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM (guidance.interrupts) that stopped a command that knows how far it
    got: the message says what is kept and how to go on. The command line prints it after
    "interrupted: " and exits with code 130 (143 for SIGTERM), as for any other interruption
    of a command."""


class LibraryNotBuiltError(RuntimeError):
    """A flight library or C driver the call needs is not built; the message names the file
    and the make target that builds it. The command line prints it and exits with code 2."""


class WorkerDiedError(RuntimeError):
    """A worker process of a resumable run died (killed by a signal: a crash in a C solver,
    out of memory); the message (guidance.pool.worker_died) says what is kept and how to go
    on. The command line prints it after "error: " and exits with code 1."""


class ModelEvaluationError(ArithmeticError):
    """The dynamics or their discretization are not finite at a trajectory (an iterate or a
    guess at the edge of the range the model is meant for, e.g. v0 = 1e4)."""


# What reading a damaged or foreign .npz (or one of its members) can raise: OSError and
# BadZipFile from a cut file, zlib.error from a damaged compressed member, RecursionError
# from deeply nested JSON entries, MemoryError from a header claiming a huge shape,
# ValueError from object arrays (allow_pickle=False) or bad JSON, KeyError from a missing
# member. The readers turn it into an InputError naming the file.
UNREADABLE_NPZ = (
    OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error, RecursionError,
    MemoryError,
)  # fmt: skip


def npz_damage(exc: BaseException) -> str:
    """What a reader says of a file np.load failed on (one of UNREADABLE_NPZ): the system's
    reason when there is one (permission denied, an I/O error), else that it is damaged. Not
    numpy's message, which for a file that is no .npz tells of pickled data and allow_pickle:
    nothing the user should do."""
    if isinstance(exc, OSError) and exc.errno is not None:
        return f"unreadable ({exc.strerror})"
    return "damaged (not an .npz numpy can read)"


class DuplicateKeyError(ValueError):
    """A JSON object with a key given twice (``unique_keys``); ``key`` names it."""

    def __init__(self, key: str) -> None:
        super().__init__(key)
        self.key = key


def unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """``json.loads(..., object_pairs_hook=unique_keys)``: json keeps the last of two equal
    keys without a word; in a file a person wrote, the second is a typo, not a choice."""
    seen: dict[str, Any] = {}
    for key, value in pairs:
        if key in seen:
            raise DuplicateKeyError(key)
        seen[key] = value
    return seen


def describe(value: object) -> str:
    """A wrong argument named in a message: its type and the start of its repr."""
    text = repr(value)
    return f"{type(value).__name__} {text if len(text) <= 40 else text[:37] + '...'}"
