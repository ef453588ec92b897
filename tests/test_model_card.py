"""What the model card (guidance/nn/card.py) and the tight-set scores say, on small synthetic
metrics records; no torch, no trained network."""

from __future__ import annotations

import json

import numpy as np
import pytest

from guidance.mask_ceiling import Score, results_dict


def _card_text(section, *args) -> str:
    lines: list[str] = []
    section(lines.append, *args)
    return "\n".join(lines)


def _row(text: str, first_cell: str) -> list[str]:
    """The cells of the table row of ``text`` whose first cell is ``first_cell``."""
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0] == first_cell:
            return cells
    raise AssertionError(f"no row {first_cell!r} in\n{text}")


# A constraint type never tight and never predicted, as metrics.json records it: the
# shipped file (written before 28 Nov 2026: 1.0 for 0/0) and a record of today's code.
OLD_VACUOUS = dict(binary_accuracy=1.0, all_zeros_accuracy=1.0, all_ones_accuracy=0.0,
                   precision=1.0, recall=1.0, f1=1.0, share_of_tight=0.0)  # fmt: skip
NEW_VACUOUS = OLD_VACUOUS | dict(precision=None, recall=None, f1=None, tight_bits=0,
                                 predicted_bits=0)  # fmt: skip
# tight bits, none predicted (old file: precision 1.0 for 0/0, recall 0)
OLD_NONE_PREDICTED = dict(binary_accuracy=0.9, all_zeros_accuracy=0.9, all_ones_accuracy=0.1,
                          precision=1.0, recall=0.0, f1=0.0, share_of_tight=0.5)  # fmt: skip
# a real row: 3 of 4 predicted bits tight, all 3 tight bits found
REAL = dict(binary_accuracy=0.9, all_zeros_accuracy=0.7, all_ones_accuracy=0.3,
            precision=0.75, recall=1.0, f1=6 / 7, share_of_tight=0.5)  # fmt: skip


@pytest.mark.parametrize("vacuous", [OLD_VACUOUS, NEW_VACUOUS], ids=["old file", "new file"])
def test_card_shows_an_undefined_precision_and_recall_as_a_dash(vacuous) -> None:
    """The card's omega row said precision 1.000 and recall 1.000 for a constraint with no
    tight and no predicted bit in the test split: 0/0, undefined, not perfect."""
    from guidance.nn.card import _breakdown

    by_iter = {"1": dict(REAL, rows=4), "2": dict(vacuous, rows=4)}
    b = {"by_type": {"omega": vacuous, "tilt": OLD_NONE_PREDICTED, "glideslope": REAL},
         "by_iteration": by_iter}  # fmt: skip
    text = _card_text(_breakdown, b)
    assert _row(text, "omega")[2:] == ["–", "–"]
    assert _row(text, "tilt")[2:] == ["–", "0.000"]  # 1 tight bit in 10, none predicted
    assert _row(text, "glideslope")[2:] == ["0.750", "1.000"]
    assert _row(text, "2")[3:] == ["–", "–"]
    assert "undefined" in text


def test_card_test_table_and_goal_with_undefined_rates() -> None:
    """A test split without tight bits: no recall, no precision, F1 undefined, the goal not
    met (it was 'met' with recall 1.000 and precision 1.000)."""
    from guidance.nn.card import _constraint_metrics, _goals_section

    c = {"arch": dict(tokens="single", d_model=8, n_layers=1, n_heads=1, d_ff=8),
         "threshold": 0.1, "train_config": dict(target_recall=0.99, recall_confidence=0.95),
         "n_calibration_bases": 3, "test": OLD_VACUOUS, "test_at_0.5": NEW_VACUOUS}  # fmt: skip
    table = _card_text(_constraint_metrics, c)
    for name in ("precision of the tight set", "recall of the tight set", "F1 of the tight set"):
        assert _row(table, name)[1:] == ["–", "n/a", "–"]
    assert _row(table, "binary accuracy")[1:] == ["1.0000", "n/a", "1.0000"]
    goal = _card_text(_goals_section, {"constraint": c}, {"constraint": 1})
    assert "**not met** (recall –, precision –" in goal


def test_mask_metrics_leave_a_zero_denominator_undefined() -> None:
    from guidance.nn.tight_set import mask_metrics

    y = np.array([[1, 0, 0], [1, 0, 0]])
    for pred, precision, recall in [
        ([[1, 0, 0], [0, 0, 0]], 1.0, 0.5),
        ([[0, 0, 0], [0, 0, 0]], None, 0.0),  # nothing predicted: no precision
        ([[1, 1, 0], [1, 0, 0]], 2 / 3, 1.0),
    ]:
        m = mask_metrics(y, np.array(pred))
        assert (m["precision"], m["recall"]) == (precision, recall)
    # the never-tight columns: no recall; predicted there, precision 0
    m = mask_metrics(y[:, 1:], np.array([[0, 0], [0, 1]]))
    assert m["recall"] is None and m["precision"] == 0.0 and m["f1"] is None
    m = mask_metrics(y[:, 1:], np.zeros((2, 2)))
    assert m["precision"] is None and m["recall"] is None and m["f1"] is None
    json.dumps(m, allow_nan=False)  # null in metrics.json, valid JSON


