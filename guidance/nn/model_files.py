"""The networks' files of a models folder as `guidance export` recorded them, and the check that
the files present are those.

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

from guidance.errors import InputError
from guidance.json_files import read_json_object
from guidance.nn.conventions import KINDS, METRICS_FILE, TNN_SUFFIX, network_file
from guidance.provenance import file_digest


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


def recorded_digests(models: Path) -> dict[str, dict[str, str]]:
    """``{kind: {"onnx": sha256, "tnn": sha256}}`` of the networks ``models``/metrics.json
    records; empty without metrics.json, and without the networks exported before the digests
    were recorded (27 Nov 2026: their files cannot be checked)."""
    path = Path(models) / METRICS_FILE
    if not path.is_file():
        return {}
    metrics = read_json_object(path, "the metrics `guidance export` writes",
                               "re-run `guidance export`", {"shipped": dict})  # fmt: skip
    out: dict[str, dict[str, str]] = {}
    for kind, entry in metrics["shipped"].items():
        blob = entry.get("flight_blob") if isinstance(entry, dict) else None
        if kind in KINDS and isinstance(blob, dict) and "sha256" in entry and "sha256" in blob:
            out[kind] = {"onnx": str(entry["sha256"]), "tnn": str(blob["sha256"])}
    return out


def model_file_problems(models: Path, blobs: Path | None = None) -> list[str]:
    """What is wrong with the networks' files of ``models`` (and the flight blobs in
    ``blobs``, e.g. build/models), one sentence per file whose sha256 is not the one
    metrics.json records; empty when all are the recorded ones or nothing is recorded."""
    models = Path(models)
    recorded = recorded_digests(models)
    metrics = models / METRICS_FILE
    problems: list[str] = []
    for kind, want in sorted(recorded.items()):
        onnx, tnn = network_file(kind), network_file(kind, TNN_SUFFIX)
        candidates = [
            (models / onnx, "onnx", "re-run `guidance export` (or restore the exported file)"),
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
