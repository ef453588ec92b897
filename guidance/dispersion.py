"""Dispersion campaign (`guidance dispersion`): many sampled landings solved by the flight
library, each trajectory flown open loop, and the spread of the work a guidance call takes.

The landings are fresh draws from the networks' training distribution (the T-SCvx benchmark's
sampler: sampling.SamplingRanges, each turned about the up axis), on N nodes. Each is solved by
the C library (SCvx, or with ``--method tscvx`` the on-board T-SCvx call with the shipped
networks), and each solved trajectory is checked as ``guidance verify`` checks a file
(file_check.trajectory_checks: scipy integration of independent dynamics from x[0] under its
thrust; the landing, the node states and the path constraints against its tolerances). The
report gives the statuses, the open-loop figures, the median, 95th percentile (nearest rank)
and largest of the iterations, subproblems and IPM iterations per solved call, and the
smallest ``socp_max_iter_total`` (``--ipm-budget``) that leaves every landing of the campaign
as it is (``untouched_budget``). ``--failures DIR`` writes each landing that was not solved,
or failed the check, as a scenario file, with ``campaign.json`` saying how to solve it again.
``--run-dir DIR`` keeps each landing as it finishes (runs.RunResults: ``run.json`` with
the campaign's parameters and code versions, ``results/NNNNNN.json``); the same command again
resumes, solving only the missing landings, and a campaign with other parameters is refused.
Ctrl-C or SIGTERM stops the workers, says what is kept and exits 130 (``interrupted``).
Exit 1 when a solved landing fails the open-loop check (as ``guidance verify`` does).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import shlex
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from guidance.argtypes import add_workers_option, at_least, worker_count
from guidance.errors import InputError, Interrupted
from guidance.params import INT_SETTING_RANGES, N_MAX, N_MIN, Scenario, SCvxSettings
from guidance.provenance import code_version
from guidance.scvx import BUDGET_SPENT

if TYPE_CHECKING:
    from guidance.runs import RunResults

METHODS = ("scvx", "tscvx")
NETWORK_N = Scenario().params.N  # the grid the shipped networks are trained for


@dataclass(frozen=True)
class Landing:
    """One landing of the campaign: the call's outcome and, when solved, its open-loop check."""

    index: int
    status: str
    reason: str
    m_f: float
    iterations: int
    subproblems: int
    ipm_iterations: int  # the call's, failed warm-started runs included
    untouched_budget: int  # the least socp_max_iter_total that changes nothing of this call
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


def untouched_budget(ipm_per_subproblem: Sequence[int]) -> int:
    """The least socp_max_iter_total under which no subproblem of a call that took these IPM
    iterations would have been cut short (scvx.iteration_cap): the first subproblem starts cold
    and may use all that is left; each later one may be warm-started and then gets half of it.
    A failed warm start run again cold counts both runs: an upper bound there."""
    need = used = 0
    for j, n in enumerate(ipm_per_subproblem):
        need = max(need, used + (n if j == 0 else 2 * n))
        used += n
    return need


def solve_landing(job: tuple[int, Scenario, SCvxSettings, str]) -> Landing:
    """Solve one landing in the C library and check it open loop (a worker's job)."""
    from guidance.cguidance import solve_c, solve_tscvx_c
    from guidance.file_check import trajectory_checks
    from guidance.verify import audit

    index, scenario, settings, method = job
    r = solve_tscvx_c(scenario, settings) if method == "tscvx" else solve_c(scenario, settings)
    # the polish is one more subproblem, warm-started as the others
    per_subproblem = [h.solver_iterations for h in r.history]
    per_subproblem += [r.polish.ipm_iterations] if r.polish.ipm_iterations else []
    row = Landing(
        index=index,
        status=r.status,
        reason=r.reason,
        m_f=r.m_f if r.x.size else math.nan,
        iterations=r.iterations,
        subproblems=r.subproblems_solved,
        ipm_iterations=r.ipm_iterations,
        untouched_budget=untouched_budget(per_subproblem),
        wall_s=r.solve_time_s,
    )
    if r.status != "solved":
        return row
    a = audit(r.x, r.u, r.t_f, scenario.params)  # verify's checks (between the nodes: reports)
    failed = [c.name for c in trajectory_checks(a, scenario.params) if not c.ok]
    return replace(
        row,
        landing_error=a.landing_position_error,
        velocity_error=a.landing_velocity_error,
        node_deviation=a.max_node_deviation,
        path_value=a.max_path_violation,
        verified=not failed,
        failed_checks=", ".join(failed),
    )


