"""Dataset pipeline: physical sampling, resumable parallel solving, rotation augmentation."""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import signal
import struct
import time
import zipfile
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

import numpy as np
import pytest

from guidance import dataset_run
from guidance.cli import main
from guidance.dataset import load_dataset, pack, random_dataset
from guidance.dataset_run import (
    RK4_KEY,
    RUN_KEYS,
    done_ids,
    generate,
    read_sample,
    sample_path,
    scvx_solver,
    solve_sample,
    write_sample,
)
from guidance.errors import InputError
from guidance.params import NC, Params, SCvxSettings
from guidance.pool import imap_pool
from guidance.provenance import code_version
from guidance.sampling import (
    N_ROTATIONS,
    ROTATION_DEG,
    SamplingRanges,
    base_scenario,
    rotate_theta,
    scenario_of,
    theta_of,
)
from guidance.scenario import validate
from guidance.symmetry import rotate_scenario


def test_base_samples_are_physical_and_reproducible() -> None:
    ranges = SamplingRanges()
    for i in range(60):
        s, _ = base_scenario(3, i, ranges)
        validate(s)  # glideslope, tilt, rate, roll rate, mass
        t = theta_of(s)
        assert t[1] >= 0 and t[2] >= 0  # positive east / north only
        assert t[10] == 0.0  # no roll rate
        assert 2.0 < t[13] <= 3.0
        assert ranges.glideslope_deg[0] <= t[14] <= ranges.glideslope_deg[1]
        assert abs(np.linalg.norm(t[6:10]) - 1.0) < 1e-12
        np.testing.assert_array_equal(theta_of(scenario_of(t)), t)
    a, _ = base_scenario(3, 7, ranges)
    b, _ = base_scenario(3, 7, ranges)
    assert a == b


def test_rotate_theta_matches_rotate_scenario() -> None:
    s, _ = base_scenario(0, 1, SamplingRanges())
    for deg in ROTATION_DEG:
        psi = math.radians(deg)
        np.testing.assert_allclose(
            rotate_theta(theta_of(s), psi), theta_of(rotate_scenario(s, psi))
        )


# narrow ranges near the default landing: the tiny run's landings are feasible
EASY = SamplingRanges(
    horizontal=(0.5, 2.0), v_up=(-0.5, 0.0), v_horizontal=(-1.0, 0.0), m0=(2.9, 3.0)
)


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory: pytest.TempPathFactory):
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


def die_on_job_1(job):
    """A worker that dies on job 1 as a segfault or the OOM killer would end it."""
    i = job if isinstance(job, int) else job[0]
    if i == 1:
        os.kill(os.getpid(), signal.SIGKILL)
    return i if isinstance(job, int) else {"id": i, "status": "solved"}


def sleep_after_job_0(i: int) -> int:
    if i > 0:
        time.sleep(60)
    return i


def test_a_dead_worker_stops_the_pool_instead_of_hanging(deadline) -> None:
    got = []
    with pytest.raises(BrokenProcessPool):
        for i in imap_pool(die_on_job_1, list(range(8)), 2):
            got.append(i)
    assert 1 not in got


def test_stopping_the_caller_stops_the_pool_now(deadline) -> None:
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        for _ in imap_pool(sleep_after_job_0, list(range(4)), 2):
            raise KeyboardInterrupt  # as Ctrl-C in the loop body
    assert time.monotonic() - t0 < 10  # the 60 s solves in flight were not waited for


def test_cli_reports_a_dead_worker_and_how_to_resume(tmp_path, monkeypatch, capsys, deadline):
    monkeypatch.setattr(dataset_run, "solve_sample", die_on_job_1)
    argv = ["dataset", "--run-dir", str(tmp_path), "--output", str(tmp_path / "d.npz")]
    assert main([*argv, "--n-base", "6", "--workers", "2", "--backend", "c", "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: a worker process died")
    kept = len(done_ids(tmp_path))
    assert f"{kept} of 6 are kept in {tmp_path}; run the same command again to resume" in err


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


def test_resume_by_other_code_warns_and_the_header_lists_every_version(tiny_run, tmp_path, capsys):
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    config = json.loads((run / "run.json").read_text())
    assert config["code_versions"] == [code_version()]
    (run / "run.json").write_text(json.dumps({**config, "code_versions": ["guidance 0.0 old"]}))
    rec = read_sample(sample_path(run, 0))
    write_sample(run, {**rec, "code_version": "guidance 0.0 old"})
    # nothing left to solve: the resume only checks the run
    generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    err = capsys.readouterr().err
    assert "warning:" in err and "guidance 0.0 old" in err and code_version() in err
    config = json.loads((run / "run.json").read_text())
    assert config["code_versions"] == ["guidance 0.0 old", code_version()]
    header = pack(run, tmp_path / "d.npz")
    assert header["code_versions"] == sorted(["guidance 0.0 old", code_version()])


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
    run = _copy_run(tiny_run, tmp_path)
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


# ---- samples record their run; sample ids past six digits; packed files checked whole ------
def _copy_run(tiny_run, tmp_path: Path) -> Path:
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    return run


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
    run = _copy_run(tiny_run, tmp_path)
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
    run = _copy_run(tiny_run, tmp_path)
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
    run = _copy_run(tiny_run, tmp_path)
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
    run = _copy_run(tiny_run, tmp_path)
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


def test_a_sample_damaged_again_keeps_every_set_aside_file(tiny_run, tmp_path, capsys) -> None:
    """A resume renamed a damaged sample to NNNNNN.unreadable, replacing the one set aside by
    an earlier resume: a sample damaged twice lost the first evidence. Each is now kept, under
    the first free name, and the message names the file written."""
    run = _copy_run(tiny_run, tmp_path)
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


def test_pack_stores_sample_ids_as_int64_and_loads_int32_files(tiny_run, tmp_path) -> None:
    """pack stored base_id as int32: an id past 2**31 - 1 wrapped. It is int64 now, and a
    dataset packed before (int32 ids) still loads."""
    run = _copy_run(tiny_run, tmp_path)
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
