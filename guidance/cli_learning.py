"""Subcommands of the learning half: ``dataset``, ``train``, ``export``, ``baselines``.

    guidance dataset --n-base 1592 --run-dir data/runs/default --output data/dataset.npz
    guidance train --dataset data/dataset.npz --train-dir data/train --sizes all
    guidance export --train-dir data/train --dataset data/dataset.npz --models-dir models
    guidance baselines --dataset data/dataset.npz --models-dir models

Heavy imports (torch, onnx) happen inside the commands.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from guidance.argtypes import add_workers_option, worker_count
from guidance.atomic import check_folder, write_text_atomic
from guidance.budget import est_instructions, fits_budget
from guidance.errors import InputError, Interrupted
from guidance.json_files import missing_or_mistyped, read_json_object
from guidance.nn.conventions import (
    BASELINES_FILE,
    CONSTRAINT,
    EPOCHS,
    KINDS,
    LEARNING_RATE,
    MANIFEST_FILE,
    MASK_CEILING_FILE,
    METRICS_FILE,
    MODEL_CARD_FILE,
    MODELS_DIR,
    ONNX_SUFFIX,
    REFERENCE_EPOCHS,
    SOLUTION,
    TNN_SUFFIX,
    network_file,
)

if TYPE_CHECKING:
    from guidance.dataset import Dataset
    from guidance.nn.train import TrainConfig, TrainResult

# Sizes trained by ``guidance train`` (label -> architecture). "flight" sizes are meant to fit
# DESIGN.md's budget (budget.NN_INSTRUCTION_BUDGET per inference, see budget.INSTR_PER_MAC);
# "reference" sizes are the paper's (Section "Training, Validation, and Testing").
FLIGHT_SIZES = {
    "flight-s": dict(tokens="scalar", d_model=32, n_heads=2, n_layers=2, d_ff=64),
    "flight-m": dict(tokens="scalar", d_model=64, n_heads=2, n_layers=2, d_ff=128),
    "flight-mlp": dict(tokens="single", d_model=256, n_heads=2, n_layers=2, d_ff=512),
}
REFERENCE_SIZES = {
    "constraint": dict(tokens="single", d_model=384, n_heads=2, n_layers=4, d_ff=2048),
    "solution": dict(tokens="single", d_model=768, n_heads=2, n_layers=4, d_ff=2048),
}
DEFAULT_DATASET = "data/dataset.npz"
DEFAULT_RUN_DIR = "data/runs/default"
DEFAULT_TRAIN_DIR = "data/train"
DEFAULT_MODELS_DIR = str(MODELS_DIR)  # the repository's, as guidance solve's, from anywhere
# Choices of --backend of the commands that solve sampled landings (dataset, mask-ceiling);
# without it, dataset_run.default_backend().
_SAMPLE_BACKENDS = ["c", "clarabel", "c-socp"]
# Largest --threads: torch takes any positive count, but crashes (segmentation fault) on the
# first matrix product with 100,000; 1,024 runs.
MAX_THREADS = 1024
# Largest seed: torch.manual_seed takes an unsigned 64-bit integer (the split seed seeds torch).
MAX_SEED = 2**64 - 1
# Largest --eps of mask-ceiling, in standard deviations of theta's components: the sampling box
# is sqrt(12) = 3.5 of them wide per component, sqrt(11) times that (11.5) across the
# perturbed ones; much farther, every neighbour is redrawn as not a landing.
MAX_EPS = 10.0


def add_commands(sub: argparse._SubParsersAction) -> None:
    """Registers the learning subcommands on the main parser."""
    _add_dataset(sub)
    _add_train(sub)
    _add_export(sub)
    _add_baselines(sub)
    _add_mask_ceiling(sub)


# The helpers import guidance.cli when called, not at this module's import: guidance.cli
# imports the solvers, and guidance.nn.card imports this module.
def _add_dataset(sub: argparse._SubParsersAction) -> None:
    from guidance.argtypes import at_least
    from guidance.cli import add_prox_u
    from guidance.sampling import SamplingRanges

    d = sub.add_parser(
        "dataset",
        help="sample landings, solve them with SCvx (all cores, resumable), rotate, pack",
    )
    d.add_argument(
        "--n-base", type=at_least(1), default=1592, help="base samples (before rotation)"
    )
    d.add_argument("--seed", type=at_least(0), default=0)
    d.add_argument("--run-dir", default=DEFAULT_RUN_DIR, help="per-sample files (resumable)")
    d.add_argument("--output", default=DEFAULT_DATASET, help="packed dataset (.npz)")
    add_workers_option(d, "samples solved at once")
    d.add_argument(
        "--backend",
        choices=_SAMPLE_BACKENDS,
        help="SCvx that solves the samples (default: the C library when built, else clarabel)",
    )
    add_prox_u(d, "with which the networks shipped until 23 Nov were trained")
    d.add_argument("--pack-only", action="store_true", help="pack the samples solved so far")
    d.add_argument("--no-progress", action="store_true")
    d.set_defaults(
        func=cmd_dataset, ranges=SamplingRanges(), interrupted=_kept_in_run_dir("samples")
    )


def _add_train(sub: argparse._SubParsersAction) -> None:
    from guidance.argtypes import at_least
    from guidance.cli import positive_float

    t = sub.add_parser("train", help="train the constraint and solution transformers (resumable)")
    t.add_argument("--dataset", default=DEFAULT_DATASET)
    t.add_argument("--train-dir", default=DEFAULT_TRAIN_DIR, help="checkpoints and report")
    t.add_argument("--kind", choices=[*KINDS, "both"], default="both")
    t.add_argument(
        "--sizes",
        type=_sizes,
        default="all",
        help="comma list of flight-s, flight-m, flight-mlp, reference; or 'flight' / 'all'",
    )
    t.add_argument(
        "--epochs",
        type=at_least(1),
        default=EPOCHS[CONSTRAINT],
        help="per fold, constraint net",
    )
    t.add_argument(
        "--solution-epochs",
        type=at_least(1),
        default=EPOCHS[SOLUTION],
        help="per fold, solution net",
    )
    t.add_argument(
        "--reference-epochs",
        type=at_least(1),
        default=REFERENCE_EPOCHS,
        help="per fold, for the paper-size reference (the paper: 2)",
    )
    t.add_argument("--lr", type=positive_float, default=LEARNING_RATE)
    t.add_argument(
        "--max-minutes", type=_non_negative_float, default=0.0, help="cap per model (0: none)"
    )
    t.add_argument(
        "--threads",
        type=_int_in(0, MAX_THREADS),
        default=0,
        help=f"torch threads (0: default; at most {MAX_THREADS})",
    )
    t.add_argument("--seed", type=_seed, default=0, help="split and initialization seed")
    t.add_argument(
        "--restart",
        action="store_true",
        help="delete the networks and run states in TRAIN_DIR and start over (default: resume "
        "the interrupted run, keep the finished networks)",
    )
    t.add_argument("--no-progress", action="store_true")
    t.set_defaults(func=cmd_train)


def _add_export(sub: argparse._SubParsersAction) -> None:
    e = sub.add_parser("export", help="export the best flight-size networks to ONNX")
    e.add_argument("--train-dir", default=DEFAULT_TRAIN_DIR)
    e.add_argument(
        "--dataset",
        default=DEFAULT_DATASET,
        help="the dataset the networks were trained on (checked): its problem parameters go "
        "into the ONNX files, its header into the card's Data section, its test split into "
        "the inference measurements",
    )
    e.add_argument("--models-dir", default=DEFAULT_MODELS_DIR)
    e.set_defaults(func=cmd_export)


def _add_baselines(sub: argparse._SubParsersAction) -> None:
    from guidance.argtypes import at_least

    b = sub.add_parser("baselines", help="lookup-table baselines against the networks")
    b.add_argument("--dataset", default=DEFAULT_DATASET)
    b.add_argument("--models-dir", default=DEFAULT_MODELS_DIR)
    b.add_argument(
        "--kind",
        choices=[*KINDS, "both"],
        default="both",
        help="the tasks scored (default both); each one's network must be in MODELS_DIR",
    )
    # the interpolation's PCA needs n - 1 >= 1 components: two rows span a line
    b.add_argument(
        "--interp-train", type=at_least(2), default=1000, help="subset (paper: 100; >= 2)"
    )
    b.add_argument("--interp-test", type=at_least(1), default=100, help="subset (paper: 10)")
    b.add_argument(
        "--max-queries", type=at_least(1), default=2000, help="test rows for KD-tree / NN"
    )
    b.add_argument("--seed", type=_seed, default=0, help="the split seed used in training")
    b.add_argument("--json", help=f"write the results here (default: MODELS_DIR/{BASELINES_FILE})")
    b.set_defaults(func=cmd_baselines)


def _add_mask_ceiling(sub: argparse._SubParsersAction) -> None:
    from guidance.argtypes import at_least

    c = sub.add_parser(
        "mask-ceiling",
        help="how well any (theta, k) -> tight-mask predictor can do: masks of near landings",
    )
    c.add_argument("--landings", type=at_least(1), default=20)
    c.add_argument(
        "--neighbours",
        type=at_least(3),  # one predicted from the votes of two
        default=9,
        help="solved landings per eps (>= 3)",
    )
    c.add_argument(
        "--eps",
        type=_radii,
        default="0.005,0.02,0.1",
        help=f"neighbourhood radii, in std units (0 to {MAX_EPS:g})",
    )
    c.add_argument("--backend", choices=_SAMPLE_BACKENDS, help="default: as dataset")
    c.add_argument(
        "--train-landings",
        type=at_least(1),
        help="for the data spacing (default: the shipped constraint network's, models/)",
    )
    c.add_argument("--models-dir", default=DEFAULT_MODELS_DIR)
    c.add_argument("--seed", type=at_least(0), default=7)
    add_workers_option(c, "landings solved at once")
    c.add_argument(
        "--run-dir",
        default="data/runs/mask_ceiling",
        help="neighbour masks kept as solved (resumable); '' to keep nothing",
    )
    c.add_argument(
        "--json", help=f"write the results here (default: MODELS_DIR/{MASK_CEILING_FILE})"
    )
    c.set_defaults(func=cmd_mask_ceiling, interrupted=_kept_in_run_dir("neighbourhoods"))


def _kept_in_run_dir(what: str) -> Callable[[argparse.Namespace], str]:
    """What a command that keeps each of its ``what`` in --run-dir as it is solved says when
    interrupted, at any point of it (guidance.cli.main prints it after "interrupted: ")."""

    def note(args: argparse.Namespace) -> str:
        if not args.run_dir:
            return "nothing is kept without a --run-dir"
        return f"solved {what} are kept in {args.run_dir}; run the same command again to resume"

    return note


# ---- dataset ------------------------------------------------------------------------------
def cmd_dataset(args: argparse.Namespace) -> int:
    from guidance.atomic import check_outputs
    from guidance.dataset import pack, summary
    from guidance.dataset_run import generate
    from guidance.params import SCvxSettings

    check_folder("--run-dir", args.run_dir)
    # before the solving, not after (the output cannot be the run's folder, made by the solve)
    check_outputs(("--output", args.output), inputs=(("--run-dir folder", args.run_dir),))
    if not args.pack_only:
        counts = generate(
            args.run_dir,
            args.n_base,
            seed=args.seed,
            ranges=args.ranges,
            settings=SCvxSettings(prox_u=args.prox_u),
            workers=worker_count(args.workers),
            progress=not args.no_progress,
            backend=args.backend,
        )
        done = ", ".join(f"{n} {status}" for status, n in sorted(counts.items())) or "none"
        print(f"solved this run: {done}")
    header = pack(args.run_dir, args.output, n_base=args.n_base)
    print(summary(header))
    print(f"wrote {args.output}")
    return 0


# ---- checks of the options ------------------------------------------------------------------
def _non_negative_float(text: str) -> float:
    """argparse type of a finite number >= 0 (--max-minutes, 0: none)."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return value


