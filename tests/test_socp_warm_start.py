"""The flight SOCP runtime's warm start (``tscvx_warm_start``, ``csocp.Solver.warm_start``)
against Clarabel: a solve started from a neighbouring problem's answer must reach Clarabel's
answer with the same bars as a cold one, and a warm start must not hide an infeasibility.
(The landing subproblem sequences, warm-started as the flight loop does, are checked in
``test_socp_landing.py``.)"""

from __future__ import annotations

import numpy as np
import pytest
from socp_problems import (
    cone_interior,
    dual_interior,
    random_dual_infeasible,
    random_feasible,
    random_primal_infeasible,
)
from test_socp_random import (
    assert_dual_certificate,
    assert_primal_certificate,
    check_against_clarabel,
)

from guidance import csocp
from guidance.conic import ConicProblem, ConicSolution


def _neighbour(prob: ConicProblem, rng: np.random.Generator, size: float) -> ConicProblem:
    """``prob`` with q and b moved by ``size`` relative noise (the same sparsity)."""
    return ConicProblem(
        P=prob.P,
        q=prob.q * (1.0 + size * rng.standard_normal(prob.n)),
        A=prob.A,
        b=prob.b * (1.0 + size * rng.standard_normal(prob.m)),
        cones=prob.cones,
    )


def _warm_solve(prob: ConicProblem, start: ConicSolution) -> ConicSolution:
    solver = csocp.Solver(prob)
    assert solver.warm_start(start) == 0
    return solver.solve()


# 120 feasible problems (with and without P), each warm-started from the answer of a
# neighbour 1 % away in q and b
@pytest.mark.parametrize("block", range(4))
def test_warm_start_from_a_neighbour_matches_clarabel(block: int) -> None:
    tried = warm = 0
    for seed in range(30 * block, 30 * block + 30):
        prob = random_feasible(seed, with_P=bool(seed % 2))
        start = csocp.solve(_neighbour(prob, np.random.default_rng(seed), 1e-2))
        if not start.ok:  # the neighbour may be unbounded
            continue
        sol = _warm_solve(prob, start)
        check_against_clarabel(prob, sol)
        tried += 1
        warm += int(sol.info["warm_started"])
    # an answer's s and z lie in the cones, so the centred point always lies inside them
    assert warm == tried >= 25


@pytest.mark.parametrize("backend", [csocp.KKT_BANDED, csocp.KKT_STATIC])
def test_a_warm_start_from_the_answer_itself_solves_to_full_accuracy(backend: int) -> None:
    """Started from its own answer, a problem is solved (not solved_inaccurate) and meets
    the bars against Clarabel. The warm point's mu_0 is about 1e-5; while refinement started
    at 1e-6 of it (ipm.c, REFINE_MU), the banded method's unrefined directions spoilt the
    primal residual near mu = 1e-10 and 5 of these 40 (seeds 1, 9, 21, 25, 37) ended
    solved_inaccurate at residuals of 1e-8 to 5e-8, where the cold start solves them."""
    warm = 0
    for seed in range(40):
        prob = random_feasible(seed, with_P=bool(seed % 2))
        solver = csocp.Solver(prob, kkt_backend=backend)
        if not solver.ready:  # the banded method needs stage structure
            continue
        cold = solver.solve()
        assert cold.status == "solved"
        assert solver.warm_start(cold) == 0
        sol = solver.solve()
        assert sol.info["warm_started"] == 1 and not sol.info["restart_iterations"]
        assert sol.status == "solved", (seed, sol.status)
        check_against_clarabel(prob, sol)
        warm += 1
    assert warm >= 12  # the banded method takes 14 of the 40, the static one all


def _interior_start(
    prob: ConicProblem, seed: int, primal_scale: float = 1.0, dual_scale: float = 1.0
) -> ConicSolution:
    """A point with s and z inside the cones (a warm start for a problem with no answer);
    x and s scaled by ``primal_scale``, z by ``dual_scale``."""
    rng = np.random.default_rng(seed)
    return ConicSolution(
        status="solved",
        x=primal_scale * rng.standard_normal(prob.n),
        s=primal_scale * cone_interior(rng, prob.cones),
        z=dual_scale * dual_interior(rng, prob.cones),
        obj=0.0,
        iterations=0,
        solve_time_s=0.0,
    )


