"""The mask-ceiling measurement (guidance.mask_ceiling): leave-one-out scoring counted by hand,
perturbations of the requested size, data spacing, and a deterministic solve scoring 1."""

from __future__ import annotations

import json
import os
import signal

import numpy as np
import pytest
from c_library import needs_c_library

from guidance import mask_ceiling
from guidance.cli import main
from guidance.errors import InputError
from guidance.mask_ceiling import (
    PERTURBED,
    Score,
    data_spacing,
    loo_counts,
    measure,
    neighbour,
    theta_spread,
)
from guidance.pool import WorkerDiedError
from guidance.provenance import code_version


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


def test_leave_one_out_counts_leave_out_the_always_kept_thrust_min_bits() -> None:
    """T_min (bit 7k + 6) is kept by the flight code whatever the mask says: neighbours that
    differ only there predict each other perfectly. They were counted (fp 4, fn 2 here)."""
    a = np.zeros((1, 14), np.uint8)
    a[0, [1, 4]] = 1  # glideslope at node 0, T_max at node 0
    b, c = a.copy(), a.copy()
    b[0, 6] = c[0, 13] = 1  # T_min at node 0, at node 1
    # union: a from b|c gets both T_min bits (not counted); b misses 6, c misses 13
    assert loo_counts([a, b, c], 1) == (6, 0, 0, 3, 0)
    s = Score(0.0, "union", *loo_counts([a, b, c], 1))
    assert (s.precision, s.recall) == (1.0, 1.0)


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


@needs_c_library
def test_identical_neighbours_score_one_and_a_rerun_solves_nothing(tmp_path, monkeypatch) -> None:
    """eps = 0: every neighbour is the landing itself, and the C solve is deterministic. The
    neighbour masks are kept in the run directory: a rerun reads them instead of solving."""
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
    with pytest.raises(InputError, match="another run"):
        measure(1, 4, [0.0], backend="c", std=std, progress=False, run_dir=tmp_path)
    made_by = mask_ceiling.results_dict(scores, None, None)["provenance"]  # mask_ceiling.json
    assert made_by["generator"] == code_version() and "numpy" in made_by["packages"]


def test_a_resume_with_other_options_is_bad_input(tmp_path) -> None:
    config = dict(seed=7, neighbours=9, backend="c")
    mask_ceiling._check_run(tmp_path, config)
    mask_ceiling._check_run(tmp_path, config)  # the same run resumes
    with pytest.raises(InputError, match=r"another run \(different neighbours, backend\)"):
        mask_ceiling._check_run(tmp_path, {**config, "neighbours": 4, "backend": "clarabel"})