def _int_in(minimum: int, maximum: int) -> Callable[[str], int]:
    """argparse type of an integer in [minimum, maximum]."""
    from guidance.argtypes import at_least

    at_least_minimum = at_least(minimum)

    def parse(text: str) -> int:
        value = at_least_minimum(text)
        if value > maximum:
            raise argparse.ArgumentTypeError(f"must be <= {maximum}, got {value}")
        return value

    return parse


def _seed(text: str) -> int:
    """argparse type of a split seed: 0 to MAX_SEED (numpy refuses negative seeds, torch
    larger ones)."""
    return _int_in(0, MAX_SEED)(text)


# ---- train --------------------------------------------------------------------------------
def _sizes(spec: str) -> list[str]:
    """argparse type of --sizes: the sizes named, in order, each once."""
    if spec == "all":
        return [*FLIGHT_SIZES, "reference"]
    if spec == "flight":
        return list(FLIGHT_SIZES)
    names = list(dict.fromkeys(s.strip() for s in spec.split(",") if s.strip()))
    known = f"known: {', '.join(FLIGHT_SIZES)}, reference; or 'flight' / 'all'"
    for n in names:
        if n not in FLIGHT_SIZES and n != "reference":
            raise argparse.ArgumentTypeError(f"unknown size {n!r} ({known})")
    if not names:
        raise argparse.ArgumentTypeError(f"no size named in {spec!r} ({known})")
    return names


