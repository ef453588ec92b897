"""ONNX export: one self-contained file per network, normalization folded into the graph.

The graph maps raw inputs to raw outputs: theta (16) [+ k] -> 7N tight logits, or
theta (16) -> (x (N*14, node-major), u (N*3), t_f). The metadata property ``tscvx`` (JSON)
carries what a loader needs to refuse a model that does not fit the problem: kind, input and
output sizes, theta names, the problem parameters the model was trained for, the code
version that exported it (and, from ``guidance export``, its training data's content digest
and split seed), the normalization statistics (also folded into the graph), the decision
threshold, and a probe (inputs and the outputs the exported graph must reproduce).
"""

from __future__ import annotations

import json
import logging
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import torch

from guidance.atomic import atomic_write
from guidance.nn.model import Normalized
from guidance.nn.train import TrainResult
from guidance.provenance import code_version
from guidance.sampling import THETA_NAMES

META_KEY = "tscvx"
META_FORMAT = "tscvx-onnx"
META_VERSION = 1
N_PROBE = 4
OPSET = 18


def normalized_module(res: TrainResult) -> Normalized:
    t = torch.from_numpy
    mod = Normalized(
        res.net,
        t(np.asarray(res.in_mean, np.float64)),
        t(np.asarray(res.in_std, np.float64)),
        t(np.asarray(res.out_mean, np.float64)),
        t(np.asarray(res.out_std, np.float64)),
    )
    return mod.eval()


def probe_inputs(res: TrainResult, n: int = N_PROBE, seed: int = 7) -> np.ndarray:
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((n, res.arch.d_in))
    return (np.asarray(res.in_mean) + z * np.asarray(res.in_std)).astype(np.float32)


def export_onnx(
    res: TrainResult, path: str | Path, params: dict[str, Any], extra: dict | None = None
) -> dict:
    """Writes ``path`` (one file, weights inside) and returns its metadata."""
    import onnx

    mod = normalized_module(res)
    example = torch.from_numpy(probe_inputs(res))
    out_name = "tight_logits" if res.kind == "constraint" else "solution"
    batch = torch.export.Dim("batch", min=1, max=1 << 20)
    logging.getLogger("torch.onnx").setLevel(logging.ERROR)  # e.g. "torchvision not installed"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        program = torch.onnx.export(
            mod,
            (example,),
            input_names=["inputs"],
            output_names=[out_name],
            dynamic_shapes=({0: batch},),
            opset_version=OPSET,
            dynamo=True,
            verbose=False,
        )
    if program is None:  # torch's dynamo exporter returns its program
        raise RuntimeError("torch.onnx.export returned no ONNX program")
    proto = program.model_proto
    probe_in = probe_inputs(res)
    with torch.no_grad():
        probe_out = mod(torch.from_numpy(probe_in)).numpy()
    meta = {
        "format": META_FORMAT,
        "format_version": META_VERSION,
        "code_version": code_version(),
        "kind": res.kind,
        "d_in": res.arch.d_in,
        "d_out": res.arch.d_out,
        "input_names": [*THETA_NAMES, "k"] if res.kind == "constraint" else list(THETA_NAMES),
        "output": out_name,
        "N": int(params["N"]),
        "params": params,
        "arch": res.arch.to_dict(),
        "in_mean": np.asarray(res.in_mean, float).tolist(),
        "in_std": np.asarray(res.in_std, float).tolist(),
        "out_mean": np.asarray(res.out_mean, float).tolist(),
        "out_std": np.asarray(res.out_std, float).tolist(),
        "threshold": float(res.threshold),
        "probe_input": probe_in.astype(float).tolist(),
        "probe_output": probe_out.astype(float).tolist(),
        **(extra or {}),
    }
    del proto.metadata_props[:]
    entry = proto.metadata_props.add()
    entry.key, entry.value = META_KEY, json.dumps(meta)
    proto.doc_string = f"T-SCvx {res.kind} network {res.arch.label()}"
    path = Path(path)
    onnx.checker.check_model(proto)
    with atomic_write(path) as f:  # an interrupted export leaves the previous model whole
        onnx.save_model(proto, f, save_as_external_data=False)
    return meta
