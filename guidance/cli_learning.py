"""Subcommands of the learning half: ``dataset``, ``train``, ``export``, ``baselines``.

    guidance dataset --n-base 1592 --run-dir data/runs/default --output data/dataset.npz
    guidance train --dataset data/dataset.npz --train-dir data/train --sizes all
    guidance export --train-dir data/train --dataset data/dataset.npz --models-dir models
    guidance baselines --dataset data/dataset.npz --models-dir models

Heavy imports (torch, onnx) happen inside the commands.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

# Sizes trained by ``guidance train`` (label -> architecture). "flight" sizes are meant to fit
# DESIGN.md's budget (<= 5 million host instructions per inference, see INSTR_PER_MAC);
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
# Planning estimate of host (x86-64) instructions per multiply-accumulate of the C inference
# (c_runtime/nn, scalar double code), calibrated on its callgrind count: 2.8 to 2.9 on the
# networks of the first shipped set (3.22 M for 1.14 M MACs, 3.69 M for 1.27 M). It ranks the
# candidates at export; the model card prints the callgrind count of the shipped files.
INSTR_PER_MAC = 3.0
INSTR_BUDGET = 5e6
# Epochs per fold. The constraint task has one row per (landing, iteration), about 14 times
# the solution task's rows, so it needs fewer passes. It is limited by the number of base
# landings, not by training time: the eight rotations of a landing share one mask, and the
# net memorizes the ~1,100 training landings within a few passes (the held-out fold-1 val
# loss rises from the third epoch on). With 1, 2, 3 and 6 epochs per fold (6: dropout 0.3)
# the calibration-split precision at recall 0.99 was 0.557, 0.542, 0.533 and 0.536.
TRAIN_DEFAULTS = {"epochs": 1, "solution_epochs": 8, "reference_epochs": 2, "lr": 1e-3}
DEFAULT_DATASET = "data/dataset.npz"
DEFAULT_RUN_DIR = "data/runs/default"
DEFAULT_TRAIN_DIR = "data/train"
DEFAULT_MODELS_DIR = "models"


def add_commands(sub: argparse._SubParsersAction) -> None:
    """Registers the learning subcommands on the main parser."""
    from guidance.cli import _count
    from guidance.dataset import SamplingRanges

    d = sub.add_parser(
        "dataset",
        help="sample landings, solve them with SCvx (all cores, resumable), rotate, pack",
    )
    d.add_argument("--n-base", type=_count(1), default=1592, help="base samples (before rotation)")
    d.add_argument("--seed", type=_count(0), default=0)
    d.add_argument("--run-dir", default=DEFAULT_RUN_DIR, help="per-sample files (resumable)")
    d.add_argument("--output", default=DEFAULT_DATASET, help="packed dataset (.npz)")
    d.add_argument("--workers", type=_count(0), default=0, help="worker processes (0: all cores)")
    d.add_argument(
        "--backend",
        choices=["c", "clarabel", "c-socp"],
        help="SCvx that solves the samples (default: the C library when built, else clarabel)",
    )
    d.add_argument("--pack-only", action="store_true", help="pack the samples solved so far")
    d.add_argument("--no-progress", action="store_true")
    d.set_defaults(func=cmd_dataset, ranges=SamplingRanges())

    t = sub.add_parser("train", help="train the constraint and solution transformers")
    t.add_argument("--dataset", default=DEFAULT_DATASET)
    t.add_argument("--train-dir", default=DEFAULT_TRAIN_DIR, help="checkpoints and report")
    t.add_argument("--kind", choices=["constraint", "solution", "both"], default="both")
    t.add_argument(
        "--sizes",
        default="all",
        help="comma list of flight-s, flight-m, flight-mlp, reference; or 'flight' / 'all'",
    )
    t.add_argument(
        "--epochs", type=int, default=TRAIN_DEFAULTS["epochs"], help="per fold, constraint net"
    )
    t.add_argument(
        "--solution-epochs",
        type=int,
        default=TRAIN_DEFAULTS["solution_epochs"],
        help="per fold, solution net",
    )
    t.add_argument(
        "--reference-epochs",
        type=int,
        default=TRAIN_DEFAULTS["reference_epochs"],
        help="per fold, for the paper-size reference (the paper: 2)",
    )
    t.add_argument("--lr", type=float, default=TRAIN_DEFAULTS["lr"])
    t.add_argument("--max-minutes", type=float, default=0.0, help="cap per model (0: none)")
    t.add_argument("--threads", type=int, default=0, help="torch threads (0: default)")
    t.add_argument("--seed", type=int, default=0, help="split and initialization seed")
    t.set_defaults(func=cmd_train)

    e = sub.add_parser("export", help="export the best flight-size networks to ONNX")
    e.add_argument("--train-dir", default=DEFAULT_TRAIN_DIR)
    e.add_argument("--dataset", default=DEFAULT_DATASET, help="for the inference measurements")
    e.add_argument("--models-dir", default=DEFAULT_MODELS_DIR)
    e.set_defaults(func=cmd_export)

    b = sub.add_parser("baselines", help="lookup-table baselines against the networks")
    b.add_argument("--dataset", default=DEFAULT_DATASET)
    b.add_argument("--models-dir", default=DEFAULT_MODELS_DIR)
    b.add_argument("--interp-train", type=int, default=1000, help="subset (paper: 100)")
    b.add_argument("--interp-test", type=int, default=100, help="subset (paper: 10)")
    b.add_argument("--max-queries", type=int, default=2000, help="test rows for KD-tree / NN")
    b.add_argument("--seed", type=int, default=0, help="the split seed used in training")
    b.add_argument("--json", help="write the results here (default: MODELS_DIR/baselines.json)")
    b.set_defaults(func=cmd_baselines)

    c = sub.add_parser(
        "mask-ceiling",
        help="how well any (theta, k) -> tight-mask predictor can do: masks of near landings",
    )
    c.add_argument("--landings", type=_count(1), default=20)
    c.add_argument(
        "--neighbours",
        type=_count(3),  # one predicted from the votes of two
        default=9,
        help="solved landings per eps (>= 3)",
    )
    c.add_argument(
        "--eps", type=_radii, default="0.005,0.02,0.1", help="neighbourhood radii, in std units"
    )
    c.add_argument("--backend", choices=["c", "clarabel", "c-socp"], help="default: as dataset")
    c.add_argument(
        "--train-landings",
        type=_count(1),
        help="for the data spacing (default: the shipped constraint network's, models/)",
    )
    c.add_argument("--models-dir", default=DEFAULT_MODELS_DIR)
    c.add_argument("--seed", type=_count(0), default=7)
    c.add_argument("--workers", type=_count(0), default=0, help="worker processes (0: all cores)")
    c.add_argument(
        "--run-dir",
        default="data/runs/mask_ceiling",
        help="neighbour masks kept as solved (resumable); '' to keep nothing",
    )
    c.add_argument("--json", help="write the results here (default: MODELS_DIR/mask_ceiling.json)")
    c.set_defaults(func=cmd_mask_ceiling)


# ---- dataset ------------------------------------------------------------------------------
def cmd_dataset(args: argparse.Namespace) -> int:
    from guidance.dataset import WorkerDiedError, generate, pack, summary

    if not args.pack_only:
        try:
            counts = generate(
                args.run_dir,
                args.n_base,
                seed=args.seed,
                ranges=args.ranges,
                workers=args.workers or None,
                progress=not args.no_progress,
                backend=args.backend,
            )
        except KeyboardInterrupt:
            print(
                f"\ninterrupted: solved samples are kept in {args.run_dir}; "
                "run the same command again to resume",
                file=sys.stderr,
            )
            return 130
        except WorkerDiedError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
        print(f"solved this run: {counts}")
    header = pack(args.run_dir, args.output, n_base=args.n_base)
    print(summary(header))
    print(f"wrote {args.output}")
    return 0


# ---- train --------------------------------------------------------------------------------
def _sizes(spec: str) -> list[str]:
    if spec == "all":
        return [*FLIGHT_SIZES, "reference"]
    if spec == "flight":
        return list(FLIGHT_SIZES)
    names = [s.strip() for s in spec.split(",") if s.strip()]
    for n in names:
        if n not in FLIGHT_SIZES and n != "reference":
            raise SystemExit(f"unknown size {n!r} (known: {', '.join(FLIGHT_SIZES)}, reference)")
    return names


def cmd_train(args: argparse.Namespace) -> int:
    from guidance.dataset import load_dataset
    from guidance.nn.train import TrainConfig, summarize, train

    ds = load_dataset(args.dataset)
    out = Path(args.train_dir)
    out.mkdir(parents=True, exist_ok=True)
    kinds = ["constraint", "solution"] if args.kind == "both" else [args.kind]
    for kind in kinds:
        for size in _sizes(args.sizes):
            arch = REFERENCE_SIZES[kind] if size == "reference" else FLIGHT_SIZES[size]
            epochs = args.epochs if kind == "constraint" else args.solution_epochs
            if size == "reference":
                epochs = args.reference_epochs
            cfg = TrainConfig(
                epochs=epochs,
                lr=args.lr if size != "reference" else min(args.lr, 3e-4),
                split_seed=args.seed,
                threads=args.threads,
                max_seconds=60 * args.max_minutes if args.max_minutes > 0 else float("inf"),
            )
            res = train(ds, kind, arch, cfg)
            res.metrics["size"] = size
            res.metrics["dataset"] = {
                "path": str(args.dataset),
                "n_base": ds.header["n_base"],
                "n_samples": ds.header["n_samples"],
                "created_utc": ds.header["created_utc"],
                "feasible_fraction": ds.header["feasible_fraction"],
            }
            res.save(out / f"{kind}-{size}.pt")
            est = est_instructions(res.metrics["macs"])
            entry = {
                "kind": kind,
                "size": size,
                "arch": res.arch.to_dict(),
                "est_instructions": est,
                "fits_budget": fits_budget(res.metrics["macs"]),
                "final_val_loss": res.metrics["history"][-1]["val"],
                "heldout_val_loss": _fold1_val(res.metrics["history"]),
                **{k: v for k, v in res.metrics.items() if k not in ("history", "test_bases")},
            }
            (out / f"{kind}-{size}.json").write_text(json.dumps(entry, indent=1, default=float))
            print(summarize(res), flush=True)
    print(f"wrote checkpoints and reports to {out}")
    return 0


def sweep_report(train_dir: Path) -> dict[str, dict]:
    """Every trained model's report (``KIND-SIZE.json`` beside its checkpoint)."""
    return {
        p.stem: json.loads(p.read_text())
        for p in sorted(train_dir.glob("*.json"))
        if p.stem.split("-")[0] in ("constraint", "solution")
    }


