"""The mask-ceiling measurement (guidance.mask_ceiling): leave-one-out scoring counted by hand,
perturbations of the requested size, data spacing, and a deterministic solve scoring 1."""

from __future__ import annotations

import numpy as np
import pytest

from guidance import cguidance
from guidance.mask_ceiling import (
    PERTURBED,
    data_spacing,
    loo_counts,
    measure,
    neighbour,
    theta_spread,
)


def test_leave_one_out_counts_by_hand() -> None:
    a = np.array([[1, 1, 0, 0], [0, 1, 0, 0]], np.uint8)
    b = np.array([[1, 0, 0, 0], [0, 1, 1, 0], [1, 1, 1, 1]], np.uint8)  # third row unscored
    c = np.array([[1, 0, 1, 0], [0, 1, 0, 0]], np.uint8)
    # union: a from b|c = [1,0,1,0],[0,1,1,0]: tp 2, fp 2, fn 1 (a's bit 1 of row 0)
    #        b from a|c = [1,1,1,0],[0,1,0,0]: tp 2, fp 2, fn 1 (b's bit 2 of row 1)
    #        c from a|b = [1,1,0,0],[0,1,1,0]: tp 2, fp 2, fn 1 (c's bit 2 of row 0)
    assert loo_counts([a, b, c], 1) == (6, 6, 3, 6, 3)
    # vote >= 2: a from (b, c) = [1,0,0,0],[0,1,0,0]: tp 2, fn 1; b: [1,0,0,0],[0,1,0,0]:
    # tp 2, fn 1; c: [1,0,0,0],[0,1,0,0]: tp 2, fn 1
    assert loo_counts([a, b, c], 2) == (6, 0, 3, 6, 3)


def test_neighbour_moves_only_the_perturbed_components_by_eps() -> None:
    std = theta_spread(200)
    rng = np.random.default_rng(0)
    theta = np.arange(16, dtype=float) + 1.0
    for eps in (0.01, 0.3):
        moved = neighbour(theta, eps, std, rng)
        d = (moved - theta) / std
        assert np.linalg.norm(d) == pytest.approx(eps, rel=1e-12)
        fixed = np.setdiff1d(np.arange(16), PERTURBED)
        np.testing.assert_array_equal(moved[fixed], theta[fixed])  # q0 and the roll rate


def test_more_training_landings_are_never_farther() -> None:
    # the first n base landings of a seed are a prefix of any larger draw, queries are the same
    std = theta_spread(200)
    d = [data_spacing(n, std, n_query=50) for n in (20, 80, 320)]
    assert d[0] >= d[1] >= d[2] > 0.0
    assert d[0] > d[2]


@pytest.mark.skipif(not cguidance.LIB_PATH.exists(), reason="build/libtscvx_gnc.so not built")
def test_identical_neighbours_score_one_and_a_rerun_solves_nothing(tmp_path, monkeypatch) -> None:
    """eps = 0: every neighbour is the landing itself, and the C solve is deterministic. The
    neighbour masks are kept in the run directory: a rerun reads them instead of solving."""
    from guidance import mask_ceiling

    std = theta_spread(200)
    scores = measure(1, 3, [0.0], backend="c", std=std, progress=False, run_dir=tmp_path)
    for s in scores:
        assert s.rows > 0 and s.fn == 0 and s.fp == 0
        assert s.precision == 1.0 and s.recall == 1.0
    assert len(list(tmp_path.glob("eps0_landing*.npz"))) == 1

    def no_solving(job):
        raise AssertionError("solved again")

    monkeypatch.setattr(mask_ceiling, "neighbour_masks", no_solving)
    again = measure(1, 3, [0.0], backend="c", std=std, progress=False, run_dir=tmp_path)
    assert again == scores
    with pytest.raises(ValueError, match="another run"):
        measure(1, 4, [0.0], backend="c", std=std, progress=False, run_dir=tmp_path)
