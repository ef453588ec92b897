"""``guidance verify``: the independent open-loop check of trajectory files.

A file written by any backend (or by another tool that follows DESIGN.md's contract) is read
back, its problem rebuilt from the file's own ``params`` (and ``scenario`` when present), and
its thrust flown open loop by ``guidance.verify`` (scipy on numpy dynamics that share no code
with the solvers). Each check has a tolerance; a file passes when every check does.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from guidance.errors import InputError
from guidance.params import CONSTRAINT_NAMES, IM, PARAM_NAMES, Params
from guidance.scenario import (
    REQUIRED_KEYS,
    ScenarioError,
    params_from_dict,
    scenario_from_dict,
)
from guidance.trajectory_io import read_trajectory
from guidance.verify import (
    Audit,
    audit,
    checked_trajectory,
    engine_landing_error,
)

# states and thrust sampled inside each interval, where the method does not impose the path
# constraints: what the flight does there is reported, not checked
SAMPLES_BETWEEN_NODES = 8


@dataclass(frozen=True)
class Tolerances:
    """What a trajectory must reach, in nondimensional units (U_L, U_T, U_M). The landing
    figures allow what a converged solve leaves open loop: the nonlinear defects SCvx stops
    with (up to defect_tol) and the discretization error of the first-order hold (RK4, 2
    steps per interval at N = 50, no longer ones on coarser grids). 2.3e-4 on the default
    landing (1.8e-5 of it the RK4 error, 27 Nov), at most 2.7e-4 over the catalog and 40
    sampled landings solved by SCvx and T-SCvx in C, node states 2.2e-4; flown by an engine
    held at T_min where the plan dips below it, 4.5e-4 (23 Nov 2026). A vehicle outside the
    sampled envelope can miss it (docs/scvx.md, "What the defects cost open loop")."""

    initial: float = 1e-9  # max |x[0] - x0| against the file's scenario
    landing: float = 1e-3  # |r(t_f) - r_f| and |v(t_f) - v_f|, propagated
    attitude: float = 1e-3  # final_attitude_error and |omega(t_f) - omega_f|, propagated
    node_deviation: float = 1e-3  # max |x_propagated - x| over the nodes
    path: float = 1e-6  # max h at the nodes, each constraint in its own units
    # max h of the state constraints (mass, glideslope, tilt, rate) at the flown trajectory's
    # nodes: the flight may leave the nodes by node_deviation, and a converged solve's flight
    # passes the glideslope at touchdown (the cone's apex) by up to 2.7e-4, as far as it lands
    # off (catalog and 20 sampled landings, SCvx and T-SCvx in C, 28 Nov 2026; 1.4e-4 on the
    # default landing). Between the nodes, where the method imposes nothing, a coarse grid's
    # flight may tilt further (N = 20: by up to 2.9e-3 on 4 of 188 sampled landings): reported
    flown_path: float = 1e-3

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if not (np.isfinite(value) and value > 0.0):
                raise InputError(f"tolerance {f.name} must be a finite number > 0, got {value!r}")


@dataclass
class Check:
    name: str
    value: float
    tol: float

    @property
    def ok(self) -> bool:
        return bool(self.value <= self.tol)  # NaN fails


@dataclass
class FileVerdict:
    path: Path
    header: str  # method, backend, status, N, t_f, m_f
    checks: list[Check]
    audit: Audit
    # landing position and velocity errors flown by an engine held within [T_min, T_max],
    # when the plan's thrust dips below T_min between the nodes (else None)
    engine: tuple[float, float] | None = None

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)


def _problem(data: dict[str, object], path: Path) -> tuple[Params, np.ndarray | None, list[str]]:
    """The file's parameters, the initial state its scenario asks for (None without one) and
    the keys of its params that are no parameter of this package. DESIGN.md's params hold *at
    least* the parameters: every one is required, others are allowed (a tool may record more)
    and not used, which the report says."""
    recorded = data["params"]
    try:
        if not isinstance(recorded, dict):
            raise ScenarioError("<root>", "the parameters are a JSON object")
        missing = [n for n in PARAM_NAMES if n not in recorded]
        if missing:  # a trajectory file records every parameter: none is taken as a default
            raise ScenarioError(missing[0], "missing (the file records every parameter)")
        params = params_from_dict({n: recorded[n] for n in PARAM_NAMES})
    except ScenarioError as exc:
        raise InputError(f"{path}: params field '{exc.field}': {exc.reason}") from exc
    extra = [k for k in recorded if k not in PARAM_NAMES]
    if "scenario" not in data:
        return params, None, extra
    try:
        scenario = scenario_from_dict(_with_omitted_params(data["scenario"], params))
    except ScenarioError as exc:
        raise InputError(f"{path}: {exc}") from exc
    if scenario.params != params:
        differ = [
            f.name
            for f in dataclasses.fields(Params)
            if getattr(scenario.params, f.name) != getattr(params, f.name)
        ]
        raise InputError(f"{path}: params and scenario disagree on {', '.join(differ)}")
    return params, scenario.x0, extra


def _with_omitted_params(entry: object, params: Params) -> Any:
    """The file's scenario entry with the parameters it leaves out taken from the file's
    params. Files written before 28 Nov 2026 list only the parameters that differed from the
    defaults of the day; read with today's defaults, a changed default made them disagree
    with their own params (or, for the initial state's checks, be judged by another value).
    The params record what the solve used. The scenario's own keys (REQUIRED_KEYS) are not
    filled: a file without one is refused as before."""
    if not isinstance(entry, dict):
        return entry  # scenario_from_dict names what is wrong
    recorded = params.to_json_dict()
    omitted = {n: recorded[n] for n in PARAM_NAMES if n not in entry and n not in REQUIRED_KEYS}
    return {**entry, **omitted}


def _arrays(data: dict[str, object], p: Params, path: Path) -> tuple[np.ndarray, np.ndarray, float]:
    try:
        return checked_trajectory(data["x"], data["u"], data["t_f"], p)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None


def trajectory_checks(a: Audit, p: Params, tol: Tolerances = Tolerances()) -> list[Check]:
    """The open-loop checks of a trajectory's audit (a propagation that stopped gives NaN
    figures, which fail)."""
    attitude = "|(q2, q3)|" if p.final_roll_free else "|q - q_f|"
    return [
        Check("landing position |r(t_f) - r_f|", a.landing_position_error, tol.landing),
        Check("landing velocity |v(t_f) - v_f|", a.landing_velocity_error, tol.landing),
        Check(f"final attitude {attitude}", a.final_attitude_error, tol.attitude),
        Check("final rate |w(t_f) - w_f|", a.final_rate_error, tol.attitude),
        Check("node states vs propagation", a.max_node_deviation, tol.node_deviation),
        Check("path constraints at the nodes", a.max_path_violation, tol.path),
        Check("state constraints on the flight", a.max_flown_state_violation, tol.flown_path),
    ]


def verify_file(path: str | Path, tol: Tolerances = Tolerances()) -> FileVerdict:
    """Read and check one trajectory file; a file that cannot be checked raises InputError."""
    path = Path(path)
    data = read_trajectory(path)
    p, x0, extra = _problem(data, path)
    x, u, t_f = _arrays(data, p, path)
    a = audit(x, u, t_f, p, between=SAMPLES_BETWEEN_NODES)
    checks = trajectory_checks(a, p, tol)
    if x0 is not None:
        start = float(np.abs(x[0] - x0).max())
        checks.insert(0, Check("initial state vs scenario", start, tol.initial))
    header = (
        f"{data.get('method', '?')} on {data.get('backend', '?')}, status {data['status']}, "
        f"N = {p.N}, t_f = {t_f:.6f} U_T, m_f = {x[-1, IM]:.6f} U_M"
    )
    if x0 is None:  # the contract does not require the entry: say what is not checked
        header += " (no scenario in the file: x[0] not checked against one)"
    if extra:
        header += f" (params not of this package, not used by the check: {', '.join(extra)})"
    thrust_min = CONSTRAINT_NAMES.index("thrust_min")
    engine = None
    if a.path_between_nodes[thrust_min] > 0.0:
        engine = engine_landing_error(x, u, t_f, p)
    return FileVerdict(path, header, checks, a, engine)


def tolerance_text(tol: float) -> str:
    """The tolerance as given, in the fewest digits that are exactly it (2.4e-04, not 2e-04: a
    rounded tolerance could print a value above it marked ok)."""
    for digits in range(7):
        text = f"{tol:.{digits}e}"
        if float(text) == tol:
            return text
    return f"{tol:.6e}"


def format_verdict(v: FileVerdict) -> str:
    lines = [f"{v.path}: {v.header}", f"  {'check':<36} {'value':>10} {'tolerance':>10}"]
    for c in v.checks:
        lines.append(
            f"  {c.name:<36} {c.value:>10.2e} {tolerance_text(c.tol):>10}  "
            f"{'ok' if c.ok else 'FAIL'}"
        )
    between = dict(zip(CONSTRAINT_NAMES, v.audit.path_between_nodes, strict=True))
    lines.append(
        f"  between the nodes ({SAMPLES_BETWEEN_NODES} samples per interval), max h: "
        + ", ".join(f"{name} {h:.1e}" for name, h in between.items())
    )
    # the method imposes the path constraints at the nodes only: between them each is
    # reported (the thrust's norm sags below T_min, a coarse grid's flight tilts further)
    exceeded = [f"{name} by {h:.1e}" for name, h in between.items() if h > 0.0]
    if exceeded:
        lines.append(
            f"    exceeded between the nodes (reported, not checked): {', '.join(exceeded)}"
        )
    if v.engine is not None:
        lines.append(
            "    flown by an engine held at T_min there: landing position error "
            f"{v.engine[0]:.2e}, velocity error {v.engine[1]:.2e}"
        )
    if v.audit.propagation_stopped:
        lines.append(
            f"  open-loop propagation stopped in {v.audit.propagation_stopped}: the propagated "
            "figures are NaN and fail"
        )
    lines.append(f"  verdict: {'pass' if v.ok else 'FAIL'}")
    return "\n".join(lines)


def main(paths: list[str], tol: Tolerances = Tolerances()) -> int:
    """Exit 0 when every file passes, 1 when one fails (bad files raise InputError: exit 2)."""
    verdicts = [verify_file(p, tol) for p in paths]  # every file readable before any report
    for v in verdicts:
        print(format_verdict(v))
    print(
        "open loop: scipy DOP853 (rtol = atol = 1e-10, each interval on its own) of numpy "
        "dynamics that share no code with the solvers, from x[0] under the file's "
        "first-order-hold thrust"
    )
    return 0 if all(v.ok for v in verdicts) else 1
