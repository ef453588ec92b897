"""``python -m guidance`` and the ``guidance`` console script (pyproject.toml's
[project.scripts]): guidance.cli.main, imported here so that a Ctrl-C or SIGTERM during the
second that import takes ends as one anywhere in a command does (one line, exit 130 or 143),
not with a traceback. Only the standard library is loaded before it."""

from __future__ import annotations

import sys

from guidance.interrupts import exit_code, sigterm_as_interrupt


def main() -> int:
    try:
        with sigterm_as_interrupt():
            from guidance.cli import main as cli_main
    except KeyboardInterrupt as exc:  # nothing started yet: nothing to keep
        print("\ninterrupted", file=sys.stderr)
        return exit_code(exc)
    return cli_main()


if __name__ == "__main__":
    sys.exit(main())
