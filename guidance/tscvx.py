"""T-SCvx (paper Algorithm 2): SCvx warm-started by a predicted solution, with subproblems
reduced to the constraints predicted tight at each iteration.

The predictors are plain callables so that any model (the shipped ONNX networks, a lookup
table, or an oracle in tests) can drive it:

    predict_solution(scenario) -> (x (N, 14), u (N, 3), t_f)
    predict_mask(scenario, k)  -> 7N tight-constraint bits (0/1) for iteration k, or None

The penalty J is always evaluated on the full constraint set, and before returning the full
problem's constraints are checked: a violated constraint that the mask dropped is put back and
the iteration goes on (guidance.scvx), so T-SCvx never returns what the full problem rejects.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from guidance.errors import InputError, describe
from guidance.guess import is_finite_guess, project_guess
from guidance.params import Scenario, SCvxSettings
from guidance.scvx import SCvxResult, SCvxSolver

REDUCED_ETA_INIT = 0.01  # Table 1: eta_reduced,init

SolutionPredictor = Callable[[Scenario], tuple[np.ndarray, np.ndarray, float]]
MaskPredictor = Callable[[Scenario, int], np.ndarray | None]  # None: the full problem


def solve_tscvx(
    scenario: Scenario,
    predict_solution: SolutionPredictor | None,
    predict_mask: MaskPredictor | None,
    settings: SCvxSettings | None = None,
    backend: str = "clarabel",
    log: Callable[[str], None] | None = None,
    eta_init: float = REDUCED_ETA_INIT,
) -> SCvxResult:
    """Algorithm 2, orchestrated in Python (the flight library's is pdg_solve_tscvx).

    The predicted solution, projected as on board, starts the solve at the trust radius
    ``eta_init`` (Table 1's reduced one); without a solution predictor the cubic guess starts it
    at ``settings.eta_init``. ``predict_mask(scenario, k)`` gives the 7N mask bits of
    succession k, 0/1 only (a network's probabilities thresholded by the caller, at the
    threshold its model card states; see scvx.mask_bits); without it every subproblem is the
    full one. A predictor that is not a function (None aside) is refused (InputError)."""
    _check_predictor("predict_solution", predict_solution, "scenario -> (x, u, t_f)")
    _check_predictor("predict_mask", predict_mask, "(scenario, k) -> 7N 0/1 bits")
    t_start = time.perf_counter()
    st = settings or SCvxSettings()
    guess = None
    if predict_solution is not None:
        x, u, t_f = predict_solution(scenario)
        if not is_finite_guess(x, u, t_f):
            # a status, as the flight library's T-SCvx gives (pdg_solve_tscvx)
            return SCvxSolver(scenario, st, backend=backend).no_trajectory(
                "solution network: the network output is not finite (overflow inside the network)",
                t_start,
            )
        guess = project_guess(scenario, x, u, t_f)
        st = st.replace(eta_init=eta_init)
    masks = None
    if predict_mask is not None:

        def masks(k: int) -> object:  # checked by the loop (scvx.mask_bits); None: the full problem
            return predict_mask(scenario, k)

    solver = SCvxSolver(scenario, st, backend=backend, log=log)
    return solver.solve(guess=guess, masks=masks)


def _check_predictor(name: str, fn: object, form: str) -> None:
    """A predictor must be a function or None: True or a mask table given instead would
    fail deep inside the solve (a TypeError after the first subproblem's set-up)."""
    if fn is not None and not callable(fn):
        raise InputError(f"{name}: expected a function {form}, or None; got {describe(fn)}")