@pytest.mark.parametrize("seed", range(20))
def test_warm_start_keeps_the_infeasibility_certificates(seed: int) -> None:
    primal = random_primal_infeasible(seed)
    sol = _warm_solve(primal, _interior_start(primal, seed))
    assert sol.info["warm_started"] == 1
    assert_primal_certificate(primal, sol)
    dual = random_dual_infeasible(seed)
    if csocp.solve(dual).status != "dual_infeasible":
        pytest.skip("the cold solve finds no dual certificate either")
    sol = _warm_solve(dual, _interior_start(dual, seed))
    assert sol.info["warm_started"] == 1
    assert_dual_certificate(dual, sol)


def test_bad_warm_points_are_refused_and_the_solve_starts_cold() -> None:
    prob = random_feasible(7)
    good = csocp.solve(prob)
    assert good.ok
    solver = csocp.Solver(prob)
    short = ConicSolution("solved", good.x[:-1], good.s, good.z, 0.0, 0, 0.0)
    assert solver.warm_start(good) == 0
    assert solver.warm_start(short) == -1  # ... and the good point given before is dropped
    assert solver.solve().info["warm_started"] == 0
    nan = ConicSolution("solved", good.x, good.s, np.full(prob.m, np.nan), 0.0, 0, 0.0)
    assert solver.warm_start(good) == 0
    assert solver.warm_start(nan) != 0  # ... and the good point given before is dropped
    sol = solver.solve()
    assert sol.info["warm_started"] == 0 and sol.ok
    assert abs(sol.obj - good.obj) <= 1e-9 * max(1.0, abs(good.obj))
    # the point serves one solve only
    assert solver.warm_start(good) == 0
    assert solver.solve().info["warm_started"] == 1
    assert solver.solve().info["warm_started"] == 0


def test_warm_start_is_centred_as_far_as_its_residuals_need() -> None:
    """The warm point's complementarity (row 0 of the log: mu) follows its infeasibility on
    the new data: about a tenth of its relative residuals, at least 1e-5 (ipm.c,
    warm_initialize). From a neighbour's answer mu grows with the residuals; from the
    problem's own answer it stays at the floor instead of restarting the path."""
    ratios, own_mu = [], []
    for seed in range(40):
        prob = random_feasible(seed, with_P=bool(seed % 2))
        for size in (1e-2, 1e-1):
            start = csocp.solve(_neighbour(prob, np.random.default_rng(seed), size))
            if not start.ok:
                continue
            solver = csocp.Solver(prob)
            assert solver.warm_start(start) == 0
            row = solver.solve(log=True).info["log"][0]
            ratios.append(row["mu"] / max(row["pres"], row["dres"]))
        solver = csocp.Solver(prob)
        assert solver.warm_start(csocp.solve(prob)) == 0
        sol = solver.solve(log=True)
        assert sol.info["warm_started"] and sol.ok
        own_mu.append(sol.info["log"][0]["mu"])
    assert len(ratios) >= 60
    # each cone gets mu_0 / 4 to 5 mu_0 / 4 (cones.c), mu_0 = max(1e-5, 0.1 max(pres, dres))
    # before the centring moves the residuals a little
    assert min(ratios) >= 0.01
    assert max(own_mu) <= 2e-5


def test_a_warm_start_that_fails_is_run_again_cold() -> None:
    """From a far point (x and s at 1e6, z at 1e-6) the IPM needs about three times the
    cold start's iterations; with an iteration limit between the two the warm run fails, and
    the solve runs again from the cold start (ipm.c, tscvx_ipm): Clarabel's answer, info of
    the cold run (warm_started 0), the failed run's iterations in restart_iterations and
    counted in ``iterations``."""
    limit, restarted = 14, 0
    for seed in range(10):
        prob = random_feasible(seed)
        cold = csocp.Solver(prob, max_iter=limit).solve()
        assert cold.ok and not cold.info["restart_iterations"]
        solver = csocp.Solver(prob, max_iter=limit)
        assert solver.warm_start(_interior_start(prob, seed, 1e6, 1e-6)) == 0
        sol = solver.solve()
        check_against_clarabel(prob, sol)
        if sol.info["restart_iterations"]:
            restarted += 1
            assert sol.info["warm_started"] == 0
            assert sol.info["restart_iterations"] == limit
            assert sol.info["iterations"] == cold.iterations  # the cold run, all over again
            assert sol.iterations == limit + cold.iterations
    assert restarted >= 5  # far points took 18 to 37 iterations on 8 of these 10
