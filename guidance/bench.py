"""Benchmark of the reference SCvx on the default and ten further scenarios, and of the other
backends against it (same scenarios, same run)."""

from __future__ import annotations

import os
import platform
from typing import TYPE_CHECKING

import numpy as np

from guidance.catalog import SCENARIOS
from guidance.params import SCvxSettings

if TYPE_CHECKING:
    from guidance.scvx import SCvxResult

REFERENCE = "clarabel"  # the ground reference: Python SCvx on Clarabel
# Issue 4's target for the whole solve in the C library, against the reference in the same run
TARGET_SPEED_UP = 30.0
TARGET_SECONDS = 0.050


def run_scvx_bench(backends: list[str], repeats: int = 1, method: str = "scvx") -> None:
    """Solves every catalog scenario on each backend (best of ``repeats`` wall times), prints a
    table per backend, then each backend against the reference if it ran."""
    print(
        f"{'T-SCvx' if method == 'tscvx' else 'SCvx'} benchmark: {len(SCENARIOS)} scenarios, "
        f"N = 50, host {platform.machine()}, "
        f"{os.cpu_count()} cores, repeats {repeats}; the backends take turns on each scenario"
    )
    results, failures = solve_interleaved(backends, repeats, method)
    for backend in results:
        print(f"\nmethod: {method}, backend: {backend}")
        print(
            f"{'scenario':12s} {'status':10s} {'k':>3s} {'solves':>6s} {'t_f':>7s} "
            f"{'m_f':>8s} {'total[s]':>9s} {'sub[ms]':>8s}"
        )
        subs = []
        for name, best in results[backend].items():
            sub = [h.subproblem_time_s for h in best.history]
            subs.extend(sub)
            print(
                f"{name:12s} {best.status:10s} {best.iterations:3d} "
                f"{best.subproblems_solved:6d} {best.t_f:7.3f} {best.m_f:8.5f} "
                f"{best.solve_time_s:9.3f} {1e3 * np.median(sub):8.1f}"
            )
        done = results[backend].values()
        print(
            f"median: total {np.median([r.solve_time_s for r in done]):.3f} s per solve, "
            f"subproblem {1e3 * np.median(subs):.1f} ms (over all subproblems), "
            f"iterations {np.median([r.iterations for r in done]):.0f}"
        )
    for line in against_reference(results):
        print(line)
    if failures:  # the others' figures are printed first; the command still fails
        raise RuntimeError(
            "; ".join(f"backend {b} failed on scenario {n}: {e}" for b, (n, e) in failures.items())
        )


def solve_interleaved(
    backends: list[str], repeats: int, method: str
) -> tuple[dict[str, dict[str, SCvxResult]], dict[str, tuple[str, str]]]:
    """Every catalog scenario on every backend, the best of ``repeats`` wall times each. The
    backends take turns within each scenario and repeat, so that a slow spell of the machine
    meets them alike: the speed-ups are paired under the same conditions, not taken from
    phases run minutes apart. A backend that raises (its library not built, say) leaves the
    rotation: its (scenario, error) is returned beside the others' results."""
    from tqdm import tqdm

    from guidance.api import solve

    results: dict[str, dict[str, SCvxResult]] = {b: {} for b in backends}
    failures: dict[str, tuple[str, str]] = {}
    for name, scenario in tqdm(SCENARIOS.items(), desc="scenarios", unit="scenario", leave=False):
        for _ in range(repeats):
            for backend in [b for b in backends if b not in failures]:
                try:
                    r = solve(scenario, method, backend, SCvxSettings())
                except Exception as exc:  # reported with the others' figures
                    failures[backend] = (name, f"{type(exc).__name__}: {exc}")
                    continue
                best = results[backend].get(name)
                if best is None or r.solve_time_s < best.solve_time_s:
                    results[backend][name] = r
    for backend in failures:
        del results[backend]
    return results, failures


def against_reference(results: dict[str, dict[str, SCvxResult]]) -> list[str]:
    """Each backend against the reference on the scenarios both solved in this run: how many
    end on the reference's trajectory (``agreement.same_trajectory``), the median time per
    landing, and the speed-up (ratio of mean times, with its 95 % bootstrap interval over the
    scenarios); for the C library, issue 4's target next to it. Empty without the reference
    or another backend."""
    from guidance.agreement import same_trajectory
    from guidance.bench_socp import near_target
    from guidance.bench_tscvx import ratio_interval

    ref = results.get(REFERENCE, {})
    others = [b for b in results if b != REFERENCE and results[b]]
    if not ref or not others:
        return []
    lines = [
        f"\nagainst the reference (Python SCvx on {REFERENCE}), same scenarios, this run:",
        f"{'backend':10s} {'same trajectory':>15s} {'median[s]':>10s} {'speed-up':>9s} "
        f"{'95% interval':>14s}",
    ]
    for backend in others:
        names = [n for n in ref if n in results[backend]]
        t_ref = np.array([ref[n].solve_time_s for n in names])
        t = np.array([results[backend][n].solve_time_s for n in names])
        same = sum(same_trajectory(results[backend][n], ref[n]) for n in names)
        speed_up = float(t_ref.mean() / t.mean())
        lo, hi = ratio_interval(t_ref, t)
        lines.append(
            f"{backend:10s} {f'{same} of {len(names)}':>15s} {np.median(t):10.3f} "
            f"{speed_up:8.2f}x {f'[{lo:.2f}, {hi:.2f}]':>14s}"
        )
        if backend == "c":
            median = float(np.median(t))
            met = speed_up >= TARGET_SPEED_UP and median < TARGET_SECONDS
            lines.append(
                f"  issue 4's target for the C library: >= {TARGET_SPEED_UP:.0f}x and "
                f"< {TARGET_SECONDS:.3f} s per landing; this run "
                f"{near_target(speed_up, TARGET_SPEED_UP)}x (ratio of means) and "
                f"{near_target(median, TARGET_SECONDS, 4)} s (median): "
                f"{'met' if met else 'not met'}"
            )
    lines += [
        "  median[s]: the backend's median time per landing; speed-up: the reference's mean "
        "time over the backend's (ratio of means, not of the medians)",
        "  95% interval: bootstrap over this run's scenarios (the backends took turns on each); "
        "repeat runs on a shared machine can move the ratio further",
    ]
    return lines