def cmd_train(args: argparse.Namespace) -> int:
    from guidance.dataset import load_dataset
    from guidance.nn.train import dataset_digest

    check_folder("--train-dir", args.train_dir)
    ds = load_dataset(args.dataset)
    out = Path(args.train_dir)
    if args.restart:
        _clear_train_dir(out)
    digest = dataset_digest(ds)
    _claim_train_dir(out, args.dataset, digest)
    kinds = list(KINDS) if args.kind == "both" else [args.kind]
    jobs = [(kind, size) for kind in kinds for size in args.sizes]
    for n_done, (kind, size) in enumerate(jobs):
        try:
            _train_one(ds, kind, size, args, out, digest)
        except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM: the finished epochs are checkpointed
            raise Interrupted(_training_kept(exc, kind, size, n_done, len(jobs), out)) from None
    print(f"wrote checkpoints and reports to {out}")
    return 0


def _training_kept(
    exc: KeyboardInterrupt, kind: str, size: str, n_done: int, n_jobs: int, out: Path
) -> str:
    """What interrupted training says after "interrupted: " (guidance.cli.main prints it): the
    network it was training and how far (a TrainingInterrupted knows its epochs), the networks
    finished, and what is kept."""
    done, total = getattr(exc, "done", None), getattr(exc, "total", None)  # TrainingInterrupted
    how_far = f" after {done} of {total} epochs" if done is not None else ""
    kept = (
        f"the progress is kept in {out}: run the same command again to resume"
        if n_done or done
        else f"nothing was finished yet: running the same command again starts {kind}-{size} "
        "from its first epoch"
    )
    return f"{kind}-{size}{how_far} ({n_done} of {n_jobs} models finished); {kept}"


