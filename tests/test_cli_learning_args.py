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


# ---- one models folder for every command ---------------------------------------------------
def test_every_models_dir_default_is_the_repositorys_models_folder() -> None:
    """baselines' was "models" of the current directory, solve's the repository's: run from
    elsewhere, baselines scored no network and said nothing."""
    from guidance.cli import build_parser
    from guidance.nn.conventions import MODELS_DIR

    assert Path(__file__).resolve().parents[1] / "models" == MODELS_DIR
    parser = build_parser()
    assert parser.parse_args(["solve"]).models == str(MODELS_DIR)
    for command in ("export", "baselines", "mask-ceiling"):
        assert parser.parse_args([command]).models_dir == str(MODELS_DIR), command


@pytest.mark.parametrize(
    "kind, missing", [((), "constraint.onnx and "), (("--kind", "solution"), "solution.onnx")]
)
def test_baselines_without_the_networks_is_bad_input(kind, missing, data, tmp_path, capsys):
    """A models folder without the networks asked for (default: both) was scored as tables
    alone, exit 0."""
    models, out = tmp_path / "models", tmp_path / "b.json"
    models.mkdir()
    small = ["--max-queries", "5", "--interp-train", "5", "--interp-test", "2"]
    argv = ["baselines", "--dataset", str(data), "--models-dir", str(models), "--json", str(out),
            *kind, *small]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {models / missing}") and "no such network" in err
    assert not out.exists()


# ---- damaged JSON files: exit 2 naming the file, never a traceback --------------------------
@pytest.mark.parametrize(
    "record, problem",
    [
        ("{", "not valid JSON"),
        ('{"path": "x"}', "no 'content_sha256'"),
        ("[]", "a list, not a JSON object"),
    ],
)
def test_train_refuses_a_damaged_dataset_record(record, problem, data, tmp_path, capsys):
    out = tmp_path / "train"
    out.mkdir()
    (out / "dataset.json").write_text(record)
    argv = ["train", "--dataset", str(data), "--train-dir", str(out), "--kind", "solution",
            "--sizes", "flight-s", "--no-progress"]  # fmt: skip
    assert main(argv) == 2  # was: JSONDecodeError, KeyError 'content_sha256'
    err = capsys.readouterr().err
    assert err.startswith(f"error: {out / 'dataset.json'}: not the record of the dataset")
    assert problem in err and "--restart" in err
    assert sorted(p.name for p in out.iterdir()) == ["dataset.json"]


@pytest.mark.parametrize("report", ["[]", "{", '{"kind": "solution"'])
def test_train_refuses_a_damaged_report_of_a_finished_model(report, data, tmp_path, capsys):
    out = tmp_path / "train"
    out.mkdir()
    (out / "solution-flight-s.json").write_text(report)
    argv = ["train", "--dataset", str(data), "--train-dir", str(out), "--kind", "solution",
            "--sizes", "flight-s", "--no-progress"]  # fmt: skip
    assert main(argv) == 2  # was: AttributeError ('list' has no attribute 'get')
    err = capsys.readouterr().err
    assert err.startswith(f"error: {out / 'solution-flight-s.json'}: not a trained model's report")
    assert "re-run `guidance train`" in err


REPORT = {"kind": "solution", "arch": {}, "n_params": 10, "macs": 1000,
          "heldout_val_loss": 1.0, "final_val_loss": 1.0, "train_seconds": 1.0}  # fmt: skip


@pytest.mark.parametrize(
    "text, problem",
    [
        ("{", "not valid JSON"),
        (json.dumps({k: v for k, v in REPORT.items() if k != "macs"}), "no 'macs'"),
        (json.dumps({**REPORT, "macs": "x"}), "'macs' is a string, not an integer"),
        (json.dumps({**REPORT, "heldout_val_loss": None}), "'heldout_val_loss' is null"),
        (json.dumps({**REPORT, "kind": "constraint"}), "reports a 'constraint' network"),
    ],
)
def test_export_refuses_a_damaged_report(text, problem, data, tmp_path, capsys) -> None:
    train_dir, models = tmp_path / "train", tmp_path / "models"
    train_dir.mkdir()
    (train_dir / "solution-flight-s.json").write_text(text)
    argv = ["export", "--train-dir", str(train_dir), "--dataset", str(data),
            "--models-dir", str(models)]  # fmt: skip
    assert main(argv) == 2  # was: JSONDecodeError, KeyError 'macs', TypeError
    err = capsys.readouterr().err
    assert err.startswith(f"error: {train_dir / 'solution-flight-s.json'}: ") and problem in err
    assert not models.exists()


def test_card_refuses_a_damaged_metrics_file(tmp_path) -> None:
    """write_card read metrics.json unchecked (JSONDecodeError, KeyError)."""
    from guidance.errors import InputError
    from guidance.nn.card import write_card

    shipped = Path(__file__).resolve().parents[1] / "models" / "metrics.json"
    good = json.loads(shipped.read_text())
    for text, problem in [
        ("{", "not valid JSON"),
        ("{}", "no 'dataset_header', no 'sweep', no 'shipped'"),
        (json.dumps({**good, "shipped": {}}), "no shipped network"),
        (json.dumps({**good, "sweep": {"x": {}}}), "no 'sweep.x.kind'"),
    ]:
        (tmp_path / "metrics.json").write_text(text)
        with pytest.raises(InputError) as exc:
            write_card(tmp_path)
        assert str(exc.value).startswith(f"{tmp_path / 'metrics.json'}: ") and problem in str(
            exc.value
        )
        assert str(exc.value).endswith("re-run `guidance export`")
    (tmp_path / "metrics.json").write_text(json.dumps(good))
    (tmp_path / "baselines.json").write_text("[]")
    with pytest.raises(InputError, match=r"baselines.json: not what `guidance baselines` writes"):
        write_card(tmp_path)
    assert not (tmp_path / "MODEL_CARD.md").exists()


def test_one_definition_of_the_kinds_files_and_budget() -> None:
    """The kinds, their files and the instruction budget were spelled out in many modules."""
    from guidance import api, budget, cguidance
    from guidance.nn import card, conventions, flight

    kinds = conventions.KINDS
    assert set(cguidance.NET_KINDS) == set(kinds) == set(flight.KIND_CODES)
    assert list(budget.NN_MODELS) == list(kinds)
    assert [p.name for p in budget.NN_MODELS.values()] == ["constraint.tnn", "solution.tnn"]
    assert (api.CONSTRAINT_MODEL, api.SOLUTION_MODEL) == ("constraint.onnx", "solution.onnx")
    assert api.MODELS_DIR is conventions.MODELS_DIR
    assert card.fits_budget is budget.fits_budget  # was cli_learning's, with its own 5e6
    m = budget.NN_INSTRUCTION_BUDGET / budget.INSTR_PER_MAC
    assert budget.fits_budget(int(m)) and not budget.fits_budget(int(m) + 1)
