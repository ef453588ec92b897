"""The errors the guidance code raises on purpose.

Bad user input (a scenario, setting, model or data file that must not be used) is an
:class:`InputError` (a ``ValueError``) whose message says what is wrong; the command line prints
it and exits with code 2, before anything is written. A trajectory at which the dynamics cannot
be evaluated is a :class:`ModelEvaluationError`; the SCvx loop turns it into a solver_error
status, as the C library does. ``check_output_path`` refuses an output file that cannot be
written, before the work that would fill it.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


class InputError(ValueError):
    """Input that cannot be used as given; the message names it and says why."""


class ModelEvaluationError(ArithmeticError):
    """The dynamics or their discretization are not finite at a trajectory (an iterate or a
    guess at the edge of the range the model is meant for, e.g. v0 = 1e4)."""


def check_output_path(flag: str, path: Path) -> None:
    """Create an output file's folder and make sure the file can be written there, before
    solving: a solve must not end in an error because of where its result goes."""
    target = Path(os.path.realpath(path))  # where the writers write: a link's target
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{flag} {path}: cannot create its folder ({exc.strerror})") from None
    if target.is_dir():
        raise InputError(f"{flag} {path}: is a folder, not a file")
    if target.exists() and not target.is_file():  # the writers replace what is there
        raise InputError(f"{flag} {path}: is a device, pipe or socket, not a regular file")
    try:  # a file written and removed beside it, as the writers do (root passes os.access)
        with tempfile.NamedTemporaryFile(dir=target.parent, prefix=".write-check-"):
            pass
    except OSError as exc:
        raise InputError(f"{flag} {path}: cannot write there ({exc.strerror})") from None
