"""guidance.dataset_run: the base samples solved into a run folder, resumed without redoing
samples; damaged samples, samples of another run and run records refused by name or set
aside and solved again; sample ids past six digits."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest
from dataset_runs import EASY, copy_run

from guidance.cli import main
from guidance.dataset import load_dataset, pack
from guidance.dataset_run import (
    RK4_KEY,
    RUN_KEYS,
    done_ids,
    generate,
    read_sample,
    sample_path,
    solve_sample,
    write_sample,
)
from guidance.errors import InputError
from guidance.params import Params
from guidance.provenance import code_version
from guidance.sampling import base_scenario, theta_of


def test_generation_resumes_without_redoing_samples(tiny_run) -> None:
    run, first, second, _, _ = tiny_run
    assert sum(first.values()) == 1
    assert sum(second.values()) == 1
    assert done_ids(run) == {0, 1}
    assert sample_path(run, 1).exists()
    with pytest.raises(InputError, match=r"different seed \(11, not 12\)"):
        generate(run, 2, seed=12, ranges=EASY, workers=1, progress=False, backend="clarabel")
    with pytest.raises(InputError, match=r"different backend \('clarabel', not 'c'\)"):
        generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="c")


@pytest.mark.parametrize(
    "damage",
    [
        lambda data: data[:100],  # a copy cut short: zipfile's "File is not a zip file"
        lambda data: b"junk " + data,  # no .npz: numpy's "contains pickled (object) data"
        lambda data: b"",  # an empty file: numpy's "No data left in file"
    ],
    ids=["cut short", "junk", "empty"],
)
def test_a_damaged_sample_is_named_by_pack_and_solved_again_on_resume(
    damage, tiny_run, tmp_path, capsys
) -> None:
    """`guidance dataset --pack-only` named the file but passed on numpy's reason, which for
    most damage tells of pickled data and allow_pickle, and said to rerun "with the same
    settings" (--pack-only again fails again). It now says the file is damaged and that a
    run without --pack-only sets it aside and solves its sample again, which it does."""
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    damaged = sample_path(run, 1)
    damaged.write_bytes(damage(damaged.read_bytes()))
    argv = ["dataset", "--pack-only", "--run-dir", str(run), "--output", str(tmp_path / "d.npz")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: sample file {damaged} is damaged (not an .npz numpy can read)")
    assert "without --pack-only, which sets the file aside (as .unreadable)" in err
    assert "pickle" not in err.lower() and len(err.splitlines()) == 1, err
    again = generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    assert sum(again.values()) == 1  # id 1 alone
    assert damaged.with_suffix(".unreadable").exists()
    assert pack(run, tmp_path / "d.npz")["n_base"] == 2


def test_a_sample_the_system_cannot_read_is_not_called_damaged(tiny_run, tmp_path) -> None:
    """An error of the system (here a folder where the file should be) is said as the system
    says it, not as damage."""
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    path = sample_path(run, 1)
    path.unlink()
    path.mkdir()
    with pytest.raises(InputError, match=rf"sample file {path} is unreadable \(Is a directory\):"):
        pack(run, tmp_path / "d.npz")


@pytest.mark.parametrize("misfit", ["another N", "no masks", "another id"])
def test_a_sample_that_does_not_fit_the_run_is_named_and_solved_again(
    misfit: str, tiny_run, tmp_path
) -> None:
    """A readable sample of another run (another N), one without masks, or one whose id is
    not its file's counted as done: resume kept it and pack crashed with numpy's broadcast
    error or a KeyError, naming no file. pack now names it, and resume solves it again."""
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    path = sample_path(run, 1)
    rec = dict(np.load(path, allow_pickle=False))
    if misfit == "another N":
        rec["x"], rec["u"] = rec["x"][:10], rec["u"][:10]
    elif misfit == "no masks":
        del rec["masks"]
    else:
        rec["id"] = np.asarray(7)
    np.savez(path, **rec)
    with pytest.raises(InputError, match=f"sample file {path} does not fit this run"):
        pack(run, tmp_path / "d.npz")
    again = generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    assert sum(again.values()) == 1  # id 1 alone
    assert pack(run, tmp_path / "d.npz")["n_base"] == 2


def test_cli_refuses_a_resume_with_other_options(tiny_run, tmp_path, capsys) -> None:
    argv = ["dataset", "--run-dir", str(tiny_run[0]), "--output", str(tmp_path / "d.npz")]
    assert main([*argv, "--n-base", "60", "--seed", "1", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "different seed (11, not 1)" in err


def test_a_run_recorded_before_a_setting_existed_resumes_with_its_default(
    tiny_run, tmp_path
) -> None:
    """A run whose run.json and samples record the settings without socp_max_iter_total
    (added on 26 Nov with a default that keeps the older code's behaviour) resumes, its
    samples kept; one recorded with another value of a setting is still refused."""
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    config = json.loads((run / "run.json").read_text())
    del config["scvx_settings"]["socp_max_iter_total"]
    (run / "run.json").write_text(json.dumps(config))
    rec = read_sample(sample_path(run, 0))
    recorded = json.loads(str(rec["run"]))
    del recorded["scvx_settings"]["socp_max_iter_total"]
    write_sample(run, {**rec, "run": json.dumps(recorded, sort_keys=True)})
    sample_path(run, 1).unlink()  # solved again by this code, recording the new setting
    solved = generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    assert sum(solved.values()) == 1  # sample 0 kept, sample 1 solved
    assert done_ids(run) == {0, 1}
    assert (
        "socp_max_iter_total"
        in json.loads(str(read_sample(sample_path(run, 1))["run"]))["scvx_settings"]
    )
    assert pack(run, tmp_path / "d.npz")["n_base"] == 2  # the old and the new sample pack
    # a setting whose default is not what the older code did is still a different run
    for key, value in (("socp_max_iter", 199), ("prox_u", None)):
        changed = json.loads(json.dumps(config))
        if value is None:
            del changed["scvx_settings"][key]  # prox_u's default is not the paper's 0
        else:
            changed["scvx_settings"][key] = value
        (run / "run.json").write_text(json.dumps(changed))
        with pytest.raises(InputError, match="different scvx_settings"):
            generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")


def test_a_run_recorded_before_the_rk4_rule_resumes_only_where_the_steps_agree(
    tiny_run, tmp_path
) -> None:
    """Runs recorded before 27 Nov carry no rk4_steps_per_interval and took rk4_substeps
    steps on every grid. At N = 50 that is today's rule: the run resumes and its samples
    pack. On a coarser grid the steps now differ (6 at N = 20): its resume is refused, as
    its old samples and new ones would have been solved on different discretizations."""
    run = copy_run(tiny_run, tmp_path)
    config = json.loads((run / "run.json").read_text())
    assert config[RK4_KEY] == 2
    del config[RK4_KEY]
    config["code_versions"] = ["0.1.0 (before the rk4 rule)"]  # so that the resume records
    (run / "run.json").write_text(json.dumps(config))
    rec = read_sample(sample_path(run, 0))
    recorded = json.loads(str(rec["run"]))
    del recorded[RK4_KEY]
    write_sample(run, {**rec, "run": json.dumps(recorded, sort_keys=True)})
    solved = generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    assert sum(solved.values()) == 0  # both kept
    assert pack(run, tmp_path / "d.npz")[RK4_KEY] == 2
    # the resume adds its code version, not the inferred steps as if recorded
    resumed = json.loads((run / "run.json").read_text())
    assert len(resumed["code_versions"]) == 2 and RK4_KEY not in resumed
    coarse = tmp_path / "coarse"
    kw = dict(seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    generate(coarse, 0, params=Params(N=20), **kw)
    config = json.loads((coarse / "run.json").read_text())
    assert config[RK4_KEY] == 6
    del config[RK4_KEY]
    (coarse / "run.json").write_text(json.dumps(config))
    with pytest.raises(InputError, match=f"different {RK4_KEY} \\(2, not 6\\)"):
        generate(coarse, 0, params=Params(N=20), **kw)


@pytest.mark.parametrize("record", ["{not json", "[1, 2]", '{"seed": 0}'])
def test_a_damaged_run_record_is_refused_by_name(record: str, tmp_path) -> None:
    """A run.json that is not JSON, not an object or missing keys raised JSONDecodeError,
    AttributeError or KeyError on resume and on --pack-only (a traceback); both now refuse
    the run directory by naming the file (exit 2 from the CLI)."""
    (tmp_path / "samples").mkdir()
    (tmp_path / "run.json").write_text(record)
    with pytest.raises(InputError, match=r"run\.json: not a"):
        generate(tmp_path, 1, progress=False, workers=1)
    with pytest.raises(InputError, match=r"run\.json: not a"):
        pack(tmp_path, tmp_path / "d.npz")


def _another_run(config: dict, key: str) -> dict:
    """run.json as a run differing from ``config`` in ``key`` alone would have it."""
    other = {
        "seed": 12,
        "ranges": {**config["ranges"], "m0": [2.8, 3.0]},
        "params": {**config["params"], "T_max": 4.5},
        "scvx_settings": {**config["scvx_settings"], "prox_u": 0.0},
        "backend": "c",
        RK4_KEY: 6,  # the rule of a coarser grid, or another code's
    }
    return {**config, key: other[key]}


@pytest.mark.parametrize("key", RUN_KEYS)
def test_pack_refuses_samples_of_another_run(key: str, tiny_run, tmp_path) -> None:
    """With run.json replaced by another run's, pack wrote the samples under the other run's
    seed, ranges, ... without a word. Each sample now records its run: pack names it."""
    run = copy_run(tiny_run, tmp_path)
    config = json.loads((run / "run.json").read_text())
    (run / "run.json").write_text(json.dumps(_another_run(config, key)))
    path = re.escape(str(sample_path(run, 0)))
    with pytest.raises(
        InputError, match=rf"sample file {path} does not fit this run .*another {key}"
    ):
        pack(run, tmp_path / "d.npz")
    assert not (tmp_path / "d.npz").exists()


def test_a_resume_without_run_json_sets_aside_samples_of_another_seed(
    tiny_run, tmp_path, capsys
) -> None:
    """run.json lost, the run resumed with another seed: the seed-11 samples were kept as
    seed 12's (nothing solved, a mixed dataset). They are now set aside and solved again."""
    run = copy_run(tiny_run, tmp_path)
    (run / "run.json").unlink()
    again = generate(run, 1, seed=12, ranges=EASY, workers=1, progress=False, backend="clarabel")
    assert sum(again.values()) == 1  # id 0, for seed 12
    assert "another seed (seed 11, not 12)" in capsys.readouterr().err
    for i in (0, 1):
        assert sample_path(run, i).with_suffix(".unreadable").exists()
    assert done_ids(run) == {0}
    header = pack(run, tmp_path / "d.npz")
    assert header["seed"] == 12 and header["n_base"] == 1
    theta = load_dataset(tmp_path / "d.npz").theta[0]  # rotation 0 of base sample 0
    np.testing.assert_allclose(theta, theta_of(base_scenario(12, 0, EASY)[0]), rtol=1e-12)


def test_samples_that_record_no_run_are_checked_by_their_theta(tiny_run, tmp_path) -> None:
    """Samples written before samples recorded their run: a resume of their own run keeps
    them (an upgrade mid-run loses no solve), as their theta is the run's draw; with another
    seed or ranges in run.json, their theta is not, and pack names them."""
    run = copy_run(tiny_run, tmp_path)
    for i in (0, 1):
        rec = read_sample(sample_path(run, i))
        rec.pop("run", None)
        np.savez(sample_path(run, i), **rec)
    kept = generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    assert kept == {} and done_ids(run) == {0, 1}
    assert pack(run, tmp_path / "d.npz")["n_base"] == 2
    config = json.loads((run / "run.json").read_text())
    for key in ("seed", "ranges"):
        (run / "run.json").write_text(json.dumps(_another_run(config, key)))
        path = re.escape(str(sample_path(run, 0)))
        with pytest.raises(InputError, match=rf"{path} does not fit .*theta is not draw 0"):
            pack(run, tmp_path / "d.npz")


def test_sample_ids_past_999999_are_found_resumed_and_packed(tiny_run, tmp_path) -> None:
    """Sample 1,000,000 is named 1000000.npz; the 6-digit glob of done_ids missed it, so a
    resume solved it again and pack left it out."""
    run = copy_run(tiny_run, tmp_path)
    config = json.loads((run / "run.json").read_text())
    i = 1_000_000
    job = (i, 11, config["ranges"], config["params"], config["scvx_settings"], "clarabel")
    recorded = {k: v for k, v in read_sample(sample_path(run, 0)).items() if k == "run"}
    write_sample(run, {**solve_sample(job), "code_version": code_version(), **recorded})
    assert sample_path(run, i).name == "1000000.npz"
    for name in ("0000002.npz", "12.npz", ".1000001.npz.tmp", "1000003.unreadable"):
        (run / "samples" / name).write_bytes(b"")  # not names of sample files: not counted
    assert done_ids(run) == {0, 1, i}
    resumed = generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    assert resumed == {} and sample_path(run, i).exists()  # fits the run: not set aside
    assert pack(run, tmp_path / "d.npz")["n_base"] == 3
    ds = load_dataset(tmp_path / "d.npz")
    assert sorted(set(ds.base_id.tolist())) == [0, 1, i]
    first = np.flatnonzero((ds.base_id == i) & (ds.rotation == 0))[0]
    np.testing.assert_allclose(ds.theta[first], theta_of(base_scenario(11, i, EASY)[0]))
    assert pack(run, tmp_path / "d2.npz", n_base=2)["n_base"] == 2


def test_a_sample_damaged_again_keeps_every_set_aside_file(tiny_run, tmp_path, capsys) -> None:
    """A resume renamed a damaged sample to NNNNNN.unreadable, replacing the one set aside by
    an earlier resume: a sample damaged twice lost the first evidence. Each is now kept, under
    the first free name, and the message names the file written."""
    run = copy_run(tiny_run, tmp_path)
    config = json.loads((run / "run.json").read_text())
    damaged = sample_path(run, 1)
    first = damaged.with_suffix(".unreadable")
    names = [first, first.with_name(f"{first.name}.1"), first.with_name(f"{first.name}.2")]
    for n, aside in enumerate(names):
        damaged.write_bytes(f"damage {n}".encode())
        assert done_ids(run, set_aside_unreadable=True, run=config) == {0}
        assert f"set aside as {aside}, solved again" in capsys.readouterr().err
    for n, aside in enumerate(names):
        assert aside.read_bytes() == f"damage {n}".encode()
    assert not damaged.exists()
