"""Successive convexification (paper Algorithm 1) and its T-SCvx variant (Algorithm 2).

The penalty J (paper Eq. (12)) is always evaluated on the FULL constraint set, on the scaled
variables of ``guidance.subproblem``:

    J(z) = -m_hat(t_f) + lambda * ( sum_k |Sx^-1 (x_{k+1} - F(x_k, u_k, u_{k+1}, sigma))|_1
                                    + sum_{k,c} max(0, h_c(x_k, u_k)) / scale_c )

and the subproblem's optimal value is the predicted cost L (Eq. (13)). A step is accepted when
rho = dJ / dL >= rho0; the trust radius follows Eq. (15), or its tau_r-scaled form in T-SCvx.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from guidance import conic
from guidance.conic import ConicProblem, ConicSolution
from guidance.constraints import constraint_scales, path_constraint_values, tight_mask
from guidance.errors import InputError, ModelEvaluationError, describe
from guidance.guess import checked_guess, initial_guess
from guidance.model import discretize, vehicle_pattern
from guidance.params import IM, NC, NU, NX, Scenario, SCvxSettings, rk4_steps_per_interval
from guidance.scenario import checked
from guidance.subproblem import (
    TR_PAIRS,
    TR_SCALAR_STATES,
    Layout,
    Scaling,
    SubproblemTemplate,
    carry_solution,
    physical,
    scaled,
)

STATE_NAMES = ("r1", "r2", "r3", "v1", "v2", "v3", "q0", "q1", "q2", "q3", "w1", "w2", "w3", "m")


# How the reason of a call stopped by socp_max_iter_total starts (C: pdg_scvx.c budget_spent)
BUDGET_SPENT = "IPM iteration budget spent"

# The reason of a solve whose step was rejected at eta_lb from an iterate that meets every
# tolerance (C: pdg_scvx.c). Near a plan whose defects are far below defect_tol (a polished
# or exactly predicted one), every step of the subproblem is rejected: lambda times its
# second-order defects outweighs the little it gains (the Maratos effect of an exact penalty).
# An accepted step would only move the plan within step_tol, so it is returned, solved (paper
# Algorithm 1 returns the reference when dJ = 0), where a reference short of a tolerance
# ends "step rejected at the smallest trust radius".
CONVERGED_AT_REFERENCE = (
    "converged; the step at the smallest trust radius, within step_tol, was rejected: "
    "the iterate kept"
)

# The reason of a solve whose last accepted step was longer than step_tol but changed the
# penalty cost J by at most cost_tol (paper Algorithm 1: while dJ > eps_tol), every other
# tolerance met: a creep along a flat valley of J, which the step test alone let run to the
# iteration limit (C: pdg_scvx.c, the same words).
CONVERGED_ON_COST = "converged; the accepted step changed J by at most cost_tol"


# The reasons of a solve stopped short of convergence by its iteration limit (_diagnose; C:
# pdg_scvx.c diagnose, the same words). Whatever the numbers, each fits the flight library's
# message (cguidance.MESSAGE_LEN - 1 = 255 characters): test_scvx_termination.py builds the
# longest (246). The mass at the floor used to be printed (%.6f: as long as m_dry is), and
# with long settings the C text was cut mid-word.
def not_converged_reason(k: int, defect: float, viol: float) -> str:
    """At the iteration limit with no virtual control left."""
    return (
        f"not converged after {k} iterations; virtual control is zero (the linearized "
        f"dynamics are met), largest nonlinear defect {defect:.2e}, largest "
        f"path-constraint value {viol:.2e}"
    )


def infeasible_reason(
    vc: float, vc_tol: float, k: int, defect: float, interval: int, state: str, at_floor: bool
) -> str:
    """At the iteration limit with virtual control left; ``at_floor``: the final mass at
    m_dry."""
    parts = [f"virtual control {vc:.3g} > {vc_tol:g} after {k} iterations"]
    parts.append(f"largest defect {defect:.3g} at interval {interval}, state {state}")
    if at_floor:
        parts.append("mass at the floor: not enough fuel, or no landing within the constraints")
    return "; ".join(parts)


def stalled_reason(eta_lb: float, reason: str) -> str:
    """``reason`` of a solve whose step was rejected at the smallest trust radius."""
    return f"step rejected at the smallest trust radius {eta_lb:g}; {reason}"


@dataclass
class IterationRecord:
    k: int
    J: float
    dJ: float
    dL: float
    rho: float
    eta: float
    vc_norm1: float  # block norm of nu (see subproblem.N_NU_BLOCKS) + |s'|_1, scaled units
    n_tight: int
    subproblem_time_s: float
    accepted: bool
    solver_status: str
    solver_iterations: int
    restored: int = 0  # T-SCvx: dropped constraints the full-constraint guard put back here


# What became of the polish (SCvxSettings.polish), in the C library's order (pdg_polish_status)
POLISH_OUTCOMES = ("off", "kept", "no_budget", "failed", "not_better")
POLISH_MEANINGS = (
    "not run (off, prox_u = 0, or the solve did not converge)",
    "the answer is the polished iterate",
    "not run: the IPM iteration budget was spent",
    "its conic solve or the model evaluation failed; the converged iterate kept",
    "it left virtual control, no smaller defects or a path constraint unmet; the converged "
    "iterate kept",
)


@dataclass(frozen=True)
class Polish:
    """The polish of a converged solve: one more subproblem about the answer without the fuel
    term, whose solution replaces the answer when it has smaller defects (SCvxSettings.polish).
    """

    outcome: str = "off"  # POLISH_OUTCOMES
    ipm_iterations: int = 0  # its IPM iterations (also in the call's total)
    defect_before: float = float("nan")  # largest defect of the converged iterate
    m_f_before: float = float("nan")  # its final mass

    def describe(self, defect: float, m_f: float) -> str:
        """What became of it, in a line; ``defect`` and ``m_f`` are the answer's."""
        if self.outcome == "kept":
            return (
                f"largest defect {self.defect_before:.2e} -> {defect:.2e}, final mass changed "
                f"by {m_f - self.m_f_before:+.2e} U_M, {self.ipm_iterations} IPM iterations"
            )
        return POLISH_MEANINGS[POLISH_OUTCOMES.index(self.outcome)]


