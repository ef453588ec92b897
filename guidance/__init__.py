"""T-SCvx guidance: 6-DoF powered-descent guidance by successive convexification.

The Python API in a few names (README, "From Python")::

    from guidance import InitialState, Scenario, audit, solve

    scenario = Scenario(InitialState(r0=(5.0, 2.0, 1.0), v0=(-0.5, -1.0, 0.0)))
    result = solve(scenario, backend="c")        # status, t_f, m_f, x (N x 14), u (N x 3)

The names load their modules on first use, so that ``import guidance`` stays light.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_EXPORTS = {
    "InitialState": "guidance.params",
    "Params": "guidance.params",
    "Scenario": "guidance.params",
    "SCvxSettings": "guidance.params",
    "SCvxResult": "guidance.scvx",
    "InputError": "guidance.errors",
    "load_scenario": "guidance.scenario",
    "solve": "guidance.api",
    "plan_remainder": "guidance.guess",
    "read_trajectory": "guidance.trajectory_io",
    "write_trajectory": "guidance.trajectory_io",
    "audit": "guidance.verify",
    "verify_file": "guidance.file_check",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module 'guidance' has no attribute {name!r}")
    return getattr(import_module(_EXPORTS[name]), name)
