"""Scores of a predicted tight set (mask bits), shared by training, the mask ceiling and the
model card; no torch.

A ratio with a zero denominator is undefined and is None here (null in the JSON files, "–" in
the card), not a perfect score: a constraint type that is never tight has no recall, and a
predictor that marks no bit has no precision. (Before 28 Nov 2026 both read 1.0: the card's
omega row said precision 1.000 and recall 1.000 for a constraint never tight in the test
split and never predicted.)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from guidance.params import ALWAYS_KEPT, CONSTRAINT_NAMES

RATES = ("precision", "recall", "f1")

# The constraints the flight code keeps whatever their mask bit (params.ALWAYS_KEPT: T_min).
# Predicting or missing such a bit changes nothing that is solved, so the headline scores of
# the constraint network (test, OOD, per iteration) and of the mask ceiling, and the
# threshold's recall target, count only the other bits (metrics key "headline_excludes";
# before 28 Nov 2026 they counted all 7N).


def droppable_bits(n_bits: int) -> np.ndarray:
    """Which of ``n_bits`` mask bits (bit 7k + c: constraint c at node k) belong to a
    constraint the flight code can drop (not in ALWAYS_KEPT)."""
    kept = [CONSTRAINT_NAMES.index(name) for name in ALWAYS_KEPT]
    return ~np.isin(np.arange(n_bits) % len(CONSTRAINT_NAMES), kept)


def ratio(num: float, den: float) -> float | None:
    """num / den; None when den is 0 (undefined, not 1 or 0)."""
    return float(num) / float(den) if den else None


def f1_score(precision: float | None, recall: float | None) -> float | None:
    """The harmonic mean; None when either is undefined, 0 when both are 0."""
    if precision is None or recall is None:
        return None
    return 2 * precision * recall / (precision + recall) if precision + recall else 0.0


def mask_metrics(y: np.ndarray, pred: np.ndarray) -> dict[str, Any]:
    """Scores of the predicted bits ``pred`` against the tight bits ``y`` (rows x bits), with
    the counts of tight and predicted bits that say whether precision and recall exist."""
    y = np.asarray(y).astype(bool)
    pred = np.asarray(pred).astype(bool)
    tp = int(np.sum(y & pred))
    tight, predicted = int(y.sum()), int(pred.sum())
    precision, recall = ratio(tp, predicted), ratio(tp, tight)
    return {
        "binary_accuracy": float(np.mean(y == pred)),
        "all_zeros_accuracy": float(np.mean(~y)),
        "all_ones_accuracy": float(np.mean(y)),
        "precision": precision,
        "recall": recall,
        "f1": f1_score(precision, recall),
        "mse": float(np.mean((y.astype(float) - pred.astype(float)) ** 2)),
        "rows_fully_correct": float(np.mean(np.all(y == pred, axis=1))),
        "tight_bits": tight,
        "predicted_bits": predicted,
    }


def defined_rates(m: Mapping[str, Any]) -> dict[str, float | None]:
    """precision, recall and F1 of a record of :func:`mask_metrics`, None where undefined.

    Records written before 28 Nov 2026 hold no counts and 1.0 for an undefined ratio; their
    vacuous values are recognized from the record: recall with no tight bit (tight fraction
    0), precision of 1.0 where no bit can have been predicted correctly (no tight bit, or
    recall 0)."""
    precision, recall = _number(m.get("precision")), _number(m.get("recall"))
    if "tight_bits" not in m:  # an old record
        no_tight = m.get("all_ones_accuracy") == 0
        if no_tight:
            recall = None
        if precision == 1.0 and (no_tight or recall == 0):
            precision = None
    return {"precision": precision, "recall": recall, "f1": f1_score(precision, recall)}


def _number(v: Any) -> float | None:
    try:
        return None if v is None else float(v)
    except (TypeError, ValueError):
        return None


UNDEFINED = "–"  # how the card and the logs print an undefined ratio


def fmt_rate(v: float | None, fmt: str = "{:.3f}") -> str:
    """A ratio as text: UNDEFINED when it is None."""
    return UNDEFINED if v is None else fmt.format(v)


def rate_text(m: Mapping[str, Any]) -> str:
    """'P 0.614, R 0.993, F1 0.759' of a record of :func:`mask_metrics` ("–" where undefined)."""
    r = defined_rates(m)
    return f"P {fmt_rate(r['precision'])}, R {fmt_rate(r['recall'])}, F1 {fmt_rate(r['f1'])}"