def step_label(accepted: bool, restored: int) -> str:
    """The log's last column: a guard rejection (constraints put back) reads apart from a rho
    one."""
    if accepted:
        return "acc"
    return f"rej, {restored} put back" if restored else "rej"


# The statuses a solve ends with, on every backend (the C library's pdg_status in this order,
# less its refusal PDG_INVALID_INPUT, which returns no result): the only ones a trajectory
# file may hold.
STATUSES = ("solved", "infeasible", "max_iterations", "solver_error")


@dataclass
class SCvxResult:
    status: str  # one of STATUSES
    reason: str
    x: np.ndarray  # (N, 14)
    u: np.ndarray  # (N, 3), T_B
    t_f: float
    iterations: int  # successions k: accepted steps (Algorithm 1)
    subproblems_solved: int  # convex subproblems solved, rejected steps included
    solve_time_s: float
    history: list[IterationRecord] = field(default_factory=list)
    # tight-constraint mask (7N) of the subproblem solution accepted at each iteration k
    masks: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.uint8))
    max_defect: float = float("nan")  # max |x_{k+1} - F(...)| over nodes, physical units
    max_violation: float = float("nan")  # max h over nodes and constraints (<= 0 when met)
    subproblems: list[ConicProblem] = field(default_factory=list)
    settings: SCvxSettings | None = None  # what the solve ran with (trajectory files record it)
    polish: Polish = field(default_factory=Polish)

    @property
    def final_mask(self) -> np.ndarray:
        return self.masks[-1] if len(self.masks) else np.zeros(0, np.uint8)

    @property
    def m_f(self) -> float:
        return float(self.x[-1, IM])

    @property
    def ipm_iterations(self) -> int:
        """The call's IPM iterations: its subproblems' and the polish's."""
        return sum(h.solver_iterations for h in self.history) + self.polish.ipm_iterations


# T-SCvx masks: a 7N mask per iteration k (the last repeats), or a function k -> mask; each
# is checked (mask_table, mask_bits), so any object may come. _Checked: the table checked.
_Masks = Callable[[int], object] | Sequence[object] | None
_Checked = Callable[[int], object] | list[np.ndarray] | None


@dataclass
class _Candidate:
    """A subproblem's solution z_new, evaluated on the FULL constraint set."""

    z: np.ndarray
    disc: dict[str, np.ndarray]  # its discretization (the next subproblem's, if accepted)
    J: float  # penalty J(z_new), Eq. (12)
    defect: float  # largest nonlinear defect (physical units)
    viol: float  # largest path-constraint value
    L: float  # predicted cost, Eq. (13)
    vc: float  # virtual control + buffers, max(sum, 0)
    step: float  # |z_new - z|_inf over the trajectory variables
    tr_step: float  # |z_new - z| in the trust region's norm
    h: np.ndarray  # path-constraint values (N, 7)
    tight: np.ndarray  # tight labels (7N)


@dataclass
class _LoopState:
    """What Algorithm 1 carries from one subproblem to the next."""

    z: np.ndarray  # the iterate (scaled)
    disc: dict[str, np.ndarray]  # its discretization
    J: float  # its penalty
    defect: float  # its largest defect
    viol: float  # its largest path-constraint value
    eta: float  # trust radius of the next subproblem
    forced: np.ndarray  # constraints put back by the full-constraint guard (7N)
    k: int = 0  # successions (accepted steps); a rejection retries the same k
    vc: float = float("inf")  # virtual control + buffers of the last candidate
    # tau_r (Algorithm 2, step 4) compares the predicted masks of successions k+1 and k:
    # prev_pred is the prediction of the last accepted succession (a retry keeps it).
    prev_pred: np.ndarray | None = None
    last_sol: ConicSolution | None = None  # where the next IPM starts
    last_tpl: SubproblemTemplate | None = None  # the template (mask) last_sol answers
    stalled: bool = False  # rejected at the smallest radius
    ipm_used: int = 0  # IPM iterations so far (failed warm-started runs included)
    capped: bool = False  # the last subproblem's limit was the budget's, not socp_max_iter
    spent: bool = False  # the IPM iteration budget (socp_max_iter_total) is spent
    status: str = "max_iterations"
    reason: str = "iteration limit reached"
    history: list[IterationRecord] = field(default_factory=list)
    mask_log: list[np.ndarray] = field(default_factory=list)  # tight labels per succession
    subproblems: list[ConicProblem] = field(default_factory=list)


