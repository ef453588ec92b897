"""Files are written whole or not at all, and through symbolic links (guidance/atomic.py)."""

from __future__ import annotations

import json
import threading
from pathlib import Path

import numpy as np
import pytest

from guidance.atomic import atomic_write, write_json_atomic, write_text_atomic
from guidance.catalog import SCENARIOS
from guidance.params import Params
from guidance.plots import landing_figure
from guidance.scvx import SCvxResult, SCvxSolver
from guidance.trajectory_io import read_trajectory, write_trajectory


def test_an_interrupted_write_leaves_the_previous_file_and_no_temporary(tmp_path: Path) -> None:
    path = tmp_path / "run.json"
    path.write_text("old")
    with pytest.raises(KeyboardInterrupt), atomic_write(path) as f:
        f.write(b"half of the n")
        raise KeyboardInterrupt
    assert path.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.json"]


def test_a_symbolic_link_is_written_through(tmp_path: Path) -> None:
    target = tmp_path / "store" / "run.json"
    target.parent.mkdir()
    target.write_text("old")
    link = tmp_path / "run.json"
    link.symlink_to(target)
    write_json_atomic(link, {"a": 1})
    assert link.is_symlink() and link.resolve() == target
    assert json.loads(target.read_text()) == {"a": 1}
    assert sorted(p.name for p in target.parent.iterdir()) == ["run.json"]


def test_a_new_file_appears_only_when_complete(tmp_path: Path) -> None:
    path = tmp_path / "new.txt"
    with atomic_write(path) as f:
        f.write(b"first half, ")
        assert not path.exists()
        f.write(b"second half")
    assert path.read_text() == "first half, second half"
    write_text_atomic(path, "replaced")
    assert path.read_text() == "replaced"


def test_a_trajectory_written_to_a_link_lands_in_its_target(
    tmp_path: Path, default_solved: tuple[SCvxSolver, SCvxResult]
) -> None:
    _, result = default_solved
    target = tmp_path / "archive" / "landing.npz"
    target.parent.mkdir()
    link = tmp_path / "latest.npz"
    link.symlink_to(target)
    write_trajectory(link, result, Params(), SCENARIOS["default"], "scvx", "clarabel")
    assert link.is_symlink()
    assert float(read_trajectory(target)["t_f"]) == result.t_f


@pytest.mark.parametrize(("name", "magic"), [("f.png", b"\x89PNG"), ("f.pdf", b"%PDF")])
def test_a_figure_is_written_in_the_format_its_name_says(
    tmp_path: Path, default_solved: tuple[SCvxSolver, SCvxResult], name: str, magic: bytes
) -> None:
    _, r = default_solved
    landing_figure(r.x, r.u, r.t_f, Params(), tmp_path / name)
    assert (tmp_path / name).read_bytes().startswith(magic)
    assert [p.name for p in tmp_path.iterdir()] == [name]


