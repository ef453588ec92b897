"""argparse types shared by the commands (``guidance.cli`` and the tools that add their own
options: ``budget``, ``dispersion``, ``cli_learning``)."""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable


def at_least(minimum: int, maximum: int | None = None) -> Callable[[str], int]:
    """argparse type of an integer count >= minimum (and <= maximum when given)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if maximum is not None and not minimum <= value <= maximum:
            raise argparse.ArgumentTypeError(f"must lie in [{minimum}, {maximum}], got {value}")
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {value}")
        return value

    return parse


def add_workers_option(ap: argparse.ArgumentParser, what: str) -> None:
    """--workers, the same for every command that solves in parallel: a count of processes,
    0 (the default) for every core (worker_count)."""
    ap.add_argument(
        "--workers",
        type=at_least(0),
        default=0,
        help=f"{what}, one process each (default 0: every core, {os.cpu_count() or 1} here)",
    )


def worker_count(workers: int) -> int:
    """--workers' value as a number of processes: 0 is every core."""
    return workers or os.cpu_count() or 1
