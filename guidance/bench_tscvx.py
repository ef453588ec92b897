"""What the networks buy: SCvx against T-SCvx on fresh sampled landings (paper Algorithm 2).

The landings are drawn from the training distribution with a seed of their own (so none was
trained on) and turned by a random multiple of 45 degrees about the up axis. Each is solved by
plain SCvx (cubic guess, eta_init 2) and by two T-SCvx variants with the shipped networks:

  warm start   the solution network's trajectory as the initial guess, eta_reduced,init 0.01
  Algorithm 2  the same plus the constraint network's per-iteration tight masks
  Algorithm 2 with Algorithm 1's radius update (Eq. (15))
               the same, the trust radius updated as in Algorithm 1 (tau_r_update off)

Subproblems solved (accepted and rejected) is the figure that flight time follows; the final
mass difference says what the warm start costs in fuel (a different local optimum).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from guidance.params import IM, Scenario, SCvxSettings
from guidance.scvx import SCvxResult

BENCH_SEED = 20261122  # not the dataset's seed: these landings were never trained on


@dataclass
class Variant:
    name: str
    results: list[SCvxResult] = field(default_factory=list)
    wall_s: list[float] = field(default_factory=list)


def sample_landings(n: int, seed: int = BENCH_SEED) -> list[Scenario]:
    from guidance.sampling import ROTATION_DEG, SamplingRanges, base_scenario
    from guidance.symmetry import rotate_scenario

    rng = np.random.default_rng(seed)
    ranges = SamplingRanges()
    out = []
    for i in range(n):
        scenario, _ = base_scenario(seed, i, ranges)
        deg = ROTATION_DEG[int(rng.integers(len(ROTATION_DEG)))]  # the dataset's symmetry
        out.append(rotate_scenario(scenario, math.radians(deg)))
    return out


def _solver(backend: str) -> Callable[..., SCvxResult]:
    if backend == "c":
        from guidance.cguidance import solve_c

        return solve_c

    from guidance.scvx import SCvxSolver

    conic_backend = "c" if backend == "c-socp" else backend

    def solve(scenario, settings, guess=None, masks=None):
        return SCvxSolver(scenario, settings, conic_backend).solve(guess=guess, masks=masks)

    return solve


def run(n: int, backend: str = "c", models_dir: Path | None = None, progress: bool = True):
    from tqdm import tqdm

    from guidance.guess import project_guess
    from guidance.nn.conventions import CONSTRAINT_MODEL, MODELS_DIR, SOLUTION_MODEL
    from guidance.nn.infer import ConstraintModel, SolutionModel
    from guidance.sampling import theta_of
    from guidance.tscvx import REDUCED_ETA_INIT

    models = models_dir or MODELS_DIR
    solve = _solver(backend)
    full = SCvxSettings()
    variants = [Variant("SCvx"), Variant("T-SCvx warm start"), Variant("T-SCvx (Algorithm 2)"),
                Variant("Alg. 2, Alg. 1 radius")]  # fmt: skip
    reduced = full.replace(eta_init=REDUCED_ETA_INIT)
    # (settings, masks) of each T-SCvx variant
    tscvx_runs = ((reduced, False), (reduced, True), (reduced.replace(tau_r_update=False), True))
    sol_model = con_model = None
    landings = sample_landings(n)
    if backend == "c":  # the on-board call: both networks run in C too (pdg_solve_tscvx)
        from guidance.cguidance import _nets, solve_tscvx_c

        nets = _nets(models, True, landings[0].params)
    for scenario in tqdm(landings, desc="landings", disable=not progress):
        t0 = time.perf_counter()
        variants[0].results.append(solve(scenario, full))
        variants[0].wall_s.append(time.perf_counter() - t0)
        if backend == "c":
            for v, (st, masked) in zip(variants[1:], tscvx_runs, strict=True):
                t0 = time.perf_counter()
                v.results.append(
                    solve_tscvx_c(scenario, st, masks=masked, eta_init=st.eta_init, nets=nets)
                )
                v.wall_s.append(time.perf_counter() - t0)
            continue
        if sol_model is None:
            sol_model = SolutionModel(models / SOLUTION_MODEL, scenario.params)
            con_model = ConstraintModel(models / CONSTRAINT_MODEL, scenario.params)
        assert con_model is not None
        theta = theta_of(scenario)
        t0 = time.perf_counter()
        guess = project_guess(scenario, *sol_model.solution(theta))
        masks = con_model.mask_fn(theta)
        t_nn = time.perf_counter() - t0  # both networks and the projection, in Python
        for v, (st, masked) in zip(variants[1:], tscvx_runs, strict=True):
            t0 = time.perf_counter()
            v.results.append(solve(scenario, st, guess=guess, masks=masks if masked else None))
            v.wall_s.append(time.perf_counter() - t0 + t_nn)
    return variants


def ratio_interval(
    num: np.ndarray, den: np.ndarray, level: float = 0.95, n_boot: int = 2000, seed: int = 0
) -> tuple[float, float]:
    """Bootstrap interval of mean(num) / mean(den) over resampled landings (paired)."""
    num, den = np.asarray(num, float), np.asarray(den, float)
    idx = np.random.default_rng(seed).integers(0, len(num), size=(n_boot, len(num)))
    r = num[idx].mean(axis=1) / den[idx].mean(axis=1)
    lo, hi = np.quantile(r, [(1.0 - level) / 2.0, (1.0 + level) / 2.0])
    return float(lo), float(hi)


def report(variants: list[Variant], backend: str) -> list[str]:
    base = variants[0]
    n = len(base.results)
    both = [i for i in range(n) if base.results[i].status == "solved"]
    lines = [
        f"T-SCvx benchmark: {n} fresh landings (seed {BENCH_SEED}), backend {backend}; "
        f"fuel and ratios over the {len(both)} that SCvx solves",
        f"{'variant':22s} {'solved':>6s} {'subprob.':>8s} {'iter.':>6s} {'time[s]':>8s} "
        f"{'speed-up':>8s} {'95% interval':>14s} {'dm_f med':>9s} {'dm_f min':>9s}",
    ]
    base_s = np.array([base.wall_s[i] for i in both])
    t_base = float(base_s.mean()) if both else math.nan
    for v in variants:
        ok = [i for i in both if v.results[i].status == "solved"]
        dm = [
            (v.results[i].x[-1, IM] - base.results[i].x[-1, IM]) / base.results[i].x[-1, IM]
            for i in ok
        ]
        v_s = np.array([v.wall_s[i] for i in both])
        t = float(v_s.mean()) if both else math.nan
        lo, hi = ratio_interval(base_s, v_s) if len(both) > 1 else (math.nan, math.nan)
        lines.append(
            f"{v.name:22s} {sum(r.status == 'solved' for r in v.results):6d} "
            f"{np.mean([v.results[i].subproblems_solved for i in both]):8.2f} "
            f"{np.mean([v.results[i].iterations for i in both]):6.2f} {t:8.3f} "
            f"{t_base / t:7.2f}x {f'[{lo:.2f}, {hi:.2f}]':>14s} {np.median(dm):+9.1e} "
            f"{np.min(dm):+9.1e}"
        )
    lines.append(
        "subprob./iter./time: means per landing; speed-up: mean SCvx time / mean time, with its "
        "95% bootstrap interval over the landings; dm_f: final mass relative to SCvx's "
        "(negative: more fuel burnt); time includes the network inference for T-SCvx (in C "
        "with the C backend: the on-board call pdg_solve_tscvx)"
    )
    return lines


def main(n: int = 24, backend: str = "c") -> int:
    variants = run(n, backend)
    print("\n".join(report(variants, backend)))
    return 0
