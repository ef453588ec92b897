"""Training of the constraint and solution networks (paper, "Training, Validation, and Testing").

- Only converged (``solved``) samples are used: they are what T-SCvx warm-starts and reduces.
- Split BY BASE SAMPLE: 20 % of the base landings (all eight rotations of each) are the test
  split; the rest is train+validation. Splitting after augmentation, as the paper appears to,
  would put rotations of test landings into training.
- Standardization: mean and standard deviation of the train+validation inputs and outputs
  (components with zero spread, e.g. the pinned final position, get scale 1).
- K-fold with K = 3 (folds by base sample too): one model is trained through the three folds in
  turn, each time on the other two folds, validated on the held-out one; the paper reports the
  third fold's numbers. AdamW, batch 128, linear learning-rate warm-up (the paper's 4000 steps,
  capped at a tenth of all steps for small data) then cosine decay.
- Constraint network: BCE on the 7N tight bits; the decision threshold is the largest one
  reaching the target recall of the tight set (a missed tight constraint costs an SCvx
  iteration; a spurious one only a little speed) on a calibration split: 10 % of the
  train+validation base landings kept out of the folds. The recall, and the test scores, are
  of the bits the flight code can drop: it keeps T_min whatever its bit, so T_min's bits count
  in neither (until 28 Nov 2026 they did). (By the end of the sequential K-fold
  every validation row has been trained on, and a threshold chosen there is overconfident.)
  Data too small for a calibration split (train+validation landings <= K), or
  calibration_fraction 0, leave only that: the threshold is then chosen on the last fold's
  validation rows, with a warning, and the metrics ("threshold_chosen_on") and the card say so.
  The target must hold with 95 % confidence over bootstrap resamples of the calibration
  landings, not only on them. On the 4,000-landing data a threshold that just reached 0.99 on
  the 304 calibration landings gave 0.988 on the test split; the bootstrap one (0.0407 instead
  of 0.0451) gave 0.989, so the test landings vary more than the calibration sample shows.
  The percentile bootstrap is a little optimistic: the resamples of a sample vary less than
  samples do. Measured 28 Nov with the shipped network on 375 fresh landings (`guidance dataset
  --n-base 400 --seed 777`) as the population, 1,000 calibration sets of 301 landings drawn
  from it: the population's recall reached 0.99 for 92 % of the thresholds chosen at a
  nominal 95 % (96.5 % at a nominal 97.5 %; 48 % without the bootstrap). The card says
  "nominal".
  One threshold for all bits: thresholds per constraint type, per (type, iteration) or per
  (type, 5-node block) chosen on the calibration split for the same overall recall were no
  better on the test split (+0.01 precision at most, for a lower recall), and per-bit ones
  overfit the calibration split (test recall 0.989 for a 0.99 target).
- Solution network: MSE on standardized (x, u, t_f), with t_f weighted as N outputs in the
  training loss (one output among 17N + 1 would otherwise be ignored, and a warm start with a
  wrong t_f is a poor one); the reported MSE is the plain mean over all outputs.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import pickle
import re
import struct
import time
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from guidance.atomic import atomic_write
from guidance.dataset import Dataset
from guidance.errors import InputError
from guidance.nn.conventions import (
    KINDS,
    LEARNING_RATE,
    TEST_FRACTION,
    THRESHOLD_ON_CALIBRATION,
    THRESHOLD_ON_LAST_FOLD,
    default_epochs,
)
from guidance.nn.model import ArchConfig, Transformer, n_params
from guidance.nn.tight_set import ALWAYS_KEPT, droppable_bits, mask_metrics, rate_text
from guidance.params import CONSTRAINT_NAMES
from guidance.provenance import LEARNING_PACKAGES, code_version, provenance

STD_FLOOR = 1e-9


@dataclass(frozen=True)
class TrainConfig:
    # per fold; no default here: the kinds train for different numbers of epochs (train()
    # without a configuration takes conventions.default_epochs, as `guidance train` does)
    epochs: int
    folds: int = 3
    batch_size: int = 128
    lr: float = LEARNING_RATE
    weight_decay: float = 1e-4
    warmup_steps: int = 4000
    test_fraction: float = TEST_FRACTION
    split_seed: int = 0
    target_recall: float = 0.99
    recall_confidence: float = 0.95  # over resamples of the calibration landings
    calibration_fraction: float = 0.1  # of train+val base landings, constraint net only
    max_seconds: float = float("inf")  # wall-clock cap on the whole training
    threads: int = 0  # torch threads (0: leave torch's default)


def default_config(kind: str) -> TrainConfig:
    """The configuration ``guidance train`` trains a flight-size ``kind`` network with when
    given no option."""
    return TrainConfig(epochs=default_epochs(kind))


# ---- data ---------------------------------------------------------------------------------
def split_bases(base_id: np.ndarray, test_fraction: float, seed: int) -> tuple[np.ndarray, ...]:
    """(train+val base ids, test base ids), disjoint, chosen by base sample."""
    bases = np.unique(base_id)
    rng = np.random.default_rng(seed)
    perm = rng.permutation(bases)
    n_test = max(1, round(test_fraction * len(bases))) if len(bases) > 1 else 0
    return np.sort(perm[n_test:]), np.sort(perm[:n_test])


def xy(ds: Dataset, kind: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Inputs, targets, the row's base id and its theta (for OOD tests) for one network."""
    if kind == "constraint":
        X, Y, idx = ds.constraint_pairs()
        return X, Y.astype(np.float32), ds.base_id[idx], ds.theta[idx]
    if kind == "solution":
        return ds.theta.copy(), ds.solution_targets(), ds.base_id.copy(), ds.theta.copy()
    raise ValueError(f"kind must be one of {KINDS}")