def _fold1_val(history: list[dict]) -> float:
    """Validation loss at the end of fold 1: the only validation rows that the sequential
    K-fold (one model trained through the folds, as in the paper) has never trained on."""
    return [h["val"] for h in history if h["fold"] == 1][-1]


def est_instructions(macs: int) -> float:
    """Planning estimate of host instructions per inference (today's INSTR_PER_MAC: reports
    written under an older factor are re-estimated, not read back)."""
    return INSTR_PER_MAC * macs


def fits_budget(macs: int) -> bool:
    return est_instructions(macs) <= INSTR_BUDGET


def best_checkpoints(train_dir: Path) -> dict[str, str]:
    """Per kind, the flight-fitting checkpoint with the lowest held-out (fold 1) val loss."""
    report = sweep_report(train_dir)
    best: dict[str, tuple[float, str]] = {}
    for name, r in report.items():
        if not fits_budget(r["macs"]):
            continue
        if r["kind"] not in best or r["heldout_val_loss"] < best[r["kind"]][0]:
            best[r["kind"]] = (r["heldout_val_loss"], name)
    return {k: v[1] for k, v in best.items()}


# ---- export -------------------------------------------------------------------------------
def cmd_export(args: argparse.Namespace) -> int:
    from guidance.baselines import task_data
    from guidance.dataset import load_dataset
    from guidance.nn.card import measure_onnx, write_card
    from guidance.nn.export import export_onnx
    from guidance.nn.train import load_checkpoint
    from guidance.params import Params

    train_dir, models = Path(args.train_dir), Path(args.models_dir)
    models.mkdir(parents=True, exist_ok=True)
    best = best_checkpoints(train_dir)
    if not best:
        print(f"no flight-size checkpoint in {train_dir}: run `guidance train`", file=sys.stderr)
        return 1
    ds = load_dataset(args.dataset)
    report = sweep_report(train_dir)
    metrics: dict = {"sweep": report, "shipped": {}, "dataset_header": ds.header}
    for kind, name in sorted(best.items()):
        res = load_checkpoint(train_dir / f"{name}.pt")
        path = models / f"{kind}.onnx"
        export_onnx(
            res,
            path,
            Params().to_json_dict(),
            extra={"checkpoint": name, "metrics": _brief(res.metrics)},
        )
        td = task_data(ds, kind, seed=int(res.metrics["train_config"]["split_seed"]))
        ort = measure_onnx(path, kind, td.X_te_raw[:500])
        metrics["shipped"][kind] = {
            "checkpoint": name,
            "file": path.name,
            "bytes": path.stat().st_size,
            "onnxruntime": ort,
            **{k: v for k, v in res.metrics.items() if k != "test_bases"},
            "arch": res.arch.to_dict(),
        }
        print(f"wrote {path} ({name}, {path.stat().st_size:,} bytes): {ort}")
    (models / "metrics.json").write_text(json.dumps(metrics, indent=1, default=float))
    write_card(models)
    print(f"wrote {models / 'metrics.json'} and {models / 'MODEL_CARD.md'}")
    return 0


