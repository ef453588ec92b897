"""Problem parameters: the one place that defines every number of the landing problem.

Values are paper Table 1 in nondimensional units (U_L, U_T, U_M); the derived values follow
DESIGN.md. Field names are exactly the keys of the trajectory ``params`` contract, so a
scenario JSON may override any of them by name.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from guidance.errors import InputError

# State layout (DESIGN.md): r_I (3), v_I (3), q_B<-I (4, scalar first), omega_B (3), m (1).
NX = 14
NU = 3
IR = slice(0, 3)
IV = slice(3, 6)
IQ = slice(6, 10)
IW = slice(10, 13)
IM = 13
# The parts the path constraints read: the inertial x axis points up (g = (-|g|, 0, 0)) and the
# body x axis is the thrust axis, so altitude is r1, the horizontal position (r2, r3), the tilt
# of the thrust axis from vertical |(q2, q3)|, and the thrust's axial component u1.
I_UP = 0
I_HORIZONTAL = slice(1, 3)
I_TILT = slice(8, 10)
U_AXIAL = 0
U_LATERAL = slice(1, 3)

# Path constraints per node, in mask order (bit 7k + c).
CONSTRAINT_NAMES = (
    "mass",  # 0  m >= m_dry
    "glideslope",  # 1  tan(gs) |(r2, r3)| <= r1
    "tilt",  # 2  |(q2, q3)| <= sqrt((1 - cos(tilt_max)) / 2)
    "omega",  # 3  |omega| <= omega_max
    "thrust_max",  # 4  |T| <= T_max
    "gimbal",  # 5  cos(delta_max) |T| <= T1
    "thrust_min",  # 6  T_min <= |T|   (nonconvex)
)
NC = len(CONSTRAINT_NAMES)
# Constraints every subproblem keeps whatever their mask bit (T_min: nonconvex, its buffer is
# penalized instead; c_runtime/guidance/pdg_scvx.c keeps the same in keep[]).
ALWAYS_KEPT = ("thrust_min",)

# Table 1 quantities from which the contract's derived values are computed.
I_SP = 30.0  # U_T, specific impulse (g0 = 1)
P_AMB = 0.1  # ambient pressure
A_NOZ = 0.5  # nozzle exit area
RHO_SA_CA = 0.2  # rho * S_A * C_A, aerodynamic drag product


@dataclass(frozen=True)
class Params:
    """Vehicle, environment, constraints, boundary conditions and discretization size."""

    g_I: tuple[float, float, float] = (-1.0, 0.0, 0.0)
    J_B: tuple[float, float, float] = (0.001, 0.01, 0.01)  # diagonal of J_B
    r_T_B: tuple[float, float, float] = (-0.01, 0.0, 0.0)
    r_cp_B: tuple[float, float, float] = (0.0, 0.0, 0.0)
    alpha_mdot: float = 1.0 / I_SP  # 1 / (I_sp g0)
    beta_mdot: float = P_AMB * A_NOZ / I_SP  # alpha_mdot * P_amb * A_noz (back-pressure loss)
    aero_coeff: float = 0.5 * RHO_SA_CA  # c_A in A_B = -c_A |v_B| v_B
    m_dry: float = 2.0
    T_min: float = 0.3
    T_max: float = 5.0
    gimbal_max_deg: float = 20.0
    tilt_max_deg: float = 90.0
    glideslope_deg: float = 20.0
    omega_max_deg: float = 90.0  # deg / U_T
    r_f: tuple[float, float, float] = (0.0, 0.0, 0.0)
    v_f: tuple[float, float, float] = (-0.1, 0.0, 0.0)
    q_f: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    omega_f: tuple[float, float, float] = (0.0, 0.0, 0.0)
    final_roll_free: bool = True  # True: only q2(t_f) = q3(t_f) = 0; False: q(t_f) = q_f
    N: int = 50

    # ---- derived quantities (radians, cone constants) -------------------------------------
    @property
    def omega_max(self) -> float:
        return math.radians(self.omega_max_deg)

    @property
    def cos_gimbal(self) -> float:
        return math.cos(math.radians(self.gimbal_max_deg))

    @property
    def tan_glideslope(self) -> float:
        return math.tan(math.radians(self.glideslope_deg))

    @property
    def tilt_q_max(self) -> float:
        """Bound on |(q2, q3)| equivalent to the tilt limit: sqrt((1 - cos tilt_max) / 2)."""
        return math.sqrt((1.0 - math.cos(math.radians(self.tilt_max_deg))) / 2.0)

    @property
    def roll_decoupled(self) -> bool:
        """True when no torque acts about body axis 1, so omega_1 is constant in time."""
        J = self.J_B
        off_axis = (self.r_T_B[1], self.r_T_B[2], self.r_cp_B[1], self.r_cp_B[2])
        return J[1] == J[2] and all(c == 0.0 for c in off_axis)

    def to_json_dict(self) -> dict:
        return {f.name: _plain(getattr(self, f.name)) for f in dataclasses.fields(self)}

    def replace(self, **changes: Any) -> Params:
        return dataclasses.replace(self, **changes)


def _plain(value: object) -> object:
    if isinstance(value, tuple):
        return [float(v) for v in value]
    return value


# The grids the solvers take: N nodes in [N_MIN, N_MAX] (the C library's PDG_N_MIN, PDG_N_MAX).
N_MIN, N_MAX = 3, 400

PARAM_NAMES = tuple(f.name for f in dataclasses.fields(Params))
VECTOR_PARAM_SIZES = {
    f.name: len(f.default) for f in dataclasses.fields(Params) if isinstance(f.default, tuple)
}


# Integer settings and their ranges (the flight library's bounds on its fixed-size loops).
DISCRETIZATIONS = ("auto", "c", "casadi")  # SCvxSettings.discretization
INT_SETTING_RANGES = {
    "iter_max": (1, 100),
    "max_subproblems": (1, 500),
    "rk4_substeps": (1, 64),
    "socp_max_iter": (1, 500),
    "socp_max_iter_total": (1, 500_000),  # PDG_MAX_ITER_TOTAL
}


# Largest penalty weight lambda (C: PDG_LAM_MAX). The exact penalty needs lambda above the
# subproblems' multipliers (Table 1: 500); 1e8 solves as the Clarabel reference does
# (tests/test_cguidance.py), while at 1e12 Clarabel called the first subproblem of the default
# landing dual infeasible where the C runtime solved it, and at 1e300 every backend failed there.
LAM_MAX = 1e8

# Smallest trust-region shrink factor alpha (C: PDG_ALPHA_MIN). A rejected step is retried at
# eta / alpha: at alpha = 1 at the same radius, so the same step comes back and is rejected
# until max_subproblems is spent (the default landing: "not converged after 0 iterations"), and
# just above 1 it is hardly better. Over the 11 catalog landings (C library, 27 Nov): at
# alpha = 1.001 none solved and each accepted 0 to 4 steps in 60 subproblems (low_fast was
# called infeasible, which it is not); with the largest budget the settings allow (iter_max
# 100, max_subproblems 500) 1.01 solved 1 of them (low_fast infeasible again within 60), 1.05
# 10 and 1.1 all 11 (Table 1's 2: 11 within the default budget). beta = 1 (no growth) is valid.
ALPHA_MIN = 1.1

# Largest proximal weight prox_u (C: PDG_PROX_U_MAX). The term shortens every step, and SCvx
# stops on the step's size (step_tol), so a heavier weight stops it short of the optimum and
# calls that solved. Over the 11 catalog landings (C library, 27 Nov; docs/scvx.md, "Beyond the
# paper") the final masses against prox_u = 0.02 were, median (best): +3.4e-4 (+1.3e-3) at
# 0.01, -5.6e-4 (+4.8e-4) at 0.03, the spread of the local optima; -1.7e-3 (-2.5e-4) at 0.05,
# every landing lighter; at 0.1 -3.9e-3 and 6 of 11 out of iterations, 0.2 to 1 none solved,
# and 10 "solved" all 11, 5.5e-2 lighter (11 % more propellant). 0.03 is the largest weight
# whose answers are not lighter than the default's across the board; it is also the top of
# the 55-landing sweep that chose 0.02.
PROX_U_MAX = 0.03


# RK4 steps over the whole normalized time [0, 1] at least: 2 per interval at N = 50, the grid
# whose discretization error rk4_substeps = 2 was chosen for. With a fixed count per interval
# the error grew with the interval (a step's error like its length^5): at N = 10 the default
# landing, reported solved, missed its landing point open loop by 9.8e-3 (the tolerance is
# 1e-3); with 11 steps per interval by 2.7e-5 (the C library; 7.6e-5 the Python reference).
RK4_MIN_STEPS_TOTAL = 98


def rk4_steps_per_interval(substeps: int, N: int) -> int:
    """RK4 steps of each of the N - 1 FOH intervals: ``substeps`` (SCvxSettings.rk4_substeps)
    at least, and enough that the N - 1 intervals take RK4_MIN_STEPS_TOTAL steps together
    (at most 49, at N = 3). N < 3 (no grid the solvers take) gives ``substeps``. The C
    library's rule is the same (pdg_rk4_steps)."""
    if N < N_MIN:
        return substeps
    return max(substeps, -(-RK4_MIN_STEPS_TOTAL // (N - 1)))


@dataclass(frozen=True)
class SCvxSettings:
    """Paper Algorithm 1 / 2 settings (Table 1), plus this implementation's tolerances."""

    lam: float = 500.0  # penalty weight lambda on virtual control and buffers
    rho0: float = 0.0
    rho1: float = 0.1
    rho2: float = 0.7
    alpha: float = 2.0  # trust-region shrink factor
    beta: float = 2.0  # trust-region growth factor
    eta_init: float = 2.0  # initial trust radius (full); 0.01 for reduced problems
    eta_lb: float = 0.001
    eta_ub: float = 10.0
    iter_max: int = 20  # successions k (accepted steps)
    max_subproblems: int = 60  # bound on subproblem solves, rejected steps included
    # Convergence: an accepted step whose scaled infinity-norm is below step_tol or whose
    # actual change of the penalty cost |dJ| (paper Eq. (16); J in scaled units, its fuel
    # term the final mass over the propellant budget m0 - m_dry) is below cost_tol (paper
    # Algorithm 1's dJ <= eps_tol), whose virtual control and buffers are below vc_tol
    # (scaled units), and whose nonlinear defects are below defect_tol.
    step_tol: float = 5e-3
    # The paper's eps_tol stops a creep the step test never ends: re-planned from its own
    # plan, the default landing crept along a flat valley of J (steps of 1e-2, dJ 1e-6 each)
    # and converged at 18 of its 20 iterations, or at none when the last bits moved (docs/
    # scvx.md, "Convergence"). 1e-5 (of the propellant budget) ends it at 4 and changed none
    # of 211 sampled landings, whose accepted steps before the last all changed J by more
    # than 1.5e-5.
    cost_tol: float = 1e-5
    vc_tol: float = 1e-6
    defect_tol: float = 1e-5  # physical units; path constraints must hold to 1e-6 anyway
    # RK4 steps per FOH interval, at least: 2 keeps the discretization within 1e-7 of scipy's
    # integration at N = 50 (tests/test_model.py) at a quarter of the cost of 8. A coarser grid
    # takes more (rk4_steps_per_interval), so that no step is longer than at N = 50.
    rk4_substeps: int = 2
    # "c": the generated C of the model (build/libtscvx_gnc.so); "casadi": CasADi's VM;
    # "auto": C when the library is built. Both evaluate the same expressions (equal to 1e-10).
    discretization: str = "auto"
    tight_tol: float = 1e-6  # slack threshold of the tight-constraint labelling
    # Beyond the paper: weight w of the proximal term (w/2) |u_hat - u_hat_ref|^2 on the
    # scaled thrust, added to the subproblem objective (not to L, Eq. (13)). The paper's
    # linear objective leaves the subproblem's optimal set flat in the thrust history, so two
    # correct conic solvers stop at different points of it and SCvx follows them apart (final
    # masses 1e-4 apart); with w = 2e-2 the answer is unique and the solvers agree to about
    # 1e-8 (docs/scvx.md, "Beyond the paper"). 0 gives the
    # paper's objective; at most PROX_U_MAX (heavier, SCvx stops short of the optimum).
    prox_u: float = 2e-2
    # Beyond the paper, off by default: once SCvx has converged, one more subproblem about
    # the answer without the fuel term (scvx.POLISH_WEIGHT, scvx.POLISH_TOL_FACTOR), which
    # moves the thrust as little as the linearized dynamics allow and so removes the defects
    # the last trust-region steps left (a Gauss-Newton step onto the dynamics). On the
    # default landing: largest defect 7.1e-6 -> 1.6e-10, open-loop miss 2.3e-4 -> 1.8e-5,
    # final mass -7.1e-5 (what the defects had bought), 16 IPM iterations. Kept only when it
    # leaves no virtual control, smaller defects and every path constraint met; needs
    # prox_u > 0. Not the default: 6.8 % more instructions on the default landing (docs/scvx.md,
    # "What the defects cost open loop").
    polish: bool = False
    # Conic subproblem solver (either backend, and the C loop): gap and feasibility
    # tolerances, and the interior-point iteration limit.
    socp_tol: float = 1e-9
    socp_max_iter: int = 200
    # IPM iterations of the whole solve at most (failed warm-started runs included): a
    # subproblem is given at most what is left (scvx.iteration_cap), and none once it is
    # spent, which ends the solve with status max_iterations at the last accepted iterate.
    # The default, the 60 x 200 x 2 that max_subproblems and socp_max_iter allow, never
    # binds; a flight configuration sets it to bound the time of a guidance call.
    socp_max_iter_total: int = 24_000
    # The flight runtime's IPM starts each subproblem from the last subproblem's solution
    # (tscvx_warm_start: centred at a complementarity balanced against its residuals on the
    # new data), in the C loop and with `--backend c-socp` alike. Clarabel has no warm
    # start: the reference always starts cold. The answer is the same to the conic
    # tolerance, in fewer iterations.
    socp_warm_start: bool = True
    # T-SCvx trust radius: True is Algorithm 2's update (alpha^tau_r, beta^(1 - tau_r), tau_r
    # the fraction of bits in which the predicted masks of successions k+1 and k differ);
    # False keeps Eq. (15) of Algorithm 1 with the masks as well (`guidance bench` compares
    # the two).
    tau_r_update: bool = True

    def __post_init__(self) -> None:
        """The ranges the flight library checks too, in its order (pdg_check_settings in
        pdg_scvx.c): with two bad settings both name the same one."""
        for f in dataclasses.fields(self):  # numpy scalars stored as the Python numbers
            kind = str(f.type)  # the annotation's text (postponed annotations)
            object.__setattr__(self, f.name, _checked_type(f.name, kind, getattr(self, f.name)))
        if self.discretization not in DISCRETIZATIONS:
            raise InputError(
                f"discretization must be one of {', '.join(DISCRETIZATIONS)}, "
                f"got {self.discretization!r}"
            )
        for name, (lo, hi) in INT_SETTING_RANGES.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
                raise InputError(f"{name} must be an integer within {lo}..{hi}, got {value!r}")
        for name, holds, requirement in self._ranges():
            if not holds:
                must = requirement.format_map(vars(self))
                raise InputError(f"{name} must {must}, got {getattr(self, name)!r}")

    def _ranges(self) -> Iterator[tuple[str, bool, str]]:
        """(field, whether its range holds, what it must do) of each real setting in the order
        they are checked: a generator, each comparison made once the earlier ones held. What
        it must do is a template over the fields, filled in only for the message."""
        yield "eta_lb", self.eta_lb > 0.0, "be > 0"
        yield "eta_ub", self.eta_ub >= self.eta_lb, "be >= eta_lb = {eta_lb:g}"
        yield (
            "eta_init",
            self.eta_lb <= self.eta_init <= self.eta_ub,
            "lie within [eta_lb, eta_ub] = [{eta_lb:g}, {eta_ub:g}]",
        )
        yield "lam", 0.0 < self.lam <= LAM_MAX, f"lie within (0, {LAM_MAX:g}]"
        # rho0 < 0 accepts steps that raise the penalty J: SCvx then no longer descends
        # (rho0 = -1e300 ended the default landing at max_iterations, not solved)
        yield "rho0", self.rho0 >= 0.0, "be >= 0 (a step that raises the penalty is refused)"
        yield "rho1", self.rho0 <= self.rho1, "satisfy rho0 <= rho1 (rho0 = {rho0:g})"
        yield "rho2", self.rho1 <= self.rho2, "satisfy rho1 <= rho2 (rho1 = {rho1:g})"
        yield (
            "alpha",
            self.alpha >= ALPHA_MIN,
            f"be >= {ALPHA_MIN:g} (the trust region's shrink factor: a rejected step is "
            "retried at eta / alpha)",
        )
        yield "beta", self.beta >= 1.0, "be >= 1 (the trust region's growth factor)"
        for name in ("step_tol", "cost_tol", "vc_tol", "defect_tol", "tight_tol"):
            yield name, getattr(self, name) >= 0.0, "be >= 0"
        yield (
            "prox_u",
            0.0 <= self.prox_u <= PROX_U_MAX,
            f"lie within [0, {PROX_U_MAX:g}] (a larger weight stops SCvx short of the optimum)",
        )
        yield "socp_tol", 0.0 < self.socp_tol < 1.0, "lie within (0, 1)"

    def replace(self, **changes: Any) -> SCvxSettings:
        return dataclasses.replace(self, **changes)


def _checked_type(name: str, kind: str, value: object) -> object:
    """A setting of the type its field declares (``kind``: the annotation; numpy scalars
    taken as the Python numbers they stand for), finite if real; as that Python type."""
    if isinstance(value, np.generic):
        value = value.item()
    if kind == "bool":
        if not isinstance(value, bool):
            raise InputError(f"{name} must be True or False, got {value!r}")
    elif kind == "float":
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(f"{name} must be a number, got {value!r}")
        if isinstance(value, int) and abs(value) > sys.float_info.max:
            raise InputError(f"{name} must be finite, got an integer of {len(str(value))} digits")
        if not math.isfinite(value):
            raise InputError(f"{name} must be finite, got {value}")
    return value


DEFAULT_PARAMS = Params()


@dataclass(frozen=True)
class InitialState:
    r0: tuple[float, float, float] = (4.0, 4.0, 0.0)
    v0: tuple[float, float, float] = (0.0, -1.0, -2.0)
    q0: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    w0: tuple[float, float, float] = (0.0, 0.0, 0.0)  # rad / U_T
    m0: float = 3.0

    def as_vector(self) -> np.ndarray:
        return np.concatenate([self.r0, self.v0, self.q0, self.w0, [self.m0]]).astype(float)


@dataclass(frozen=True)
class Scenario:
    """One landing problem: the initial state and the parameters (with any overrides)."""

    initial: InitialState = field(default_factory=InitialState)
    params: Params = field(default_factory=Params)

    @property
    def x0(self) -> np.ndarray:
        return self.initial.as_vector()

    def x_final_target(self) -> np.ndarray:
        """Terminal state with the mass slot left at zero (mass is free). q_f is taken in q0's
        hemisphere: q and -q are the same attitude, and from q0 . q_f < 0 the pinned condition
        q(t_f) = q_f as written would ask for a turn of 360 degrees more (pdg_x_final_target
        in C does the same)."""
        p = self.params
        x = np.zeros(NX)
        x[IR] = p.r_f
        x[IV] = p.v_f
        x[IQ] = p.q_f if np.dot(self.initial.q0, p.q_f) >= 0.0 else -np.asarray(p.q_f)
        x[IW] = p.omega_f
        return x