def spread(values: Sequence[float], q: float = 95) -> tuple[float, float, float]:
    """(median, q-th percentile by nearest rank: a value that occurred, largest); NaN for
    none."""
    if not values:
        return (math.nan, math.nan, math.nan)
    v = np.asarray(values, float)
    pq = np.percentile(v, q, method="inverted_cdf")
    return (float(np.median(v)), float(pq), float(v.max()))


def _figures(values: tuple[float, float, float], fmt: str) -> str:
    return " ".join(f"{'-':>8s}" if math.isnan(x) else f"{x:8{fmt}}" for x in values)


def _largest(rows: Sequence[Landing], key: str, fmt: str) -> str:
    worst = max(rows, key=lambda r: getattr(r, key))
    return f"{getattr(worst, key):{fmt}} (landing {worst.index})"


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
    lines.append(f"  per solved call             {'median':>8s} {'95 %':>8s} {'largest':>8s}")
    for label, key in (
        ("iterations", "iterations"),
        ("subproblems", "subproblems"),
        ("IPM iterations", "ipm_iterations"),
    ):
        figures = spread([getattr(r, key) for r in solved])
        lines.append(f"    {label:25s} {_figures(figures, '.0f')}")
    figures = spread([1e3 * r.wall_s for r in solved])
    lines.append(f"    {'host wall time (ms)':25s} {_figures(figures, '.1f')}")
    if solved:
        lines.append(
            f"  open loop, largest over the solved landings: landing error "
            f"{_largest(solved, 'landing_error', '.2e')}, velocity "
            f"{_largest(solved, 'velocity_error', '.2e')}, node deviation "
            f"{_largest(solved, 'node_deviation', '.2e')}, path-constraint value "
            f"{_largest(solved, 'path_value', '.1e')}"
        )
    if rows:
        most = max(rows, key=lambda r: r.ipm_iterations)
        need = max(r.untouched_budget for r in rows)
        stopped = sum(r.reason.startswith(BUDGET_SPENT) for r in rows)
        lines.append(
            f"  IPM iterations of a call, every landing: largest {most.ipm_iterations} (landing "
            f"{most.index}); an --ipm-budget (socp_max_iter_total) of {need} or more leaves "
            "every landing as it is (a warm-started subproblem is given half of what is left)"
            + (f"; --ipm-budget {ipm_budget} stopped {stopped}" if stopped else "")
        )
    failed = [r for r in rows if r.failed]
    if failed:
        lines.append(f"  not solved, or failing the open-loop check ({len(failed)}):")
        for r in failed:
            why = r.reason if r.status != "solved" else f"open loop: {r.failed_checks}"
            lines.append(f"    landing {r.index}: {r.status}: {why}")
    return "\n".join(lines)


def campaign_record(args: argparse.Namespace) -> dict[str, object]:
    """What a campaign ran with, and the command that solves one of its landings again."""
    solve = ["guidance", "solve", "--backend", "c", "--method", args.method]
    if args.ipm_budget != SCvxSettings().socp_max_iter_total:
        solve += ["--ipm-budget", str(args.ipm_budget)]
    landing_file = Path("landing_<i>.json")
    if getattr(args, "failures", None) is not None:  # the file as written there
        landing_file = args.failures / landing_file
    return {
        "count": args.landings,
        "seed": args.seed,
        "nodes": args.nodes,
        "method": args.method,
        "ipm_budget": args.ipm_budget,
        "solve_again": " ".join(solve) + " " + shlex.quote(str(landing_file)),
    }


def _plain(row: Landing) -> dict[str, object]:
    """A landing as strict JSON: NaN (no figure) as null."""
    plain = asdict(row)
    return {k: None if isinstance(v, float) and math.isnan(v) else v for k, v in plain.items()}


def _failures_folder(folder: Path) -> None:
    """Make the --failures folder before the campaign; refuse one holding an earlier one's
    files (they would mix) or that cannot be made."""
    from guidance.atomic import check_folder

    check_folder("--failures", folder)
    if folder.is_dir() and any(folder.glob("landing_*.json")):
        raise InputError(f"--failures {folder}: holds an earlier campaign's landings")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"--failures {folder}: cannot create it ({exc.strerror})") from None


