"""The discretization's accuracy does not hang on the grid: a coarse grid's intervals take more
RK4 steps (rk4_steps_per_interval), so that a trajectory reported solved at any N lands open
loop. With a fixed 2 steps per interval the default landing at N = 10, solved, missed its
landing point by 9.8e-3 open loop and at N = 15 by 1.7e-3 (the tolerance is 1e-3)."""

from __future__ import annotations

import ctypes

import pytest
from c_library import needs_c_library

from guidance import cgnc, cguidance
from guidance.file_check import Tolerances
from guidance.params import INT_SETTING_RANGES, Params, Scenario, rk4_steps_per_interval
from guidance.scvx import SCvxSolver
from guidance.verify import audit


def test_a_coarse_grid_takes_more_steps_per_interval() -> None:
    assert rk4_steps_per_interval(2, 50) == 2  # the grid the default was chosen for
    assert rk4_steps_per_interval(2, 10) == 11  # 98 / 9, rounded up
    assert rk4_steps_per_interval(2, 3) == 49
    assert rk4_steps_per_interval(2, 400) == 2
    assert rk4_steps_per_interval(4, 50) == rk4_steps_per_interval(4, 30) == 4
    assert rk4_steps_per_interval(1, 99) == 1  # 98 intervals: one step each


@needs_c_library
def test_the_c_library_takes_the_same_steps() -> None:
    fun = cgnc.library().pdg_rk4_steps
    fun.restype, fun.argtypes = ctypes.c_int, [ctypes.c_int, ctypes.c_int]
    lo, hi = INT_SETTING_RANGES["rk4_substeps"]
    for N in range(1, 401):
        for substeps in (lo, 2, 3, 7, hi):
            assert fun(substeps, N) == rk4_steps_per_interval(substeps, N), (substeps, N)


@needs_c_library
@pytest.mark.parametrize("N", [5, 10, 15])
def test_a_coarse_grid_lands_open_loop(N: int) -> None:
    """Solved in the C library, flown open loop by scipy: within file_check's tolerances."""
    scenario = Scenario(params=Params(N=N))
    c = cguidance.solve_c(scenario)
    assert c.status == "solved", c.reason
    a = audit(c.x, c.u, c.t_f, scenario.params)
    tol = Tolerances()
    assert a.landing_position_error <= tol.landing / 4, a
    assert a.landing_velocity_error <= tol.landing / 4, a
    assert a.max_node_deviation <= tol.node_deviation / 4, a


def test_the_reference_lands_open_loop_on_a_coarse_grid() -> None:
    """The Python reference (Clarabel) at N = 10 too."""
    scenario = Scenario(params=Params(N=10))
    ref = SCvxSolver(scenario).solve()
    assert ref.status == "solved", ref.reason
    a = audit(ref.x, ref.u, ref.t_f, scenario.params)
    assert a.landing_position_error <= Tolerances().landing / 4, a
    assert a.max_node_deviation <= Tolerances().node_deviation / 4, a
