"""Dispersion campaign (`guidance dispersion`): many sampled landings solved by the flight
library, each trajectory flown open loop, and the spread of the work a guidance call takes.

The landings are fresh draws from the networks' training distribution (the T-SCvx benchmark's
sampler: dataset.SamplingRanges, each turned about the up axis), on N nodes. Each is solved by
the C library (SCvx, or with ``--method tscvx`` the on-board T-SCvx call with the shipped
networks), and each solved trajectory is checked as ``guidance verify`` checks a file: scipy
integration of independent dynamics from x[0] under its thrust, the landing, the node states
and the path constraints against file_check.Tolerances. The report gives the statuses, the
open-loop figures, and the median, 95th percentile and largest of the iterations, subproblems
and IPM iterations per call: the largest IPM count is the smallest ``socp_max_iter_total``
(``--ipm-budget``) that leaves every landing of the campaign as it is. ``--failures DIR``
writes each landing that was not solved, or failed the check, as a scenario file that
``guidance solve`` takes.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from guidance.params import Scenario, SCvxSettings
from guidance.scvx import BUDGET_SPENT

METHODS = ("scvx", "tscvx")


@dataclass(frozen=True)
class Landing:
    """One landing of the campaign: the call's outcome and, when solved, its open-loop check."""

    index: int
    status: str
    reason: str
    iterations: int
    subproblems: int
    ipm_iterations: int  # the call's, failed warm-started runs included
    wall_s: float
    landing_error: float = math.nan  # |r(t_f) - r_f| propagated (NaN when not solved)
    velocity_error: float = math.nan
    node_deviation: float = math.nan
    path_value: float = math.nan  # largest path-constraint value at the nodes (<= 0: met)
    verified: bool = False  # solved and within every tolerance of guidance verify
    failed_checks: str = ""  # the open-loop checks a solved landing failed

    @property
    def failed(self) -> bool:
        return not self.verified


def solve_landing(job: tuple[int, Scenario, SCvxSettings, str]) -> Landing:
    """Solve one landing in the C library and check it open loop (a worker's job)."""
    from guidance.cguidance import solve_c, solve_tscvx_c
    from guidance.file_check import trajectory_checks
    from guidance.verify import audit

    index, scenario, settings, method = job
    r = solve_tscvx_c(scenario, settings) if method == "tscvx" else solve_c(scenario, settings)
    common = dict(
        index=index,
        status=r.status,
        reason=r.reason,
        iterations=r.iterations,
        subproblems=r.subproblems_solved,
        ipm_iterations=sum(h.solver_iterations for h in r.history),
        wall_s=r.solve_time_s,
    )
    if r.status != "solved":
        return Landing(**common)  # type: ignore[arg-type]
    a = audit(r.x, r.u, r.t_f, scenario.params)
    failed = [c.name for c in trajectory_checks(a, scenario.params) if not c.ok]
    return Landing(
        **common,  # type: ignore[arg-type]
        landing_error=a.landing_position_error,
        velocity_error=a.landing_velocity_error,
        node_deviation=a.max_node_deviation,
        path_value=a.max_path_violation,
        verified=not failed,
        failed_checks=", ".join(failed),
    )


def spread(values: Sequence[float]) -> tuple[float, float, float]:
    """(median, 95th percentile, largest); NaN for none."""
    if not values:
        return (math.nan, math.nan, math.nan)
    v = np.asarray(values, float)
    return (float(np.median(v)), float(np.percentile(v, 95)), float(v.max()))


def report(rows: Sequence[Landing], method: str, nodes: int, seed: int, ipm_budget: int) -> str:
    solved = [r for r in rows if r.status == "solved"]
    verified = [r for r in solved if r.verified]
    lines = [
        f"Dispersion: {len(rows)} sampled landings (the training distribution, seed {seed}), "
        f"N = {nodes}, {'SCvx' if method == 'scvx' else 'T-SCvx'} in the C library",
        f"  solved {len(solved)} of {len(rows)}; of these {len(verified)} pass the open-loop "
        "check of guidance verify",
    ]
    for status, n in sorted(Counter(r.status for r in rows).items()):
        lines.append(f"    {status:16s} {n:5d}")
    lines.append(f"  per call, solved landings   {'median':>8s} {'95 %':>8s} {'largest':>8s}")
    for label, key in (
        ("SCvx iterations", "iterations"),
        ("subproblems", "subproblems"),
        ("IPM iterations", "ipm_iterations"),
    ):
        med, p95, top = spread([getattr(r, key) for r in solved])
        lines.append(f"    {label:25s} {med:8.1f} {p95:8.1f} {top:8.0f}")
    med, p95, top = spread([1e3 * r.wall_s for r in solved])
    lines.append(f"    {'host wall time (ms)':25s} {med:8.1f} {p95:8.1f} {top:8.1f}")
    if solved:
        worst = max(solved, key=lambda r: r.landing_error)
        lines += [
            f"  open loop, largest: landing error {worst.landing_error:.2e} (landing "
            f"{worst.index}), velocity {max(r.velocity_error for r in solved):.2e}, node "
            f"deviation {max(r.node_deviation for r in solved):.2e}, path-constraint value "
            f"{max(r.path_value for r in solved):.1e}",
        ]
    top = max((r.ipm_iterations for r in rows), default=0)
    bound = sum(r.reason.startswith(BUDGET_SPENT) for r in rows)
    lines.append(
        f"  IPM iterations in a call, largest: {top}"
        + (
            f"; the budget (--ipm-budget {ipm_budget}) stopped {bound} landing(s)"
            if bound
            else f": an --ipm-budget (socp_max_iter_total) of {top} or more leaves every "
            "landing here as it is"
        )
    )
    failed = [r for r in rows if r.failed]
    if failed:
        lines.append(f"  not solved, or failing the open-loop check ({len(failed)}):")
        for r in failed:
            why = r.reason if r.status != "solved" else f"open loop: {r.failed_checks}"
            lines.append(f"    landing {r.index}: {r.status}: {why}")
    return "\n".join(lines)


