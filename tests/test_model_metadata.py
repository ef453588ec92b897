"""The shipped networks' decision threshold (no torch): `guidance.nn.infer` and the flight
blob's reader refuse a model whose recorded threshold is missing or not a probability, as the
flight library refuses such a blob (tscvx_nn.h)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import onnx
import onnxruntime as ort
import pytest

from guidance.nn.flight import OnnxLayoutError, read_onnx
from guidance.nn.infer import ModelMismatchError, load_model

SHIPPED = Path(__file__).resolve().parent.parent / "models"
pytestmark = pytest.mark.skipif(
    not (SHIPPED / "constraint.onnx").exists(), reason="no shipped models"
)


def _rewritten(kind: str, dst: Path, edit: Callable[[dict[str, Any]], object]) -> Path:
    """The shipped ``kind`` network with only its `tscvx` metadata edited (graph untouched)."""
    model = onnx.load(str(SHIPPED / f"{kind}.onnx"))
    entry = next(e for e in model.metadata_props if e.key == "tscvx")
    meta = json.loads(entry.value)
    edit(meta)
    entry.value = json.dumps(meta)
    onnx.save(model, str(dst))
    return dst


@pytest.mark.parametrize("kind", ["constraint", "solution"])
def test_the_shipped_networks_pass_the_checks(kind: str) -> None:
    model = load_model(SHIPPED / f"{kind}.onnx", kind)
    assert 0 < model.threshold < 1


@pytest.mark.parametrize(
    "threshold, why",
    [(None, "no decision threshold"), (1.5, "outside"), (0.0, "outside"), (-1.0, "outside"),
     (float("nan"), "outside"), ("0.03", "not a number"), (True, "not a number")],
)  # fmt: skip
def test_a_constraint_network_without_a_probability_threshold_is_refused(
    threshold: object, why: str, tmp_path: Path
) -> None:
    def edit(meta: dict[str, Any]) -> None:
        if threshold is None:
            del meta["threshold"]
        else:
            meta["threshold"] = threshold

    bad = _rewritten("constraint", tmp_path / "t.onnx", edit)
    # read as 0.5, a missing threshold would drop about one tight bit in eight (model card:
    # recall 0.871 at p >= 0.5); 1.5 would drop every constraint, -1 keep all
    with pytest.raises(ModelMismatchError, match=why):
        load_model(bad, "constraint")
    with pytest.raises(OnnxLayoutError, match=why):  # the flight blob's reader alike
        read_onnx(bad)


def test_the_recorded_threshold_decides_the_mask(tmp_path: Path) -> None:
    """A valid threshold other than the shipped one is the model's: the mask is p >= it, p the
    logistic of onnxruntime's logits."""
    ok = _rewritten("constraint", tmp_path / "ok.onnx", lambda m: m.update(threshold=0.3))
    model = load_model(ok, "constraint")
    theta = np.asarray(model.meta["in_mean"][:16])
    session = ort.InferenceSession(str(ok), providers=["CPUExecutionProvider"])
    x = np.r_[theta, 3.0].astype(np.float32)[None]
    logits = session.run(None, {session.get_inputs()[0].name: x})[0][0].astype(np.float64)
    np.testing.assert_array_equal(model.mask(theta, 3), 1 / (1 + np.exp(-logits)) >= 0.3)
    assert read_onnx(ok).threshold == 0.3
