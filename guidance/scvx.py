"""Successive convexification (paper Algorithm 1) and its T-SCvx variant (Algorithm 2).

The penalty J (paper Eq. (12)) is always evaluated on the FULL constraint set, on the scaled
variables of ``guidance.subproblem``:

    J(z) = -m_hat(t_f) + lambda * ( sum_k |Sx^-1 (x_{k+1} - F(x_k, u_k, u_{k+1}, sigma))|_1
                                    + sum_{k,c} max(0, h_c(x_k, u_k)) / scale_c )

and the subproblem's optimal value is the predicted cost L (Eq. (13)). A step is accepted when
rho = dJ / dL >= rho0; the trust radius follows Eq. (15), or its tau_r-scaled form in T-SCvx.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from guidance import conic
from guidance.conic import ConicProblem, ConicSolution
from guidance.constraints import constraint_scales, path_constraint_values, tight_mask
from guidance.errors import InputError, ModelEvaluationError
from guidance.guess import initial_guess, is_finite_guess
from guidance.model import discretize, vehicle_pattern
from guidance.params import IM, NC, NU, NX, Scenario, SCvxSettings
from guidance.subproblem import (
    TR_PAIRS,
    TR_SCALAR_STATES,
    Layout,
    Scaling,
    SubproblemTemplate,
    physical,
    scaled,
)

STATE_NAMES = ("r1", "r2", "r3", "v1", "v2", "v3", "q0", "q1", "q2", "q3", "w1", "w2", "w3", "m")


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


def step_label(accepted: bool, restored: int) -> str:
    """The log's last column: a guard rejection (same radius) reads apart from a rho one."""
    if accepted:
        return "acc"
    return f"rej, {restored} put back" if restored else "rej"