def test_run_records_every_code_version(tmp_path, capsys) -> None:
    """run.json lists the code versions that solved into the run; a resume by another warns."""

    config = {"seed": 1, "neighbours": 3, "backend": "c"}
    assert mask_ceiling._check_run(tmp_path, config) == [code_version()]
    record = json.loads((tmp_path / "run.json").read_text())
    (tmp_path / "run.json").write_text(json.dumps({**record, "code_versions": ["guidance old"]}))
    assert mask_ceiling._check_run(tmp_path, config) == ["guidance old", code_version()]
    assert "warning: " in capsys.readouterr().err
    assert mask_ceiling._check_run(tmp_path, config) == ["guidance old", code_version()]
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    "option",
    [
        ("--landings", "0"),
        ("--neighbours", "2"),
        ("--workers", "-1"),
        ("--train-landings", "0"),
        ("--seed", "-2"),
        ("--eps", "0.1,x"),
        ("--eps", "-0.1"),
        ("--eps", ","),
    ],
)
def test_cli_refuses_bad_numbers_up_front(option, tmp_path, capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        # every output in tmp_path: a regression must not write the shipped models/
        out = ["--json", str(tmp_path / "m.json"), "--models-dir", str(tmp_path / "models")]
        main(["mask-ceiling", "--run-dir", str(tmp_path / "run"), *out, *option])
    assert exc.value.code == 2
    assert f"argument {option[0]}: " in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


def die_on_landing_1(job):
    """A worker that dies on landing 1 as a segfault or the OOM killer would end it."""
    eps, i = job[:2]
    if i == 1:
        os.kill(os.getpid(), signal.SIGKILL)
    return eps, i, []


def test_a_dead_worker_stops_the_run_with_how_to_resume(tmp_path, monkeypatch, deadline):
    monkeypatch.setattr(mask_ceiling, "neighbour_masks", die_on_landing_1)
    with pytest.raises(WorkerDiedError, match=r"worker process died.* of 3 are kept in .*resume"):
        measure(3, 3, [0.0], std=np.ones(16), progress=False, workers=2, run_dir=tmp_path)


@pytest.mark.parametrize(
    ("scores", "expected"),
    [
        # met within 0.02 std, not at 0.1: 2.4 / 0.02 = 120 (not 2.4 / 0.1 = 24)
        ([(0.02, 0.95, 0.995), (0.1, 0.85, 0.994)], "120 times farther apart than 0.02 std"),
        (
            [(0.02, 0.85, 0.995), (0.1, 0.80, 0.99)],
            "more than 120 times farther apart than 0.02 std",
        ),
    ],
)
def test_card_compares_the_data_spacing_with_where_the_goal_is_met(scores, expected) -> None:
    from guidance.nn.card import _ceiling_section

    run = dict(landings=20, neighbours=9, backend="c")
    rows = [
        dict(eps=e, rule="union", precision=p, recall=r, rows_missing=0, rows=1)
        for e, p, r in scores
    ]
    lines: list[str] = []
    _ceiling_section(
        lines.append, dict(run=run, scores=rows, data_spacing_std=2.4, n_train_landings=3008)
    )
    text = "\n".join(lines)
    assert f"The training landings are {expected}:" in text


@pytest.mark.parametrize("where", ["folder", "run dir"])
def test_cli_refuses_a_json_it_could_not_write_before_solving(where, tmp_path, capsys, monkeypatch):
    """--json was written only after every neighbourhood was solved: a folder in its place or
    the run's folder failed at the end. Now exit 2 before any solve."""
    (tmp_path / "taken").mkdir()
    out = {"folder": tmp_path / "taken", "run dir": tmp_path / "run"}[where]

    def no_measure(*args, **kwargs):
        raise AssertionError("measured before the output was checked")

    monkeypatch.setattr(mask_ceiling, "measure", no_measure)
    argv = ["mask-ceiling", "--run-dir", str(tmp_path / "run"), "--json", str(out),
            "--models-dir", str(tmp_path / "models")]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--json" in err and ("is a folder" in err or "is the --run-dir folder" in err), err


def test_baselines_refuse_a_json_they_could_not_write_before_running(tmp_path, capsys) -> None:
    """The baselines' report was checked only when written, after every baseline ran."""
    (tmp_path / "taken").mkdir()
    argv = ["baselines", "--dataset", str(tmp_path / "none.npz"), "--json", str(tmp_path / "taken")]
    assert main(argv) == 2
    assert "--json" in capsys.readouterr().err


# ---- damaged files: exit 2 naming the file, before any solve -------------------------------
@pytest.mark.parametrize(
    "text, card, problem",
    [
        ("{", False, "not valid JSON"),
        ("{}", False, "no 'shipped'"),
        ('{"shipped": {"solution": {}}}', False, "no 'shipped.constraint'"),
        ('{"shipped": {"constraint": {"n_trainval_bases": "x"}}}', False, "is a string"),
        ('{"shipped": {"constraint": {"n_trainval_bases": 0}}}', False, "is 0, not a number"),
        ("{", True, "not valid JSON"),
        ("{}", True, "no 'dataset_header'"),
    ],
)
def test_cli_refuses_a_damaged_metrics_file(text, card, problem, tmp_path, capsys, monkeypatch):
    """metrics.json was read unchecked: JSONDecodeError, KeyError 'shipped'."""

    def no_measure(*args, **kwargs):
        raise AssertionError("measured before metrics.json was checked")

    monkeypatch.setattr(mask_ceiling, "measure", no_measure)
    models = tmp_path / "models"
    models.mkdir()
    (models / "metrics.json").write_text(text)
    out = [] if card else ["--json", str(tmp_path / "m.json")]  # the card is updated without
    argv = ["mask-ceiling", "--run-dir", "", "--models-dir", str(models), *out]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {models / 'metrics.json'}: ") and problem in err
    assert "re-run `guidance export`" in err
    assert sorted(p.name for p in models.iterdir()) == ["metrics.json"]


@pytest.mark.parametrize("text", ["{", "[]"])
def test_cli_refuses_a_damaged_run_record(text, tmp_path, capsys, monkeypatch) -> None:
    """run.json of --run-dir was read unchecked (JSONDecodeError)."""
    monkeypatch.setattr(mask_ceiling, "theta_spread", lambda: np.ones(16))
    run = tmp_path / "run"
    run.mkdir()
    (run / "run.json").write_text(text)
    argv = ["mask-ceiling", "--run-dir", str(run), "--json", str(tmp_path / "m.json"),
            "--landings", "1", "--neighbours", "3", "--eps", "0", "--workers", "1",
            "--train-landings", "5"]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {run / 'run.json'}: not the record of a run of neighbours")
    assert f"delete the folder {run}" in err and not (tmp_path / "m.json").exists()


def test_a_damaged_neighbourhood_file_is_named(tmp_path) -> None:
    """A cut or foreign .npz in the run folder raised numpy's ValueError (pickled data)."""
    path = tmp_path / "eps0_landing0000.npz"
    masks = [np.array([[0, 1], [1, 0]], np.uint8)] * 3
    np.savez(path, *masks)
    found, missing = mask_ceiling._cached_masks(tmp_path, [0.0], 1)
    assert missing == [] and all(np.array_equal(m, masks[0]) for m in found[0.0, 0])
    for content, problem in [
        (lambda f: f.write(b"junk"), "(damaged (not an .npz numpy can read))"),
        (lambda f: np.savez(f, np.array([{"a": 1}], dtype=object)), "(damaged (not an .npz"),
        (lambda f: np.savez(f, np.zeros((2, 3))), "float64 array of shape (2, 3), not 0/1"),
        (lambda f: np.savez(f, np.zeros((2, 3), np.uint8), np.zeros((2, 4), np.uint8)),
         "differ in width"),
    ]:  # fmt: skip
        with open(path, "wb") as f:
            content(f)
        with pytest.raises(InputError) as exc:
            mask_ceiling._cached_masks(tmp_path, [0.0], 1)
        message = str(exc.value)
        assert message.startswith(f"{path}: not a neighbourhood a mask-ceiling run keeps (")
        assert problem in message and "delete it" in message and "pickle" not in message
