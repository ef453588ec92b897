"""guidance.pool: a dead worker stops the pool (and the dataset command says what is kept),
and stopping the caller stops the workers at once."""

from __future__ import annotations

import os
import signal
import time
from concurrent.futures.process import BrokenProcessPool

import pytest

from guidance import dataset_run
from guidance.cli import main
from guidance.dataset_run import done_ids
from guidance.pool import imap_pool


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
