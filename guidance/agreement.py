"""How many digits of an SCvx answer two correct conic solvers share (`guidance agreement`).

Every landing is solved by the reference (Python SCvx + Clarabel, subproblems at
``SCvxSettings.socp_tol`` = 1e-9) and by four variants:

  reference at 1e-10   the same loop and solver, subproblems one decade tighter
  Python + C SOCP      the reference loop on the flight conic solver (``--backend c-socp``)
  C library            the whole solve in the flight library (``--backend c``)
  converged            the C library with every subproblem solved to 1e-12

Each variant is scored against the reference and against the converged answer: how many
landings end within 1e-6 relative final mass with the same iteration count (issue 3's figure of
"the same trajectory"), and the median and largest final-mass gaps; the row "reference at 1e-10"
says how much of any disagreement the reference shows against itself. ``--prox-u 0`` runs every
variant with the paper's linear subproblem objective, whose optimal sets are flat in the thrust
history: each solver stops at its own point of them within its tolerance, and SCvx's
accept/reject steps amplify that (SCvxSettings.prox_u).
"""

from __future__ import annotations

import hashlib
import json
import math
import statistics
import sys
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from guidance.errors import Interrupted
from guidance.params import Scenario, SCvxSettings

if TYPE_CHECKING:
    from guidance.runs import RunResults
    from guidance.scvx import SCvxResult

STRICT_REL_MF = 1e-6  # issue 3's "same trajectory": final mass within 1e-6 relative ...
# ... and the same iteration count.
CONVERGED_TOL = 1e-12
CELL = 20  # width of a variant's column in the per-landing table


class Landed(Protocol):
    """What the comparison reads of a solve: an Outcome, or an SCvxResult itself."""

    @property
    def m_f(self) -> float: ...
    @property
    def iterations(self) -> int: ...
    @property
    def status(self) -> str: ...


@dataclass(frozen=True)
class Outcome:
    """The figures of one solve that the comparison uses."""

    m_f: float
    iterations: int
    status: str


def _reference(scenario: Scenario, st: SCvxSettings, tol: float) -> Outcome:
    from guidance.scvx import solve_scvx

    return _outcome(solve_scvx(scenario, st.replace(socp_tol=tol)))


def _python_c_socp(scenario: Scenario, st: SCvxSettings) -> Outcome:
    from guidance.scvx import solve_scvx

    return _outcome(solve_scvx(scenario, st, backend="c"))


def _c_library(scenario: Scenario, st: SCvxSettings, tol: float) -> Outcome:
    from guidance.cguidance import solve_c

    return _outcome(solve_c(scenario, st.replace(socp_tol=tol)))


def _outcome(result: SCvxResult) -> Outcome:
    return Outcome(result.m_f, result.iterations, result.status)


REFERENCE = "reference (Clarabel, 1e-9)"
CONVERGED = "converged (C, 1e-12)"
VARIANTS: dict[str, Callable[[Scenario, SCvxSettings], Outcome]] = {
    REFERENCE: lambda s, st: _reference(s, st, st.socp_tol),
    "reference at 1e-10": lambda s, st: _reference(s, st, 1e-10),
    "Python + C SOCP": _python_c_socp,
    "C library": lambda s, st: _c_library(s, st, st.socp_tol),
    CONVERGED: lambda s, st: _c_library(s, st, CONVERGED_TOL),
}


def solve_landing(job: tuple[int, Scenario, SCvxSettings]) -> tuple[int, dict[str, Outcome]]:
    """Every variant on landing ``i`` (a pool job: module-level, picklable)."""
    i, scenario, st = job
    return i, {variant: solve(scenario, st) for variant, solve in VARIANTS.items()}


def outcomes_json(outcomes: dict[str, Outcome]) -> dict[str, dict[str, object]]:
    """A landing's outcomes as strict JSON (a NaN final mass as null), for a run directory."""
    return {
        v: {**asdict(o), "m_f": None if math.isnan(o.m_f) else o.m_f} for v, o in outcomes.items()
    }