def write_failures(
    folder: Path, rows: Sequence[Landing], scenarios: Sequence[Scenario], args: argparse.Namespace
) -> None:
    """Each failed landing as ``landing_<index>.json`` (a scenario file), and
    ``campaign.json``: the campaign's options, each failure's status and reason, and the
    command that solves a landing again."""
    from guidance.atomic import write_text_atomic
    from guidance.scenario import scenario_to_dict

    failed = [r for r in rows if r.failed]
    try:
        for r in failed:
            text = json.dumps(scenario_to_dict(scenarios[r.index]), indent=1) + "\n"
            write_text_atomic(folder / f"landing_{r.index}.json", text)
        record = {
            **campaign_record(args),
            "failures": {
                f"landing_{r.index}.json": {"status": r.status, "reason": r.reason}
                | ({"open_loop_failed": r.failed_checks} if r.failed_checks else {})
                for r in failed
            },
        }
        write_text_atomic(folder / "campaign.json", json.dumps(record, indent=1) + "\n")
    except OSError as exc:
        raise InputError(f"--failures {folder}: {exc.strerror}") from None


def add_arguments(ap: argparse.ArgumentParser) -> None:
    from guidance.bench_tscvx import BENCH_SEED

    budget_min, budget_max = INT_SETTING_RANGES["socp_max_iter_total"]
    ap.add_argument("--landings", type=at_least(1), default=100, help="landings (default 100)")
    ap.add_argument(
        "--seed", type=at_least(0), default=BENCH_SEED,
        help="draw seed (default %(default)s, the T-SCvx benchmark's: never trained on)",
    )  # fmt: skip
    ap.add_argument(
        "--nodes", type=at_least(N_MIN, N_MAX), default=NETWORK_N,
        help=f"N, in [{N_MIN}, {N_MAX}] (default %(default)s; tscvx: the networks' {NETWORK_N})",
    )  # fmt: skip
    ap.add_argument("--method", choices=METHODS, default="scvx", help="default scvx")
    ap.add_argument(
        "--ipm-budget", type=at_least(budget_min, budget_max),
        default=SCvxSettings().socp_max_iter_total,
        help="socp_max_iter_total of every call (default %(default)s: never binds)",
    )  # fmt: skip
    add_workers_option(ap, "landings solved at once")
    ap.add_argument(
        "--failures", type=Path,
        help="new folder for each landing not solved or failing the open-loop check "
        "(landing_<i>.json, a scenario file) and campaign.json (how to solve one again)",
    )  # fmt: skip
    ap.add_argument(
        "--run-dir", type=Path,
        help="folder keeping each landing as it finishes (run.json: the campaign's options); "
        "the same command again resumes an interrupted campaign, solving only what is missing",
    )  # fmt: skip
    ap.add_argument("--json", action="store_true", help="print the campaign and every landing")


def run(args: argparse.Namespace, progress: bool = True) -> int:
    """The campaign for parsed options (add_arguments): 0, or 1 when a solved landing fails the
    open-loop check. Interrupted while solving (Ctrl-C, SIGTERM), it raises Interrupted saying
    how far it got; a worker process that died, WorkerDiedError saying what is kept."""
    from guidance.bench_tscvx import sample_landings

    _check_options(args)
    settings = SCvxSettings(socp_max_iter_total=args.ipm_budget)
    scenarios = [
        Scenario(s.initial, s.params.replace(N=args.nodes))
        for s in sample_landings(args.landings, seed=args.seed)
    ]
    store = None
    if args.run_dir is not None:
        from guidance.runs import RunResults

        store = RunResults(args.run_dir, run_config(args, scenarios, settings), "landings")
    done = {} if store is None else store.kept(args.landings, landing_of)
    jobs = [(i, s, settings, args.method) for i, s in enumerate(scenarios) if i not in done]
    try:
        _solve(jobs, done, store, args, progress)
    except KeyboardInterrupt:
        raise Interrupted(interrupted(args, len(done))) from None
    rows = [done[i] for i in range(args.landings)]
    if args.json:
        versions = store.versions if store is not None else [code_version()]
        record = {**campaign_record(args), "code_versions": versions}
        record["landings"] = [_plain(r) for r in rows]
        print(json.dumps(record, indent=1, allow_nan=False))
    else:
        print(report(rows, args.method, args.nodes, args.seed, args.ipm_budget))
    sys.stdout.flush()  # the report stands even if the failures cannot be written
    if args.failures is not None:
        write_failures(args.failures, rows, scenarios, args)
    return 1 if any(r.status == "solved" and not r.verified for r in rows) else 0


