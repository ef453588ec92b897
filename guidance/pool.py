"""The worker pool of the resumable runs (dataset, dispersion, agreement, mask-ceiling):
jobs solved in single-threaded worker processes, each result handed to the caller as it
finishes so that it is kept at once; Ctrl-C or SIGTERM stops the workers now, and a worker
killed by a signal stops the run with WorkerDiedError saying what is kept."""

from __future__ import annotations

import itertools
import os
import signal
from collections.abc import Callable, Generator, Iterator, Sequence
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from guidance.errors import WorkerDiedError
from guidance.interrupts import sigterm_as_interrupt


def limit_threads() -> None:
    """One thread per process for the numerical libraries (set before they start)."""
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "RAYON_NUM_THREADS"):
        os.environ[var] = "1"


def worker_died(kept: int, total: int, run_dir: Path | None) -> WorkerDiedError:
    """The error of a run stopped by a dead worker: what is kept and how to go on."""
    where = (
        f"{kept} of {total} are kept in {run_dir}; run the same command again to resume"
        if run_dir is not None
        else "nothing is kept without a run directory"
    )
    return WorkerDiedError(
        "a worker process died (killed by a signal: a crash in the solver or out of memory); "
        + where
    )


def imap_pool(fn: Callable[[Any], Any], jobs: Sequence, workers: int) -> Generator[Any, None, None]:
    """fn over jobs in a pool of single-threaded worker processes, results as they finish (in
    this process when workers <= 1). An exception in the caller (Ctrl-C) stops the pool;
    results already yielded are the caller's to keep. A worker killed by a signal (a crash in
    a C solver, out of memory) raises BrokenProcessPool once the results finished before it
    are yielded."""
    if workers <= 1 or len(jobs) <= 1:
        yield from map(fn, jobs)
        return
    import multiprocessing as mp
    from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait

    ctx = mp.get_context("spawn")  # CasADi/Clarabel state is not fork-safe
    pool = ProcessPoolExecutor(workers, mp_context=ctx, initializer=_worker_init)
    todo = iter(jobs)
    running: set[Future] = set()

    def submit(n: int) -> None:
        for job in itertools.islice(todo, n):
            running.add(pool.submit(fn, job))

    try:
        with _ctrl_c_held():  # the workers start here, on the first submits
            submit(2 * workers)  # a few queued per worker, not every job at once
        while running:
            done, running = wait(running, return_when=FIRST_COMPLETED)
            submit(len(done))
            failed = [f for f in done if f.exception() is not None]
            for f in done:
                if f.exception() is None:
                    yield f.result()
            if failed:
                raise failed[0].exception()  # type: ignore[misc]
    except BaseException:
        _stop(pool)
        raise
    pool.shutdown()


@contextmanager
def pool_results(
    fn: Callable[[Any], Any],
    jobs: Sequence,
    workers: int,
    kept: Callable[[], int],
    total: int,
    run_dir: Path | None,
) -> Iterator[Generator[Any, None, None]]:
    """``with pool_results(...) as results: for r in results: keep(r)``: imap_pool's results
    for a resumable run that keeps each one as it comes (in ``run_dir``; None: nowhere).
    SIGTERM (a killed job) stops the run as Ctrl-C does, with interrupts.Terminated (a
    KeyboardInterrupt) in the loop, also when the pool is used outside guidance.cli.main;
    leaving the block stops the pool now, also when the loop fails; a dead worker raises
    WorkerDiedError saying how many of ``total`` are kept (``kept()``) and how to go on."""
    with sigterm_as_interrupt():
        results = imap_pool(fn, jobs, workers)
        try:
            yield results
        except BrokenProcessPool as exc:
            raise worker_died(kept(), total, run_dir) from exc
        finally:
            results.close()  # stops the pool now, also when the loop fails


@contextmanager
def _ctrl_c_held() -> Iterator[None]:
    """SIGINT blocked in this thread for the block: the workers started in it inherit the
    mask, so a Ctrl-C while they start stays pending in them until _worker_init ignores it
    (which discards it); this process gets its own as soon as the block ends."""
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _worker_init() -> None:
    limit_threads()
    # Ctrl-C reaches the whole process group: the parent stops the workers, which would
    # otherwise each print a KeyboardInterrupt traceback. Ignored, it can be let through.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _stop(pool: Any) -> None:
    """Ends the workers now, not after their current solve (no public API before 3.14)."""
    for proc in list((pool._processes or {}).values()):
        proc.terminate()
    pool.shutdown(wait=True, cancel_futures=True)