def outcomes_of(plain: dict[str, dict[str, Any]]) -> dict[str, Outcome]:
    """``outcomes_json`` read back; ValueError, KeyError or TypeError for anything else."""
    if list(plain) != list(VARIANTS):
        raise ValueError("not the outcomes of every variant")
    out = {}
    for v, o in plain.items():
        m_f, iterations, status = o["m_f"], o["iterations"], o["status"]
        if not (m_f is None or type(m_f) in (int, float)) or type(iterations) is not int:
            raise TypeError(f"{v}: not a final mass and an iteration count")
        out[v] = Outcome(math.nan if m_f is None else float(m_f), iterations, str(status))
    return out


def rel_gap(a: Landed, b: Landed) -> float:
    return abs(a.m_f - b.m_f) / abs(b.m_f)


def same_trajectory(a: Landed, b: Landed) -> bool:
    """Issue 3's figure: same status, final mass within 1e-6 relative, same iterations."""
    return a.status == b.status and rel_gap(a, b) <= STRICT_REL_MF and a.iterations == b.iterations


@dataclass(frozen=True)
class Score:
    """One variant against one baseline over all landings."""

    same: int  # landings meeting same_trajectory
    total: int
    median_gap: float
    max_gap: float


def score(results: Sequence[dict[str, Outcome]], variant: str, baseline: str) -> Score:
    gaps = [rel_gap(r[variant], r[baseline]) for r in results]
    same = sum(same_trajectory(r[variant], r[baseline]) for r in results)
    return Score(same, len(results), statistics.median(gaps), max(gaps))


