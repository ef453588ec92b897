"""Closed-loop flight with in-flight re-planning: the vehicle flies its plan's thrust through a
disturbance the plan does not know of (an engine that gives a fraction more or less thrust
than commanded, an unmodelled acceleration), integrated by scipy; every ``period`` it
re-plans the landing from the state it has reached, started from the rest of its plan
(``guess.plan_remainder``), and flies the new plan. The same landing flown open loop (the
first plan to its end, through the same disturbance) is the yardstick.

A re-plan that does not end ``solved``, or a state the scenario check refuses (outside the
glideslope, out of fuel), leaves the vehicle on its current plan, as flight software keeps
the last good plan. Re-planning stops once less than ``lock`` of the plan is left: the last
seconds are flown on the last plan. A re-plan starts from what navigation knows of the state:
the true state with a knowledge error in position and velocity (``Navigation``: Gaussian,
seeded; none by default), its roll rate, rounding noise of the integration, set to the
plan's zero. The thrust commands are flown from the true state.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from guidance.constraints import path_constraint_values
from guidance.errors import InputError
from guidance.guess import hold_at, plan_remainder
from guidance.params import CONSTRAINT_NAMES, IM, IQ, IR, IV, IW, NC, InitialState, Scenario
from guidance.verify import PropagationError, fly_interval
from guidance.verify import final_attitude_error as attitude_error

if TYPE_CHECKING:
    from guidance.scvx import SCvxResult

RTOL = 1e-10  # as guidance verify's open-loop check
ROLL_NOISE = 1e-9  # rad/U_T: a roll rate below this is the integration's rounding (J2 = J3)
SAMPLES = 4  # states sampled inside each flown interval for the path constraints


@dataclass(frozen=True)
class Disturbance:
    """What the plan does not know of: the engine gives (1 + thrust_error) times the thrust
    it is commanded (after its throttle limits), and an unmodelled inertial acceleration
    (U_L / U_T^2; g is (-1, 0, 0) in these units) acts throughout."""

    thrust_error: float = 0.0
    accel_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.thrust_error) and -0.5 <= self.thrust_error <= 0.5):
            raise InputError(f"thrust_error: expected a number in [-0.5, 0.5], got "
                             f"{self.thrust_error!r}")  # fmt: skip
        a = np.asarray(self.accel_bias, dtype=float)
        if a.shape != (3,) or not np.isfinite(a).all() or np.abs(a).max() > 1.0:
            raise InputError(f"accel_bias: expected 3 numbers within [-1, 1] U_L/U_T^2, got "
                             f"{self.accel_bias!r}")  # fmt: skip


@dataclass(frozen=True)
class Navigation:
    """What the re-plans know of the state: the true position and velocity plus independent
    Gaussian errors of these standard deviations per axis (U_L, U_L/U_T), drawn at each
    re-plan from a generator seeded with ``seed``. Attitude, rates and mass are known."""

    position_sigma: float = 0.0
    velocity_sigma: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("position_sigma", "velocity_sigma"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 1.0):
                raise InputError(f"{name}: expected a number in [0, 1], got {value!r}")
        if not (isinstance(self.seed, int) and 0 <= self.seed < 2**63):
            raise InputError(f"seed: expected an integer in [0, 2^63), got {self.seed!r}")

    def estimate(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The state navigation gives for the true state x (a copy; x itself with no error)."""
        est = np.array(x, dtype=float)
        est[IR] += rng.normal(0.0, self.position_sigma, 3)
        est[IV] += rng.normal(0.0, self.velocity_sigma, 3)
        return est


@dataclass(frozen=True)
class ReplanSettings:
    """period: U_T of flight between re-plans; lock: no re-plan once less than this of the
    plan is left; backend: the solver of the re-plans (guidance.api.solve's)."""

    period: float = 0.5
    lock: float = 0.5
    backend: str = "c"

    def __post_init__(self) -> None:
        for name in ("period", "lock"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.05 <= value <= 100.0):
                raise InputError(f"{name}: expected U_T within [0.05, 100], got {value!r}")


@dataclass
class Replan:
    t: float  # U_T from the start of the flight
    # |estimate - true| of the state it started from: position, velocity
    knowledge_error: tuple[float, float]
    outcome: str  # the solve's status, or why no solve was made ("refused: ...")
    kept: bool  # the new plan is flown
    subproblems: int
    touchdown: float  # the new plan's touchdown time from the start (NaN when not kept)
    m_f: float  # its final mass (NaN when not kept)


