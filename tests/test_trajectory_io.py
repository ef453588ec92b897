"""Trajectory .npz files (guidance/trajectory_io.py): what is written is read back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from guidance.params import NC, Params, Scenario, SCvxSettings
from guidance.scvx import SCvxResult
from guidance.trajectory_io import REQUIRED_KEYS, read_trajectory, write_trajectory

N = 5


def _result(status: str, reason: str) -> SCvxResult:
    x = np.arange(N * 14, dtype=float).reshape(N, 14)
    u = np.full((N, 3), 0.5)
    masks = np.zeros((2, NC * N), np.uint8)
    masks[1, 3] = 1
    return SCvxResult(status, reason, x, u, 4.25, 7, 9, 0.125, masks=masks,
                      settings=SCvxSettings(iter_max=7))  # fmt: skip


@pytest.mark.parametrize(
    ("status", "reason"),
    [("infeasible", "virtual control 0.3 > 1e-06"), ("max_iterations", "iteration limit")],
)
def test_status_and_fields_are_read_back(tmp_path: Path, status: str, reason: str) -> None:
    path = tmp_path / "t.npz"
    p = Params(N=N)
    write_trajectory(path, _result(status, reason), p, Scenario(params=p), "scvx", "clarabel")
    d = read_trajectory(path)
    assert str(d["status"]) == status
    assert str(d["reason"]) == reason
    assert float(d["t_f"]) == 4.25 and int(d["iterations"]) == 7
    assert float(d["solve_time_s"]) == 0.125
    np.testing.assert_array_equal(d["x"], np.arange(N * 14).reshape(N, 14))
    np.testing.assert_array_equal(d["u"], np.full((N, 3), 0.5))
    assert d["masks"].shape == (2, NC * N) and d["masks"].sum() == 1
    assert d["params"]["N"] == N  # type: ignore[index]
    assert d["settings"]["iter_max"] == 7  # type: ignore[index]
    assert str(d["method"]) == "scvx" and str(d["backend"]) == "clarabel"


@pytest.mark.parametrize("missing", ["t_f", "status"])
def test_a_file_missing_a_required_key_is_refused(tmp_path: Path, missing: str) -> None:
    path = tmp_path / "t.npz"
    p = Params(N=N)
    write_trajectory(path, _result("solved", "converged"), p, Scenario(params=p), "scvx", "c")
    with np.load(path) as data:
        kept = {k: data[k] for k in data.files if k != missing}
    bad = tmp_path / "bad.npz"
    np.savez(bad, **kept)
    assert missing in REQUIRED_KEYS
    with pytest.raises(ValueError, match=f"not a trajectory file, missing {missing}"):
        read_trajectory(bad)