def summary_table(results: Sequence[dict[str, Outcome]]) -> str:
    """Markdown table: each variant against the reference and against the converged answer."""
    lines = [
        "| variant | same as reference | median / max relative gap in m_f | same as converged "
        "| median / max relative gap in m_f |",
        "|---|---|---|---|---|",
    ]
    for variant in VARIANTS:
        cells = [variant]
        for baseline in (REFERENCE, CONVERGED):
            if variant == baseline:
                cells += ["–", "–"]
                continue
            s = score(results, variant, baseline)
            cells += [f"{s.same} of {s.total}", f"{s.median_gap:.1e} / {s.max_gap:.1e}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def landing_table(names: Sequence[str], results: Sequence[dict[str, Outcome]]) -> str:
    """Per landing: the reference's final mass and iterations, each variant's gap to it."""
    others = [v for v in VARIANTS if v != REFERENCE]
    head = f"{'landing':14s} {'m_f (ref)':>10s} {'it':>3s}"
    head += "".join(f" | {v[:CELL]:>{CELL}s}" for v in others)
    lines = [head]
    for name, r in zip(names, results, strict=True):
        ref = r[REFERENCE]
        row = f"{name:14s} {ref.m_f:10.6f} {ref.iterations:3d}"
        for v in others:
            o = r[v]
            mark = " " if same_trajectory(o, ref) else "*"
            row += " | " + f"{rel_gap(o, ref):.1e}{mark} it {o.iterations:3d}".rjust(CELL)
        lines.append(row)
    lines.append(
        "(each cell: the relative final-mass gap |m_f - m_f(ref)| / m_f(ref) and the iterations; "
        "*: not the reference's trajectory: 1e-6 relative final mass, same iterations)"
    )
    return "\n".join(lines)


def landings(
    catalog: Sequence[str] | None, n_random: int, files: Sequence[str] = ()
) -> list[tuple[str, Scenario]]:
    """The scenario files (named by their stem), the named catalog landings (all when None),
    then n fresh sampled landings (the T-SCvx benchmark's: from the training distribution,
    never trained on). A bad file raises ScenarioError, an unknown name ValueError."""
    from guidance.bench_tscvx import sample_landings
    from guidance.catalog import SCENARIOS
    from guidance.scenario import load_scenario

    names = list(SCENARIOS) if catalog is None else list(catalog)
    unknown = [n for n in names if n not in SCENARIOS]
    if unknown:
        raise ValueError(f"unknown catalog landings {unknown}; known: {list(SCENARIOS)}")
    jobs = [(Path(f).stem, load_scenario(f)) for f in files]
    jobs += [(n, SCENARIOS[n]) for n in names]
    jobs += [(f"sampled {i}", s) for i, s in enumerate(sample_landings(n_random))]
    return jobs


def main(
    catalog: Sequence[str] | None,
    n_random: int,
    workers: int,
    files: Sequence[str] = (),
    progress: bool = True,
    settings: SCvxSettings | None = None,
    run_dir: str | Path | None = None,
) -> int:
    """The comparison, printed: 0; 1 without the C library. With ``run_dir`` each landing's
    outcomes are kept there as they finish, and the same command again solves only the
    landings it does not hold. Interrupted while solving (Ctrl-C, SIGTERM), it raises
    Interrupted saying how far it got; a worker process that died, WorkerDiedError saying
    what is kept."""
    from guidance.cguidance import LIB_PATH

    st = settings or SCvxSettings()
    named = landings(catalog, n_random, files)
    if not LIB_PATH.exists():
        print(f"{LIB_PATH} not found: run `make lib` (the C variants need it)", file=sys.stderr)
        return 1
    store = None
    if run_dir is not None:
        from guidance.runs import RunResults

        store = RunResults(run_dir, _run_config(named, st), "landings")
    done = {} if store is None else store.kept(len(named), outcomes_of)
    jobs = [(i, s, st) for i, (_, s) in enumerate(named) if i not in done]
    try:
        _solve(jobs, done, store, len(named), workers, progress)
    except KeyboardInterrupt:
        raise Interrupted(interrupted(run_dir, len(named), len(done))) from None
    names = [name for name, _ in named]
    results = [done[i] for i in range(len(named))]
    plural = "" if len(results) == 1 else "s"
    objective = "paper's linear objective" if st.prox_u == 0 else f"prox_u = {st.prox_u:g}"
    print(
        f"SCvx final mass across conic solvers and tolerances, {len(results)} landing{plural} "
        f"(subproblems: {objective})"
    )
    print(landing_table(names, results))
    print()
    print(summary_table(results))
    return 0


def _run_config(named: Sequence[tuple[str, Scenario]], st: SCvxSettings) -> dict[str, object]:
    """What defines a run's outcomes (a --run-dir's run.json): the landings by name and a
    digest of their scenarios (a file edited since), the settings and the variants."""
    scenarios = json.dumps([asdict(s) for _, s in named]).encode()
    return {
        "landings": [name for name, _ in named],
        "scenarios_sha256": hashlib.sha256(scenarios).hexdigest(),
        "scvx_settings": asdict(st),
        "variants": list(VARIANTS),
    }


def _solve(
    jobs: list[tuple[int, Scenario, SCvxSettings]],
    done: dict[int, dict[str, Outcome]],
    store: RunResults | None,
    total: int,
    workers: int,
    progress: bool,
) -> None:
    """Solves ``jobs`` into ``done`` and the run directory, each landing as it finishes."""
    from tqdm import tqdm

    from guidance.pool import pool_results

    kept = (lambda: store.count(total)) if store is not None else (lambda: 0)
    run_dir = store.run_dir if store is not None else None
    bar = tqdm(total=len(jobs), disable=not progress, unit="landing", file=sys.stderr,
               desc=f"landings ({len(done)} done before)")  # fmt: skip
    pool = pool_results(solve_landing, jobs, workers, kept, total, run_dir)
    with bar, pool as results:
        for i, outcomes in results:
            if store is not None:
                store.keep(i, outcomes_json(outcomes))
            done[i] = outcomes
            bar.update()


def interrupted(
    run_dir: str | Path | None, total: int | None = None, finished: int | None = None
) -> str:
    """What an interrupted comparison says after "interrupted: ", at any point of it: what it
    kept and how to go on (runs.landings_kept); ``total`` and ``finished``: its landings and
    those this process finished, when it was solving them."""
    from guidance.runs import landings_kept

    return landings_kept(run_dir, total, finished, "run the same command again to resume")