def discretization_engine(setting: str) -> str:
    """The discretization SCvxSettings.discretization runs: "auto" is the generated C when
    the library is built, else CasADi's VM."""
    if setting != "auto":
        return setting
    from guidance import cgnc

    return "c" if cgnc.available() else "casadi"


class SCvxSolver:
    """SCvx / T-SCvx for one scenario. ``solve`` runs the whole loop."""

    def __init__(
        self,
        scenario: Scenario,
        settings: SCvxSettings | None = None,
        backend: str = "clarabel",
        log: Callable[[str], None] | None = None,
        record_subproblems: bool = False,
    ) -> None:
        self.scn = checked(scenario)  # as pdg_solve checks it: ScenarioError names the field
        self.p = scenario.params
        self.st = settings or SCvxSettings()
        self.backend = backend
        self.log = log
        self.record = record_subproblems
        self._templates: dict[bytes, SubproblemTemplate] = {}
        self._sessions: dict[int, conic.Session] = {}  # conic solver per sparsity pattern
        self.engine = discretization_engine(self.st.discretization)
        if self.engine != self.st.discretization:
            # the result's settings say which discretization ran, not "auto"
            self.st = self.st.replace(discretization=self.engine)

    # ---- pieces ---------------------------------------------------------------------------
    def template(self, mask: np.ndarray | None) -> SubproblemTemplate:
        key = b"full" if mask is None else np.packbits(np.asarray(mask, bool)).tobytes()
        if key not in self._templates:
            self._templates[key] = SubproblemTemplate(
                self.p.N, self.p.final_roll_free, mask, vehicle_pattern(self.p)
            )
        return self._templates[key]

    def _discretize(self, z: np.ndarray) -> dict[str, np.ndarray]:
        x, u, t_f = physical(z, self.lay, self.sc)
        steps = rk4_steps_per_interval(self.st.rk4_substeps, self.p.N)
        return discretize(x, u, t_f, self.p, steps, self.engine)

    def penalty(self, z: np.ndarray, disc: dict[str, np.ndarray]) -> tuple[float, float, float]:
        """J(z) on the full constraint set; also the max defect and max violation."""
        x, u, _ = physical(z, self.lay, self.sc)
        defect = x[1:] - disc["x_next"]
        h = path_constraint_values(x, u, self.p)
        viol = np.maximum(h, 0.0) / self.scales[None, :]
        J = -(x[-1, IM] - self.sc.cx[IM]) / self.sc.Sx[IM] + self.st.lam * (
            block_norm_sum(defect / self.sc.Sx[None, :]) + float(viol.sum())
        )
        return J, float(np.abs(defect).max()), float(h.max())

    def linear_cost(self, prob: ConicProblem, z: np.ndarray) -> float:
        """L (paper Eq. (13)): the subproblem objective without any proximal term."""
        L = self.lay
        return float(-z[L.x_index(self.p.N - 1, IM)] + self.st.lam * z[L.ivc :].sum())

    def _duals(self, tpl: SubproblemTemplate, zdual: np.ndarray) -> np.ndarray:
        """Multiplier of every (node, c) in the subproblem, NaN where it was left out."""
        N = self.p.N
        d = np.full((N, NC), np.nan)
        d[tpl.nodes_mass, 0] = zdual[tpl.r_mass : tpl.r_mass + len(tpl.nodes_mass)]
        d[:, 6] = zdual[tpl.r_tmin : tpl.r_tmin + N]
        for (node, c), row in tpl.soc_rows.items():
            d[node, c] = zdual[row]
        return d

    # ---- Algorithm 1 / 2 ------------------------------------------------------------------
    def solve(
        self,
        guess: tuple[np.ndarray, np.ndarray, float] | None = None,
        masks: _Masks = None,
    ) -> SCvxResult:
        """Runs SCvx; with ``masks`` (per-iteration 7N masks, or a function k -> mask), T-SCvx.

        With masks the subproblems keep only the masked-in path constraints; before returning,
        the full constraint set is checked and any violated constraint that the mask dropped is
        put back for the remaining iterations (DESIGN.md: never return what the full problem
        rejects).
        """
        t_start = time.perf_counter()
        check_masks_argument(masks)
        checked: _Checked = (
            masks if masks is None or callable(masks) else mask_table(masks, self.p.N)
        )
        s = self._start(guess)
        if s is None:
            # No trajectory to return (the C library leaves x, u as given and t_f NaN).
            return self.no_trajectory("model evaluation failed at the initial guess", t_start)
        self.trace: list[np.ndarray] = []
        if self.log:
            self.log(_HEADER)
        for _ in range(self.st.max_subproblems):
            if s.k >= self.st.iter_max:
                break
            if s.ipm_used >= self.st.socp_max_iter_total:  # checked after iter_max, as in C
                self._budget_spent(s)
                break
            if not self._iteration(s, checked):
                break
        polish = self._polish(s) if s.status == "solved" else Polish()
        return self._result(s, t_start, polish)

    def _start(self, guess: tuple[np.ndarray, np.ndarray, float] | None) -> _LoopState | None:
        """The iterate at the guess (the initial guess when none is given), with the scaling
        it sets; None when the model cannot be evaluated there."""
        if guess is not None:  # used as given (not projected), as pdg_solve does
            x, u, t_f = checked_guess(guess, self.p.N)
        else:
            x, u, t_f = initial_guess(self.scn)
        self.sc = Scaling.for_scenario(self.scn, t_f)
        self.scales = constraint_scales(self.p, self.sc.Sx, self.sc.Su)
        self.lay = self.template(None).lay
        z = scaled(x, u, t_f, self.lay, self.sc)
        try:
            disc = self._discretize(z)
        except ModelEvaluationError:
            return None
        J, defect, viol = self.penalty(z, disc)
        return _LoopState(
            z, disc, J, defect, viol, self.st.eta_init, np.zeros(NC * self.p.N, dtype=bool)
        )

    def _iteration(self, s: _LoopState, masks: _Checked) -> bool:
        """One subproblem of Algorithm 1 (Algorithm 2 with masks); False when the solve stops
        (converged, failed or stalled)."""
        st = self.st
        # 1. mask (T-SCvx): the prediction, plus what the full-constraint guard put back
        pred = _mask_for(masks, s.k + 1, self.p.N)
        mask = None if pred is None else pred | s.forced
        tpl = self.template(mask)
        # 2. the convex subproblem about z with radius eta; 3. its solution on the full problem
        prob, sol = self._solve_subproblem(s, tpl)
        cand = self._candidate(s, tpl, prob, sol)
        if isinstance(cand, str):
            self._failed(s, sol, cand)
            return False
        # 4. acceptance and the next radius
        record, eta_new = self._judge(s, tpl, cand, sol, mask, pred, masks is not None)
        s.history.append(record)
        if self.log:
            self.log(_format(record))
        if record.accepted:
            self._succeed(s, cand, pred)
        # 5. convergence on the FULL constraint set; T-SCvx never returns what it rejects
        if record.accepted and self._converged(s, cand, record.dJ):
            step_met = cand.step <= st.step_tol
            s.status, s.reason = "solved", "converged" if step_met else CONVERGED_ON_COST
            return False
        if not record.accepted and not record.restored and s.eta <= st.eta_lb:
            # same reference, same radius: rejected forever
            if self._converged(s, cand):  # the reference meets every tolerance
                s.status, s.reason = "solved", CONVERGED_AT_REFERENCE
            else:
                s.stalled = True
            return False
        # the retry's warm start (a guard rejection at the same radius keeps the answer)
        if not record.accepted and s.last_sol is not None and eta_new < min(s.eta, cand.tr_step):
            f = RETRY_START * eta_new / cand.tr_step
            s.last_sol = _pulled_back(s.last_sol, s.z, f, self.lay)
        s.eta = eta_new
        return True

    def _failed(self, s: _LoopState, sol: ConicSolution, why: str) -> None:
        """The subproblem gave no candidate: a solver error, or the budget spent when the
        IPM stopped at its share of it."""
        s.history.append(_failed_record(s.k + 1, s.J, s.eta, sol))
        if sol.status == "max_iterations" and s.capped:
            self._budget_spent(s)
        else:
            s.status, s.reason = "solver_error", why
        if self.log:
            self.log(f"{s.k + 1:3d}  {s.reason}")

    def _solve_subproblem(
        self, s: _LoopState, tpl: SubproblemTemplate, polish: bool = False
    ) -> tuple[ConicProblem, ConicSolution]:
        """The subproblem about s.z with radius s.eta (the polish's: no fuel term, its own
        weight and tolerance), solved from the last solution."""
        st = self.st
        prox, fuel = (POLISH_WEIGHT, 0.0) if polish else (st.prox_u, 1.0)
        prob = tpl.assemble(s.disc, s.z, s.eta, st.lam, self.scn, self.sc, prox, fuel)
        if self.record:
            s.subproblems.append(prob)
        # the polish solves to a tighter tolerance, in a session of its own (key -1)
        key, tol = (-1, st.socp_tol * POLISH_TOL_FACTOR) if polish else (id(tpl), st.socp_tol)
        if key not in self._sessions:
            self._sessions[key] = conic.session(self.backend, tol, st.socp_max_iter)
        session = self._sessions[key]
        warm = s.last_sol is not None and st.socp_warm_start and session.warm_starts
        cap, warm = iteration_cap(st, s.ipm_used, warm)
        s.capped = cap < st.socp_max_iter
        start = None
        if warm and s.last_sol is not None and s.last_tpl is not None:
            # from a subproblem of another mask too, as the C loop, whose one pattern keeps
            # dropped rows empty (a point of another size was refused: a cold start)
            start = carry_solution(s.last_sol, s.last_tpl, tpl)
        sol = session.solve(prob, start, max_iter=cap)
        s.ipm_used += sol.iterations
        if sol.ok:
            s.last_sol, s.last_tpl = sol, tpl  # the next subproblem's IPM starts from it
        return prob, sol

    def _candidate(
        self, s: _LoopState, tpl: SubproblemTemplate, prob: ConicProblem, sol: ConicSolution
    ) -> _Candidate | str:
        """The subproblem's solution evaluated on the full nonlinear problem, or why there is
        none (the C library's reasons, pdg_scvx.c)."""
        if not sol.ok:
            return f"subproblem at iteration {s.k + 1}: conic solver returned {sol.status}"
        try:
            disc = self._discretize(sol.x)
        except ModelEvaluationError:
            return f"iteration {s.k + 1}: model evaluation failed at the subproblem solution"
        z = sol.x.copy()
        J, defect, viol = self.penalty(z, disc)
        xs, us, _ = physical(z, self.lay, self.sc)
        h = path_constraint_values(xs, us, self.p)
        n = self.lay.n_traj
        return _Candidate(
            z=z,
            disc=disc,
            J=J,
            defect=defect,
            viol=viol,
            L=self.linear_cost(prob, sol.x),
            vc=float(max(sol.x[self.lay.ivc :].sum(), 0.0)),
            step=float(np.abs(z[:n] - s.z[:n]).max()),
            tr_step=tpl.trust_norm(z - s.z),
            h=h,
            tight=tight_mask(h, self.scales, self._duals(tpl, sol.z), self.st.tight_tol),
        )

    def _judge(
        self,
        s: _LoopState,
        tpl: SubproblemTemplate,
        c: _Candidate,
        sol: ConicSolution,
        mask: np.ndarray | None,
        pred: np.ndarray | None,
        has_masks: bool,
    ) -> tuple[IterationRecord, float]:
        """rho = actual / predicted change, acceptance and the next radius (Eq. (15)); the
        full-constraint guard of T-SCvx may overrule. Returns the log record and the radius."""
        st = self.st
        s.vc = c.vc
        dJ, dL = s.J - c.J, s.J - c.L
        rho = dJ / dL if dL != 0.0 else float("nan")
        # dL <= 0 only when the subproblem gives the reference back (to the solver's
        # tolerance: the reference is feasible and the proximal term is >= 0). Algorithm 1
        # stops there (dJ = 0); here the step is accepted with rho = 1 and the convergence
        # test ends the solve, or not if the reference is still infeasible.
        accepted = dJ == 0.0 or dL <= 0.0 or rho >= st.rho0
        tau_r = _changed_fraction(s.prev_pred, pred) if has_masks and st.tau_r_update else None
        eta_new = _trust_update(s.eta, rho if dL > 0 else 1.0, accepted, c.tr_step, st, tau_r)
        restored = 0
        if mask is not None:
            # Full-constraint guard: a candidate that violates a constraint the mask dropped
            # is rejected, and the constraint is put back for the rest of the solve. The retry
            # starts from the same reference (which meets every convex constraint, so the
            # subproblem stays feasible). A step rho accepted is retried at the same radius
            # (the mask failed, not the linearization); one rho rejected too at the radius
            # contracted by alpha, as step 5 of Algorithm 2 rejects it. At the same radius
            # (until 28 Nov) that retry was rejected again 5 times of 6 (Algorithm 2 with the
            # networks, 21 landings), and with SCvx's own tight masks Algorithm 2 took 30.2
            # subproblems per landing instead of 24.9 (docs/tscvx.md). T_min is never dropped
            # (tpl.mask keeps it): its buffer is penalized instead.
            dropped = (c.h.reshape(-1) > st.defect_tol) & ~tpl.mask.reshape(-1)
            if dropped.any():
                s.forced |= dropped
                eta_new = s.eta if accepted else _guard_radius(s.eta, st)
                accepted, restored = False, int(dropped.sum())
        record = IterationRecord(
            s.k + 1,
            c.J,
            dJ,
            dL,
            rho,
            s.eta,
            c.vc,
            int(c.tight.sum()),
            sol.solve_time_s,
            accepted,
            sol.status,
            sol.iterations,
            restored,
        )
        return record, eta_new

    def _succeed(self, s: _LoopState, c: _Candidate, pred: np.ndarray | None) -> None:
        """The candidate becomes the iterate: succession k + 1."""
        s.k += 1
        s.prev_pred = pred
        s.mask_log.append(c.tight)
        s.z, s.disc, s.J, s.defect, s.viol = c.z, c.disc, c.J, c.defect, c.viol
        self.trace.append(s.z.copy())

    def _converged(self, s: _LoopState, c: _Candidate, dJ: float = math.inf) -> bool:
        """The convergence test: the step within step_tol, or the change of J it made (dJ,
        accepted steps only) within cost_tol; the virtual control within vc_tol; the iterate
        (the candidate when accepted) within defect_tol."""
        st = self.st
        return (
            (c.step <= st.step_tol or abs(dJ) <= st.cost_tol)
            and s.vc <= st.vc_tol
            and s.defect <= st.defect_tol
            and s.viol <= st.defect_tol
        )

    def _polish(self, s: _LoopState) -> Polish:
        """Beyond the paper: the converged iterate's defects removed by one subproblem about
        it on the full constraint set, with the fuel term out and the trust radius at eta_ub
        (the step is of the defects' size): min lambda (sum t + sum s') + (POLISH_WEIGHT /
        2) |u_hat - u_hat_ref|^2 moves the thrust least among the trajectories that meet the
        linearized dynamics, whose nonlinear defects are then of the order of the step
        squared. Kept when it leaves no virtual control, smaller defects and every path
        constraint met (the C library's polish, pdg_scvx.c)."""
        st = self.st
        x, _, _ = physical(s.z, self.lay, self.sc)
        before = Polish(defect_before=s.defect, m_f_before=float(x[-1, IM]))
        if not st.polish or st.prox_u == 0.0:
            return before
        if s.ipm_used >= st.socp_max_iter_total:
            return replace(before, outcome="no_budget")
        s.eta = st.eta_ub
        _, sol = self._solve_subproblem(s, self.template(None), polish=True)
        done = replace(before, ipm_iterations=sol.iterations)
        if not sol.ok:
            budget = sol.status == "max_iterations" and s.capped
            return replace(done, outcome="no_budget" if budget else "failed")
        try:
            disc = self._discretize(sol.x)
        except ModelEvaluationError:
            return replace(done, outcome="failed")
        J, defect, viol = self.penalty(sol.x, disc)
        vc = float(max(sol.x[self.lay.ivc :].sum(), 0.0))
        if vc > st.vc_tol or not defect < s.defect or viol > st.defect_tol:
            return replace(done, outcome="not_better")
        s.z, s.disc, s.J, s.defect, s.viol = sol.x.copy(), disc, J, defect, viol
        return replace(done, outcome="kept")

    def _budget_spent(self, s: _LoopState) -> None:
        """The solve's IPM iteration budget is spent: the result is the last accepted iterate
        (the C library's message, pdg_scvx.c budget_spent)."""
        s.spent, s.status = True, "max_iterations"
        total = self.st.socp_max_iter_total
        # fewer used than the budget: the last subproblem ran out of its share
        share = "; the last subproblem stopped at its share" if s.ipm_used < total else ""
        s.reason = (
            f"{BUDGET_SPENT} ({s.ipm_used} of socp_max_iter_total = {total}{share}) after "
            f"{s.k} iterations; the last accepted iterate has largest nonlinear defect "
            f"{s.defect:.2e}, largest path-constraint value {s.viol:.2e}"
        )

    def _result(self, s: _LoopState, t_start: float, polish: Polish) -> SCvxResult:
        status, reason = s.status, s.reason
        if status == "max_iterations" and not s.spent:
            status, reason = self._diagnose(s.z, s.vc, s.defect, s.viol, s.k)
            if s.stalled:
                reason = stalled_reason(self.st.eta_lb, reason)
        x, u, t_f = physical(s.z, self.lay, self.sc)
        N = self.p.N
        return SCvxResult(
            status=status,
            reason=reason,
            x=x,
            u=u,
            t_f=t_f,
            iterations=s.k,
            subproblems_solved=len(s.history),
            solve_time_s=time.perf_counter() - t_start,
            history=s.history,
            masks=np.array(s.mask_log, dtype=np.uint8).reshape(len(s.mask_log), NC * N),
            max_defect=s.defect,
            max_violation=s.viol,
            subproblems=s.subproblems,
            settings=self.st,
            polish=polish,
        )

    def no_trajectory(self, reason: str, t_start: float) -> SCvxResult:
        """The result of a solve that stopped before its first subproblem (``t_start``:
        its time.perf_counter() start)."""
        nan = float("nan")
        N = self.p.N
        return SCvxResult(
            status="solver_error",
            reason=reason,
            x=np.full((N, NX), nan),
            u=np.full((N, NU), nan),
            t_f=nan,
            iterations=0,
            subproblems_solved=0,
            solve_time_s=time.perf_counter() - t_start,
            masks=np.zeros((0, NC * N), np.uint8),
            settings=self.st,
        )

    def _diagnose(
        self, z: np.ndarray, vc: float, defect: float, viol: float, k: int
    ) -> tuple[str, str]:
        """Why the iteration limit was hit: infeasible (virtual control left) or not converged."""
        st = self.st
        if vc <= st.vc_tol:
            return "max_iterations", not_converged_reason(k, defect, viol)
        x, _, _ = physical(z, self.lay, self.sc)
        disc = self._discretize(z)
        rel = np.abs((x[1:] - disc["x_next"]) / self.sc.Sx[None, :])
        interval, i = np.unravel_index(int(np.argmax(rel)), rel.shape)
        at_floor = bool(x[-1, IM] <= self.p.m_dry + 1e-6 * self.sc.Sx[IM])
        return "infeasible", infeasible_reason(
            vc, st.vc_tol, k, defect, int(interval), STATE_NAMES[i], at_floor
        )