def _brief(m: dict) -> dict:
    keep = ("threshold", "test", "test_mse", "ood_mse", "n_params", "macs")
    return {k: m[k] for k in keep if k in m}


# ---- baselines ----------------------------------------------------------------------------
def cmd_baselines(args: argparse.Namespace) -> int:
    from guidance.baselines import format_table, results_json, run_baselines
    from guidance.dataset import load_dataset
    from guidance.nn.card import write_card

    ds = load_dataset(args.dataset)
    res = run_baselines(
        ds,
        args.models_dir,
        interp_train=args.interp_train,
        interp_test=args.interp_test,
        max_queries=args.max_queries,
        seed=args.seed,
    )
    for kind in res:
        print(format_table(kind, res[kind]))
        print()
    models = Path(args.models_dir)
    out = Path(args.json) if args.json else models / "baselines.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(results_json({"dataset": ds.header, "results": res}))
    print(f"wrote {out}")
    if not args.json and (models / "metrics.json").exists():
        write_card(models)
        print(f"updated {models / 'MODEL_CARD.md'}")
    return 0


# ---- mask ceiling -------------------------------------------------------------------------
def _radii(text: str) -> list[float]:
    """argparse type of --eps: a comma list of radii >= 0."""
    try:
        eps = [float(e) for e in text.split(",") if e.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers separated by commas, got {text!r}"
        ) from None
    if not eps or min(eps) < 0 or not all(map(math.isfinite, eps)):
        raise argparse.ArgumentTypeError(f"expected radii >= 0, got {text!r}")
    return eps


