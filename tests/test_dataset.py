"""Dataset pipeline: physical sampling, resumable parallel solving, rotation augmentation."""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import time
from concurrent.futures.process import BrokenProcessPool

import numpy as np
import pytest

from guidance import dataset
from guidance.cli import main
from guidance.dataset import (
    N_ROTATIONS,
    ROTATION_DEG,
    RUN_KEYS,
    SamplingRanges,
    base_scenario,
    done_ids,
    generate,
    imap_pool,
    load_dataset,
    pack,
    read_sample,
    rotate_theta,
    sample_path,
    scenario_of,
    scvx_solver,
    theta_of,
    write_sample,
)
from guidance.errors import InputError
from guidance.params import NC, SCvxSettings
from guidance.provenance import code_version
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


def test_a_damaged_sample_is_named_by_pack_and_solved_again_on_resume(tiny_run, tmp_path) -> None:
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    damaged = sample_path(run, 1)
    damaged.write_bytes(damaged.read_bytes()[:100])  # a copy cut short
    with pytest.raises(InputError, match=f"sample file {damaged} is unreadable"):
        pack(run, tmp_path / "d.npz")
    again = generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    assert sum(again.values()) == 1  # id 1 alone
    assert damaged.with_suffix(".unreadable").exists()
    assert pack(run, tmp_path / "d.npz")["n_base"] == 2


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
    monkeypatch.setattr(dataset, "solve_sample", die_on_job_1)
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


def test_cli_prox_u_reaches_the_solves(tmp_path, monkeypatch) -> None:
    """`guidance dataset --prox-u 0` solves with the paper's objective (the data of the
    networks shipped until 23 Nov); the weight is part of the run's settings, so a resume with
    another is refused."""
    import guidance.dataset as dataset

    seen = {}

    def fake_generate(*args, settings=None, **kwargs):
        seen["settings"] = settings
        raise KeyboardInterrupt  # stop before any solve

    monkeypatch.setattr(dataset, "generate", fake_generate)
    out = ["--run-dir", str(tmp_path / "run"), "--output", str(tmp_path / "d.npz")]
    assert main(["dataset", *out, "--prox-u", "0"]) == 130
    assert seen["settings"] == SCvxSettings(prox_u=0.0)
    assert main(["dataset", *out]) == 130
    assert seen["settings"] == SCvxSettings()
    assert "scvx_settings" in RUN_KEYS


def test_constraint_pairs_number_the_iterations_from_one() -> None:
    """The flight code feeds k = 1 at the first SCvx iteration: the pair of mask row j of a
    sample has k = j + 1, and there is one pair per recorded mask."""
    ds = dataset.random_dataset(n_base=2, iters=4)
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
    with pytest.raises(dataset.InputError, match=r"run\.json: not a"):
        dataset.generate(tmp_path, 1, progress=False, workers=1)
    with pytest.raises(dataset.InputError, match=r"run\.json: not a"):
        dataset.pack(tmp_path, tmp_path / "d.npz")
