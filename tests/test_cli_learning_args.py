"""The learning commands' options (train, export, baselines, mask-ceiling, dataset): bad input
is refused before any work with one error line and exit 2, nothing written."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from guidance.cli import main
from guidance.dataset import random_dataset
from guidance.params import Params


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small dataset file of ``guidance dataset``'s layout (synthetic, not solved)."""
    ds = random_dataset(n_base=12, seed=1)
    head = {**ds.header, "n_samples": len(ds.theta), "created_utc": "2026-01-01T00:00:00Z"}
    head.update({"feasible_fraction": 1.0, "params": Params().to_json_dict()})
    arrays = {f.name: getattr(ds, f.name) for f in dataclasses.fields(ds) if f.name != "header"}
    path = tmp_path_factory.mktemp("data") / "ds.npz"
    np.savez(path, header=np.array(json.dumps(head)), **arrays)
    return path


def _refused_at_parse(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """argparse's refusal: SystemExit 2, its one error line naming the option."""
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err.strip().splitlines()[-1]


@pytest.mark.parametrize(
    "option, message",
    [
        (("--threads", "-1"), "argument --threads: must be >= 0, got -1"),
        (("--threads", "100000"), "argument --threads: must be <= 1024, got 100000"),
        (("--lr", "-1"), "argument --lr: expected a finite number > 0, got '-1'"),
        (("--lr", "nan"), "argument --lr: expected a finite number > 0, got 'nan'"),
        (("--lr", "0"), "argument --lr: expected a finite number > 0, got '0'"),
        (("--max-minutes", "-1"), "argument --max-minutes: expected a finite number >= 0"),
        (("--max-minutes", "nan"), "argument --max-minutes: expected a finite number >= 0"),
        (("--seed", "-1"), "argument --seed: must be >= 0, got -1"),
        (("--seed", str(2**64)), f"argument --seed: must be <= {2**64 - 1}"),
        (("--sizes", "foo"), "argument --sizes: unknown size 'foo' (known: flight-s,"),
        (("--sizes", "flight-s,foo"), "argument --sizes: unknown size 'foo'"),
        (("--sizes", ","), "argument --sizes: no size named in ','"),
    ],
)
def test_train_refuses_bad_options_before_writing(option, message, data, tmp_path, capsys):
    out = tmp_path / "train"
    argv = ["train", "--dataset", str(data), "--train-dir", str(out), "--kind", "solution",
            "--sizes", "flight-s", "--solution-epochs", "1", "--no-progress", *option]  # fmt: skip
    line = _refused_at_parse(argv, capsys)
    assert line.startswith("guidance train: error: ") and message in line
    assert not out.exists()  # was: dataset.json written before torch refused --threads -1


def test_train_sizes_are_parsed_once_in_order() -> None:
    from guidance.cli import build_parser

    def sizes(spec: str) -> list[str]:
        return build_parser().parse_args(["train", "--sizes", spec]).sizes

    assert sizes("all") == ["flight-s", "flight-m", "flight-mlp", "reference"]
    assert sizes("flight") == ["flight-s", "flight-m", "flight-mlp"]
    assert sizes(" reference, flight-s,reference,") == ["reference", "flight-s"]
    assert build_parser().parse_args(["train"]).sizes[-1] == "reference"  # default: all


def test_train_refuses_a_train_dir_that_is_no_folder(data, tmp_path, capsys) -> None:
    (tmp_path / "a_file").write_text("")
    for train_dir, message in [
        (tmp_path / "a_file", "is a file, not a folder"),
        (tmp_path / "a_file" / "train", "cannot create it"),
    ]:
        argv = ["train", "--dataset", str(data), "--train-dir", str(train_dir),
                "--sizes", "flight-s", "--no-progress"]  # fmt: skip
        assert main(argv) == 2  # was: FileExistsError / NotADirectoryError
        err = capsys.readouterr().err
        assert err.startswith(f"error: --train-dir {train_dir}: ") and message in err


def test_export_without_checkpoints_is_bad_input(data, tmp_path, capsys) -> None:
    models = tmp_path / "models"
    (tmp_path / "empty").mkdir()
    for train_dir, message in [
        (tmp_path / "none", "no such folder"),
        (tmp_path / "empty", "no flight-size checkpoint in"),
    ]:
        argv = ["export", "--train-dir", str(train_dir), "--dataset", str(data),
                "--models-dir", str(models)]  # fmt: skip
        assert main(argv) == 2  # was: exit 1
        err = capsys.readouterr().err
        assert err.startswith("error: ") and message in err and "run `guidance train`" in err
        assert not models.exists()


def test_export_refuses_a_models_dir_that_is_a_file(data, tmp_path, capsys) -> None:
    train_dir = tmp_path / "train"
    train_dir.mkdir()
    # a finished model's report (no checkpoint needed: the check comes before it is read)
    report = {"kind": "solution", "macs": 1000, "heldout_val_loss": 1.0}
    (train_dir / "solution-flight-s.json").write_text(json.dumps(report))
    (tmp_path / "a_file").write_text("")
    argv = ["export", "--train-dir", str(train_dir), "--dataset", str(data),
            "--models-dir", str(tmp_path / "a_file")]  # fmt: skip
    assert main(argv) == 2  # was: FileExistsError from mkdir
    err = capsys.readouterr().err
    assert err.startswith("error: --models-dir ") and "is a file, not a folder" in err


@pytest.mark.parametrize(
    "option, message",
    [
        (("--interp-train", "0"), "argument --interp-train: must be >= 2, got 0"),
        (("--interp-train", "1"), "argument --interp-train: must be >= 2, got 1"),
        (("--interp-train", "-1"), "argument --interp-train: must be >= 2, got -1"),
        (("--interp-test", "-5"), "argument --interp-test: must be >= 1, got -5"),
        (("--interp-test", "0"), "argument --interp-test: must be >= 1, got 0"),
        (("--max-queries", "-3"), "argument --max-queries: must be >= 1, got -3"),
        (("--max-queries", "0"), "argument --max-queries: must be >= 1, got 0"),
        (("--max-queries", "x"), "argument --max-queries: expected an integer, got 'x'"),
        (("--seed", "-1"), "argument --seed: must be >= 0, got -1"),
    ],
)
def test_baselines_refuse_bad_counts_before_writing(option, message, data, tmp_path, capsys):
    models = tmp_path / "models"
    argv = ["baselines", "--dataset", str(data), "--models-dir", str(models), *option]
    line = _refused_at_parse(argv, capsys)
    assert line.startswith("guidance baselines: error: ") and message in line
    assert not models.exists()


@pytest.mark.parametrize(
    "eps, message",
    [
        ("1e303", "argument --eps: expected radii in [0, 10], got '1e303'"),
        ("0.1,11", "argument --eps: expected radii in [0, 10]"),
        ("-0.1", "argument --eps: expected radii in [0, 10]"),
        ("0.1,0.1000001", "argument --eps: expected distinct radii, got '0.1,0.1000001'"),
    ],
)
def test_mask_ceiling_refuses_bad_radii(eps, message, tmp_path, capsys) -> None:
    models = tmp_path / "models"
    argv = ["mask-ceiling", "--landings", "1", "--neighbours", "3", "--workers", "1",
            "--run-dir", "", "--models-dir", str(models), f"--eps={eps}"]  # fmt: skip
    line = _refused_at_parse(argv, capsys)
    assert line.startswith("guidance mask-ceiling: error: ") and message in line
    assert not models.exists()


def test_run_dirs_that_cannot_be_folders_are_refused(tmp_path, capsys) -> None:
    (tmp_path / "a_file").write_text("")
    models = tmp_path / "models"
    for argv, run_dir, message in [
        (["mask-ceiling", "--landings", "1", "--neighbours", "3", "--workers", "1",
          "--models-dir", str(models)], tmp_path / "a_file", "is a file, not a folder"),
        (["dataset", "--n-base", "1", "--workers", "1", "--no-progress",
          "--output", str(tmp_path / "d.npz")], tmp_path / "a_file" / "run", "cannot create it"),
    ]:  # fmt: skip
        assert main([*argv, "--run-dir", str(run_dir)]) == 2  # was: FileExists/NotADirectory
        err = capsys.readouterr().err
        assert err.startswith(f"error: --run-dir {run_dir}: ") and message in err
    assert not models.exists() and not (tmp_path / "d.npz").exists()