TRAIN_DATASET_FILE = "dataset.json"  # in the train dir: the data all its checkpoints are from


def _model_files(out: Path) -> list[Path]:
    """What ``guidance train`` wrote in ``out``: checkpoints, run states, reports."""
    return [
        p for p in out.glob("*") if p.name == TRAIN_DATASET_FILE or (p.name.split("-")[0] in KINDS)
    ]


def _clear_train_dir(out: Path) -> None:
    # only our own files: --train-dir may name a folder that holds other things
    for p in _model_files(out):
        p.unlink()


def _claim_train_dir(out: Path, dataset: str, digest: str) -> None:
    """Records the dataset of a new train dir; refuses one trained on other data."""
    from guidance.provenance import file_digest

    record = out / TRAIN_DATASET_FILE
    if record.exists():
        old = read_json_object(
            record,
            "the record of the dataset a train folder's networks are trained on",
            f"delete it and rerun with --restart (deletes the networks in {out}), or use "
            "another --train-dir",
            {"path": str, "content_sha256": str},
        )
        if old["content_sha256"] != digest:
            raise InputError(
                f"{out} holds networks trained on another dataset ({old['path']}, content "
                f"sha256 {old['content_sha256'][:12]}; {dataset} is {digest[:12]}): rerun with "
                "--restart (deletes them) or use another --train-dir"
            )
        return
    out.mkdir(parents=True, exist_ok=True)
    entry = {"path": str(dataset), "content_sha256": digest, "sha256": file_digest(Path(dataset))}
    write_text_atomic(record, json.dumps(entry, indent=1))


