"""The networks' files of a models folder as `guidance export` recorded them, and the check that
the files present are those.

``manifest.json`` names the set an export wrote (the networks, the flight blobs it rewrote,
metrics.json) with each file's sha256; export moves it into the folder first, then the others
one by one, so a folder left between two moves (a killed export) holds files the manifest does
not name and says which. The card is not in it: `guidance baselines` and `guidance
mask-ceiling` write it again from metrics.json, which is.

``metrics.json`` records, for each shipped network, the sha256 of its ONNX file and of the
flight blob (``KIND.tnn``) converted from it (guidance.nn.flight.tnn_bytes: same ONNX file, same
bytes; `make lib` writes it to build/models, the C backend also reads one from the models
folder in preference to the ONNX file). A file whose sha256 is not the recorded one is not the
network the metrics and the card describe: an ONNX file replaced after the export, or a blob
converted from another ONNX file (left from an earlier export, or not rebuilt since).

No heavy import: the flight path (no torch, no onnx) runs the check.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

from guidance.atomic import write_json_atomic
from guidance.errors import InputError
from guidance.json_files import read_json_object
from guidance.nn.conventions import (
    KINDS,
    MANIFEST_FILE,
    METRICS_FILE,
    MODEL_CARD_FILE,
    ONNX_SUFFIX,
    TNN_SUFFIX,
    network_file,
)
from guidance.provenance import code_version, file_digest

MANIFEST_FORMAT = "tscvx-models-manifest"
_REEXPORT = "re-run `guidance export`"


def network_record(onnx: Path) -> dict[str, Any]:
    """What export records of an ONNX file in its metrics.json entry: its sha256, and the
    name, size and sha256 of the flight blob converted from it (needs onnx)."""
    from guidance.nn.flight import tnn_bytes

    blob = tnn_bytes(onnx)
    return {
        "sha256": file_digest(onnx),
        "flight_blob": {
            "file": Path(onnx).with_suffix(TNN_SUFFIX).name,
            "bytes": len(blob),
            "sha256": hashlib.sha256(blob).hexdigest(),
        },
    }


def write_manifest(stage: Path) -> None:
    """Writes ``stage``/manifest.json naming every file of ``stage`` but the card, each with
    its sha256, and the code that wrote them: call it when the set is complete."""
    stage = Path(stage)
    files = {
        p.name: file_digest(p)
        for p in sorted(stage.iterdir())
        if p.name not in (MANIFEST_FILE, MODEL_CARD_FILE)
    }
    manifest = {"format": MANIFEST_FORMAT, "generator": code_version(), "files": files}
    write_json_atomic(stage / MANIFEST_FILE, manifest)


def _manifest_problems(models: Path) -> list[str]:
    """The files of ``models`` that do not belong to the set its manifest names: named there
    with another sha256 or missing, and networks and blobs it does not name; empty without a
    manifest (a folder exported before 27 Nov 2026, or by hand)."""
    path = models / MANIFEST_FILE
    if not path.is_file():
        return []
    manifest = read_json_object(path, "the manifest `guidance export` writes", _REEXPORT,
                                {"files": dict, "files.*": str})  # fmt: skip
    files: dict[str, str] = manifest["files"]
    why = "(an interrupted `guidance export`, or replaced since)"
    problems: list[str] = []
    for name, want in sorted(files.items()):
        p = models / name
        if not p.is_file():
            problems.append(f"{p}: missing, and in the set {path} names {why}: {_REEXPORT}")
        elif (got := file_digest(p)) != want:
            problems.append(
                f"{p}: sha256 {got[:12]}, not that of the set {path} names ({want[:12]}): "
                f"it does not belong {why}: {_REEXPORT}"
            )
    for kind in KINDS:  # an ONNX file beside the set; a blob: when not the recorded one (below)
        p = models / network_file(kind, ONNX_SUFFIX)
        if p.is_file() and p.name not in files:
            problems.append(f"{p}: not in the set {path} names: move it away or {_REEXPORT}")
    return problems


def recorded_digests(models: Path) -> dict[str, dict[str, str]]:
    """``{kind: {"onnx": sha256, "tnn": sha256}}`` of the networks ``models``/metrics.json
    records; empty without metrics.json, and without the networks exported before the digests
    were recorded (27 Nov 2026: their files cannot be checked)."""
    path = Path(models) / METRICS_FILE
    if not path.is_file():
        return {}
    metrics = read_json_object(path, "the metrics `guidance export` writes",
                               _REEXPORT, {"shipped": dict})  # fmt: skip
    out: dict[str, dict[str, str]] = {}
    for kind, entry in metrics["shipped"].items():
        blob = entry.get("flight_blob") if isinstance(entry, dict) else None
        if kind in KINDS and isinstance(blob, dict) and "sha256" in entry and "sha256" in blob:
            out[kind] = {"onnx": str(entry["sha256"]), "tnn": str(blob["sha256"])}
    return out


def model_file_problems(models: Path, blobs: Path | None = None) -> list[str]:
    """What is wrong with the files of ``models`` (and the flight blobs in ``blobs``, e.g.
    build/models), one sentence per file: those that do not belong to the set its manifest
    names and, that set whole, the blobs whose sha256 is not the one metrics.json records;
    empty when all are the recorded ones or nothing is recorded."""
    models = Path(models)
    mixed = _manifest_problems(models)
    if mixed:  # metrics.json may be the one that does not belong
        return mixed
    recorded = recorded_digests(models)
    metrics = models / METRICS_FILE
    problems: list[str] = []
    for kind, want in sorted(recorded.items()):
        onnx, tnn = network_file(kind), network_file(kind, TNN_SUFFIX)
        candidates = [
            (models / onnx, "onnx", f"{_REEXPORT} (or restore the exported file)"),
            (models / tnn, "tnn", f"remove it, or write it again from {onnx} (python -m "
             f"guidance.nn.flight {models / onnx} {models / tnn})"),
        ]  # fmt: skip
        if blobs is not None:
            candidates.append((Path(blobs) / tnn, "tnn", "rebuild it: make lib"))
        for path, what, fix in candidates:
            if not path.is_file():
                continue
            got = file_digest(path)
            if got != want[what]:
                of = f"the exported {onnx}" if what == "onnx" else f"the flight blob of {onnx}"
                problems.append(
                    f"{path}: sha256 {got[:12]}, not that of {of} recorded in {metrics} "
                    f"({want[what][:12]}): {fix}"
                )
    return problems


def check_model_files(models: Path, blobs: Path | None = None) -> None:
    """InputError naming every network file of ``models`` (and ``blobs``) that is not the one
    metrics.json records (:func:`model_file_problems`)."""
    problems = model_file_problems(models, blobs)
    if problems:
        raise InputError("; ".join(problems))