def test_two_writers_of_one_file_never_share_a_temporary(tmp_path: Path) -> None:
    """Threads (or processes) writing the same file at once: each write lands whole, none
    fails (a shared temporary name made one writer remove the other's file midway)."""
    path, errors = tmp_path / "out.npz", []

    def write(value: float) -> None:
        try:
            for _ in range(30):
                with atomic_write(path) as f:
                    np.savez(f, a=np.full(100_000, value))
        except Exception as exc:  # reported below
            errors.append(exc)

    threads = [threading.Thread(target=write, args=(v,)) for v in (1.0, 2.0)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert len(np.unique(np.load(path)["a"])) == 1
    assert [p.name for p in tmp_path.iterdir()] == ["out.npz"]


def test_a_replaced_file_keeps_its_permissions(tmp_path: Path) -> None:
    """A private (0600) file rewritten through atomic_write became 0644, readable by all (the
    temporary file took the umask's mode); it now keeps the replaced file's mode."""
    import os
    import stat

    path = tmp_path / "private.json"
    path.write_text("{}")
    path.chmod(0o600)
    write_text_atomic(path, '{"a": 1}')
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
    assert path.read_text() == '{"a": 1}'


def test_an_output_through_a_link_into_a_missing_folder_is_checked_and_written(
    tmp_path: Path,
) -> None:
    """--out as a link whose target folder did not exist passed the pre-solve check (made in
    the link's folder) and then failed after the solve (FileNotFoundError, exit 1): the check
    and the writers now work in the target's folder, and the file is written there."""
    from guidance.cli import main

    link = tmp_path / "out.npz"
    target = tmp_path / "not" / "yet" / "there.npz"
    link.symlink_to(target)
    assert main(["solve", "--backend", "c", "--out", str(link)]) == 0
    assert link.is_symlink() and read_trajectory(target)["status"] == "solved"


def test_the_writers_folder_is_made_in_one_place(tmp_path: Path) -> None:
    """atomic_write makes a missing folder (the target's, for a link): the writers no longer
    each make their own."""
    path = tmp_path / "a" / "b" / "c.json"
    write_text_atomic(path, "{}")
    assert path.read_text() == "{}"


def test_a_failed_write_removes_the_folders_it_made_and_only_those(tmp_path: Path) -> None:
    """A write that failed left the folders atomic_write had made for it, empty."""
    kept = tmp_path / "kept"
    kept.mkdir()
    with pytest.raises(RuntimeError), atomic_write(kept / "new" / "deeper" / "f.json") as f:
        f.write(b"{")
        raise RuntimeError("the writer failed")
    assert [p.name for p in tmp_path.iterdir()] == ["kept"]
    assert list(kept.iterdir()) == []


def test_a_made_folder_another_writer_filled_is_kept(tmp_path: Path) -> None:
    """Only empty folders are removed: a file written there meanwhile stays, with its folder."""
    other = tmp_path / "new" / "other.json"
    with pytest.raises(RuntimeError), atomic_write(tmp_path / "new" / "f.json"):
        other.write_text("{}")
        raise RuntimeError("the writer failed")
    assert [p.name for p in other.parent.iterdir()] == ["other.json"]


def _no_solve(*args: object, **kwargs: object) -> None:
    raise AssertionError("the solve ran: the outputs were not checked before it")


@pytest.mark.parametrize(
    ("out", "plot"),
    [
        ("f.png", "f.png"),  # the same name
        ("./f.png", "f.png"),  # the same file by another name
        ("sub/../f.png", "f.png"),
        ("f.npz", "link.png"),  # a link to the trajectory file
        ("fig.png/t.npz", "fig.png"),  # the trajectory inside the figure, to be a file
    ],
)
def test_two_outputs_that_are_one_file_are_refused_before_solving(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    out: str,
    plot: str,
) -> None:
    """--out and --plot naming one file: the figure overwrote the trajectory file, after the
    solve; now exit 2 before solving, nothing written and no folder made."""
    from guidance import cli

    monkeypatch.chdir(tmp_path)
    (tmp_path / "link.png").symlink_to(tmp_path / "f.npz")
    monkeypatch.setattr(cli, "solve", _no_solve)
    assert cli.main(["solve", "--out", out, "--plot", plot]) == 2
    err = capsys.readouterr().err
    assert "error: " in err and "Traceback" not in err
    assert ("would overwrite the other" in err) or ("which is to be a file" in err), err
    assert [p.name for p in tmp_path.iterdir()] == ["link.png"]


def test_a_refused_output_leaves_no_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """--out into new folders with a --plot that is refused: the check made the --out
    folders, and they stayed; the check now makes none."""
    from guidance import cli

    (tmp_path / "fig.png").mkdir()
    monkeypatch.setattr(cli, "solve", _no_solve)
    out = tmp_path / "new" / "sub" / "t.npz"
    assert cli.main(["solve", "--out", str(out), "--plot", str(tmp_path / "fig.png")]) == 2
    assert "is a folder" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]


def test_a_solve_that_writes_nothing_leaves_no_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A solve that stops before its first subproblem (exit 3, nothing written) left the
    output folders the pre-solve check had made."""
    from guidance import cli

    def stopped(*args: object, **kwargs: object) -> SCvxResult:
        nan = float("nan")
        return SCvxResult("solver_error", "stopped", np.zeros((0, 14)), np.zeros((0, 3)), nan,
                          0, 0, 0.0)  # fmt: skip

    monkeypatch.setattr(cli, "solve", stopped)
    out, plot = tmp_path / "a" / "t.npz", tmp_path / "b" / "c" / "f.png"
    assert cli.main(["solve", "--out", str(out), "--plot", str(plot)]) == cli.EXIT_NO_TRAJECTORY
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("out", ["./s.json", "link.json"])
def test_an_output_that_is_the_scenario_file_is_refused_before_solving(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    out: str,
) -> None:
    """`guidance solve s.json --out s.json` wrote the trajectory over the scenario it read;
    now exit 2 before solving, the scenario file as it was (by another name or a link too)."""
    from guidance import cli

    scenario = tmp_path / "s.json"
    text = '{"r0": [4, 4, 0], "v0": [0, -1, -2], "q0": [1, 0, 0, 0], "w0": [0, 0, 0], "m0": 3.0,'
    scenario.write_text(text + ' "glideslope_deg": 20.0, "tilt_max_deg": 90.0}')
    (tmp_path / "link.json").symlink_to(scenario)
    before = scenario.read_bytes()
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli, "solve", _no_solve)
    assert cli.main(["solve", str(scenario), "--out", out]) == 2
    assert "is the scenario file" in capsys.readouterr().err
    assert scenario.read_bytes() == before