def test_mask_ceiling_score_without_tight_or_predicted_bits_is_undefined() -> None:
    """Score gave 0/max(0, 1) = 0 for 0/0 (and the card read it as a real 0)."""
    from guidance.nn.card import _ceiling_section

    s = Score(0.02, "union", tp=0, fp=0, fn=0, rows=5, rows_missing=0)
    assert s.precision is None and s.recall is None
    scores = results_dict([s, Score(0.1, "union", 3, 1, 0, 5, 0)], None, None)["scores"]
    assert json.loads(json.dumps(scores, allow_nan=False))[0]["precision"] is None
    old = dict(scores[0], precision=0.0, recall=0.0)  # as files before 28 Nov 2026 hold it
    run = dict(landings=1, neighbours=3, backend="c")
    for first in (scores[0], old):
        text = _card_text(_ceiling_section, dict(run=run, scores=[first, scores[1]]))
        assert _row(text, "0.02")[2:4] == ["–", "–"]
        assert _row(text, "0.1")[2:4] == ["0.750", "1.000"]


def _threshold_sentence(**record) -> str:
    from guidance.nn.card import _constraint_metrics

    c = {"arch": dict(tokens="single", d_model=8, n_layers=1, n_heads=1, d_ff=8),
         "threshold": 0.1, "train_config": dict(target_recall=0.99, recall_confidence=0.95),
         "test": REAL, **record}  # fmt: skip
    text = _card_text(_constraint_metrics, c)
    return " ".join(text.split("\n\n")[0].split())


OLD_FALLBACK = dict(n_calibration_bases=0)  # metrics.json before 28 Nov 2026
NEW_FALLBACK = OLD_FALLBACK | dict(
    threshold_chosen_on=dict(rows="last_fold_validation", base_landings=4)
)
OLD_CALIBRATED = dict(n_calibration_bases=301)
NEW_CALIBRATED = OLD_CALIBRATED | dict(
    threshold_chosen_on=dict(rows="calibration", base_landings=301)
)


@pytest.mark.parametrize("record", [OLD_FALLBACK, NEW_FALLBACK], ids=["old file", "new file"])
def test_card_says_when_the_threshold_was_chosen_on_trained_landings(record) -> None:
    """Without calibration landings train.py chooses the threshold on the last fold's
    validation rows, which the earlier folds trained on; the card said 'a calibration split
    of 0 train+val base landings kept out of training'."""
    sentence = _threshold_sentence(**record)
    assert "kept out of training" not in sentence and "calibration split of" not in sentence
    assert "last fold's validation rows" in sentence and "trained on" in sentence
    if "threshold_chosen_on" in record:
        assert "(4 base landings)" in sentence


@pytest.mark.parametrize("record", [OLD_CALIBRATED, NEW_CALIBRATED], ids=["old", "new"])
def test_card_names_the_calibration_split_the_threshold_was_chosen_on(record) -> None:
    sentence = _threshold_sentence(**record)
    split = "a calibration split of 301 train+val base landings kept out of training"
    assert split in sentence and "trained on" not in sentence


@pytest.mark.parametrize(
    ("record", "says"),
    [
        ({}, "count all 7N mask bits, thrust_min's included, although the flight code always "
             "keeps thrust_min"),
        ({"headline_excludes": ["thrust_min"]},
         "count only the mask bits of the constraints the flight code can drop, not those of "
         "thrust_min"),
    ],
    ids=["old file", "new file"],
)  # fmt: skip
def test_card_states_how_the_always_kept_thrust_min_bits_are_counted(record, says) -> None:
    """The flight code keeps T_min whatever its mask bit; the card's headline precision and
    recall counted its bits without saying so. Now it says how, for files written before
    (all 7N bits counted) and after (thrust_min's left out), of the network's scores and
    threshold and of the mask ceiling's."""
    from guidance.nn.card import _ceiling_section, _constraint_metrics

    c = {"arch": dict(tokens="single", d_model=8, n_layers=1, n_heads=1, d_ff=8),
         "threshold": 0.1, "train_config": dict(target_recall=0.99, recall_confidence=0.95),
         "test": REAL, "n_calibration_bases": 3, **record}  # fmt: skip
    network = " ".join(_card_text(_constraint_metrics, c).split())
    assert f"and the threshold's recall target {says}" in network
    run = dict(landings=1, neighbours=3, backend="c")
    ceiling = " ".join(_card_text(_ceiling_section, dict(run=run, scores=[], **record)).split())
    assert f"The scores below {says}" in ceiling
