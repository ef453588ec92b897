"""What the command line does with a missing C library, an output name that is not a
trajectory file's, a folder given as a file and a reader that leaves: one `error:` line and
exit 2 (or the shell's 141 for the pipe; 1 for a worker process that died), never a
traceback (CLI review, 26 Nov)."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from c_library import needs_c_library

from guidance import budget, cli, pool
from guidance.cgnc import LIB_PATH
from guidance.pool import WorkerDiedError

ROOT = Path(__file__).resolve().parent.parent


def _guidance(args: list[str], env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "guidance", *args],
        capture_output=True, text=True, cwd=ROOT, env={**os.environ, **(env or {})}, check=False,
    )  # fmt: skip


@pytest.mark.parametrize("backend", ["c", "c-socp"])
def test_a_c_backend_without_the_library_is_one_error_line(backend: str, tmp_path: Path) -> None:
    missing = {"TSCVX_GNC_LIB": str(tmp_path / "no_gnc.so"), "TSCVX_LIB": str(tmp_path / "no.so")}
    out = _guidance(["solve", "--backend", backend], missing)
    assert out.returncode == 2, out.stderr
    assert "Traceback" not in out.stderr
    last = out.stderr.strip().splitlines()[-1]
    assert last.startswith("error: ") and "not found" in last and "run `make lib`" in last


def test_budget_without_its_drivers_says_how_to_build_them(monkeypatch, tmp_path, capsys) -> None:
    monkeypatch.setattr(budget, "DRIVER", tmp_path / "pdg_budget_driver")
    assert cli.main(["budget", "--no-build"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "pdg_budget_driver not found: run `make budget`" in err


def _no_solve(*args: object, **kwargs: object) -> None:
    raise AssertionError("the solve ran: the output was not checked before it")


@pytest.mark.parametrize("name", ["README.md", "t.json", "t"])
def test_an_output_that_is_not_an_npz_name_is_refused_before_solving(
    name: str, tmp_path: Path, monkeypatch, capsys
) -> None:
    """`--out README.md` replaced the README with a zip archive."""
    monkeypatch.setattr(cli, "solve", _no_solve)
    out = tmp_path / name
    assert cli.main(["solve", "--out", str(out)]) == 2
    assert f"--out {out}: a trajectory file's name ends in .npz" in capsys.readouterr().err
    assert not out.exists()


def test_a_folder_given_as_the_guess_is_named_a_folder(tmp_path: Path, capsys) -> None:
    assert cli.main(["solve", "--guess", str(tmp_path)]) == 2
    assert f"--guess {tmp_path}: {tmp_path}: is a folder" in capsys.readouterr().err


@pytest.mark.parametrize("buffered", [False, True])
def test_a_reader_that_leaves_ends_the_command_without_a_traceback(buffered: bool) -> None:
    """`guidance solve | head -1`: a BrokenPipeError traceback; now exit 141, stderr clean.
    Unbuffered, the reader leaves after the first line, while the solve still prints; with
    Python's block buffering (stdout on a pipe), it leaves before anything arrives and the
    output meets the closed pipe when the command flushes it (at exit, it used to end in
    "Exception ignored ... BrokenPipeError" and exit 120)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    if not buffered:
        env["PYTHONUNBUFFERED"] = "1"
    with subprocess.Popen(
        [sys.executable, "-m", "guidance", "solve"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT, env=env,
    ) as p:  # fmt: skip
        assert p.stdout is not None and p.stderr is not None
        if not buffered:
            assert p.stdout.readline().startswith("scenario:")
        p.stdout.close()
        err = p.stderr.read()
    assert p.returncode == cli.EXIT_BROKEN_PIPE, err
    assert err == ""


def test_version_names_the_package_and_commit(capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        cli.main(["--version"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("guidance ") and " git " in out


def test_a_models_folder_that_does_not_exist_is_refused_before_anything_is_printed(
    tmp_path: Path, capsys
) -> None:
    assert cli.main(["solve", "--method", "tscvx", "--models", str(tmp_path / "none")]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert f"error: --models {tmp_path / 'none'}: no such folder" in captured.err


@pytest.mark.parametrize("roll_free", [True, False, None])
def test_pinning_the_attitude_over_a_roll_free_file_is_said(
    roll_free: bool | None, tmp_path: Path, capsys
) -> None:
    """--pin-final-attitude overrides a file's explicit "final_roll_free": true, and says so
    (it did so silently); a file that says false or nothing needs no note."""
    import json

    from guidance.scenario import scenario_to_dict

    data = scenario_to_dict(cli.Scenario())
    data.pop("final_roll_free", None)
    if roll_free is not None:
        data["final_roll_free"] = roll_free
    path = tmp_path / "landing.json"
    path.write_text(json.dumps(data))
    scenario = cli._load(str(path), pin_final_attitude=True)
    assert scenario.params.final_roll_free is False
    err = capsys.readouterr().err
    said = f'note: --pin-final-attitude overrides {path}\'s "final_roll_free": true'
    assert (said in err) == (roll_free is True), err


def test_pinning_the_attitude_reads_the_scenario_file_once(tmp_path: Path, monkeypatch) -> None:
    """A scenario given as a pipe (`<(cat s.json)`) can be read once: a second read for the
    note found it empty and ended in a JSONDecodeError traceback."""
    import json
    import pathlib

    from guidance.scenario import scenario_to_dict

    path = tmp_path / "landing.json"
    path.write_text(json.dumps({**scenario_to_dict(cli.Scenario()), "final_roll_free": True}))
    reads = []
    real = pathlib.Path.read_text

    def counted(self: pathlib.Path, *args: object, **kwargs: object) -> str:
        reads.append(self)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(pathlib.Path, "read_text", counted)
    assert cli._load(str(path), pin_final_attitude=True).params.final_roll_free is False
    assert reads == [path]


@pytest.mark.parametrize("command", ["agreement", "dispersion", "dataset", "mask-ceiling"])
def test_workers_means_the_same_in_every_command(command: str) -> None:
    """--workers counts processes, 0 (the default) every core, in each command that solves in
    parallel (agreement and dispersion refused 0 while dataset and mask-ceiling read it as
    every core)."""
    from guidance.argtypes import worker_count

    ap = cli.build_parser()
    assert ap.parse_args([command]).workers == 0
    assert ap.parse_args([command, "--workers", "0"]).workers == 0
    assert ap.parse_args([command, "--workers", "3"]).workers == 3
    with pytest.raises(SystemExit):
        ap.parse_args([command, "--workers", "-1"])
    assert worker_count(0) == (os.cpu_count() or 1) and worker_count(3) == 3


def _worker_dies(run: Path) -> Callable[..., None]:
    def solve(*args: object, **kwargs: object) -> None:
        raise pool.worker_died(2, 6, run)  # as pool_results raises it for a dead worker

    return solve


# (the step whose pool loses a worker, the command after its run folder)
DEAD_WORKER: dict[str, tuple[tuple[str, str], Callable[[Path], list[str]]]] = {
    "dataset": (
        ("guidance.dataset_run", "generate"),
        lambda run: ["dataset", "--run-dir", str(run), "--output", f"{run}.npz"],
    ),
    "mask-ceiling": (
        ("guidance.mask_ceiling", "measure"),
        lambda run: [
            "mask-ceiling",
            "--run-dir",
            str(run),
            "--json",
            f"{run}.json",
            "--models-dir",
            f"{run}.models",
        ],
    ),
    "dispersion": (
        ("guidance.dispersion", "_solve"),
        lambda run: ["dispersion", "--landings", "6", "--run-dir", str(run)],
    ),
    "agreement": (
        ("guidance.agreement", "_solve"),
        lambda run: ["agreement", "--catalog", "default", "--landings", "5", "--run-dir", str(run)],
    ),
}


@pytest.mark.parametrize("command", list(DEAD_WORKER))
def test_a_dead_worker_is_one_error_line_saying_what_is_kept(
    command: str, tmp_path: Path, monkeypatch, capsys
) -> None:
    """Each resumable command: exit 1 and pool.worker_died's line, what is kept and how to go
    on (guidance.cli.main says it for all four; each used to catch it itself)."""
    (module, name), argv = DEAD_WORKER[command]
    if command in ("dispersion", "agreement") and not LIB_PATH.exists():
        pytest.skip("libtscvx_gnc.so not built")
    run = tmp_path / "run"
    monkeypatch.setattr(importlib.import_module(module), name, _worker_dies(run))
    assert cli.main(argv(run)) == 1
    out, err = capsys.readouterr()
    assert err == (
        "error: a worker process died (killed by a signal: a crash in the solver or out of "
        f"memory); 2 of 6 are kept in {run}; run the same command again to resume\n"
    )
    assert "solved this run" not in out and "wrote" not in out


def test_main_reports_a_dead_worker_of_any_command(tmp_path: Path, monkeypatch, capsys) -> None:
    """The one place a dead worker is reported: guidance.cli.main, whatever the command (a
    command that did not catch WorkerDiedError itself ended in a traceback)."""
    monkeypatch.setattr(cli, "cmd_solve", _worker_dies(tmp_path))
    assert cli.main(["solve"]) == 1
    assert capsys.readouterr().err.startswith("error: a worker process died")


@needs_c_library
def test_dispersion_run_raises_a_dead_worker_for_its_caller(tmp_path: Path, monkeypatch) -> None:
    """dispersion.run leaves a dead worker to its caller, as mask_ceiling.measure and
    dataset_run.generate do (it printed the error itself and returned 1)."""
    from guidance import dispersion

    monkeypatch.setattr(dispersion, "_solve", _worker_dies(tmp_path))
    args = cli.build_parser().parse_args(["dispersion", "--landings", "6"])
    with pytest.raises(WorkerDiedError, match=r"2 of 6 are kept in .*run the same command"):
        dispersion.run(args)
