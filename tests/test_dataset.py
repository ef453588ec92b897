"""guidance.dataset and `guidance dataset`: the packed dataset (rotation augmentation,
layout, provenance), its loading with every array and value checked, and the command's
options."""

from __future__ import annotations

import json
import re
import shutil
import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest
from dataset_runs import copy_run

from guidance import dataset_run
from guidance.cli import main
from guidance.dataset import load_dataset, pack, random_dataset
from guidance.dataset_run import RUN_KEYS, read_sample, sample_path, scvx_solver
from guidance.errors import InputError
from guidance.params import NC, SCvxSettings
from guidance.provenance import code_version
from guidance.sampling import N_ROTATIONS, scenario_of


@pytest.mark.parametrize(
    "option", [("--n-base", "0"), ("--n-base", "-3"), ("--workers", "-1"), ("--seed", "-1")]
)
def test_cli_refuses_bad_counts_up_front(option, tmp_path, capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        out = ["--run-dir", str(tmp_path / "run"), "--output", str(tmp_path / "d.npz")]
        main(["dataset", *out, *option])
    assert exc.value.code == 2
    assert f"argument {option[0]}: must be >= " in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


def test_pack_only_without_a_run_is_bad_input(tmp_path, capsys) -> None:
    run = tmp_path / "no_such_run"
    argv = ["dataset", "--pack-only", "--run-dir", str(run), "--output", str(tmp_path / "d.npz")]
    assert main(argv) == 2
    assert "is not a dataset run directory (no run.json)" in capsys.readouterr().err


def test_unusable_outputs_are_refused_before_solving(tmp_path, capsys) -> None:
    (tmp_path / "a_file").write_text("")
    for args, message in [
        (["--run-dir", str(tmp_path / "a_file")], "is a file, not a folder"),
        (["--output", "/proc/d.npz"], "--output /proc/d.npz: cannot write there"),
        # the run's folder, not made yet: the pack failed after every solve
        (["--output", str(tmp_path / "run")], "is the --run-dir folder"),
    ]:
        argv = ["dataset", "--n-base", "1", "--run-dir", str(tmp_path / "run"),
                "--output", str(tmp_path / "d.npz"), *args]  # fmt: skip
        assert main(argv) == 2
        assert message in capsys.readouterr().err
        assert not (tmp_path / "run").exists()


def test_packed_dataset_layout_and_provenance(tiny_run) -> None:
    _, _, _, header, ds = tiny_run
    M = 2 * N_ROTATIONS
    assert ds.theta.shape == (M, 16)
    assert ds.x.shape == (M, 50, 14) and ds.u.shape == (M, 50, 3)
    assert ds.masks.shape == (M, 20, NC * 50)
    assert np.all(ds.n_masks == ds.iterations)
    assert set(ds.rotation.tolist()) == set(range(N_ROTATIONS))
    for key in ("seed", "sampling_ranges", "code_version", "scvx_settings", "params"):
        assert key in header
    assert header["code_versions"] == [code_version()]  # solved by this code
    prov = header["provenance"]
    assert prov["generator"] == code_version() and "numpy" in prov["packages"]
    assert {"host", "python", "created_utc"} <= set(prov)
    assert header["n_base"] == 2 and header["format_version"] == 1
    assert 0.0 <= header["feasible_fraction"] <= 1.0
    json.dumps(ds.header)
    # rows past the valid count are zero padding
    for m in range(M):
        assert not ds.masks[m, ds.n_masks[m] :].any()


def test_rotated_samples_are_the_solutions_of_the_rotated_scenarios(tiny_run) -> None:
    _, _, _, _, ds = tiny_run
    solved = np.flatnonzero((ds.status == "solved") & (ds.rotation > 0))
    assert len(solved) >= 7, "the tiny run should contain a solved landing"
    # re-solved by the solver that made the data (the C library when built)
    solve = scvx_solver(ds.header["solver_backend"])
    for m in (solved[0], solved[len(solved) // 2 + 1]):
        r = solve(scenario_of(ds.theta[m]), None)
        assert r.status == "solved"
        np.testing.assert_allclose(r.x, ds.x[m], atol=1e-4)
        np.testing.assert_allclose(r.u, ds.u[m], atol=1e-3)
        assert abs(r.t_f - ds.t_f[m]) <= 1e-4
        np.testing.assert_array_equal(r.masks, ds.masks[m, : ds.n_masks[m]])


def test_cli_packs_a_run(tiny_run, tmp_path, capsys) -> None:
    run = tiny_run[0]
    out = tmp_path / "d.npz"
    assert main(["dataset", "--pack-only", "--run-dir", str(run), "--output", str(out)]) == 0
    assert "feasible fraction" in capsys.readouterr().out
    assert load_dataset(out).header["n_base"] == 2


def test_cli_prox_u_reaches_the_solves(tmp_path, monkeypatch) -> None:
    """`guidance dataset --prox-u 0` solves with the paper's objective (the data of the
    networks shipped until 23 Nov); the weight is part of the run's settings, so a resume with
    another is refused."""
    seen = {}

    def fake_generate(*args, settings=None, **kwargs):
        seen["settings"] = settings
        raise KeyboardInterrupt  # stop before any solve

    monkeypatch.setattr(dataset_run, "generate", fake_generate)
    out = ["--run-dir", str(tmp_path / "run"), "--output", str(tmp_path / "d.npz")]
    assert main(["dataset", *out, "--prox-u", "0"]) == 130
    assert seen["settings"] == SCvxSettings(prox_u=0.0)
    assert main(["dataset", *out]) == 130
    assert seen["settings"] == SCvxSettings()
    assert "scvx_settings" in RUN_KEYS


def test_constraint_pairs_number_the_iterations_from_one() -> None:
    """The flight code feeds k = 1 at the first SCvx iteration: the pair of mask row j of a
    sample has k = j + 1, and there is one pair per recorded mask."""
    ds = random_dataset(n_base=2, iters=4)
    ds.n_masks[3] = 2  # samples may record fewer iterations
    X, Y, idx = ds.constraint_pairs()
    assert len(X) == int(ds.n_masks.sum()) == 2 * N_ROTATIONS * 4 - 2
    for m in range(len(ds.theta)):
        rows = np.flatnonzero(idx == m)
        np.testing.assert_array_equal(X[rows, -1], np.arange(1, ds.n_masks[m] + 1))
        np.testing.assert_array_equal(X[rows, :-1], np.repeat(ds.theta[m][None], len(rows), 0))
        np.testing.assert_array_equal(Y[rows], ds.masks[m, : ds.n_masks[m]])


def test_feasible_fraction_counts_base_samples(tiny_run) -> None:
    """Both base landings of the tiny run solve: the feasible fraction is exactly 1 (a
    fraction of base samples, not of the 2 x 8 rotated rows)."""
    _, _, _, header, ds = tiny_run
    assert header["base_status_counts"] == {"solved": 2}
    assert np.all(ds.status == "solved")
    assert header["feasible_fraction"] == 1.0


def _rewritten(tiny_run, path: Path, header: dict | None = None, **arrays) -> Path:
    """The tiny run's dataset with some arrays (or the header) replaced."""
    with np.load(tiny_run[0] / "dataset.npz", allow_pickle=False) as f:
        members = {k: f[k] for k in f.files}
    if header is not None:
        members["header"] = np.array(json.dumps(header))
    np.savez_compressed(path, **{**members, **arrays})
    return path


DAMAGES = (
    "x of another N",
    "a theta row short",
    "fewer mask rows",
    "float masks",
    "numeric status",
    "object status",
    "no n_samples",
)


@pytest.mark.parametrize("damage", DAMAGES)
def test_load_dataset_checks_every_array_against_the_header(damage: str, tiny_run, tmp_path):
    """load_dataset returned arrays of any shape or kind (training then failed far from the
    file, or learnt from garbage) and let numpy's ValueError of an object array through. Each
    is now InputError naming the file and the member."""
    ds, header = tiny_run[4], tiny_run[3]
    changes, message = {
        "x of another N": ({"x": ds.x[:, :10]}, "member x holds"),
        "a theta row short": ({"theta": ds.theta[:-1]}, "member theta holds"),
        "fewer mask rows": ({"masks": ds.masks[:, :5]}, "member masks holds"),
        "float masks": ({"masks": ds.masks.astype(float)}, "member masks holds"),
        "numeric status": ({"status": np.zeros(len(ds.status))}, "member status holds"),
        "object status": ({"status": ds.status.astype(object)}, "member status is unreadable"),
        "no n_samples": (
            {"header": {k: v for k, v in header.items() if k != "n_samples"}},
            "its header gives no n_samples count",
        ),
    }[damage]
    path = _rewritten(tiny_run, tmp_path / "d.npz", **changes)
    with pytest.raises(InputError, match=rf"{re.escape(str(path))}: {message}"):
        load_dataset(path)


def _damage_member(path: Path, name: str) -> None:
    """Flips bytes in the middle of a member's compressed data (the archive's index intact)."""
    with zipfile.ZipFile(path) as z:
        info = z.getinfo(f"{name}.npy")
    data = bytearray(path.read_bytes())
    name_len, extra_len = struct.unpack(
        "<HH", data[info.header_offset + 26 : info.header_offset + 30]
    )
    middle = info.header_offset + 30 + name_len + extra_len + info.compress_size // 2
    data[middle : middle + 16] = bytes(b ^ 0xFF for b in data[middle : middle + 16])
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("member", ["x", "header"])
def test_load_dataset_names_a_damaged_member(member: str, tiny_run, tmp_path) -> None:
    """A damaged compressed member raised zlib.error or zipfile's BadZipFile (a traceback
    naming neither file nor member)."""
    path = tmp_path / "d.npz"
    shutil.copy(tiny_run[0] / "dataset.npz", path)
    _damage_member(path, member)
    with pytest.raises(InputError, match=rf"{re.escape(str(path))}: member {member} is unreadable"):
        load_dataset(path)


def test_pack_stores_sample_ids_as_int64_and_loads_int32_files(tiny_run, tmp_path) -> None:
    """pack stored base_id as int32: an id past 2**31 - 1 wrapped. It is int64 now, and a
    dataset packed before (int32 ids) still loads."""
    run = copy_run(tiny_run, tmp_path)
    i = 2**31 + 5
    rec = {**read_sample(sample_path(run, 0)), "id": np.asarray(i)}  # a sample of this run
    np.savez(sample_path(run, i), **rec)
    pack(run, tmp_path / "d.npz")
    ds = load_dataset(tmp_path / "d.npz")
    assert ds.base_id.dtype == np.int64
    assert sorted(set(ds.base_id.tolist())) == [0, 1, i]
    old = _rewritten(tiny_run, tmp_path / "old.npz", base_id=tiny_run[4].base_id.astype(np.int32))
    assert load_dataset(old).base_id.tolist() == tiny_run[4].base_id.tolist()


def _with(a: np.ndarray, index: tuple, value) -> np.ndarray:
    out = a.copy()
    out[index] = value
    return out


VALUE_DAMAGES = (
    "mask bit 2",
    "negative mask bit",
    "n_masks past iter_max",
    "negative n_masks",
    "iterations past iter_max",
    "negative subproblems",
    "negative base_id",
    "rotation 8",
    "NaN theta",
    "infinite solve time",
    "NaN x of a solved sample",
    "NaN u of a solved sample",
    "NaN t_f of a solved sample",
)


@pytest.mark.parametrize("damage", VALUE_DAMAGES)
def test_load_dataset_checks_the_values_pack_writes(damage: str, tiny_run, tmp_path) -> None:
    """load_dataset checked shapes and kinds but not values: a mask bit of 2, a mask count past
    iter_max, a negative id or a NaN in a solved trajectory loaded, and training learnt from
    it (or failed far from the file). Each is now InputError naming the file and member."""
    ds = tiny_run[4]
    K = ds.masks.shape[1]
    assert ds.status[3] == "solved"
    changes = {
        "mask bit 2": {"masks": _with(ds.masks, (3, 0, 5), 2)},
        "negative mask bit": {"masks": _with(ds.masks.astype(np.int8), (3, 0, 5), -1)},
        "n_masks past iter_max": {"n_masks": _with(ds.n_masks, 3, K + 1)},
        "negative n_masks": {"n_masks": _with(ds.n_masks, 3, -1)},
        "iterations past iter_max": {"iterations": _with(ds.iterations, 3, K + 1)},
        "negative subproblems": {"subproblems": _with(ds.subproblems, 3, -2)},
        "negative base_id": {"base_id": _with(ds.base_id, 3, -1)},
        "rotation 8": {"rotation": _with(ds.rotation, 3, N_ROTATIONS)},
        "NaN theta": {"theta": _with(ds.theta, (3, 13), np.nan)},
        "infinite solve time": {"solve_time_s": _with(ds.solve_time_s, 3, np.inf)},
        "NaN x of a solved sample": {"x": _with(ds.x, (3, 7, 2), np.nan)},
        "NaN u of a solved sample": {"u": _with(ds.u, (3, 7, 2), np.nan)},
        "NaN t_f of a solved sample": {"t_f": _with(ds.t_f, 3, np.nan)},
    }[damage]
    (member,) = changes
    path = _rewritten(tiny_run, tmp_path / "d.npz", **changes)
    with pytest.raises(
        InputError, match=rf"{re.escape(str(path))}: member {member} holds .*sample 3"
    ):
        load_dataset(path)


def test_load_dataset_accepts_the_nan_padding_of_unsolved_samples(tiny_run, tmp_path) -> None:
    """A crashed solve is written with NaN x, u and t_f and no masks: such a sample loads."""
    ds = tiny_run[4]
    path = _rewritten(
        tiny_run,
        tmp_path / "d.npz",
        status=_with(ds.status, 3, "error"),
        x=_with(ds.x, 3, np.nan),
        u=_with(ds.u, 3, np.nan),
        t_f=_with(ds.t_f, 3, np.nan),
        masks=_with(ds.masks, 3, 0),
        n_masks=_with(ds.n_masks, 3, 0),
        iterations=_with(ds.iterations, 3, 0),
    )
    loaded = load_dataset(path)
    assert np.isnan(loaded.x[3]).all() and len(loaded.solved().theta) == len(ds.theta) - 1