def _train_config(args: argparse.Namespace, kind: str, size: str) -> TrainConfig:
    from guidance.nn.train import TrainConfig

    epochs = args.epochs if kind == "constraint" else args.solution_epochs
    return TrainConfig(
        epochs=args.reference_epochs if size == "reference" else epochs,
        lr=args.lr if size != "reference" else min(args.lr, 3e-4),
        split_seed=args.seed,
        threads=args.threads,
        max_seconds=60 * args.max_minutes if args.max_minutes > 0 else float("inf"),
    )


def _train_one(
    ds: Dataset, kind: str, size: str, args: argparse.Namespace, out: Path, digest: str
) -> None:
    """Trains (or resumes, or keeps when finished) one network and writes its checkpoint and
    report; the run state is dropped once they are written."""
    from tqdm import tqdm

    from guidance.nn.train import identity_mismatch, run_identity, summarize, train

    name = f"{kind}-{size}"
    arch = REFERENCE_SIZES[kind] if size == "reference" else FLIGHT_SIZES[size]
    cfg = _train_config(args, kind, size)
    report, state = out / f"{name}.json", out / f"{name}.state.pt"
    if report.exists():  # written last: the model is finished
        entry = read_json_object(report, "a trained model's report", _RETRAIN)
        why = identity_mismatch(entry.get("identity"), run_identity(kind, arch, cfg, digest))
        if why:
            raise InputError(
                f"{report} was trained with another {why}: rerun with --restart (deletes "
                "the trained networks) or use another --train-dir"
            )
        print(f"{name}: already trained ({report}), kept")
        state.unlink(missing_ok=True)
        return
    res = train(ds, kind, arch, cfg, log=tqdm.write, state_path=state, dataset=digest,
                progress=not args.no_progress)  # fmt: skip
    res.metrics["size"] = size
    res.metrics["dataset"] = {
        "path": str(args.dataset),
        "content_sha256": digest,
        "n_base": ds.header["n_base"],
        "n_samples": ds.header["n_samples"],
        "created_utc": ds.header["created_utc"],
        "feasible_fraction": ds.header["feasible_fraction"],
    }
    res.save(out / f"{name}.pt")
    entry = {
        "kind": kind,
        "size": size,
        "arch": res.arch.to_dict(),
        "est_instructions": est_instructions(res.metrics["macs"]),
        "fits_budget": fits_budget(res.metrics["macs"]),
        "final_val_loss": res.metrics["history"][-1]["val"],
        "heldout_val_loss": _fold1_val(res.metrics["history"]),
        **{k: v for k, v in res.metrics.items() if k not in ("history", "test_bases")},
    }
    write_text_atomic(report, json.dumps(entry, indent=1, default=float))
    state.unlink(missing_ok=True)
    print(summarize(res), flush=True)


# What to do about a damaged report or checkpoint in a train folder
_RETRAIN = (
    "delete it and its checkpoint (KIND-SIZE.pt) and re-run `guidance train` with the same "
    "options (it trains that network again), or --restart"
)


def sweep_report(train_dir: Path) -> dict[str, dict]:
    """Every trained model's report (``KIND-SIZE.json`` beside its checkpoint), checked for
    what export and the model card read of it; InputError naming a report that is not one."""
    from guidance.nn.card import REPORT_NEEDS

    reports = {}
    for p in sorted(train_dir.glob("*.json")):
        if p.stem.split("-")[0] not in KINDS:
            continue
        entry = read_json_object(p, "a trained model's report", _RETRAIN, REPORT_NEEDS)
        if entry["kind"] != p.stem.split("-")[0]:
            raise InputError(f"{p}: reports a {entry['kind']!r} network, not the one it names; "
                             f"{_RETRAIN}")  # fmt: skip
        reports[p.stem] = entry
    return reports