_HEADER = "  k        J         dJ         dL        rho    radius   |vc|_1  tight  sub[ms]  step"


def block_norm_sum(d: np.ndarray) -> float:
    """Sum over intervals of the virtual-control norm: |d_i| for scalar states, 2-norm of pairs."""
    total = float(np.abs(d[:, list(TR_SCALAR_STATES)]).sum())
    for a, b in TR_PAIRS:
        total += float(np.hypot(d[:, a], d[:, b]).sum())
    return total


def format_log(history: list[IterationRecord]) -> list[str]:
    """The iteration log as printed while solving: a header and one line per subproblem."""
    return [_HEADER, *(_format(r) for r in history)]


def _format(r: IterationRecord) -> str:
    return (
        f"{r.k:3d} {r.J:10.5f} {r.dJ:10.3e} {r.dL:10.3e} {r.rho:8.3f} {r.eta:9.4f} "
        f"{r.vc_norm1:8.1e} {r.n_tight:6d} {1e3 * r.subproblem_time_s:8.1f}  "
        f"{step_label(r.accepted, r.restored)}"
    )


def iteration_cap(st: SCvxSettings, used: int, warm: bool) -> tuple[int, bool]:
    """The IPM iteration limit of the next subproblem when ``used`` iterations of the
    solve's budget (``st.socp_max_iter_total``) are spent, and whether it may be warm-started:
    what is left, half of it when warm-started (the flight runtime runs a failed warm start
    again cold, with the same limit), ``st.socp_max_iter`` at most; a single iteration left
    is run cold. 0 when the budget is spent (the C library's iteration_cap, pdg_scvx.c)."""
    left = st.socp_max_iter_total - used
    if left <= 0:
        return 0, False
    warm = warm and left >= 2
    return min(left // 2 if warm else left, st.socp_max_iter), warm


def _failed_record(k: int, J: float, eta: float, sol: conic.ConicSolution) -> IterationRecord:
    nan = float("nan")
    return IterationRecord(
        k, J, nan, nan, nan, eta, nan, 0, sol.solve_time_s, False, sol.status, sol.iterations
    )


def mask_bits(mask: object, N: int, k: int) -> np.ndarray:
    """Iteration k's mask as 7N booleans: a vector of 7N entries or an N x 7 array
    (node-major either way) of bits, bools or numbers equal to 0 or 1; InputError otherwise.
    Read as nonzero = keep, a network's probabilities (never exactly 0) would keep every
    constraint without a word. Both loops (this one and the C library's through
    guidance.cguidance) read masks through it."""
    a = np.asarray(mask)
    if a.shape not in ((NC * N,), (N, NC)) or a.dtype.kind not in "biuf":
        raise InputError(
            f"masks: iteration {k}'s mask is {a.shape} {a.dtype} values, not 7N = {NC * N} "
            f"numbers (or N x 7 = {N} x {NC})"
        )
    a = a.reshape(-1)
    if a.dtype != bool:
        odd = a[~np.isin(a, (0, 1))]
        if odd.size:
            raise InputError(
                f"masks: iteration {k}'s mask holds {odd[0].item()!r} ({odd.size} values not "
                "0 or 1): give 0/1 bits (threshold the network's probabilities first)"
            )
    return a != 0


def check_masks_argument(masks: object) -> None:
    """A ``masks`` argument is a table (a sequence or an array of masks), a function
    k -> mask, or None; anything else (True, a number, a string, a dict) is refused here
    by name instead of a TypeError from len() deep in the loop."""
    if masks is None or callable(masks):
        return
    if isinstance(masks, np.ndarray) and masks.ndim >= 1:
        return
    if isinstance(masks, Sequence) and not isinstance(masks, (str, bytes, bytearray)):
        return
    raise InputError(
        "masks: expected a table of masks (one per iteration), a function k -> mask, or "
        f"None; got {describe(masks)}"
    )


def mask_table(masks: Sequence[object], N: int) -> list[np.ndarray]:
    """A table of masks (row k - 1 for iteration k, the last one repeating) checked row by
    row. One lone mask is refused: read as a table it would be 7N masks of one entry each."""
    if isinstance(masks, np.ndarray) and (masks.ndim == 1 or masks.shape == (N, NC)):
        raise InputError(
            f"masks: one mask of shape {masks.shape}; give a table of masks, one per "
            "iteration ([mask] for the same mask at every iteration), or a function k -> mask"
        )
    if len(masks) == 0:
        raise InputError("masks: an empty table; give at least one mask, or None")
    return [mask_bits(m, N, k) for k, m in enumerate(masks, start=1)]


def _mask_for(masks: _Checked, k: int, N: int) -> np.ndarray | None:
    """Iteration k's mask (checked), None for the full problem."""
    if masks is None:
        return None
    if callable(masks):
        m = masks(k)
        return None if m is None else mask_bits(m, N, k)
    return masks[min(k, len(masks)) - 1]


def _changed_fraction(prev: np.ndarray | None, cur: np.ndarray | None) -> float:
    """tau_r of Algorithm 2: the fraction of bits in which the predicted masks of two
    successive successions differ (0 at the first, or without a prediction)."""
    if prev is None or cur is None:
        return 0.0
    return float(np.mean(np.asarray(prev, bool) != np.asarray(cur, bool)))


# _retry_radius: a radius more than RETRY_MARGIN above the rejected step counts as holding it
# and is skipped (one within the margin is solved: the safe side); at most RETRY_SKIP_MAX are
# skipped (a bound for alpha near 1). The C library has the same.
RETRY_MARGIN = 1.001
RETRY_SKIP_MAX = 64

# The polish (SCvxSettings.polish, SCvxSolver._polish; C: pdg_scvx.c, the same numbers): its
# objective is lambda (sum t + sum s') + (POLISH_WEIGHT / 2) |u_hat - u_hat_ref|^2, solved to
# POLISH_TOL_FACTOR x socp_tol. Its optimum lies within about sqrt(2 gap / POLISH_WEIGHT) of
# where an IPM stops, and the whole objective is only about 1e-8: at the subproblems' 1e-9,
# with the weight prox_u = 0.02, Clarabel and the C runtime stopped 1.5e-5 apart in final mass
# on the default landing, with weight 1 at 1e-11 7.6e-9 apart (27 Nov). A weight much larger
# than 1 is no longer balanced by the penalty lambda: at 1e4 virtual control was left.
POLISH_WEIGHT = 1.0
POLISH_TOL_FACTOR = 1e-2

# The interior-point method of a retry starts from the rejected answer with its trajectory
# part pulled back towards the reference, to RETRY_START of the new radius: the retry's answer
# lies near there, on or inside the smaller trust region, and the rejected one outside it
# (4 % fewer IPM iterations on the catalog: docs/socp-runtime.md, "Warm start"). The C
# library does the same.
RETRY_START = 0.99


def _pulled_back(sol: ConicSolution, z: np.ndarray, f: float, lay: Layout) -> ConicSolution:
    """sol with its trajectory part at z + f (sol.x - z), the rest as it is."""
    x = sol.x.copy()
    n = lay.n_traj
    x[:n] = z[:n] + f * (sol.x[:n] - z[:n])
    return replace(sol, x=x)


def _retry_radius(eta: float, tr_step: float, st: SCvxSettings) -> float:
    """The radius after a rejection. The retry has the same reference and data, only a smaller
    radius: every radius eta / alpha^j that still holds the rejected step (tr_step, in the
    trust region's norm) gives the same step back and is rejected again, so those solves are
    skipped. Eq. (15)'s radius sequence is unchanged."""
    eta = eta / st.alpha
    for _ in range(RETRY_SKIP_MAX):
        if not (eta > st.eta_lb and eta > RETRY_MARGIN * tr_step):
            break
        eta = eta / st.alpha
    return max(eta, st.eta_lb)


def _guard_radius(eta: float, st: SCvxSettings) -> float:
    """The radius after a guard rejection of a step rho rejected too (_judge): eta / alpha.
    _retry_radius's skipping does not apply: the retry has another constraint, so a radius
    that holds the rejected step need not give it back (C: pdg_scvx.c guard_radius)."""
    return max(eta / st.alpha, st.eta_lb)


def _trust_update(
    eta: float,
    rho: float,
    accepted: bool,
    tr_step: float,
    st: SCvxSettings,
    tau_r: float | None,
) -> float:
    """Eq. (15); with tau_r (T-SCvx) the factors become alpha^tau_r and beta^(1 - tau_r)."""
    shrink = st.alpha if tau_r is None else st.alpha**tau_r
    grow = st.beta if tau_r is None else st.beta ** (1.0 - tau_r)
    if not accepted:
        # Algorithm 2 divides by alpha^tau_r here, which is 1 when the mask did not change and
        # would retry the same rejected step forever; a rejection always contracts.
        eta = _retry_radius(eta, tr_step, st)
    elif rho < st.rho1:
        eta = eta / shrink
    elif rho >= st.rho2:
        eta = eta * grow
    return float(min(max(eta, st.eta_lb), st.eta_ub))


def solve_scvx(
    scenario: Scenario,
    settings: SCvxSettings | None = None,
    backend: str = "clarabel",
    log: Callable[[str], None] | None = None,
) -> SCvxResult:
    return SCvxSolver(scenario, settings, backend, log).solve()


def collect_subproblems(scenario: Scenario, settings: SCvxSettings | None = None) -> list:
    """Every convex subproblem met while solving ``scenario`` with the Clarabel backend."""
    return SCvxSolver(scenario, settings, "clarabel", record_subproblems=True).solve().subproblems


__all__ = ["NX", "SCvxResult", "SCvxSolver", "collect_subproblems", "initial_guess", "solve_scvx"]
