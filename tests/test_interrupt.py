"""Ctrl-C at any point of the resumable commands (dataset, dispersion, agreement,
mask-ceiling) exits 130 with one line saying what is kept and how to go on, never a
traceback: before their worker pool (drawing the landings, checking the options), after it
(packing), and while its workers start. Until 28 Nov only an interruption inside the pool
was handled; one elsewhere escaped guidance's main as a traceback."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from c_library import needs_c_library

from guidance import atomic, bench_tscvx, cli, dataset, mask_ceiling
from guidance.cguidance import LIB_PATH

ROOT = Path(__file__).resolve().parent.parent


def _ctrl_c(*args: object, **kwargs: object) -> None:
    raise KeyboardInterrupt  # as Ctrl-C in the step this replaces


def _main(argv: list[str]) -> int:
    try:
        return cli.main(argv)
    except KeyboardInterrupt:
        pytest.fail("KeyboardInterrupt escaped guidance's main: a traceback, not exit 130")


DATASET_KEPT = "solved samples are kept in {run}; run the same command again to resume"
# (the step Ctrl-C stops, the command after its run folder, the line it prints)
CASES: dict[str, tuple[tuple[object, str], Callable[[str], list[str]], str]] = {
    "dataset, checking its options": (
        (atomic, "check_outputs"),
        lambda run: ["dataset", "--run-dir", run, "--output", run + ".npz"],
        DATASET_KEPT,
    ),
    "dataset, packing": (
        (dataset, "pack"),
        lambda run: ["dataset", "--pack-only", "--run-dir", run, "--output", run + ".npz"],
        DATASET_KEPT,
    ),
    "mask-ceiling, drawing the landings": (
        (mask_ceiling, "theta_spread"),
        lambda run: ["mask-ceiling", "--run-dir", run, "--json", run + ".json"],
        "solved neighbourhoods are kept in {run}; run the same command again to resume",
    ),
    "mask-ceiling without a run folder": (
        (mask_ceiling, "theta_spread"),
        lambda run: ["mask-ceiling", "--run-dir", "", "--json", run + ".json"],
        "nothing is kept without a --run-dir",
    ),
    "dispersion, drawing the landings": (
        (bench_tscvx, "sample_landings"),
        lambda run: ["dispersion", "--landings", "6", "--run-dir", run],
        "0 of 6 landings are kept in {run}; to resume: guidance dispersion --landings 6 ",
    ),
    "dispersion without a run folder": (
        (bench_tscvx, "sample_landings"),
        lambda run: ["dispersion", "--landings", "6"],
        "nothing is kept without --run-dir (with --run-dir DIR each landing is kept as it "
        "finishes, and the same command resumes)",
    ),
    "agreement, drawing the landings": (
        (bench_tscvx, "sample_landings"),
        lambda run: ["agreement", "--landings", "2", "--run-dir", run],
        "the landings finished are kept in {run}; run the same command again to resume",
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_ctrl_c_outside_the_pool_exits_130_with_one_line(
    case: str, tmp_path: Path, monkeypatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (module, name), argv, said = CASES[case]
    if argv("")[0] in ("dispersion", "agreement") and not LIB_PATH.exists():
        pytest.skip("libtscvx_gnc.so not built")
    monkeypatch.setattr(module, name, _ctrl_c)
    run = str(tmp_path / "run")
    assert _main(argv(run)) == 130
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("\ninterrupted: ") and len(err.strip().splitlines()) == 1, err
    assert said.format(run=run) in err, err


@needs_c_library
def test_a_real_ctrl_c_while_the_landings_are_drawn(tmp_path: Path) -> None:
    """SIGINT to the process group, as a terminal sends it, while dispersion draws its
    landings (held there until the test has signalled): exit 130, the line, no traceback."""
    ready, run = tmp_path / "drawing", tmp_path / "run"
    script = tmp_path / "slow_draws.py"
    script.write_text(
        "import sys, time\n"
        "from pathlib import Path\n"
        "from guidance import bench_tscvx\n"
        "def drawing(*args, **kwargs):\n"
        f"    Path({str(ready)!r}).touch()\n"
        "    time.sleep(60)\n"
        "bench_tscvx.sample_landings = drawing\n"
        "from guidance.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    proc = _start([str(script), "dispersion", "--landings", "6", "--run-dir", str(run)])
    out, err = _interrupt_when(proc, ready)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and out == ""
    assert f"interrupted: 0 of 6 landings are kept in {run}; to resume: " in err


def test_a_worker_still_starting_survives_ctrl_c(tmp_path: Path) -> None:
    """Ctrl-C reaches every process of the group. A worker ignores it once started
    (pool._worker_init), but one still starting (held there: spawn runs the parent's script
    in each worker before the initializer) died of it with a KeyboardInterrupt traceback, and
    the pool with BrokenProcessPool. Here SIGINT reaches such a worker alone: the pool must
    go on as if nothing happened."""
    script = tmp_path / "pool.py"
    script.write_text(
        "import os, sys, time\n"
        "from pathlib import Path\n"
        "if __name__ == '__mp_main__':  # a worker starting, before pool._worker_init\n"
        f"    Path({str(tmp_path)!r}, f'worker{{os.getpid()}}').touch()\n"
        "    time.sleep(2)\n"
        "if __name__ == '__main__':\n"
        "    from guidance.pool import imap_pool\n"
        "    print(sum(imap_pool(abs, [1, 2, 3, 4], 2)))\n"
    )
    proc = _start([str(script)])
    t0 = time.monotonic()
    while not (started := list(tmp_path.glob("worker*"))) and proc.poll() is None:
        assert time.monotonic() - t0 < 120, "no worker started"
        time.sleep(0.01)
    assert proc.poll() is None, proc.communicate()[1]
    os.kill(int(started[0].name.removeprefix("worker")), signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert proc.returncode == 0 and out == "10\n", err


@pytest.mark.parametrize(
    ("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["Ctrl-C", "SIGTERM"]
)
def test_a_signal_while_guidance_starts_ends_it_quietly(
    signum: int, code: int, tmp_path: Path
) -> None:
    """Ctrl-C (SIGINT to the process group, as a terminal sends it) or SIGTERM while the
    `guidance` console script imports its command line (about a second, held here): one
    `interrupted` line and exit 130 or 143, as anywhere in a command. The script imported
    guidance.cli itself: a KeyboardInterrupt traceback, or death by SIGTERM, before 29 Nov."""
    pyproject = (ROOT / "pyproject.toml").read_text()
    entry = re.search(r'^guidance = "([\w.]+):(\w+)"$', pyproject, re.MULTILINE)
    assert entry is not None, "no guidance entry in [project.scripts]"
    module, func = entry.groups()
    ready = tmp_path / "importing"
    script = tmp_path / "guidance_script.py"
    script.write_text(
        "import sys, time\n"
        "from pathlib import Path\n"
        "class Held:  # the import of guidance.cli, held as if it were slow\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'guidance.cli':\n"
        f"            Path({str(ready)!r}).touch()\n"
        "            time.sleep(60)\n"
        "        return None\n"
        "sys.meta_path.insert(0, Held())\n"
        f"from {module} import {func}  # what pip's console script does\n"
        f"sys.exit({func}())\n"
    )
    proc = _start([str(script), "scenario"])
    out, err = _interrupt_when(proc, ready, signum)
    assert proc.returncode == code, err
    assert out == "" and err == "\ninterrupted\n"


def _start(argv: list[str]) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, *argv],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own group, signalled as a terminal's Ctrl-C is
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # as in a terminal
    )


def _interrupt_when(
    proc: subprocess.Popen[str],
    ready: Path,
    signum: int = signal.SIGINT,
    send: Callable[[int, int], None] = os.killpg,
) -> tuple[str, str]:
    """``signum`` to ``proc``'s group (``send=os.kill``: to it alone) once ``ready`` exists;
    its stdout and stderr."""
    t0 = time.monotonic()
    while not ready.exists() and proc.poll() is None:
        assert time.monotonic() - t0 < 120, "never got there"
        time.sleep(0.01)
    assert proc.poll() is None, proc.communicate()[1]
    send(proc.pid, signum)
    return proc.communicate(timeout=60)


def _holding(tmp_path: Path, module: str, name: str, ready: Path) -> Path:
    """A script running `guidance` (its argv) with ``module.name`` held for 60 s after it
    touches ``ready`` (in the worker processes too, which import the script)."""
    script = tmp_path / "held.py"
    script.write_text(
        "import os, sys, time\n"
        "from pathlib import Path\n"
        "def held(*args, **kwargs):\n"
        f"    Path({str(tmp_path)!r}, f'solving{{os.getpid()}}.pid').touch()\n"
        f"    Path({str(ready)!r}).touch()\n"
        "    time.sleep(60)\n"
        "if __name__ == '__main__':\n"
        f"    import {module}\n"
        f"    {module}.{name} = held\n"
        "    from guidance.cli import main\n"
        "    sys.exit(main(sys.argv[1:]))\n"
    )
    return script


def test_a_real_sigterm_stops_a_command_as_ctrl_c_does(tmp_path: Path) -> None:
    """SIGTERM (a job killed) to `guidance dataset` while it checks its options, outside any
    worker pool: the one `interrupted:` line Ctrl-C prints and exit 143 = 128 + 15. Until 29
    Nov only a worker pool caught SIGTERM: here the process died of it, silently."""
    ready, run = tmp_path / "checking", tmp_path / "run"
    script = _holding(tmp_path, "guidance.atomic", "check_outputs", ready)
    proc = _start([str(script), "dataset", "--run-dir", str(run), "--output", f"{run}.npz"])
    out, err = _interrupt_when(proc, ready, signal.SIGTERM, os.kill)
    assert proc.returncode == 143, err  # cli.EXIT_TERMINATED
    assert "Traceback" not in err and out == ""
    assert err == f"\ninterrupted: {DATASET_KEPT.format(run=run)}\n"


@pytest.mark.parametrize("to", ["the group", "the command alone"])
def test_a_real_sigterm_while_workers_solve_stops_them_and_exits_143(
    to: str, tmp_path: Path
) -> None:
    """SIGTERM to the whole process group (as a batch system ends a job) or to the command
    alone (`kill PID`) while two worker processes solve: the workers end (killed by the
    signal, or stopped by the command), it says what is kept, exit 143 (the pool's own
    SIGTERM handler raised a plain KeyboardInterrupt: exit 130, as for Ctrl-C)."""
    ready, run = tmp_path / "solving", tmp_path / "run"
    script = _holding(tmp_path, "guidance.dataset_run", "solve_sample", ready)
    argv = ["dataset", "--run-dir", str(run), "--output", f"{run}.npz", "--n-base", "4"]
    proc = _start([str(script), *argv, "--workers", "2", "--no-progress"])
    send = os.killpg if to == "the group" else os.kill
    out, err = _interrupt_when(proc, ready, signal.SIGTERM, send)
    assert proc.returncode == 143, err
    assert "Traceback" not in err and out == ""
    assert err.endswith(f"\ninterrupted: {DATASET_KEPT.format(run=run)}\n")
    workers = [int(p.stem.removeprefix("solving")) for p in tmp_path.glob("solving*.pid")]
    assert workers and not any(_running(pid) for pid in workers)


def _running(pid: int) -> bool:
    """Whether process ``pid`` still runs (not gone, nor a zombie)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1][0] != "Z"
    except (FileNotFoundError, ProcessLookupError):
        return False
