"""argparse types shared by the commands (``guidance.cli`` and the tools that add their own
options: ``budget``, ``dispersion``, ``cli_learning``)."""

from __future__ import annotations

import argparse
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
