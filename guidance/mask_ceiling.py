"""How well can any (theta, k) -> tight-mask predictor do? A ceiling measured on SCvx itself.

The constraint network maps a landing's parameters theta and the iteration k to the tight set
of the k-th subproblem. That map is only as regular as the SCvx path: a change of theta far
smaller than a training set can resolve moves accept/reject decisions and tight-constraint
labels. This module measures how far. For each of a few landings it solves neighbours within
a distance eps of theta (in units of the sampling distribution's standard deviation per
component) and scores, leave-one-out, two predictors that know the exact masks of all the
other neighbours of the same iteration k:

  union     a bit is predicted tight if any other neighbour has it tight (recall first);
  vote>=2   if at least two of them have it tight.

A network cannot resolve detail finer than its training data's spacing, printed beside: the
median distance from a fresh landing to the nearest training landing (its eight rotations
included), in the same units.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from guidance.atomic import atomic_write
from guidance.dataset_run import scvx_solver
from guidance.errors import UNREADABLE_NPZ, InputError, npz_damage
from guidance.nn.tight_set import ALWAYS_KEPT, droppable_bits, fmt_rate, ratio
from guidance.params import Scenario, SCvxSettings
from guidance.pool import pool_results
from guidance.provenance import provenance
from guidance.runs import check_run
from guidance.sampling import (
    ROTATION_DEG,
    SamplingRanges,
    base_scenario,
    rotate_theta,
    scenario_of,
    theta_of,
)
from guidance.scenario import ScenarioError, validate

# theta components moved by a perturbation: r0, v0, the pitch and yaw rates, m0, glideslope
# and tilt limit. q0 (unit norm) and the roll rate (zero by design) stay as drawn.
PERTURBED = (0, 1, 2, 3, 4, 5, 11, 12, 13, 14, 15)
RULES = (("union", 1), ("vote>=2", 2))
DATA_SEED = 0  # the dataset's sampling seed (guidance dataset --seed)
LANDING_SEED = 7  # landings whose neighbourhoods are probed (any seed other than the data's)


@dataclass(frozen=True)
class Score:
    """Leave-one-out counts of one rule at one eps, over every (landing, neighbour, k)."""

    eps: float
    rule: str
    tp: int
    fp: int
    fn: int
    rows: int  # (neighbour, k) masks scored
    rows_missing: int  # of which at least one tight bit was not predicted

    @property
    def precision(self) -> float | None:
        return ratio(self.tp, self.tp + self.fp)  # None (undefined) when no bit is predicted

    @property
    def recall(self) -> float | None:
        return ratio(self.tp, self.tp + self.fn)  # None when no bit is tight


def theta_spread(n: int = 2000, seed: int = DATA_SEED) -> np.ndarray:
    """Standard deviation of each theta component over n sampled base landings (1 where the
    component does not vary)."""
    ranges = SamplingRanges()
    th = np.array([theta_of(base_scenario(seed, i, ranges)[0]) for i in range(n)])
    std = th.std(axis=0)
    return np.where(std > 0, std, 1.0)


def neighbour(theta: np.ndarray, eps: float, std: np.ndarray, rng: np.random.Generator):
    """theta moved by eps (standardized distance) in a random direction of PERTURBED."""
    d = np.zeros_like(theta)
    d[list(PERTURBED)] = rng.normal(size=len(PERTURBED))
    d *= eps / np.linalg.norm(d)
    return theta + d * std


def loo_counts(masks: Sequence[np.ndarray], min_votes: int) -> tuple[int, int, int, int, int]:
    """(tp, fp, fn, rows, rows_missing) of predicting each neighbour's (k, 7N) masks from the
    others': a bit is predicted where at least ``min_votes`` others have it, iteration by
    iteration over the iterations all of them reached. Only the bits of the constraints the
    flight code can drop count (not T_min's: tight_set.ALWAYS_KEPT)."""
    tp = fp = fn = rows = missing = 0
    cols = droppable_bits(np.shape(masks[0])[1])
    for j, target in enumerate(masks):
        others = [m for i, m in enumerate(masks) if i != j]
        K = min(len(m) for m in masks)
        T = np.asarray(target[:K], bool)[:, cols]
        votes = sum(np.asarray(o[:K], np.int64)[:, cols] for o in others)
        pred = votes >= min_votes
        tp += int((pred & T).sum())
        fp += int((pred & ~T).sum())
        fn += int((~pred & T).sum())
        rows += K
        missing += int(((~pred & T).sum(axis=1) > 0).sum())
    return tp, fp, fn, rows, missing


def data_spacing(n_train: int, std: np.ndarray, n_query: int = 500, seed: int = DATA_SEED) -> float:
    """Median standardized distance from a fresh landing to the nearest of n_train training
    landings and their rotations (all components but the roll rate)."""
    from scipy.spatial import cKDTree

    ranges = SamplingRanges()
    base = [theta_of(base_scenario(seed, i, ranges)[0]) for i in range(n_train)]
    train = np.array([rotate_theta(t, np.radians(deg)) for t in base for deg in ROTATION_DEG])
    query = np.array([theta_of(base_scenario(seed + 1, i, ranges)[0]) for i in range(n_query)])
    dist, _ = cKDTree(train / std).query(query / std)
    return float(np.median(dist))


def neighbour_masks(job: tuple) -> tuple[float, int, list[np.ndarray]]:
    """Worker: the per-iteration masks of ``n`` solved neighbours of landing ``i`` at ``eps``.
    Neighbours that are not valid landings, or that SCvx does not solve, are redrawn (at
    most 10 n draws); the draws depend only on (seed, i, eps)."""
    eps, i, theta, std, n, backend, seed = job
    rng = np.random.default_rng([seed, i, round(eps * 1e6)])
    solve: Callable[[Scenario, SCvxSettings], Any] = scvx_solver(backend)
    settings = SCvxSettings()
    masks: list[np.ndarray] = []
    for _ in range(10 * n):
        if len(masks) == n:
            break
        scenario = scenario_of(neighbour(theta, eps, std, rng))
        try:
            validate(scenario)
        except ScenarioError:
            continue
        r = solve(scenario, settings)
        if r.status == "solved":
            masks.append(np.asarray(r.masks, np.uint8))
    return eps, i, masks


def _cache_file(run_dir: Path, eps: float, i: int) -> Path:
    return run_dir / f"eps{eps:g}_landing{i:04d}.npz"


def _check_run(run_dir: Path, config: dict[str, Any]) -> list[str]:
    """A resume must use the run's options; returns the code versions that worked on it."""
    return check_run(run_dir, config, "neighbours")


def measure(
    n_landings: int,
    n_neighbours: int,
    eps_values: Sequence[float],
    backend: str = "c",
    seed: int = LANDING_SEED,
    std: np.ndarray | None = None,
    progress: bool = True,
    workers: int = 1,
    run_dir: str | Path | None = None,
) -> list[Score]:
    """Scores of every rule at every eps, over the landings with at least 3 solved
    neighbours. With ``run_dir`` each landing's neighbour masks are kept there as they are
    solved, and a rerun of the same run solves only what is missing."""
    std = theta_spread() if std is None else std
    ranges = SamplingRanges()
    landings = [theta_of(base_scenario(seed, i, ranges)[0]) for i in range(n_landings)]
    cache = Path(run_dir) if run_dir is not None else None
    if cache is not None:
        config = dict(seed=seed, neighbours=n_neighbours, backend=backend,
                      settings=dataclasses.asdict(SCvxSettings()), std=std.tolist())  # fmt: skip
        _check_run(cache, config)
    found, missing = _cached_masks(cache, eps_values, n_landings)
    jobs = [(eps, i, landings[i], std, n_neighbours, backend, seed) for eps, i in missing]
    _solve_missing(jobs, found, len(eps_values) * n_landings, workers, cache, progress)
    scores = []
    for eps in eps_values:
        groups = [found[eps, i] for i in range(n_landings) if len(found[eps, i]) >= 3]
        scores += [_score(eps, rule, votes, groups) for rule, votes in RULES]
    return scores


def _cached_masks(
    cache: Path | None, eps_values: Sequence[float], n_landings: int
) -> tuple[dict[tuple[float, int], list[np.ndarray]], list[tuple[float, int]]]:
    """The neighbour masks the run directory holds already, by (eps, landing), and the
    (eps, landing) pairs it does not hold, in the order of the run."""
    found: dict[tuple[float, int], list[np.ndarray]] = {}
    missing: list[tuple[float, int]] = []
    for eps in eps_values:
        for i in range(n_landings):
            path = _cache_file(cache, eps, i) if cache is not None else None
            if path is not None and path.exists():
                found[eps, i] = _read_masks(path)
            else:
                missing.append((eps, i))
    return found, missing


def _read_masks(path: Path) -> list[np.ndarray]:
    """The neighbour masks a run keeps in ``path`` (arr_0, arr_1, ... in the order of the
    neighbours, each (iterations, 7N) of 0/1); InputError naming the file otherwise."""
    try:
        with np.load(path, allow_pickle=False) as f:
            names = sorted(f.files, key=lambda k: int(k.removeprefix("arr_")))
            masks = [f[k] for k in names]
    except UNREADABLE_NPZ as exc:
        problem = npz_damage(exc)
    else:
        bad = [m for m in masks if m.ndim != 2 or m.dtype != np.uint8 or m.max(initial=0) > 1]
        if not bad and len({m.shape[1] for m in masks}) <= 1:
            return masks
        problem = (
            f"holds a {bad[0].dtype} array of shape {bad[0].shape}, not 0/1 masks"
            if bad
            else "its masks differ in width"
        )
    raise InputError(
        f"{path}: not a neighbourhood a mask-ceiling run keeps ({problem}); delete it (its "
        "neighbours are solved again)"
    )


def _solve_missing(
    jobs: list[tuple],
    found: dict[tuple[float, int], list[np.ndarray]],
    n_total: int,
    workers: int,
    cache: Path | None,
    progress: bool,
) -> None:
    """Solves the neighbourhoods of ``jobs`` into ``found`` and the run directory, one file
    each as it finishes: a dead worker (WorkerDiedError) loses only the unfinished ones."""
    from tqdm import tqdm

    bar = tqdm(total=len(jobs), disable=not progress, unit="landing",
               desc=f"neighbourhoods ({len(found)} done before)")  # fmt: skip
    pool = pool_results(neighbour_masks, jobs, workers, found.__len__, n_total, cache)
    with bar, pool as results:
        for eps, i, masks in results:
            found[eps, i] = masks
            if cache is not None:
                with atomic_write(_cache_file(cache, eps, i)) as f:
                    np.savez(f, *masks)
            bar.update()


def _score(eps: float, rule: str, min_votes: int, groups: list[list[np.ndarray]]) -> Score:
    """One rule's leave-one-out counts summed over the neighbourhoods ``groups``."""
    counts = np.zeros(5, np.int64)
    for masks in groups:
        counts += loo_counts(masks, min_votes)
    tp, fp, fn, rows, missing = (int(v) for v in counts)
    return Score(eps, rule, tp, fp, fn, rows, missing)


def format_table(
    scores: Sequence[Score], n_neighbours: int, spacing: float | None, n_train: int | None
) -> str:
    lines = [
        f"Tight-set ceiling of a (theta, k) -> mask predictor: each of {n_neighbours} "
        f"neighbours' masks predicted from the other {n_neighbours - 1}'s",
        f"{'eps [std]':>9}  {'rule':8}  {'precision':>9}  {'recall':>6}  "
        f"{'masks':>6}  {'missing a bit':>13}",
    ]
    for s in scores:
        lines.append(
            f"{s.eps:9.3f}  {s.rule:8}  {fmt_rate(s.precision):>9}  {fmt_rate(s.recall):>6}  "
            f"{s.rows:6d}  "
            f"{s.rows_missing / max(s.rows, 1):13.1%}"
        )
    if spacing is not None:
        lines.append(
            f"training data spacing: a fresh landing's nearest training landing (of {n_train} "
            f"x 8 rotations) is {spacing:.2f} std away (median)"
        )
    return "\n".join(lines)


def results_dict(
    scores: Sequence[Score], spacing: float | None, n_train: int | None, **run: Any
) -> dict[str, Any]:
    """What ``guidance mask-ceiling`` writes (models/mask_ceiling.json) for the model card."""
    return {
        "provenance": provenance(),
        "run": run,
        "scores": [
            {**dataclasses.asdict(s), "precision": s.precision, "recall": s.recall} for s in scores
        ],
        "data_spacing_std": spacing,
        "n_train_landings": n_train,
        "headline_excludes": list(ALWAYS_KEPT),  # bits not counted (always kept in flight)
    }