def _fold1_val(history: list[dict]) -> float:
    """Validation loss at the end of fold 1: the only validation rows that the sequential
    K-fold (one model trained through the folds, as in the paper) has never trained on."""
    return [h["val"] for h in history if h["fold"] == 1][-1]


def best_checkpoints(report: dict[str, dict]) -> dict[str, str]:
    """Per kind, the flight-fitting checkpoint with the lowest held-out (fold 1) val loss, of
    the reports of a train folder (:func:`sweep_report`)."""
    best: dict[str, tuple[float, str]] = {}
    for name, r in report.items():
        if not fits_budget(r["macs"]):
            continue
        if r["kind"] not in best or r["heldout_val_loss"] < best[r["kind"]][0]:
            best[r["kind"]] = (r["heldout_val_loss"], name)
    return {k: v[1] for k, v in best.items()}


# ---- export -------------------------------------------------------------------------------
def cmd_export(args: argparse.Namespace) -> int:
    """All or nothing: every input (the reports, the dataset, the checkpoints) is read and
    checked before anything is written, and the new networks, metrics and card replace the
    old ones in MODELS_DIR only once all of them are written (atomic.staged_files): a failure
    leaves the folder's set as it was, never new networks beside the old card. A flight blob
    (KIND.tnn) in the folder is written again from the new network. The manifest of the new
    set moves in first: a folder left between two moves says which files do not belong."""
    from guidance.atomic import staged_files
    from guidance.baselines import task_data
    from guidance.dataset import load_dataset
    from guidance.nn.card import measure_onnx, write_card
    from guidance.nn.export import export_onnx
    from guidance.nn.flight import write_tnn
    from guidance.nn.model_files import network_record, write_manifest
    from guidance.nn.train import dataset_digest
    from guidance.provenance import LEARNING_PACKAGES, SOLVER_PACKAGES, provenance

    train_dir, models = Path(args.train_dir), Path(args.models_dir)
    if not train_dir.is_dir():
        raise InputError(f"--train-dir {train_dir}: no such folder (run `guidance train`)")
    check_folder("--models-dir", models)
    report = sweep_report(train_dir)
    best = best_checkpoints(report)
    if not best:
        raise InputError(f"no flight-size checkpoint in {train_dir}: run `guidance train`")
    _check_no_stale_network(models, best)
    ds = load_dataset(args.dataset)
    if "params" not in ds.header:
        raise InputError(f"{args.dataset} records no problem parameters (header 'params')")
    digest = dataset_digest(ds)
    for name in best.values():
        _check_trained_on(report[name], name, ds, args.dataset, digest)
    nets = {kind: (name, _best_checkpoint(train_dir, name, kind)) for kind, name in best.items()}
    metrics: dict = {
        # the export's code, solver and torch/onnx versions and time (each network's
        # training's: its entry's "provenance")
        "provenance": provenance(packages=SOLVER_PACKAGES + LEARNING_PACKAGES),
        "sweep": report,
        "shipped": {},
        "dataset_header": ds.header,
        "dataset_content_sha256": digest,
    }
    written = []
    with staged_files(models, first=MANIFEST_FILE) as stage:
        for kind, (name, res) in sorted(nets.items()):
            path = stage / network_file(kind)
            split_seed = int(res.metrics["train_config"]["split_seed"])
            export_onnx(
                res,
                path,
                ds.header["params"],  # the problem the training data were solved for
                extra={
                    "checkpoint": name,
                    "metrics": _brief(res.metrics),
                    "dataset_content_sha256": digest,
                    "split_seed": split_seed,
                },
            )
            blob = network_file(kind, TNN_SUFFIX)
            if (models / blob).exists():  # not left converted from the old network
                write_tnn(path, stage / blob)
                written.append(f"{models / blob} (the flight blob of {path.name}, written again)")
            td = task_data(ds, kind, seed=split_seed)
            ort = measure_onnx(path, kind, td.X_te_raw[:500], ds.header["params"])
            metrics["shipped"][kind] = {
                "checkpoint": name,
                "file": path.name,
                "bytes": path.stat().st_size,
                **network_record(path),  # its sha256 and its flight blob's
                "onnxruntime": ort,
                **{k: v for k, v in res.metrics.items() if k != "test_bases"},
                "arch": res.arch.to_dict(),
            }
            written.append(f"{models / path.name} ({name}, {path.stat().st_size:,} bytes): {ort}")
        write_text_atomic(stage / METRICS_FILE, json.dumps(metrics, indent=1, default=float))
        write_card(stage, results=models)  # with the baselines and ceiling already in MODELS_DIR
        write_manifest(stage)
    for line in written:
        print(f"wrote {line}")
    print(f"wrote {models / METRICS_FILE}, {models / MODEL_CARD_FILE} and {models / MANIFEST_FILE}")
    return 0


