"""T-SCvx with oracle predictors: warm start and reduced subproblems keep the full answer."""

from __future__ import annotations

import numpy as np
import pytest

from guidance.catalog import SCENARIOS
from guidance.params import NC
from guidance.scvx import SCvxResult, solve_scvx
from guidance.tscvx import solve_tscvx
from guidance.verify import audit


@pytest.fixture(scope="module")
def reference() -> SCvxResult:
    return solve_scvx(SCENARIOS["north"])


def test_oracle_warm_start_and_masks_converge_fast(reference: SCvxResult) -> None:
    scenario = SCENARIOS["north"]
    final = reference.final_mask

    r = solve_tscvx(
        scenario,
        lambda s: (reference.x, reference.u, reference.t_f),
        lambda s, k: final,
    )
    assert r.status == "solved", r.reason
    assert r.iterations <= 3
    assert abs(r.m_f - reference.m_f) <= 1e-3
    a = audit(r.x, r.u, r.t_f, scenario.params)
    assert a.max_path_violation <= 1e-6 and a.landing_position_error <= 1e-3


def test_dropped_tight_constraints_are_put_back(reference: SCvxResult) -> None:
    """A mask keeping nothing but T_min would let thrust exceed T_max: the guard restores it."""
    scenario = SCENARIOS["north"]
    empty = np.zeros(NC * scenario.params.N)
    r = solve_tscvx(
        scenario, lambda s: (reference.x, reference.u, reference.t_f), lambda s, k: empty
    )
    assert r.status == "solved", r.reason
    a = audit(r.x, r.u, r.t_f, scenario.params)
    assert a.max_path_violation <= 1e-6
    assert abs(r.m_f - reference.m_f) <= 1e-3
