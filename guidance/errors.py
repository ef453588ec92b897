"""Bad user input: a scenario, setting, model or data file that must not be used.

Every such refusal is an :class:`InputError` (a ``ValueError``) whose message says what is wrong;
the command line prints it and exits with code 2, before anything is written.
"""

from __future__ import annotations


class InputError(ValueError):
    """Input that cannot be used as given; the message names it and says why."""