@dataclass
class SCvxResult:
    status: str  # "solved" | "infeasible" | "max_iterations" | "solver_error"
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

    @property
    def final_mask(self) -> np.ndarray:
        return self.masks[-1] if len(self.masks) else np.zeros(0, np.uint8)

    @property
    def m_f(self) -> float:
        return float(self.x[-1, IM])


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
        self.scn = scenario
        self.p = scenario.params
        self.st = settings or SCvxSettings()
        self.backend = backend
        self.log = log
        self.record = record_subproblems
        self._templates: dict[bytes, SubproblemTemplate] = {}
        self._sessions: dict[int, conic.Session] = {}  # conic solver per sparsity pattern
        self.engine = self.st.discretization
        if self.engine == "auto":
            from guidance import cgnc

            self.engine = "c" if cgnc.available() else "casadi"

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
        return discretize(x, u, t_f, self.p, self.st.rk4_substeps, self.engine)

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
        masks: Callable[[int], np.ndarray | None] | Sequence[np.ndarray] | None = None,
    ) -> SCvxResult:
        """Runs SCvx; with ``masks`` (per-iteration 7N masks, or a function k -> mask), T-SCvx.

        With masks the subproblems keep only the masked-in path constraints; before returning,
        the full constraint set is checked and any violated constraint that the mask dropped is
        put back for the remaining iterations (DESIGN.md: never return what the full problem
        rejects).
        """
        t_start = time.perf_counter()
        st, p = self.st, self.p
        if guess is not None:  # used as given; the C library refuses the same (pdg_solve)
            x, u, t_f = np.asarray(guess[0], float), np.asarray(guess[1], float), float(guess[2])
            if not (is_finite_guess(x, u, t_f) and t_f > 0.0):
                raise InputError("guess: x, u and t_f must be finite and t_f positive")
        else:
            x, u, t_f = initial_guess(self.scn)
        self.sc = Scaling.for_scenario(self.scn, t_f)
        self.scales = constraint_scales(p, self.sc.Sx, self.sc.Su)
        self.lay = self.template(None).lay
        z = scaled(x, u, t_f, self.lay, self.sc)
        try:
            disc = self._discretize(z)
        except ModelEvaluationError:
            # No trajectory to return (the C library leaves x, u as given and t_f NaN).
            return self.no_trajectory("model evaluation failed at the initial guess", t_start)
        J, defect, viol = self.penalty(z, disc)
        eta = st.eta_init
        history: list[IterationRecord] = []
        mask_log: list[np.ndarray] = []
        subproblems: list[ConicProblem] = []
        status, reason = "max_iterations", "iteration limit reached"
        # tau_r (Algorithm 2, step 4) compares the predicted masks of successions k+1 and k:
        # prev_pred is the prediction of the last accepted succession (a retry keeps it).
        prev_pred: np.ndarray | None = None
        forced = np.zeros(NC * p.N, dtype=bool)  # constraints put back by the full check
        vc = float("inf")
        self.trace: list[np.ndarray] = []
        if self.log:
            self.log(_HEADER)
        stalled = False
        last_sol: ConicSolution | None = None
        k = 0  # successions (accepted steps); rejected steps retry the same k (Algorithm 1)
        for _ in range(st.max_subproblems):
            if k >= st.iter_max:
                break
            pred = _mask_for(masks, k + 1)
            mask = None if pred is None else np.asarray(pred, dtype=bool) | forced
            tpl = self.template(mask)
            prob = tpl.assemble(disc, z, eta, st.lam, self.scn, self.sc, st.prox_u)
            if self.record:
                subproblems.append(prob)
            if id(tpl) not in self._sessions:
                self._sessions[id(tpl)] = conic.session(self.backend, st.socp_tol, st.socp_max_iter)
            sol = self._sessions[id(tpl)].solve(prob, last_sol if st.socp_warm_start else None)
            if sol.ok:
                last_sol = sol  # the next subproblem's IPM starts from it (as the C loop)
            failure = None  # no candidate: the C library's reasons (pdg_scvx.c)
            if not sol.ok:
                failure = f"subproblem at iteration {k + 1}: conic solver returned {sol.status}"
            else:
                try:
                    disc_new = self._discretize(sol.x)
                except ModelEvaluationError:
                    failure = (
                        f"iteration {k + 1}: model evaluation failed at the subproblem solution"
                    )
            if failure is not None:
                status, reason = "solver_error", failure
                history.append(_failed_record(k + 1, J, eta, sol))
                if self.log:
                    self.log(f"{k + 1:3d}  {reason}")
                break
            z_new = sol.x.copy()
            J_new, defect_new, viol_new = self.penalty(z_new, disc_new)
            L = self.linear_cost(prob, sol.x)
            dJ, dL = J - J_new, J - L
            vc = float(max(sol.x[self.lay.ivc :].sum(), 0.0))
            xs, us, _ = physical(z_new, self.lay, self.sc)
            h = path_constraint_values(xs, us, p)
            tmask = tight_mask(h, self.scales, self._duals(tpl, sol.z), st.tight_tol)
            rho = dJ / dL if dL != 0.0 else float("nan")
            step = float(np.abs(z_new[: self.lay.n_traj] - z[: self.lay.n_traj]).max())
            tr_step = tpl.trust_norm(z_new - z)
            # dL <= 0 only when the subproblem gives the reference back (to the solver's
            # tolerance: the reference is feasible and the proximal term is >= 0). Algorithm 1
            # stops there (dJ = 0); here the step is accepted with rho = 1 and the convergence
            # test below ends the solve, or not if the reference is still infeasible.
            accepted = dJ == 0.0 or dL <= 0.0 or rho >= st.rho0
            use_tau = masks is not None and st.tau_r_update
            tau_r = _changed_fraction(prev_pred, pred) if use_tau else None
            eta_new = _trust_update(eta, rho if dL > 0 else 1.0, accepted, tr_step, st, tau_r)
            newly_forced, restored = False, 0
            if mask is not None:
                # Full-constraint guard: a candidate that violates a constraint the mask
                # dropped is rejected, and the constraint is put back for the rest of the solve.
                # The retry starts from the same reference (which meets every convex
                # constraint, so the subproblem stays feasible) with the same radius.
                # T_min is never dropped (tpl.mask keeps it): its buffer is penalized instead.
                dropped = (h.reshape(-1) > st.defect_tol) & ~tpl.mask.reshape(-1)
                if dropped.any():
                    forced |= dropped
                    newly_forced, accepted, eta_new = True, False, eta
                    restored = int(dropped.sum())
            history.append(
                IterationRecord(
                    k + 1,
                    J_new,
                    dJ,
                    dL,
                    rho,
                    eta,
                    vc,
                    int(tmask.sum()),
                    sol.solve_time_s,
                    accepted,
                    sol.status,
                    sol.iterations,
                    restored,
                )
            )
            if self.log:
                self.log(_format(history[-1]))
            if accepted:
                k += 1
                prev_pred = pred
                mask_log.append(tmask)
                z, disc, J, defect, viol = z_new, disc_new, J_new, defect_new, viol_new
                self.trace.append(z.copy())
            converged = accepted and (
                step <= st.step_tol
                and vc <= st.vc_tol
                and defect <= st.defect_tol
                and viol <= st.defect_tol
            )
            if converged:
                status, reason = "solved", "converged"
                break
            if not accepted and eta <= st.eta_lb and not newly_forced:
                # Same reference, same radius: the same step would be rejected forever.
                stalled = True
                break
            if not accepted and not newly_forced and last_sol is not None and eta_new < tr_step:
                last_sol = _pulled_back(last_sol, z, RETRY_START * eta_new / tr_step, self.lay)
            eta = eta_new
        if status == "max_iterations":
            status, reason = self._diagnose(z, vc, defect, viol, k)
            if stalled:
                reason = f"step rejected at the smallest trust radius {st.eta_lb:g}; " + reason
        x, u, t_f = physical(z, self.lay, self.sc)
        return SCvxResult(
            status=status,
            reason=reason,
            x=x,
            u=u,
            t_f=t_f,
            iterations=k,
            subproblems_solved=len(history),
            solve_time_s=time.perf_counter() - t_start,
            history=history,
            masks=np.array(mask_log, dtype=np.uint8).reshape(len(mask_log), NC * p.N),
            max_defect=defect,
            max_violation=viol,
            subproblems=subproblems,
            settings=st,
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
            return "max_iterations", (
                f"not converged after {k} iterations; virtual control is zero, largest "
                f"defect {defect:.2e}, largest path-constraint value {viol:.2e}"
            )
        x, _, _ = physical(z, self.lay, self.sc)
        disc = self._discretize(z)
        rel = np.abs((x[1:] - disc["x_next"]) / self.sc.Sx[None, :])
        interval, i = np.unravel_index(int(np.argmax(rel)), rel.shape)
        parts = [f"virtual control {vc:.3g} > {st.vc_tol:g} after {k} iterations"]
        parts.append(f"largest defect {defect:.3g} at interval {interval}, state {STATE_NAMES[i]}")
        if x[-1, IM] <= self.p.m_dry + 1e-6 * self.sc.Sx[IM]:
            parts.append(f"mass at the floor (m_f = {x[-1, IM]:.6f} = m_dry): not enough fuel")
        return "infeasible", "; ".join(parts)


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


def _failed_record(k: int, J: float, eta: float, sol: conic.ConicSolution) -> IterationRecord:
    nan = float("nan")
    return IterationRecord(
        k, J, nan, nan, nan, eta, nan, 0, sol.solve_time_s, False, sol.status, sol.iterations
    )


def _mask_for(
    masks: Callable[[int], np.ndarray | None] | Sequence[np.ndarray] | None, k: int
) -> np.ndarray | None:
    if masks is None:
        return None
    if callable(masks):
        return masks(k)
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
# The interior-point method of a retry starts from the rejected answer with its trajectory
# part pulled back towards the reference, to RETRY_START of the new radius: the retry's answer
# lies near there, on or inside the smaller trust region, and the rejected one outside it
# (4 % fewer IPM iterations on the catalog: README, "Warm start"). The C library does the
# same.
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