def _check_no_stale_network(models: Path, best: dict[str, str]) -> None:
    """Refuses to export beside a network (or its flight blob) of a kind not exported: the
    folder would hold the old one next to the new, described by no card (guidance solve would
    use the pair)."""
    for kind, suffix in itertools.product(KINDS, (ONNX_SUFFIX, TNN_SUFFIX)):
        old = models / network_file(kind, suffix)
        if kind not in best and old.exists():
            raise InputError(
                f"--models-dir {models}: holds {old.name}, and the train folder has no "
                f"flight-size {kind} network to replace it: the new set would pair it with "
                "networks it was not exported with; export into another folder (or move "
                f"{old.name} away)"
            )


def _best_checkpoint(train_dir: Path, name: str, kind: str) -> TrainResult:
    """The checkpoint of report ``name``, checked for what export reads of it."""
    from guidance.nn.train import load_checkpoint

    path = train_dir / f"{name}.pt"
    res = load_checkpoint(path)  # InputError naming it when missing or damaged
    needs = {"train_config.split_seed": int, "n_params": int, "macs": int}
    problems = missing_or_mistyped(res.metrics, needs)
    if res.kind != kind:
        problems.insert(0, f"a {res.kind!r} network, its report says {kind!r}")
    if problems:
        raise InputError(f"{path}: not the checkpoint of its report ({', '.join(problems)}); "
                         f"{_RETRAIN}")  # fmt: skip
    return res


def _check_trained_on(entry: dict, name: str, dataset: Dataset, path: str, digest: str) -> None:
    """Refuses to export (and describe in the card) a network with a dataset it was not
    trained on: the card's data section and the test split would be another data's.

    A checkpoint from before the content digest was recorded is matched by the header fields
    it did record (when the dataset was made, its size, its feasible fraction)."""
    identity, recorded = entry.get("identity"), entry.get("dataset")
    trained = identity.get("dataset") if isinstance(identity, dict) else None
    recorded = recorded if isinstance(recorded, dict) else {}
    if trained is not None:
        if trained != digest:
            raise InputError(
                f"{name} was trained on another dataset (content sha256 {str(trained)[:12]}, "
                f"{recorded.get('path')}) than {path} ({digest[:12]}): "
                "give the dataset it was trained on"
            )
        return
    keys = ("created_utc", "n_base", "n_samples", "feasible_fraction")
    if not all(k in recorded for k in keys):
        print(f"warning: {name} records neither a dataset digest nor its header (trained "
              f"before these checks); assuming {path}", file=sys.stderr)  # fmt: skip
        return
    differ = [k for k in keys if recorded[k] != dataset.header.get(k)]
    if differ:
        raise InputError(
            f"{name} was trained on another dataset ({', '.join(differ)} differ from {path}'s "
            "header): give the dataset it was trained on"
        )
    print(f"{name} records no dataset digest (trained before it was recorded); {path} has the "
          f"header it recorded ({', '.join(keys)})")  # fmt: skip


def _brief(m: dict) -> dict:
    keep = ("threshold", "test", "test_mse", "ood_mse", "n_params", "macs", "provenance")
    return {k: m[k] for k in keep if k in m}