def _check_options(args: argparse.Namespace) -> None:
    """Refuse, before any work, what the campaign could not run or keep."""
    from guidance.atomic import check_folder
    from guidance.cgnc import require_library

    require_library()
    if args.method == "tscvx" and args.nodes != NETWORK_N:
        raise InputError(
            f"--method tscvx: the shipped networks are for N = {NETWORK_N}, "
            f"not --nodes {args.nodes}"
        )
    if args.run_dir is not None:
        check_folder("--run-dir", args.run_dir)
        if args.failures is not None and _same_folder(args.failures, args.run_dir):
            raise InputError(f"--failures {args.failures}: is the --run-dir folder")
    if args.failures is not None:
        _failures_folder(args.failures)


def _same_folder(a: Path, b: Path) -> bool:
    return os.path.realpath(a) == os.path.realpath(b)


def run_config(
    args: argparse.Namespace, scenarios: Sequence[Scenario], settings: SCvxSettings
) -> dict[str, object]:
    """What defines a campaign's landings (a --run-dir's run.json): the options, the settings
    of every call, a digest of the landings drawn (the sampler's code) and, for T-SCvx, of
    the networks. A resume must have every one."""
    drawn = json.dumps([asdict(s) for s in scenarios]).encode()
    config: dict[str, object] = {
        "landings": args.landings,
        "seed": args.seed,
        "nodes": args.nodes,
        "method": args.method,
        "ipm_budget": args.ipm_budget,
        "scvx_settings": asdict(settings),
        "drawn_landings_sha256": hashlib.sha256(drawn).hexdigest(),
    }
    if args.method == "tscvx":
        from guidance.cguidance import BUILD_MODELS_DIR, NET_KINDS, net_source
        from guidance.provenance import file_digest

        config["networks_sha256"] = {
            kind: file_digest(net_source(BUILD_MODELS_DIR, kind)) for kind in NET_KINDS
        }
    return config


def landing_of(plain: dict[str, object]) -> Landing:
    """A landing kept in a run directory (``_plain``) read back: the same fields, each of its
    kind (null: NaN); ValueError or TypeError otherwise."""
    names = {f.name: f.type for f in fields(Landing)}
    if not isinstance(plain, dict) or set(plain) != set(names):
        raise ValueError("not a landing's figures")
    values: dict[str, object] = {}
    for name, kind in names.items():
        v = plain[name]
        if kind == "float" and (v is None or type(v) in (int, float)):
            values[name] = math.nan if v is None else float(v)  # type: ignore[arg-type]
        elif type(v).__name__ == kind:  # exactly: a bool is no int here
            values[name] = v
        else:
            raise ValueError(f"{name} is {v!r}, not a {kind}")
    return Landing(**values)  # type: ignore[arg-type]


def _solve(
    jobs: list[tuple[int, Scenario, SCvxSettings, str]],
    done: dict[int, Landing],
    store: RunResults | None,
    args: argparse.Namespace,
    progress: bool,
) -> None:
    """Solves ``jobs`` into ``done`` and, with a run directory, into it, each landing as it
    finishes: an interruption or a dead worker loses only the landings in flight."""
    from tqdm import tqdm

    from guidance.pool import pool_results

    run_dir = store.run_dir if store is not None else None
    kept = (lambda: store.count(args.landings)) if store is not None else (lambda: 0)
    bar = tqdm(total=len(jobs), disable=not progress, unit="landing", file=sys.stderr,
               desc=f"landings ({len(done)} done before)")  # fmt: skip
    pool = pool_results(
        solve_landing, jobs, worker_count(args.workers), kept, args.landings, run_dir
    )
    with bar, pool as rows:
        for row in rows:
            if store is not None:
                store.keep(row.index, _plain(row))
            done[row.index] = row
            bar.update()


def interrupted(args: argparse.Namespace, finished: int | None = None) -> str:
    """What an interrupted campaign says after "interrupted: ", at any point of it: what it
    kept and how to go on (runs.landings_kept); ``finished``: the landings this process
    finished, when it was solving them."""
    from guidance.runs import landings_kept

    resume = f"to resume: {resume_command(args)}"
    return landings_kept(args.run_dir, args.landings, finished, resume)


def resume_command(args: argparse.Namespace) -> str:
    """The command that goes on with this campaign (its options, each written out)."""
    cmd = ["guidance", "dispersion", "--landings", str(args.landings), "--seed", str(args.seed),
           "--nodes", str(args.nodes), "--method", args.method,
           "--ipm-budget", str(args.ipm_budget)]  # fmt: skip
    if args.workers != 0:
        cmd += ["--workers", str(args.workers)]
    if args.failures is not None:
        cmd += ["--failures", str(args.failures)]
    cmd += ["--run-dir", str(args.run_dir)] + (["--json"] if args.json else [])
    return shlex.join(cmd)