def standardization(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mean = A.mean(axis=0)
    std = A.std(axis=0)
    scale = np.maximum(np.abs(mean), 1.0)
    std = np.where(std > STD_FLOOR * scale, std, 1.0)
    return mean, std


# ---- metrics ------------------------------------------------------------------------------
def mahalanobis(theta_train: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Distance of each row of ``theta`` from the training distribution (pseudo-inverse S)."""
    mu = theta_train.mean(axis=0)
    S_inv = np.linalg.pinv(np.cov(theta_train, rowvar=False), hermitian=True)
    d = theta - mu
    return np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", d, S_inv, d), 0.0))


def ood_flags(theta_train: np.ndarray, theta_test: np.ndarray) -> tuple[np.ndarray, float]:
    """Test points beyond the 95th percentile of the training Mahalanobis distances."""
    cut = float(np.percentile(mahalanobis(theta_train, theta_train), 95.0))
    return mahalanobis(theta_train, theta_test) > cut, cut


def prob_threshold(
    y: np.ndarray,
    p: np.ndarray,
    target_recall: float,
    groups: np.ndarray | None = None,
    confidence: float = 0.95,
    n_boot: int = 200,
    seed: int = 0,
) -> float:
    """Largest probability threshold whose recall of the tight bits is >= target.

    With ``groups`` (the base landing of each row of y, p), the recall must hold with
    ``confidence`` over bootstrap resamples of the landings: the threshold is the
    (1 - confidence) quantile of the resamples' own thresholds. The calibration landings are a
    sample, and a threshold that just reaches the target on them misses it on new landings
    about half the time.
    """
    y = y.astype(bool)
    if groups is None:
        return _recall_threshold(p[y], target_recall)
    rows, cols = np.nonzero(y)
    _, g = np.unique(np.asarray(groups)[rows], return_inverse=True)
    order = np.argsort(g, kind="stable")
    pos = p[rows, cols][order]
    by_group = np.split(pos, np.flatnonzero(np.diff(g[order])) + 1)
    rng = np.random.default_rng(seed)
    thr = [
        _recall_threshold(
            np.concatenate([by_group[i] for i in rng.integers(0, len(by_group), len(by_group))]),
            target_recall,
        )
        for _ in range(n_boot)
    ]
    return float(np.quantile(thr, 1.0 - confidence))


def headline_threshold(
    y: np.ndarray, p: np.ndarray, target_recall: float, groups: np.ndarray, confidence: float
) -> float:
    """:func:`prob_threshold` for the recall of the bits the flight code can drop: those of
    the constraints it always keeps (tight_set.ALWAYS_KEPT, T_min) change nothing it solves."""
    cols = droppable_bits(p.shape[1])
    return prob_threshold(y[:, cols], p[:, cols], target_recall, groups, confidence)


def _recall_threshold(pos: np.ndarray, target_recall: float) -> float:
    """The threshold that keeps a fraction target_recall of the positives' probabilities."""
    if len(pos) == 0:
        return 0.5
    k = math.floor((1.0 - target_recall) * len(pos))
    thr = float(np.partition(pos, k)[k]) if k < len(pos) else 0.5
    return float(min(0.5, max(thr * (1 - 1e-6), 1e-6)))


# ---- training -----------------------------------------------------------------------------
def _lr_lambda(warmup: int, total: int):
    def f(step: int) -> float:
        if step < warmup:
            return (step + 1) / warmup
        frac = (step - warmup) / max(1, total - warmup)
        return 0.05 + 0.95 * 0.5 * (1 + math.cos(math.pi * min(1.0, frac)))

    return f


def _predict(net: nn.Module, X: np.ndarray, batch: int = 4096) -> np.ndarray:
    net.eval()
    out = []
    with torch.no_grad():
        for i in range(0, len(X), batch):
            out.append(net(torch.from_numpy(X[i : i + batch]).float()).numpy())
    return np.concatenate(out) if out else np.zeros((0, 0))


@dataclass
class TrainResult:
    kind: str
    arch: ArchConfig
    net: Transformer
    in_mean: np.ndarray
    in_std: np.ndarray
    out_mean: np.ndarray
    out_std: np.ndarray
    threshold: float  # probability threshold (constraint net), 0.5 otherwise
    metrics: dict[str, Any]

    def save(self, path: str | Path) -> None:
        save_atomic(
            {
                "kind": self.kind,
                "arch": self.arch.to_dict(),
                "state_dict": self.net.state_dict(),
                **{
                    n: torch.from_numpy(np.ascontiguousarray(getattr(self, n)))
                    for n in NORMALIZATION
                },
                "threshold": float(self.threshold),
                "metrics": plain(self.metrics),
            },
            Path(path),
        )


NORMALIZATION = ("in_mean", "in_std", "out_mean", "out_std")


def plain(obj: Any) -> Any:
    """obj with numpy scalars and arrays made Python numbers and lists (dictionaries, lists
    and tuples kept as they are): what a weights-only load accepts."""
    if isinstance(obj, dict):
        return {k: plain(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return type(obj)(plain(v) for v in obj)
    if isinstance(obj, np.ndarray | np.generic):
        return obj.tolist()
    return obj


def save_atomic(obj: Any, path: Path) -> None:
    """torch.save through a temporary file: an interruption leaves the old file or the new.
    Only tensors and plain Python data go in, so that loading needs no pickled code."""
    with atomic_write(path) as f:
        torch.save(obj, f)


def load_plain(path: str | Path) -> dict[str, Any]:
    """A file save_atomic wrote. ``weights_only``: tensors and plain data only, so a
    checkpoint from elsewhere cannot run code on loading (torch's default since 2.6)."""
    try:
        return torch.load(path, weights_only=True)
    except OSError as exc:  # missing, a folder, unreadable
        raise InputError(
            f"{path}: cannot read the checkpoint ({exc.strerror or exc}); re-run `guidance "
            "train` with the same options (it trains the missing networks again)"
        ) from None
    except (RuntimeError, EOFError, ValueError, struct.error, zipfile.BadZipFile) as exc:
        raise InputError(
            f"{path}: not a readable checkpoint (damaged or cut: {exc}); delete it and its "
            "report (the .json beside it) and re-run `guidance train` with the same options"
        ) from None
    except pickle.UnpicklingError as exc:
        # torch's text is mostly advice to load unsafely; keep what it refused
        found = re.search(r"Unsupported global: GLOBAL (\S+)", str(exc))
        first = f"it refers to {found.group(1)}" if found else str(exc).strip().splitlines()[0]
        raise InputError(
            f"{path}: not a checkpoint this package wrote: it holds more than tensors and plain "
            f"data (checkpoints before 26 Nov held numpy arrays: retrain with --restart) ({first})"
        ) from None


# ---- resumable runs -----------------------------------------------------------------------
# Header entries that say when and by which commit a dataset was packed, not what it holds:
# `guidance dataset` re-packs the same samples on every run.
_PACKING_KEYS = ("created_utc", "code_version")


def dataset_digest(ds: Dataset) -> str:
    """sha256 of what a dataset holds (its arrays and defining header), not of its file: the
    packed file's bytes change with every re-pack of the same samples."""
    h = hashlib.sha256()
    header = {k: v for k, v in ds.header.items() if k not in _PACKING_KEYS}
    h.update(json.dumps(header, sort_keys=True, default=str).encode())
    for f in sorted(dataclasses.fields(ds), key=lambda f: f.name):
        if f.name != "header":
            a = np.ascontiguousarray(getattr(ds, f.name))
            h.update(f"{f.name} {a.dtype.str} {a.shape}".encode())
            h.update(a.tobytes())
    return h.hexdigest()


def run_identity(
    kind: str, arch: dict[str, Any] | None, cfg: TrainConfig, dataset: str | None
) -> dict[str, Any]:
    """What a training run computes from: a checkpoint is resumed only under the same one.
    Torch threads only change the speed, so they are left out."""
    config = {k: v for k, v in dataclasses.asdict(cfg).items() if k != "threads"}
    return {"kind": kind, "arch": dict(arch or {}), "config": config, "dataset": dataset}


def identity_mismatch(saved: dict[str, Any] | None, wanted: dict[str, Any]) -> str | None:
    """Which part of a saved run's identity differs from ``wanted`` (None when none does)."""
    if not saved:
        return "run (the file records no dataset and configuration)"
    if saved.get("dataset") != wanted["dataset"]:
        return (
            f"dataset (content sha256 {str(saved.get('dataset'))[:12]}, "
            f"now {str(wanted['dataset'])[:12]})"
        )
    diffs = [
        f"{part}.{k} {saved.get(part, {}).get(k)!r} -> {wanted[part].get(k)!r}"
        for part in ("arch", "config")
        for k in sorted(set(saved.get(part, {})) | set(wanted[part]))
        if saved.get(part, {}).get(k) != wanted[part].get(k)
    ]
    if saved.get("kind") != wanted["kind"]:
        diffs.insert(0, f"kind {saved.get('kind')!r} -> {wanted['kind']!r}")
    return "configuration: " + ", ".join(diffs) if diffs else None


class TrainingInterrupted(KeyboardInterrupt):
    """Ctrl-C during training; the epochs before it are in the run's checkpoint."""

    def __init__(self, done: int, total: int) -> None:
        super().__init__(f"{done} of {total} epochs done")
        self.done, self.total = done, total


def load_checkpoint(path: str | Path) -> TrainResult:
    """A network :meth:`TrainResult.save` wrote; InputError naming the file when it is not one
    (missing, damaged, or without the entries it writes)."""
    ck = load_plain(path)
    try:
        arch = ArchConfig(**ck["arch"])
        net = Transformer(arch)
        net.load_state_dict(ck["state_dict"])
        net.eval()
        in_mean, in_std, out_mean, out_std = (ck[name].numpy() for name in NORMALIZATION)
        kind, threshold, metrics = ck["kind"], float(ck["threshold"]), dict(ck["metrics"])
    except (KeyError, TypeError, ValueError, AttributeError, RuntimeError) as exc:
        raise InputError(
            f"{path}: not a checkpoint `guidance train` wrote ({type(exc).__name__}: {exc}); "
            "delete it and its report (the .json beside it) and re-run `guidance train`"
        ) from None
    return TrainResult(kind, arch, net, in_mean, in_std, out_mean, out_std, threshold, metrics)


def train(
    ds: Dataset,
    kind: str,
    arch: dict[str, Any] | None = None,
    cfg: TrainConfig | None = None,
    log: Callable[[str], object] = print,
    state_path: str | Path | None = None,
    dataset: str | None = None,
    progress: bool = False,
) -> TrainResult:
    """Trains one network through the K folds.

    With ``state_path``, the run is checkpointed there after every epoch (model, optimizer,
    schedule, random states) and resumed from it, provided it was written for the same
    configuration and ``dataset`` (its :func:`dataset_digest`); otherwise InputError.
    Ctrl-C raises :class:`TrainingInterrupted`. Without ``cfg``: the defaults of `guidance
    train` for a flight-size network of this kind.
    """
    cfg = cfg or default_config(kind)
    if cfg.epochs < 1:
        raise InputError(f"epochs per fold must be at least 1, got {cfg.epochs}")
    if cfg.threads:
        torch.set_num_threads(cfg.threads)
    torch.manual_seed(cfg.split_seed)  # the initial weights, then dropout
    rng = np.random.default_rng(cfg.split_seed + 1)  # calibration landings, folds, batch order
    data = _prepare_data(ds, kind, cfg, rng)
    trainer = _Trainer.new(kind, arch, cfg, data, rng, ds.N)
    log(trainer.describe())
    identity = run_identity(kind, arch, cfg, dataset)
    saved = trainer.run_state(Path(state_path), identity) if state_path else None
    run = _resume(saved, kind, trainer.n_epochs, log)
    _record_code_version(run, kind, log)
    t_start = time.perf_counter() - run.seconds  # the wall-clock cap spans the resumes
    _train_epochs(trainer, run, saved, t_start, log, progress)
    if run.stopped_early:
        log(f"[{kind}] stopped at the wall-clock cap of {cfg.max_seconds:.0f} s")
    trainer.net.eval()
    threshold, chosen_on = 0.5, None
    if kind == "constraint":
        threshold, chosen_on = trainer.threshold(last_fold=run.history[-1]["fold"] - 1)
        if chosen_on["rows"] != THRESHOLD_ON_CALIBRATION:
            log(f"[{kind}] warning: no calibration landings; the threshold is chosen on the "
                "last fold's validation rows, which earlier folds trained on")  # fmt: skip
    metrics = trainer.evaluate(threshold)
    if chosen_on:
        metrics["threshold_chosen_on"] = chosen_on
    metrics.update(_run_record(trainer, run, identity, time.perf_counter() - t_start))
    in_mean, in_std, out_mean, out_std = (getattr(data, name) for name in NORMALIZATION)
    return TrainResult(
        kind, trainer.arch, trainer.net, in_mean, in_std, out_mean, out_std, threshold, metrics
    )


def _record_code_version(run: _Progress, kind: str, log: Callable[[str], object]) -> None:
    """Adds this code's version to the run's, saved with its next epoch; a resume by another
    version is not refused (each epoch is sound) but said: the network then mixes them."""
    version = code_version()
    if version not in run.code_versions:
        if run.code_versions:
            log(f"[{kind}] warning: epochs of this run were trained by "
                f"{', '.join(run.code_versions)}; this code is {version}")  # fmt: skip
        run.code_versions.append(version)


def _run_record(
    trainer: _Trainer, run: _Progress, identity: dict[str, Any], seconds: float
) -> dict[str, Any]:
    """What the metrics record of the run beside the test-split numbers: among them the code
    and library versions that trained it (``provenance``; ``code_versions``: every version
    that trained epochs of it)."""
    split = trainer.data.split
    return dict(
        provenance={**provenance(packages=LEARNING_PACKAGES), "code_versions": run.code_versions},
        history=run.history,
        train_seconds=seconds,
        stopped_early=run.stopped_early,
        n_params=n_params(trainer.net),
        macs=trainer.arch.macs(),
        train_config=dataclasses.asdict(trainer.cfg),
        identity=identity,
        n_trainval_bases=len(split.trainval_b),
        n_calibration_bases=len(split.calib_b),
        n_test_bases=len(split.test_b),
        test_bases=[int(b) for b in split.test_b],
    )


@dataclass(frozen=True)
class _Split:
    """Where the base landings, and so their rows, go: the test split, the calibration
    landings (constraint network only) and the K folds of the rest of train+validation."""

    trainval_b: np.ndarray  # base ids
    test_b: np.ndarray
    calib_b: np.ndarray
    tv: np.ndarray  # row masks: train+validation (calibration included), test, calibration
    te: np.ndarray
    cal: np.ndarray
    fit: np.ndarray  # rows of the folds: train+validation without the calibration rows
    fold: np.ndarray  # each row's fold (-1: not in a fold)

    def train_rows(self, f: int) -> np.ndarray:
        return np.flatnonzero(self.fit & (self.fold != f))

    def val_rows(self, f: int) -> np.ndarray:
        return np.flatnonzero(self.fit & (self.fold == f))


@dataclass(frozen=True)
class _Data:
    """One network's rows, standardized with the train+validation statistics."""

    Xs: np.ndarray  # float32 inputs and targets
    Ys: np.ndarray
    bid: np.ndarray  # each row's base landing
    theta: np.ndarray  # each row's theta, for the OOD tests
    iteration: np.ndarray | None  # the constraint rows' SCvx iteration k
    split: _Split
    in_mean: np.ndarray  # the NORMALIZATION statistics
    in_std: np.ndarray
    out_mean: np.ndarray
    out_std: np.ndarray


def _prepare_data(ds: Dataset, kind: str, cfg: TrainConfig, rng: np.random.Generator) -> _Data:
    solved = ds.solved()
    if len(solved.theta) == 0:
        raise InputError("the dataset has no solved samples to train on")
    X, Y, bid, theta = xy(solved, kind)
    split = _split_rows(kind, cfg, solved.base_id, bid, rng)
    in_mean, in_std = standardization(X[split.tv])
    if kind == "solution":
        out_mean, out_std = standardization(Y[split.tv])
    else:  # 0/1 labels, as they are
        out_mean, out_std = np.zeros(Y.shape[1]), np.ones(Y.shape[1])
    return _Data(
        Xs=((X - in_mean) / in_std).astype(np.float32),
        Ys=((Y - out_mean) / out_std).astype(np.float32),
        bid=bid,
        theta=theta,
        iteration=X[:, -1] if kind == "constraint" else None,
        split=split,
        in_mean=in_mean,
        in_std=in_std,
        out_mean=out_mean,
        out_std=out_std,
    )


def _split_rows(
    kind: str, cfg: TrainConfig, sample_b: np.ndarray, bid: np.ndarray, rng: np.random.Generator
) -> _Split:
    """The split of the rows of base ids ``bid``; ``sample_b``: the solved samples' base ids."""
    trainval_b, test_b = split_bases(sample_b, cfg.test_fraction, cfg.split_seed)
    calib_b = _calibration_bases(kind, cfg, trainval_b, rng)
    fit_b = np.setdiff1d(trainval_b, calib_b)
    if len(fit_b) < cfg.folds:
        raise InputError(
            f"need at least K = {cfg.folds} base landings for the folds (each fold validates "
            f"on its own landings), have {len(fit_b)}: the dataset has "
            f"{len(np.unique(sample_b))} solved base landings, {len(test_b)} go to the "
            f"test split and {len(calib_b)} to calibration; make a larger dataset"
        )
    fold_of_base = dict(zip(fit_b.tolist(), rng.permutation(len(fit_b)) % cfg.folds, strict=True))
    tv = np.isin(bid, trainval_b)
    cal = np.isin(bid, calib_b)
    return _Split(
        trainval_b,
        test_b,
        calib_b,
        tv=tv,
        te=np.isin(bid, test_b),
        cal=cal,
        fit=tv & ~cal,
        fold=np.array([fold_of_base.get(int(b), -1) for b in bid]),
    )


def _calibration_bases(
    kind: str, cfg: TrainConfig, trainval_b: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """The train+validation base landings kept out of the folds to choose the constraint
    network's threshold on (none for the solution network, or when the folds need them)."""
    calib_b = np.zeros(0, trainval_b.dtype)
    if kind == "constraint" and cfg.calibration_fraction > 0 and len(trainval_b) > cfg.folds:
        n_cal = max(1, round(cfg.calibration_fraction * len(trainval_b)))
        calib_b = np.sort(rng.permutation(trainval_b)[:n_cal])
    return calib_b


@dataclass(frozen=True)
class _Steps:
    """Optimizer steps: in one epoch of each fold, in all, and of the learning-rate warm-up."""

    per_epoch: list[int]  # of fold 1, 2, ...
    epochs: int  # per fold
    total: int
    warmup: int

    @classmethod
    def of(cls, split: _Split, cfg: TrainConfig) -> _Steps:
        per_epoch = [math.ceil(len(split.train_rows(f)) / cfg.batch_size) for f in range(cfg.folds)]
        total = sum(per_epoch) * cfg.epochs
        return cls(per_epoch, cfg.epochs, total, max(1, min(cfg.warmup_steps, total // 10)))

    def done_after(self, epochs_done: int) -> int:
        return sum(self.per_epoch[e // self.epochs] for e in range(epochs_done))


@dataclass
class _Progress:
    """How far a run is; saved in its checkpoint after every epoch."""

    epochs_done: int = 0
    history: list[dict[str, Any]] = dataclasses.field(default_factory=list)  # one per epoch
    seconds: float = 0.0  # of training, over all resumes (as of the last checkpoint)
    stopped_early: bool = False  # at the wall-clock cap
    # every code version that trained epochs of the run (a resume may be by another one)
    code_versions: list[str] = dataclasses.field(default_factory=list)


@dataclass
class _Trainer:
    """One network in training: its data, the objects the epochs advance, and the steps."""

    kind: str
    cfg: TrainConfig
    data: _Data
    arch: ArchConfig
    net: Transformer
    opt: torch.optim.Optimizer
    sched: torch.optim.lr_scheduler.LRScheduler
    loss_fn: Callable[[torch.Tensor, torch.Tensor], torch.Tensor]
    rng: np.random.Generator  # the batch order
    steps: _Steps

    @classmethod
    def new(
        cls,
        kind: str,
        arch: dict[str, Any] | None,
        cfg: TrainConfig,
        data: _Data,
        rng: np.random.Generator,
        N: int,
    ) -> _Trainer:
        a = ArchConfig(d_in=data.Xs.shape[1], d_out=data.Ys.shape[1], **(arch or {}))
        net = Transformer(a)
        loss_fn = _loss(kind, data.Ys.shape[1], N)
        opt = torch.optim.AdamW(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
        steps = _Steps.of(data.split, cfg)
        sched = torch.optim.lr_scheduler.LambdaLR(opt, _lr_lambda(steps.warmup, steps.total))
        return cls(kind, cfg, data, a, net, opt, sched, loss_fn, rng, steps)

    @property
    def n_epochs(self) -> int:
        return self.cfg.folds * self.cfg.epochs

    def describe(self) -> str:
        split, a = self.data.split, self.arch
        return (
            f"[{self.kind}] {a.label()}: {n_params(self.net):,} parameters, "
            f"{a.macs():,} MACs/inference; "
            f"{int(split.tv.sum())} train+val rows ({len(split.trainval_b)} base landings, "
            f"{len(split.calib_b)} of them for calibration), "
            f"{int(split.te.sum())} test rows ({len(split.test_b)} base landings); "
            f"{self.steps.total} steps, warm-up {self.steps.warmup}"
        )

    def run_state(self, path: Path, identity: dict[str, Any]) -> _RunState:
        return _RunState(path, identity, self.net, self.opt, self.sched, self.rng)

    def epoch(self, e: int, deadline: float, bar: Any) -> dict[str, Any]:
        """Trains the run's epoch ``e`` (0-based, fold by fold); its history entry."""
        f, ep = divmod(e, self.cfg.epochs)
        bar.set_description(
            f"{self.kind} fold {f + 1}/{self.cfg.folds} epoch {ep + 1}/{self.cfg.epochs}"
        )
        d = self.data
        tr = self.rng.permutation(d.split.train_rows(f))
        va = d.split.val_rows(f)
        train_loss = self._train_pass(tr, deadline, bar)
        val_pred = torch.from_numpy(_predict(self.net, d.Xs[va]))
        val_loss = float(self.loss_fn(val_pred, torch.from_numpy(d.Ys[va])))
        return {"fold": f + 1, "epoch": ep + 1, "train": train_loss, "val": val_loss}

    def _train_pass(self, perm: np.ndarray, deadline: float, bar: Any) -> float:
        """One pass over the rows ``perm`` (in that order), or fewer past ``deadline``; the
        mean batch loss."""
        self.net.train()
        d, batch_size = self.data, self.cfg.batch_size
        running, nb = 0.0, 0
        for i in range(0, len(perm), batch_size):
            b = perm[i : i + batch_size]
            loss = self.loss_fn(self.net(torch.from_numpy(d.Xs[b])), torch.from_numpy(d.Ys[b]))
            self.opt.zero_grad()
            loss.backward()
            self.opt.step()
            self.sched.step()
            running += loss.item()
            nb += 1
            bar.update(1)
            if time.perf_counter() > deadline:
                break
        return running / max(nb, 1)

    def threshold(self, last_fold: int) -> tuple[float, dict[str, Any]]:
        """The constraint network's decision threshold, chosen on the calibration landings
        (on the last fold's validation rows, which earlier folds trained on, when there are
        none), and which rows those were (the metrics' "threshold_chosen_on")."""
        split = self.data.split
        if split.cal.any():
            rows, on = np.flatnonzero(split.cal), THRESHOLD_ON_CALIBRATION
        else:
            rows, on = split.val_rows(last_fold), THRESHOLD_ON_LAST_FOLD
        p_cal = 1 / (1 + np.exp(-_predict(self.net, self.data.Xs[rows])))
        threshold = headline_threshold(
            self.data.Ys[rows], p_cal, self.cfg.target_recall, self.data.bid[rows],
            self.cfg.recall_confidence,
        )  # fmt: skip
        return threshold, {"rows": on, "base_landings": len(np.unique(self.data.bid[rows]))}

    def evaluate(self, threshold: float) -> dict[str, Any]:
        d = self.data
        return evaluate(
            self.net, self.kind, d.Xs, d.Ys, d.split.tv, d.split.te, d.theta, threshold,
            d.iteration,
        )  # fmt: skip


def _resume(
    saved: _RunState | None, kind: str, n_epochs: int, log: Callable[[str], object]
) -> _Progress:
    """The progress of the run's checkpoint, restored into the run's objects; a fresh start
    without one."""
    if not (saved and saved.path.exists()):
        return _Progress()
    state = saved.load()
    log(f"[{kind}] resumed from {saved.path}: {state['epochs_done']} of {n_epochs} epochs done")
    return _Progress(
        state["epochs_done"], state["history"], state["seconds"], state["stopped_early"],
        list(state.get("code_versions", [])),  # run states before 27 Nov 2026 record none
    )  # fmt: skip


def _train_epochs(
    trainer: _Trainer,
    run: _Progress,
    saved: _RunState | None,
    t_start: float,
    log: Callable[[str], object],
    show_progress: bool,
) -> None:
    """Trains the epochs of ``run`` not done yet, or until the wall-clock cap, checkpointing after
    each; Ctrl-C raises TrainingInterrupted (the epochs before it are in the checkpoint)."""
    kind, n_epochs = trainer.kind, trainer.n_epochs
    deadline = t_start + trainer.cfg.max_seconds
    initial = trainer.steps.done_after(run.epochs_done)
    bar = _bar(trainer.steps.total, initial, f"{kind} {trainer.arch.label()}", show_progress)
    try:
        while run.epochs_done < n_epochs and not run.stopped_early:
            entry = trainer.epoch(run.epochs_done, deadline, bar)
            run.history.append(entry)
            run.stopped_early = time.perf_counter() > deadline
            run.epochs_done += 1
            if saved:
                run.seconds = time.perf_counter() - t_start
                saved.save(run)
            log(
                f"[{kind}] fold {entry['fold']} epoch {entry['epoch']}: "
                f"train {entry['train']:.4f} val {entry['val']:.4f}"
            )
    except KeyboardInterrupt:
        raise TrainingInterrupted(run.epochs_done, n_epochs) from None
    finally:
        bar.close()


def _loss(kind: str, d_out: int, N: int) -> Callable[[torch.Tensor, torch.Tensor], torch.Tensor]:
    if kind == "constraint":
        return nn.BCEWithLogitsLoss()
    w = torch.ones(d_out)
    w[-1] = float(N)  # t_f weighs as much as N outputs
    w = w * (len(w) / w.sum())

    def loss_fn(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
        return torch.mean(w * (pred - target) ** 2)

    return loss_fn


def _bar(total: int, initial: int, desc: str, enabled: bool) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=desc, unit="step", disable=not enabled)


@dataclass
class _RunState:
    """The checkpoint of a resumable run: everything the rest of the run depends on, so that a
    resumed run equals an unbroken one (the torch random state drives dropout, the numpy one
    the batch order), tied to the run's identity (configuration and dataset)."""

    path: Path
    identity: dict[str, Any]
    net: nn.Module
    opt: torch.optim.Optimizer
    sched: torch.optim.lr_scheduler.LRScheduler
    rng: np.random.Generator

    def save(self, progress: _Progress) -> None:
        state = {
            "identity": self.identity,
            "net": self.net.state_dict(),
            "opt": self.opt.state_dict(),
            "sched": self.sched.state_dict(),
            "numpy_rng": plain(self.rng.bit_generator.state),
            "torch_rng": torch.get_rng_state(),
            "saved_by": provenance(packages=LEARNING_PACKAGES),  # this session's code, torch
            **plain(dataclasses.asdict(progress)),
        }
        save_atomic(state, self.path)

    def load(self) -> dict[str, Any]:
        """Restores the saved state into the run's objects; returns the saved progress."""
        state = load_plain(self.path)
        why = identity_mismatch(state.get("identity"), self.identity)
        if why:
            raise InputError(
                f"{self.path} is a checkpoint of another {why}: rerun with --restart (or delete "
                "it) to start over"
            )
        self.net.load_state_dict(state["net"])
        self.opt.load_state_dict(state["opt"])
        self.sched.load_state_dict(state["sched"])
        self.rng.bit_generator.state = state["numpy_rng"]
        torch.set_rng_state(state["torch_rng"])
        return state


def evaluate(
    net: nn.Module,
    kind: str,
    Xs: np.ndarray,
    Ys: np.ndarray,
    tv: np.ndarray,
    te: np.ndarray,
    theta: np.ndarray,
    threshold: float,
    iteration: np.ndarray | None = None,
) -> dict[str, Any]:
    """Test-split metrics, on all test rows and on the out-of-distribution ones; for the
    constraint network also their breakdown by constraint type and SCvx iteration (the rows'
    raw k, ``iteration``)."""
    out: dict[str, Any] = {"threshold": threshold}
    if not te.any():
        return out
    ood, cut = ood_flags(theta[tv], theta[te])
    out["ood_cut_mahalanobis"] = cut
    out["n_test_rows"] = int(te.sum())
    out["n_ood_rows"] = int(ood.sum())
    pred = _predict(net, Xs[te])
    Y = Ys[te]
    if kind == "constraint":
        prob = 1 / (1 + np.exp(-pred))
        if iteration is not None:  # every constraint type, the iterations as the headline
            out["test_breakdown"] = breakdown(Y, prob >= threshold, iteration[te])
        # the headline: the bits of the constraints the flight code can drop
        out["headline_excludes"] = list(ALWAYS_KEPT)
        cols = droppable_bits(Y.shape[1])
        Y, prob = Y[:, cols], prob[:, cols]
        out["test"] = mask_metrics(Y, prob >= threshold)
        out["test_at_0.5"] = mask_metrics(Y, prob >= 0.5)
        out["test_prob_mse"] = float(np.mean((prob - Y) ** 2))
        if ood.any():
            out["ood"] = mask_metrics(Y[ood], prob[ood] >= threshold)
            out["ood_prob_mse"] = float(np.mean((prob[ood] - Y[ood]) ** 2))
    else:
        out["test_mse"] = float(np.mean((pred - Y) ** 2))
        out["test_mse_tf"] = float(np.mean((pred[:, -1] - Y[:, -1]) ** 2))
        if ood.any():
            out["ood_mse"] = float(np.mean((pred[ood] - Y[ood]) ** 2))
        out["train_val_mse"] = float(np.mean((_predict(net, Xs[tv]) - Ys[tv]) ** 2))
    return out


ITERATION_BINS = ((1, 1), (2, 2), (3, 5), (6, 10), (11, 10**6))


def breakdown(y: np.ndarray, pred: np.ndarray, k: np.ndarray) -> dict:
    """Where the tight set's errors are: metrics of the predicted mask bits ``pred`` per
    constraint type (bit 7k + c: column c of every node; every type) and per SCvx iteration
    bin (the bits the headline counts: not those of ALWAYS_KEPT)."""
    n_types = len(CONSTRAINT_NAMES)
    by_type = {}
    for c, name in enumerate(CONSTRAINT_NAMES):
        yc, pc = y[:, c::n_types], pred[:, c::n_types]
        by_type[name] = {
            **mask_metrics(yc, pc),
            "share_of_tight": float(yc.sum() / max(y.sum(), 1)),
        }
    by_iter = {}
    cols = droppable_bits(y.shape[1])
    y, pred = y[:, cols], pred[:, cols]
    for lo, hi in ITERATION_BINS:
        rows = (k >= lo) & (k <= hi)
        if rows.any():
            label = str(lo) if lo == hi else f"{lo}+" if hi >= 10**6 else f"{lo}-{hi}"
            by_iter[label] = {**mask_metrics(y[rows], pred[rows]), "rows": int(rows.sum())}
    return {"by_type": by_type, "by_iteration": by_iter}


def summarize(res: TrainResult) -> str:
    m = res.metrics
    head = f"{res.kind} {res.arch.label()} ({m['n_params']:,} params, {m['macs']:,} MACs)"
    if res.kind == "constraint" and "test" in m:
        t = m["test"]
        return (
            f"{head}: acc {100 * t['binary_accuracy']:.2f} % (zeros "
            f"{100 * t['all_zeros_accuracy']:.2f} %), {rate_text(t)} at p >= {res.threshold:.3g}"
        )
    if "test_mse" in m:
        return f"{head}: test MSE {m['test_mse']:.4f}, OOD MSE {m.get('ood_mse', float('nan')):.4f}"
    return head


def metrics_json(res: TrainResult) -> str:
    return json.dumps(res.metrics, indent=1, default=float)