# ---- baselines ----------------------------------------------------------------------------
def cmd_baselines(args: argparse.Namespace) -> int:
    from guidance.atomic import check_outputs
    from guidance.baselines import format_table, results_json, run_baselines
    from guidance.dataset import load_dataset
    from guidance.nn.card import card_sources, write_card
    from guidance.provenance import provenance

    models = Path(args.models_dir)
    out = Path(args.json) if args.json else models / BASELINES_FILE
    check_outputs(("--json", out))  # before the baselines, not after
    card = not args.json and (models / METRICS_FILE).exists()
    if card:  # what the card is made from, checked before the baselines run
        card_sources(models, skip=(BASELINES_FILE,))
    ds = load_dataset(args.dataset)
    res = run_baselines(
        ds,
        args.models_dir,
        interp_train=args.interp_train,
        interp_test=args.interp_test,
        max_queries=args.max_queries,
        seed=args.seed,
        kinds=KINDS if args.kind == "both" else (args.kind,),
    )
    for kind in res:
        print(format_table(kind, res[kind]))
        print()
    report = {"provenance": provenance(), "dataset": ds.header, "results": res}
    write_text_atomic(out, results_json(report))
    print(f"wrote {out}")
    if card:
        write_card(models)
        print(f"updated {models / MODEL_CARD_FILE}")
    return 0


# ---- mask ceiling -------------------------------------------------------------------------
def _radii(text: str) -> list[float]:
    """argparse type of --eps: a comma list of distinct radii in [0, MAX_EPS]."""
    try:
        eps = [float(e) for e in text.split(",") if e.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers separated by commas, got {text!r}"
        ) from None
    if not eps or not all(math.isfinite(e) and 0 <= e <= MAX_EPS for e in eps):
        raise argparse.ArgumentTypeError(f"expected radii in [0, {MAX_EPS:g}], got {text!r}")
    # a radius names its neighbours' files in --run-dir by its 6 significant digits
    names = [f"{e:g}" for e in eps]
    if len(set(names)) < len(names):
        raise argparse.ArgumentTypeError(f"expected distinct radii, got {text!r}")
    return eps


def cmd_mask_ceiling(args: argparse.Namespace) -> int:
    from guidance.atomic import check_outputs
    from guidance.dataset_run import default_backend
    from guidance.mask_ceiling import (
        data_spacing,
        format_table,
        measure,
        results_dict,
        theta_spread,
    )
    from guidance.nn.card import card_sources, write_card

    models = Path(args.models_dir)
    out = Path(args.json) if args.json else models / MASK_CEILING_FILE
    # before the solves, not after; nor the run's folder, which the solves fill
    check_outputs(("--json", out), inputs=(("--run-dir folder", args.run_dir),))
    if args.run_dir:
        check_folder("--run-dir", args.run_dir)
    eps = args.eps
    metrics = models / METRICS_FILE
    card = not args.json and metrics.exists()
    if card:  # what the card is made from, checked before the solves
        card_sources(models, skip=(MASK_CEILING_FILE,))
    n_train = args.train_landings
    if n_train is None and metrics.exists():
        n_train = _shipped_training_landings(metrics)
    std = theta_spread()
    backend = args.backend or default_backend()
    scores = measure(
        args.landings, args.neighbours, eps, backend, args.seed, std,
        workers=worker_count(args.workers), run_dir=args.run_dir or None,
    )  # fmt: skip
    spacing = data_spacing(n_train, std) if n_train else None
    print(format_table(scores, args.neighbours, spacing, n_train))
    run = dict(landings=args.landings, neighbours=args.neighbours, backend=backend, seed=args.seed)
    write_text_atomic(out, json.dumps(results_dict(scores, spacing, n_train, **run), indent=1))
    print(f"wrote {out}")
    if card:
        write_card(models)
        print(f"updated {models / MODEL_CARD_FILE}")
    return 0


def _shipped_training_landings(metrics: Path) -> int:
    """The train+validation base landings of the constraint network metrics.json describes."""
    key = f"shipped.{CONSTRAINT}.n_trainval_bases"
    fix = "re-run `guidance export`, or give --train-landings"
    record = read_json_object(metrics, "the metrics `guidance export` writes", fix, {key: int})
    n = record["shipped"][CONSTRAINT]["n_trainval_bases"]
    if n < 1:
        raise InputError(f"{metrics}: '{key}' is {n}, not a number of landings; {fix}")
    return int(n)