@dataclass
class Flight:
    """The end of one flight and the worst of its path: landing errors against the pad."""

    touchdown: float  # U_T
    position_error: float  # |r - r_f|
    velocity_error: float  # |v - v_f|
    attitude_error: float  # verify.final_attitude_error
    rate_error: float  # |omega - omega_f|
    m_f: float
    # largest path-constraint value in flight, of the true states and of the commands
    # (<= 0: all met), and the constraint it is (params.CONSTRAINT_NAMES; "" with no path)
    max_path_value: float
    max_path_constraint: str = ""


@dataclass
class ClosedLoop:
    plan_status: str  # the first plan's
    plan_m_f: float
    closed: Flight
    open: Flight  # the first plan flown to its end through the same disturbance
    replans: list[Replan] = field(default_factory=list)


def _fly(
    x0: np.ndarray, u: np.ndarray, t_f: float, s0: float, s1: float, scn: Scenario,
    dist: Disturbance,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Flies the plan (thrust u on N nodes over [0, t_f]) from its time s0 to s1 from the true
    state x0: its first-order-hold command through the engine's limits and the disturbance.
    Returns the state at s1 and the path-constraint values (M x 7) of the sampled states and
    commands (the thrust constraints bind the command guidance gives; the engine's error on
    it is the disturbance's). Each plan interval (or part of one) is integrated on its own by
    ``verify.fly_interval``, as guidance verify does: the thrust has a kink at every node."""
    p = scn.params
    N = u.shape[0]
    h = t_f / (N - 1)
    frac = np.linspace(0.0, 1.0, SAMPLES + 2)[:, None]  # sampled fractions of a piece

    x, xs, us = np.asarray(x0, dtype=float), [], []
    j = min(int(s0 / h), N - 2)
    a = s0
    while a < s1 and j <= N - 2:  # at most N - 1 intervals
        b = min((j + 1) * h if j < N - 2 else t_f, s1)
        if b > a:  # the hold is linear over the piece [a, b] of interval j
            ua, ub = hold_at(u, t_f, np.array([a, b]))
            try:
                sol = fly_interval(x, ua, ub, b - a, p, RTOL, True, engine=True,
                                   thrust_scale=1.0 + dist.thrust_error,
                                   accel_bias=np.asarray(dist.accel_bias))  # fmt: skip
            except PropagationError as exc:
                msg = f"the flight stopped at t = {a:.4f} of the plan: {exc}"
                raise PropagationError(msg) from None
            x = sol.y[:, -1]
            xs.append(sol.sol(frac[:, 0] * (b - a)).T)
            us.append(ua + frac * (ub - ua))
        a, j = b, j + 1
    if not xs:
        return x, np.zeros((0, 7))
    return x, path_constraint_values(np.vstack(xs), np.vstack(us), p)


def _landing(x: np.ndarray, t: float, scn: Scenario, path: list[np.ndarray]) -> Flight:
    p = scn.params
    worst, which = -math.inf, ""
    for h in (v.reshape(-1, NC) for v in path if v.size):
        row, col = np.unravel_index(int(np.argmax(h)), h.shape)
        if h[row, col] > worst:
            worst, which = float(h[row, col]), CONSTRAINT_NAMES[col]
    return Flight(
        touchdown=t,
        position_error=float(np.linalg.norm(x[IR] - np.array(p.r_f))),
        velocity_error=float(np.linalg.norm(x[IV] - np.array(p.v_f))),
        attitude_error=attitude_error(x[IQ], p),
        rate_error=float(np.linalg.norm(x[IW] - np.array(p.omega_f))),
        m_f=float(x[IM]),
        max_path_value=worst,
        max_path_constraint=which,
    )


def state_scenario(x: np.ndarray, scn: Scenario) -> Scenario:
    """The landing from the true state x with the scenario's parameters: the quaternion
    renormalized, the roll rate's rounding noise (the engine makes no roll torque) zeroed.
    InputError for a roll rate beyond noise."""
    if abs(x[10]) > ROLL_NOISE:
        raise InputError(f"roll rate {x[10]:.3g} rad/U_T in flight: the vehicle cannot "
                         "make one, the disturbance model is broken")  # fmt: skip
    s = [float(a) for a in x]
    q = [float(a) for a in x[IQ] / np.linalg.norm(x[IQ])]
    init = InitialState(
        r0=(s[0], s[1], s[2]),
        v0=(s[3], s[4], s[5]),
        q0=(q[0], q[1], q[2], q[3]),
        w0=(0.0, s[11], s[12]),
        m0=s[IM],
    )
    return Scenario(init, scn.params)


def fly_closed_loop(
    scn: Scenario, dist: Disturbance, settings: ReplanSettings, plan: SCvxResult | None = None,
    nav: Navigation | None = None,
) -> ClosedLoop:  # fmt: skip
    """Plans the landing (or takes ``plan``, a solve of it), then flies it twice through
    ``dist``: open loop, and closed loop with a re-plan every settings.period from the state
    ``nav`` knows (default: the true state). InputError when the first plan is not solved
    (there is nothing to fly); PropagationError when a flight cannot be integrated."""
    from guidance.api import solve

    first = solve(scn, backend=settings.backend) if plan is None else plan
    if first.status != "solved":
        raise InputError(f"the landing's plan is {first.status} ({first.reason}): nothing to fly")
    x_open, h_open = _fly(scn.x0, first.u, first.t_f, 0.0, first.t_f, scn, dist)
    open_flight = _landing(x_open, first.t_f, scn, [h_open])

    nav = Navigation() if nav is None else nav
    rng = np.random.default_rng(nav.seed)
    cur, start = first, 0.0  # the plan flown and the flight time its t = 0 stands for
    x, t, path, replans = scn.x0, 0.0, [], []
    for _ in range(int(first.t_f / settings.period) + 1000):  # each pass flies one period
        if start + cur.t_f - (t + settings.period) < settings.lock:
            break
        x, h = _fly(x, cur.u, cur.t_f, t - start, t + settings.period - start, scn, dist)
        path.append(h)
        t += settings.period
        record, new = _replan(x, nav.estimate(x, rng), t, t - start, cur, scn, settings)
        replans.append(record)
        if new is not None:
            cur, start = new, t
    x, h = _fly(x, cur.u, cur.t_f, t - start, cur.t_f, scn, dist)
    path.append(h)
    closed = _landing(x, start + cur.t_f, scn, path)
    return ClosedLoop(first.status, first.m_f, closed, open_flight, replans)


def _replan(
    x: np.ndarray, est: np.ndarray, t: float, s: float, cur: SCvxResult, scn: Scenario,
    settings: ReplanSettings,
) -> tuple[Replan, SCvxResult | None]:  # fmt: skip
    """The re-plan at flight time t from navigation's estimate est of the true state x,
    started from the current plan's remainder from its time s, and the new plan when it is
    kept (solved)."""
    from guidance.api import solve

    known = (float(np.linalg.norm(est[IR] - x[IR])), float(np.linalg.norm(est[IV] - x[IV])))
    try:
        here = state_scenario(est, scn)
        guess = plan_remainder(here, cur.x, cur.u, cur.t_f, s)
        res = solve(here, backend=settings.backend, guess=guess)
    except InputError as exc:
        return Replan(t, known, f"refused: {exc}", False, 0, math.nan, math.nan), None
    n = res.subproblems_solved
    if res.status != "solved":
        return Replan(t, known, res.status, False, n, math.nan, math.nan), None
    return Replan(t, known, res.status, True, n, t + res.t_f, res.m_f), res


def _row(name: str, f: Flight) -> str:
    errors = (f.position_error, f.velocity_error, f.attitude_error, f.rate_error)
    return (
        f"  {name:<12} {f.touchdown:9.4f} " + " ".join(f"{e:10.2e}" for e in errors)
        + f" {f.m_f:9.6f} {f.max_path_value:10.2e} {f.max_path_constraint}"
    )  # fmt: skip


def report(
    res: ClosedLoop, dist: Disturbance, settings: ReplanSettings, nav: Navigation | None = None
) -> str:
    """The re-plans and the two flights' landings, as ``guidance closed-loop`` prints them."""
    nav = Navigation() if nav is None else nav
    kept = sum(r.kept for r in res.replans)
    lines = [
        f"Closed loop: thrust error {dist.thrust_error:+g}, acceleration bias "
        f"{tuple(dist.accel_bias)} U_L/U_T^2; a re-plan every {settings.period:g} U_T "
        f"until {settings.lock:g} U_T of the plan is left ({settings.backend} backend)",
        f"  navigation: position error {nav.position_sigma:g} U_L, velocity error "
        f"{nav.velocity_sigma:g} U_L/U_T (1 sigma per axis, seed {nav.seed})"
        if nav.position_sigma or nav.velocity_sigma
        else "  navigation: perfect (re-plans start from the true state)",
        f"  first plan: {res.plan_status}, m_f {res.plan_m_f:.6f}",
        f"  re-plans: {len(res.replans)}, {kept} kept (solved); the others left the vehicle "
        "on its plan",
        "      t  |dr| known  |dv| known  outcome             subproblems  touchdown        m_f",
    ]
    for r in res.replans:
        dr, dv = r.knowledge_error
        lines.append(f"  {r.t:5.2f}  {dr:10.2e}  {dv:10.2e}  {r.outcome[:60]:<20} "
                     f"{r.subproblems:10d} {r.touchdown:10.4f} {r.m_f:10.6f}")  # fmt: skip
    lines += [
        "  flight       touchdown  |r - r_f|  |v - v_f|   attitude  |w - w_f|       m_f  max path"
        " (constraint)",
        _row("open loop", res.open),
        _row("closed loop", res.closed),
    ]
    o, c = res.open.position_error, res.closed.position_error
    if o > 0.0 and c > 0.0:
        ratio, word = (o / c, "smaller") if c <= o else (c / o, "larger")
        lines.append(f"  landing error: closed loop {ratio:.1f}x {word} than open loop")
    return "\n".join(lines)


def _plain(value: object) -> object:
    """JSON numbers: NaN and inf as null."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def add_arguments(ap: argparse.ArgumentParser) -> None:
    from guidance.api import BACKENDS

    ap.add_argument("scenario", nargs="?", help="scenario JSON (default: the default landing)")
    ap.add_argument("--thrust-error", type=float, default=0.02,
                    help="the engine gives (1 + E) times the thrust commanded, E in [-0.5, 0.5] "
                    "(default %(default)s)")  # fmt: skip
    ap.add_argument("--accel-bias", type=float, nargs=3, default=(0.0, 0.0, 0.0),
                    metavar=("AX", "AY", "AZ"),
                    help="unmodelled inertial acceleration, U_L/U_T^2 (|g| = 1; default 0)",
                    )  # fmt: skip
    ap.add_argument("--nav-error", type=float, nargs=2, default=(0.0, 0.0),
                    metavar=("SIGMA_R", "SIGMA_V"),
                    help="navigation's knowledge error at each re-plan: standard deviations "
                    "per axis of position (U_L) and velocity (U_L/U_T), each in [0, 1] "
                    "(default 0 0: perfect)")  # fmt: skip
    ap.add_argument("--seed", type=int, default=0,
                    help="seed of the navigation errors (default %(default)s)")  # fmt: skip
    ap.add_argument("--period", type=float, default=ReplanSettings().period,
                    help="U_T of flight between re-plans (default %(default)s)")  # fmt: skip
    ap.add_argument("--lock", type=float, default=ReplanSettings().lock,
                    help="no re-plan once less than this (U_T) of the plan is left "
                    "(default %(default)s)")  # fmt: skip
    ap.add_argument("--backend", choices=BACKENDS, default="c",
                    help="solver of the plans (default c: the flight library)")  # fmt: skip
    ap.add_argument("--json", action="store_true", help="print the figures as JSON")


def run(args: argparse.Namespace) -> int:
    """``guidance closed-loop``: 0 (the figures say how well it landed), 1 when a flight
    cannot be integrated (the reason on stderr)."""
    from guidance.scenario import read_scenario_data, scenario_from_dict

    dist = Disturbance(args.thrust_error, tuple(args.accel_bias))
    settings = ReplanSettings(args.period, args.lock, args.backend)
    nav = Navigation(args.nav_error[0], args.nav_error[1], args.seed)
    scn = scenario_from_dict(read_scenario_data(args.scenario)) if args.scenario else Scenario()
    try:
        res = fly_closed_loop(scn, dist, settings, nav=nav)
    except PropagationError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    if args.json:
        from guidance.provenance import provenance

        out = {"disturbance": asdict(dist), "navigation": asdict(nav),
               "settings": asdict(settings), **asdict(res), "provenance": provenance()}  # fmt: skip
        print(json.dumps(_plain(out), indent=1))
    else:
        print(report(res, dist, settings, nav))
    return 0
