"""The networks' conventions, one definition each: their kinds, the files of a models folder,
and the default training run (what ``make models`` trains with, models/models.mk).

No heavy import here: the flight path (no torch) and the command line's option defaults read
it.
"""

from __future__ import annotations

from guidance.paths import ROOT

# The folder of the shipped networks, the default of every command that reads or writes one
# (guidance solve, export, baselines, mask-ceiling): the repository's, wherever the command
# runs from.
MODELS_DIR = ROOT / "models"

CONSTRAINT = "constraint"  # (theta, k) -> the k-th subproblem's tight constraints
SOLUTION = "solution"  # theta -> the warm start (x, u, t_f)
KINDS = (CONSTRAINT, SOLUTION)

# A model file carries probe inputs and the outputs its exporter computed; a reader (onnxruntime
# or the flight blob's C inference) that does not reproduce them to this relative tolerance
# is running another model, or running it wrongly.
PROBE_RTOL = 1e-4

ONNX_SUFFIX = ".onnx"  # what `guidance export` writes, onnxruntime reads
TNN_SUFFIX = ".tnn"  # the flight blob `make lib` converts it to (guidance.nn.flight)


def network_file(kind: str, suffix: str = ONNX_SUFFIX) -> str:
    """The file name of the ``kind`` network in a models folder: ``constraint.onnx``, ..."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    return kind + suffix


CONSTRAINT_MODEL = network_file(CONSTRAINT)
SOLUTION_MODEL = network_file(SOLUTION)

# Beside the networks: what `guidance export` measured (the card's source), what `guidance
# baselines` and `guidance mask-ceiling` measured (optional), and the card made from them.
METRICS_FILE = "metrics.json"
BASELINES_FILE = "baselines.json"
MASK_CEILING_FILE = "mask_ceiling.json"
MODEL_CARD_FILE = "MODEL_CARD.md"
# The set `guidance export` wrote: each file's sha256 (guidance.nn.model_files).
MANIFEST_FILE = "manifest.json"

# ---- the default training run (guidance train; guidance.nn.train.TrainConfig) -------------
# Epochs per fold. The constraint task has one row per (landing, iteration), about 14 times
# the solution task's rows, so it needs fewer passes. It is limited by the number of base
# landings, not by training time: the eight rotations of a landing share one mask, and the
# net memorizes the ~1,100 training landings within a few passes (the held-out fold-1 val
# loss rises from the third epoch on). With 1, 2, 3 and 6 epochs per fold (6: dropout 0.3)
# the calibration-split precision at recall 0.99 was 0.557, 0.542, 0.533 and 0.536.
EPOCHS = {CONSTRAINT: 1, SOLUTION: 8}
REFERENCE_EPOCHS = 2  # the paper-size reference networks: the paper's two epochs per fold
LEARNING_RATE = 1e-3  # AdamW's peak rate (after the warm-up)
TEST_FRACTION = 0.2  # of the base landings (all eight rotations of each): the test split


def default_epochs(kind: str) -> int:
    """Epochs per fold of a flight-size ``kind`` network when none are given."""
    if kind not in EPOCHS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    return EPOCHS[kind]


# Which rows the constraint network's decision threshold was chosen on (metrics key
# "threshold_chosen_on": {"rows": ..., "base_landings": n}): the calibration landings, kept out
# of the folds, or, when the data leave none (too few train+validation landings, or
# calibration_fraction 0), the last fold's validation rows, which the earlier folds of the
# sequential K-fold trained on.
THRESHOLD_ON_CALIBRATION = "calibration"
THRESHOLD_ON_LAST_FOLD = "last_fold_validation"
