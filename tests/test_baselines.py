"""Lookup-table baselines: exactness of the tables, the two tables from one run."""

from __future__ import annotations

import numpy as np
import pytest

from guidance.baselines import (
    KDTreeTable,
    PCALinearTable,
    format_table,
    run_baselines,
    training_data_warning,
)
from guidance.dataset import random_dataset
from guidance.nn.train import mahalanobis, ood_flags


def test_pca_linear_table_equals_delaunay_interpolation() -> None:
    from scipy.interpolate import LinearNDInterpolator

    rng = np.random.default_rng(0)
    X, Y = rng.standard_normal((40, 4)), rng.standard_normal((40, 3))
    table = PCALinearTable(X, Y, n_components=4)
    Z = rng.standard_normal((25, 4)) * 0.5
    ref = LinearNDInterpolator(table.Z, Y)(Z)
    inside = ~np.isnan(ref).any(axis=1)
    assert inside.sum() >= 10
    got = np.array([table.weights(z) @ Y for z in Z[inside]])
    np.testing.assert_allclose(got, ref[inside], atol=1e-9)
    # outside the hull: nearest neighbour, counted
    far = table.pca.inverse_transform(np.full((1, 4), 50.0))
    table.predict(far)
    assert table.outside == 1


def test_kdtree_returns_the_table_entry() -> None:
    rng = np.random.default_rng(1)
    X, Y = rng.standard_normal((30, 17)), rng.standard_normal((30, 5))
    np.testing.assert_array_equal(KDTreeTable(X, Y).predict(X[7] + 1e-9), Y[7:8])


def test_ood_is_the_tail_of_the_training_distances() -> None:
    rng = np.random.default_rng(2)
    train = rng.standard_normal((500, 3))
    flags, _ = ood_flags(train, np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]]))
    assert flags.tolist() == [False, True]


def test_mahalanobis_is_scipys_and_weighs_the_axes_by_their_spread() -> None:
    """Against scipy's distance on correlated, anisotropic data; and an offset along the
    widest axis is not out of distribution where the same offset along the narrowest is
    (a plain Euclidean distance would flag both or neither)."""
    from scipy.spatial import distance

    rng = np.random.default_rng(7)
    mix = np.array([[3.0, 0.0, 0.0], [1.0, 0.3, 0.0], [0.0, 0.2, 0.1]])
    train = rng.standard_normal((3000, 3)) @ mix
    points = rng.standard_normal((20, 3)) * 2.0
    VI = np.linalg.inv(np.cov(train, rowvar=False))
    mu = train.mean(axis=0)
    want = [distance.mahalanobis(p, mu, VI) for p in points]
    np.testing.assert_allclose(mahalanobis(train, points), want, rtol=1e-9)
    wide, narrow = mix[0] / np.linalg.norm(mix[0]), np.array([0.0, 0.0, 1.0])
    flags, _ = ood_flags(train, mu + 1.5 * np.vstack([wide, narrow]))
    assert flags.tolist() == [False, True]


def test_both_tables_from_one_run() -> None:
    ds = random_dataset(n_base=10, seed=3)
    res = run_baselines(ds, None, interp_train=40, interp_test=5, max_queries=30)
    for kind in ("constraint", "solution"):
        r = res[kind]
        assert set(r) == {"Linear Interpolation", "KDTree"}
        for m in r.values():
            assert m["time_ms"] > 0 and np.isfinite(m["mse"]) and m["peak_mb"] >= 0
        text = format_table(kind, r)
        assert "Inference Time (ms)" in text and "OOD MSE" in text and "Peak Memory" in text


def test_networks_trained_on_other_data_or_split_are_flagged(tmp_path) -> None:
    pytest.importorskip("torch")
    from guidance.nn.export import export_onnx
    from guidance.nn.train import TrainConfig, dataset_digest, train
    from guidance.params import Params

    ds = random_dataset(n_base=10, seed=3)
    cfg = TrainConfig(epochs=1, batch_size=64, threads=1)
    res = train(ds, "solution", dict(d_model=16, n_heads=2, n_layers=1, d_ff=32), cfg, str)
    digest = dataset_digest(ds)
    model = tmp_path / "solution.onnx"
    extra = {"dataset_content_sha256": digest, "split_seed": 0}
    export_onnx(res, model, Params().to_json_dict(), extra)
    assert training_data_warning(model, digest, 0) is None
    assert "split with seed 0, not 1" in training_data_warning(model, digest, 1)
    other = dataset_digest(random_dataset(n_base=10, seed=4))
    assert "trained on another dataset" in training_data_warning(model, other, 0)
    out = run_baselines(ds, tmp_path, interp_train=20, interp_test=3, max_queries=10, seed=1,
                        kinds=("solution",))  # fmt: skip
    assert "WARNING: the T-SCvx network solution.onnx was split with seed 0, not 1" in format_table(
        "solution", out["solution"]
    )


def test_card_states_the_outside_hull_fraction() -> None:
    from guidance.nn.card import _baseline_table

    row = dict(time_ms=1.0, mse=0.1, ood_mse=0.2, peak_mb=3.0, rows_train=40, rows_test=8)
    text = _baseline_table("solution", {"Linear Interpolation": {**row, "outside_hull": 2}})
    assert "2 of 8 test points (25.00 %) outside the hull" in text


def test_ood_flags_five_percent_of_the_training_set_itself() -> None:
    """The cut is the 95th percentile of the training distances: 5 % of the training points
    lie beyond it (not 10 %)."""
    rng = np.random.default_rng(5)
    train = rng.standard_normal((2000, 4)) @ np.diag([1.0, 2.0, 0.5, 3.0])
    flags, cut = ood_flags(train, train)
    assert flags.mean() == pytest.approx(0.05, abs=0.01)
    # the 95th percentile of the squared distance of a 4-D Gaussian is chi2(4)'s (9.49)
    from scipy.stats import chi2

    assert cut**2 == pytest.approx(chi2.ppf(0.95, 4), rel=0.05)
