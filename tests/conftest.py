"""Shared fixtures."""

from __future__ import annotations

import signal
from collections.abc import Iterator

import pytest
from dataset_runs import solve_tiny_run

from guidance.catalog import SCENARIOS
from guidance.scvx import SCvxResult, SCvxSolver, solve_scvx


@pytest.fixture(scope="session")
def default_solved() -> tuple[SCvxSolver, SCvxResult]:
    """The default landing solved by the reference SCvx (cubic guess, default settings), once
    for every test module that starts from it."""
    solver = SCvxSolver(SCENARIOS["default"])
    result = solver.solve()
    assert result.status == "solved", result.reason
    return solver, result


@pytest.fixture(scope="session")
def catalog_solved() -> dict[str, SCvxResult]:
    """Every catalog landing solved by the reference SCvx (Clarabel, default settings), once
    for the modules that check it (test_scvx) or compare against it (test_cguidance)."""
    return {name: solve_scvx(s) for name, s in SCENARIOS.items()}


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory: pytest.TempPathFactory):
    """A tiny dataset run, solved and packed (dataset_runs.solve_tiny_run), once for the
    modules of the dataset pipeline, which change only copies of it."""
    return solve_tiny_run(tmp_path_factory)


@pytest.fixture
def deadline() -> Iterator[None]:
    """Fails a test that would otherwise hang (a pool waiting for a dead worker) after 20 s.
    An alarm, not a thread: the code under test installs signal handlers (main thread only)."""

    def expired(signum: int, frame: object) -> None:
        raise TimeoutError("still running after 20 s: hung")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(20)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
