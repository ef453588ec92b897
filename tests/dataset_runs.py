"""The tiny dataset run the tests of the dataset pipeline share (test_dataset_run,
test_dataset, test_runs; solved once, by conftest's ``tiny_run``): its sampling ranges and a
copy to change."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from guidance.dataset import load_dataset, pack
from guidance.dataset_run import generate
from guidance.sampling import SamplingRanges

# narrow ranges near the default landing: the tiny run's landings are feasible
EASY = SamplingRanges(
    horizontal=(0.5, 2.0), v_up=(-0.5, 0.0), v_horizontal=(-1.0, 0.0), m0=(2.9, 3.0)
)


def solve_tiny_run(tmp_path_factory: pytest.TempPathFactory):
    """Two base landings solved in two resumed runs and packed: (run folder, the first run's
    status counts, the second's, the packed header, the loaded dataset)."""
    run = tmp_path_factory.mktemp("run")
    # The Python reference solves the tiny run: its rotated solves reproduce the rotated data
    # to 1e-4 (the C library's SCvx path is as equivariant in exact arithmetic, but amplifies
    # rounding to 6e-4 on these landings; test_cguidance bounds that drift).
    first = generate(run, 1, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    # a stray temporary file from a killed run must not count as a finished sample
    (run / "samples" / ".000001.npz.tmp").write_bytes(b"partial")
    second = generate(  # only id 1
        run, 2, seed=11, ranges=EASY, workers=2, progress=False, backend="clarabel"
    )
    out = run / "dataset.npz"
    header = pack(run, out)
    return run, first, second, header, load_dataset(out)


def copy_run(tiny_run, tmp_path: Path) -> Path:
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    return run
