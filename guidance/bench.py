"""Benchmark of the reference SCvx on the default and ten further scenarios."""

from __future__ import annotations

import os
import platform

import numpy as np

from guidance.catalog import SCENARIOS
from guidance.params import SCvxSettings


def run_scvx_bench(backends: list[str], repeats: int = 1, method: str = "scvx") -> None:
    from guidance.api import solve

    print(
        f"SCvx benchmark: {len(SCENARIOS)} scenarios, N = 50, host {platform.machine()}, "
        f"{os.cpu_count()} cores, repeats {repeats}"
    )
    for backend in backends:
        print(f"\nmethod: {method}, backend: {backend}")
        print(
            f"{'scenario':12s} {'status':10s} {'k':>3s} {'solves':>6s} {'t_f':>7s} "
            f"{'m_f':>8s} {'total[s]':>9s} {'sub[ms]':>8s}"
        )
        totals, subs, iters = [], [], []
        for name, scenario in SCENARIOS.items():
            best = None
            for _ in range(repeats):
                r = solve(scenario, method, backend, SCvxSettings())
                if best is None or r.solve_time_s < best.solve_time_s:
                    best = r
            assert best is not None
            sub = [h.subproblem_time_s for h in best.history]
            totals.append(best.solve_time_s)
            subs.extend(sub)
            iters.append(best.iterations)
            print(
                f"{name:12s} {best.status:10s} {best.iterations:3d} "
                f"{best.subproblems_solved:6d} {best.t_f:7.3f} {best.m_f:8.5f} "
                f"{best.solve_time_s:9.3f} {1e3 * np.median(sub):8.1f}"
            )
        print(
            f"median: total {np.median(totals):.3f} s per solve, subproblem "
            f"{1e3 * np.median(subs):.1f} ms, iterations {np.median(iters):.0f}"
        )