def cmd_mask_ceiling(args: argparse.Namespace) -> int:
    from guidance.dataset import WorkerDiedError, default_backend
    from guidance.mask_ceiling import (
        data_spacing,
        format_table,
        measure,
        results_dict,
        theta_spread,
    )
    from guidance.nn.card import write_card

    eps = args.eps
    n_train = args.train_landings
    metrics = Path(args.models_dir) / "metrics.json"
    if n_train is None and metrics.exists():
        n_train = json.loads(metrics.read_text())["shipped"]["constraint"]["n_trainval_bases"]
    std = theta_spread()
    backend = args.backend or default_backend()
    try:
        scores = measure(
            args.landings, args.neighbours, eps, backend, args.seed, std,
            workers=args.workers or os.cpu_count() or 1, run_dir=args.run_dir or None,
        )  # fmt: skip
    except KeyboardInterrupt:
        print(f"\ninterrupted: solved neighbourhoods are kept in {args.run_dir}; "
              "run the same command again to resume", file=sys.stderr)  # fmt: skip
        return 130
    except WorkerDiedError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    spacing = data_spacing(n_train, std) if n_train else None
    print(format_table(scores, args.neighbours, spacing, n_train))
    models = Path(args.models_dir)
    out = Path(args.json) if args.json else models / "mask_ceiling.json"
    run = dict(landings=args.landings, neighbours=args.neighbours, backend=backend, seed=args.seed)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results_dict(scores, spacing, n_train, **run), indent=1))
    print(f"wrote {out}")
    if not args.json and metrics.exists():
        write_card(models)
        print(f"updated {models / 'MODEL_CARD.md'}")
    return 0
