"""One landing by SCvx or T-SCvx on any backend: the entry point of the Python API (and of
``guidance solve``)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from guidance.errors import InputError
from guidance.guess import given_guess
from guidance.nn.conventions import CONSTRAINT_MODEL, MODELS_DIR, SOLUTION_MODEL
from guidance.params import Scenario, SCvxSettings
from guidance.scenario import checked
from guidance.scvx import SCvxResult, SCvxSolver, format_log
from guidance.tscvx import REDUCED_ETA_INIT, solve_tscvx

if TYPE_CHECKING:
    import numpy as np

METHODS = ("scvx", "tscvx")
BACKENDS = ("clarabel", "c-socp", "c")


def solve(
    scenario: Scenario | None = None,
    method: str = "scvx",
    backend: str = "clarabel",
    settings: SCvxSettings | None = None,
    models_dir: Path | str | None = MODELS_DIR,
    log: Callable[[str], None] | None = None,
    eta_init: float | None = None,
    guess: tuple[object, object, object] | None = None,
) -> SCvxResult:
    """Solve ``scenario`` (default: the default landing) by ``method`` on ``backend``:

    clarabel  the Python SCvx with Clarabel (ground reference)
    c-socp    the Python SCvx with the flight C SOCP runtime for the subproblems
    c         the whole solve in the flight C library (for tscvx the networks too:
              guidance.cguidance.solve_tscvx_c, not onnxruntime)

    ``method="tscvx"`` starts from the shipped networks' warm start and masks (``models_dir``,
    None: the shipped ones).
    ``eta_init`` overrides the initial trust radius; without it SCvx starts from
    settings.eta_init and T-SCvx (from the networks' warm start) from Table 1's reduced radius.
    ``guess`` (x, u, t_f), a trajectory of the scenario's N such as an earlier solve's, starts
    SCvx instead of the cubic guess, projected onto the scenario's boundary conditions and
    convex path constraints (``guess.given_guess``): re-planning from a neighbouring landing.
    ``log`` receives one line per subproblem. An infeasible landing is a result (its
    ``status`` and ``reason`` say so); bad input raises InputError.
    """
    _check_request(method, backend, guess, settings)
    # checked as a scenario file is: a Scenario built in Python skips no rule
    scenario = checked(Scenario() if scenario is None else scenario)
    start = None if guess is None else given_guess(scenario, *guess)
    settings = _run_settings(settings, method, backend, eta_init)
    models_dir = Path(MODELS_DIR if models_dir is None else models_dir)
    if backend == "c":
        return _solve_in_c(scenario, method, settings, models_dir, start, log)
    conic = "c" if backend == "c-socp" else backend  # the Python loop's name for its solver
    if method == "tscvx":
        return _solve_tscvx_onnx(scenario, settings, conic, models_dir, log)
    return SCvxSolver(scenario, settings, backend=conic, log=log).solve(guess=start)


def _check_request(method: str, backend: str, guess: object, settings: object) -> None:
    if settings is not None and not isinstance(settings, SCvxSettings):
        raise InputError(
            f"settings: expected a guidance.SCvxSettings, got {type(settings).__name__}"
        )
    if method not in METHODS:
        raise InputError(f"method {method!r}: use one of {', '.join(METHODS)}")
    if backend not in BACKENDS:
        raise InputError(f"backend {backend!r}: use one of {', '.join(BACKENDS)}")
    if guess is not None and method == "tscvx":
        raise InputError("guess: T-SCvx starts from its solution network; give a guess to SCvx")
    if guess is not None and (not isinstance(guess, tuple | list) or len(guess) != 3):
        raise InputError("guess: give (x, u, t_f)")


def _run_settings(
    settings: SCvxSettings | None, method: str, backend: str, eta_init: float | None
) -> SCvxSettings:
    """The settings the solve runs with: its initial trust radius, and what the backend does."""
    settings = SCvxSettings() if settings is None else settings
    if method == "tscvx":
        eta_init = REDUCED_ETA_INIT if eta_init is None else eta_init
    if eta_init is not None:
        settings = settings.replace(eta_init=eta_init)
    if backend == "clarabel":  # Clarabel has no warm start: record what runs
        settings = settings.replace(socp_warm_start=False)
    return settings


def _solve_in_c(
    scenario: Scenario,
    method: str,
    settings: SCvxSettings,
    models_dir: Path,
    start: tuple[np.ndarray, np.ndarray, float] | None,
    log: Callable[[str], None] | None,
) -> SCvxResult:
    """The whole solve in the C library (for T-SCvx the complete on-board call: networks,
    projection and SCvx), its log replayed after it."""
    from guidance.cguidance import solve_c, solve_tscvx_c

    if method == "tscvx":
        result = solve_tscvx_c(
            scenario, settings, models_dir=models_dir, eta_init=settings.eta_init
        )
    else:
        result = solve_c(scenario, settings, guess=start)
    if log:
        for line in format_log(result.history):
            log(line)
    return result


def _solve_tscvx_onnx(
    scenario: Scenario,
    settings: SCvxSettings,
    conic: str,
    models_dir: Path,
    log: Callable[[str], None] | None,
) -> SCvxResult:
    """T-SCvx in Python, the networks run by onnxruntime."""
    from guidance.nn.infer import ConstraintModel, SolutionModel
    from guidance.sampling import theta_of

    sol_model = SolutionModel(models_dir / SOLUTION_MODEL, scenario.params)
    con_model = ConstraintModel(models_dir / CONSTRAINT_MODEL, scenario.params)
    return solve_tscvx(
        scenario,
        lambda s: sol_model.solution(theta_of(s)),
        lambda s, k: con_model.mask(theta_of(s), k),
        settings,
        conic,
        log,
        eta_init=settings.eta_init,
    )