def write_failures(folder: Path, rows: Sequence[Landing], scenarios: Sequence[Scenario]) -> None:
    """Each failed landing as ``landing_<index>.json`` (a scenario file)."""
    from guidance.atomic import write_text_atomic
    from guidance.scenario import scenario_to_dict

    folder.mkdir(parents=True, exist_ok=True)
    for r in rows:
        if r.failed:
            text = json.dumps(scenario_to_dict(scenarios[r.index]), indent=1) + "\n"
            write_text_atomic(folder / f"landing_{r.index}.json", text)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    from guidance.bench_tscvx import BENCH_SEED
    from guidance.cli import at_least
    from guidance.params import N_MAX, N_MIN

    ap.add_argument("--landings", type=at_least(1), default=100, help="landings (default 100)")
    ap.add_argument(
        "--seed", type=at_least(0), default=BENCH_SEED,
        help="draw seed (default %(default)s, the T-SCvx benchmark's: never trained on)",
    )  # fmt: skip
    ap.add_argument(
        "--nodes", type=at_least(N_MIN, N_MAX), default=Scenario().params.N,
        help=f"N, in [{N_MIN}, {N_MAX}] (default %(default)s; tscvx: the networks' 50)",
    )  # fmt: skip
    ap.add_argument("--method", choices=METHODS, default="scvx", help="default scvx")
    ap.add_argument(
        "--ipm-budget", type=at_least(1), default=SCvxSettings().socp_max_iter_total,
        help="socp_max_iter_total of every call (default %(default)s: never binds)",
    )  # fmt: skip
    ap.add_argument(
        "--workers", type=at_least(1), default=os.cpu_count() or 1,
        help="landings solved at once, one process each (default: the cores, %(default)s)",
    )  # fmt: skip
    ap.add_argument("--failures", type=Path, help="folder for the failed landings' scenarios")
    ap.add_argument("--json", action="store_true", help="print every landing as JSON")


def run(args: argparse.Namespace, progress: bool = True) -> int:
    """The campaign for parsed options (add_arguments). Exit 0 when it ran, whatever it found."""
    from guidance.bench_tscvx import sample_landings
    from guidance.cguidance import LIB_PATH
    from guidance.dataset import imap_pool
    from guidance.errors import InputError, LibraryNotBuiltError

    if not LIB_PATH.exists():
        raise LibraryNotBuiltError(f"{LIB_PATH} not found: run `make lib`")
    if args.method == "tscvx" and args.nodes != Scenario().params.N:
        raise InputError(
            f"--method tscvx: the shipped networks are for N = {Scenario().params.N}, "
            f"not --nodes {args.nodes}"
        )
    if args.failures is not None:
        from guidance.atomic import check_folder

        check_folder("--failures", args.failures)
    settings = SCvxSettings(socp_max_iter_total=args.ipm_budget)
    scenarios = [
        Scenario(s.initial, s.params.replace(N=args.nodes))
        for s in sample_landings(args.landings, seed=args.seed)
    ]
    jobs = [(i, s, settings, args.method) for i, s in enumerate(scenarios)]
    rows: list[Landing] = []
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(jobs), desc="landings", unit="landing", file=sys.stderr)
    for row in imap_pool(solve_landing, jobs, args.workers):
        rows.append(row)
        if bar is not None:
            bar.update()
    if bar is not None:
        bar.close()
    rows.sort(key=lambda r: r.index)
    if args.failures is not None:
        write_failures(args.failures, rows, scenarios)
    if args.json:
        print(json.dumps([asdict(r) for r in rows], indent=1))
    else:
        print(report(rows, args.method, args.nodes, args.seed, args.ipm_budget))
    return 0
