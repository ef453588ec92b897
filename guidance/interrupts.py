"""Ctrl-C and SIGTERM stop a command one way.

Ctrl-C raises KeyboardInterrupt wherever the command is; SIGTERM (a job killed, a session
ended), inside :func:`sigterm_as_interrupt`, raises :class:`Terminated`, a KeyboardInterrupt
too. So both stop a worker pool at once, keep what is finished, and end in guidance.cli.main
with one line saying what is kept and how to go on; the command exits as a shell reports a
command killed by the signal, 128 + its number (:func:`exit_code`). Light (the standard
library only): the console script uses it while guidance.cli is still being imported.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import NoReturn

EXIT_INTERRUPTED = 128 + signal.SIGINT  # 130, as a shell reports a command killed by SIGINT
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143, as a shell reports a command killed by SIGTERM


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the command is as Ctrl-C's KeyboardInterrupt is."""


def _terminate(signum: int, frame: object) -> NoReturn:
    raise Terminated


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM raises :class:`Terminated` in the block. Nothing changes outside the main
    thread (Python sets handlers there only) or when SIGTERM is ignored (whoever started the
    process wants it to go on)."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    ):
        yield
        return
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def exit_code(exc: BaseException) -> int:
    """The exit code of a command stopped by ``exc``: 143 for SIGTERM (a Terminated, or an
    interruption raised while handling one: the Interrupted of a command that says how far it
    got), else 130 (Ctrl-C)."""
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, Terminated):
            return EXIT_TERMINATED
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return EXIT_INTERRUPTED
