"""Hand values of the SCvx pieces: constraint scales and tightness, trust-region update, the
penalty J, the predicted cost L against Clarabel's objective, and the subproblem's mass rows.

Every expected value is derived from the definitions (DESIGN.md, the docstrings), not from an
earlier output of the code.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from guidance import conic
from guidance.catalog import SCENARIOS
from guidance.constraints import TIGHT_DUAL_TOL, constraint_scales, tight_mask
from guidance.errors import InputError
from guidance.guess import initial_guess
from guidance.model import discretize
from guidance.params import IM, NC, NX, Params, Scenario, SCvxSettings
from guidance.scvx import SCvxSolver, _changed_fraction, _trust_update, iteration_cap
from guidance.subproblem import (
    N_NU_BLOCKS,
    TR_PAIRS,
    TR_SCALAR_STATES,
    Scaling,
    SubproblemTemplate,
    carry_solution,
    scaled,
)

SCN = SCENARIOS["default"]


# ---- constraint scales and the tight-constraint rule ----------------------------------------
def test_constraint_scales_hand_values() -> None:
    """Units: mass -> Sx[m], glideslope -> Sx[r1] (a length), tilt -> 1 (quaternion),
    omega -> omega_max, the three thrust constraints -> Su."""
    p = Params()
    Sx = np.arange(1.0, 15.0) * 1.5  # Sx[0] = 1.5, Sx[13] = 21
    got = constraint_scales(p, Sx, 7.0)
    want = [21.0, 1.5, 1.0, math.pi / 2, 7.0, 7.0, 7.0]
    np.testing.assert_allclose(got, want, rtol=1e-15)


def test_tight_mask_slack_threshold_and_duals() -> None:
    """Tight when -h <= 1e-6 max(1, scale) or the dual is >= TIGHT_DUAL_TOL; bit 7k + c."""
    scales = np.array([4.0, 4.0, 1.0, 0.5, 5.0, 5.0, 5.0])
    h = np.full((2, NC), -1.0)  # every constraint far from active
    h[0, 0] = -3.9e-6  # threshold 4e-6: tight
    h[0, 1] = -4.1e-6  # just above it: not tight
    h[0, 3] = -0.9e-6  # scale 0.5 < 1: threshold 1e-6, tight
    h[1, 3] = -1.1e-6  # not tight
    h[1, 2] = 0.2  # violated: tight
    mask = tight_mask(h, scales)
    want = np.zeros(2 * NC, np.uint8)
    want[[0, 3, NC + 2]] = 1
    np.testing.assert_array_equal(mask, want)
    # the multiplier rule: a dual above TIGHT_DUAL_TOL marks an inactive slack as tight
    duals = np.full((2, NC), np.nan)
    duals[1, 4] = 2 * TIGHT_DUAL_TOL
    duals[1, 5] = 0.5 * TIGHT_DUAL_TOL
    assert TIGHT_DUAL_TOL == 1e-5
    mask = tight_mask(h, scales, duals)
    want[NC + 4] = 1
    np.testing.assert_array_equal(mask, want)


# ---- trust region update ----------------------------------------------------------------------
def test_trust_update_hand_values() -> None:
    st = SCvxSettings()  # alpha = beta = 2, rho1 = 0.1, rho2 = 0.7, eta in [1e-3, 10]
    assert (st.alpha, st.beta, st.rho1, st.rho2, st.eta_lb, st.eta_ub) == (
        2.0, 2.0, 0.1, 0.7, 1e-3, 10.0,
    )  # fmt: skip
    # Eq. (15): grow, keep, shrink
    assert _trust_update(1.0, 0.9, True, 0.5, st, None) == pytest.approx(2.0)
    assert _trust_update(1.0, 0.5, True, 0.5, st, None) == pytest.approx(1.0)
    assert _trust_update(1.0, 0.05, True, 0.5, st, None) == pytest.approx(0.5)
    # growth beyond eta_ub is clamped
    assert _trust_update(8.0, 0.9, True, 0.5, st, None) == pytest.approx(10.0)
    assert _trust_update(8.0, 0.9, True, 0.5, st, 0.0) == pytest.approx(10.0)
    # shrink below eta_lb is clamped
    assert _trust_update(1.5e-3, 0.05, True, 1e-3, st, None) == pytest.approx(1e-3)
    # T-SCvx: tau_r = 0.5 grows by beta^0.5 and shrinks by alpha^0.5
    assert _trust_update(1.0, 0.9, True, 0.5, st, 0.5) == pytest.approx(math.sqrt(2.0))
    assert _trust_update(1.0, 0.05, True, 0.5, st, 0.5) == pytest.approx(1.0 / math.sqrt(2.0))
    # a rejection halves the radius until it no longer holds the rejected step (0.3):
    # 1 -> 0.5 (still > 1.001 * 0.3, skipped) -> 0.25
    assert _trust_update(1.0, -1.0, False, 0.3, st, None) == pytest.approx(0.25)


def test_changed_fraction_hand_value() -> None:
    a = np.zeros(350, np.uint8)
    b = a.copy()
    b[::10] = 1  # 35 bits differ
    assert _changed_fraction(a, b) == pytest.approx(0.1)
    assert _changed_fraction(None, b) == 0.0


# ---- penalty J ----------------------------------------------------------------------------------
def _solver_at_guess() -> tuple[SCvxSolver, np.ndarray, np.ndarray, float]:
    solver = SCvxSolver(SCN, SCvxSettings(discretization="casadi"))
    x, u, t_f = initial_guess(SCN)
    solver.sc = Scaling.for_scenario(SCN, t_f)
    solver.scales = constraint_scales(SCN.params, solver.sc.Sx, solver.sc.Su)
    solver.lay = solver.template(None).lay
    return solver, x, u, t_f


def test_penalty_counts_path_violation() -> None:
    """|T| = T_max + 0.5 at one node (thrust along e1, gimbal and T_min met): with the same
    discretization, J is larger by lambda * 0.5 / T_max (scale of constraint 4: S_u = T_max)
    than with |T| = T_max - 0.5 there."""
    solver, x, u, t_f = _solver_at_guess()
    p = SCN.params
    k = 10
    u_ok, u_bad = u.copy(), u.copy()
    u_ok[k] = [p.T_max - 0.5, 0.0, 0.0]
    u_bad[k] = [p.T_max + 0.5, 0.0, 0.0]
    z_ok = scaled(x, u_ok, t_f, solver.lay, solver.sc)
    z_bad = scaled(x, u_bad, t_f, solver.lay, solver.sc)
    disc = solver._discretize(z_ok)  # the same defects for both
    J_ok, _, _ = solver.penalty(z_ok, disc)
    J_bad, _, viol_bad = solver.penalty(z_bad, disc)
    lam = SCvxSettings().lam
    assert J_bad - J_ok == pytest.approx(lam * 0.5 / p.T_max, rel=1e-9)
    assert viol_bad == pytest.approx(0.5, rel=1e-12)


# ---- L against Clarabel's objective, and the logged virtual control ---------------------------
@pytest.fixture(scope="module")
def first_subproblem():
    # a small trust radius keeps the first step far from dynamic feasibility: nu != 0
    st = SCvxSettings(prox_u=0.0, max_subproblems=1, eta_init=0.01)
    solver = SCvxSolver(SCN, st, record_subproblems=True)
    result = solver.solve()
    prob = result.subproblems[0]
    assert prob.P is None  # prox_u = 0: a pure SOCP, objective q'z
    sol = conic.solve_clarabel(prob)
    assert sol.status == "solved"
    return solver, result, prob, sol


def test_linear_cost_is_clarabel_objective(first_subproblem) -> None:
    """With prox_u = 0 the subproblem objective is L itself (no constant term)."""
    solver, _, prob, sol = first_subproblem
    lay = solver.lay
    # the virtual control epigraph t carries real weight here, not only the buffers
    assert sol.x[lay.ivc : lay.ibuf].sum() > 1e-3
    L = solver.linear_cost(prob, sol.x)
    assert pytest.approx(sol.obj, rel=1e-8, abs=1e-10) == L


def test_logged_vc_is_virtual_control_plus_buffers(first_subproblem) -> None:
    """vc_norm1 = block norms of nu (the epigraph t at the optimum) + |s'|_1."""
    solver, result, _, sol = first_subproblem
    lay, N = solver.lay, SCN.params.N
    nu = sol.x[lay.inu : lay.ivc].reshape(N - 1, NX)
    block = np.abs(nu[:, list(TR_SCALAR_STATES)]).sum()
    block += sum(np.hypot(nu[:, a], nu[:, b]).sum() for a, b in TR_PAIRS)
    buffers = sol.x[lay.ibuf : lay.ibuf + N].sum()
    assert lay.ibuf - lay.ivc == (N - 1) * N_NU_BLOCKS
    assert block > 1e-3
    vc = result.history[0].vc_norm1
    assert vc == pytest.approx(block + buffers, rel=1e-6)


# ---- mass rows of the subproblem follow the mask --------------------------------------------
def _expected_rows(N: int, mass_rows: int) -> int:
    """Row count from the layout (final roll free; every cone constraint kept)."""
    dyn = NX * (N - 1)
    bc = NX + (9 + 2)  # full x0; r, v, omega, q2, q3 at t_f
    nu_scalar = 2 * len(TR_SCALAR_STATES) * (N - 1)
    buf, sig = N, 1
    tr_scalar = 2 * (len(TR_SCALAR_STATES) * N + 3 * N + 1)  # states, u_hat, sigma_hat
    tmin = N
    soc = N * (3 + 3 + 4 + 4 + 4)  # constraints 1..5
    nu_pairs = 3 * len(TR_PAIRS) * (N - 1)
    tr_pairs = 3 * len(TR_PAIRS) * N
    return (
        dyn + bc + nu_scalar + buf + sig + tr_scalar + mass_rows + tmin + soc + nu_pairs + tr_pairs
    )


def test_masked_mass_constraint_has_no_rows() -> None:
    N = 6
    full = SubproblemTemplate(N, True)
    mask = np.ones((N, NC), bool)
    mask[:, 0] = False
    nomass = SubproblemTemplate(N, True, mask.reshape(-1))
    assert full.m == _expected_rows(N, N)
    assert nomass.m == _expected_rows(N, 0)
    assert len(nomass.nodes_mass) == 0
    # the assembled conic problems: N fewer nonnegative rows
    scn = Scenario(SCN.initial, SCN.params.replace(N=N))
    x, u, t_f = initial_guess(scn)
    sc = Scaling.for_scenario(scn, t_f)
    z = scaled(x, u, t_f, full.lay, sc)
    disc = discretize(x, u, t_f, scn.params, 2)
    pf = full.assemble(disc, z, 1.0, 500.0, scn, sc)
    pm = nomass.assemble(disc, z, 1.0, 500.0, scn, sc)
    assert pf.A.shape[0] - pm.A.shape[0] == N
    assert (
        sum(d for kind, d in pf.cones if kind == "nonneg")
        - sum(d for kind, d in pm.cones if kind == "nonneg")
        == N
    )
    # a masked-in mass row at one node only: exactly one row, on that node's m_hat
    one = np.zeros((N, NC), bool)
    one[:, 1:] = True
    one[3, 0] = True
    tpl = SubproblemTemplate(N, True, one.reshape(-1))
    assert tpl.m == _expected_rows(N, 1)
    A = tpl.assemble(disc, z, 1.0, 500.0, scn, sc).A.tocsr()
    row = A[tpl.r_mass].toarray().ravel()
    assert np.flatnonzero(row).tolist() == [tpl.lay.x_index(3, IM)]


def test_a_masked_subproblem_is_the_full_one_without_the_dropped_rows() -> None:
    """row_ids names each row of a masked template in the full one, so an answer carries
    from one mask to the next (carry_solution: the C loop, one pattern for every mask,
    warm-starts across masks; the Python loop started cold after every mask change)."""
    N = 6
    scn = Scenario(SCN.initial, SCN.params.replace(N=N))
    x, u, t_f = initial_guess(scn)
    full = SubproblemTemplate(N, True)
    sc = Scaling.for_scenario(scn, t_f)
    z = scaled(x, u, t_f, full.lay, sc)
    disc = discretize(x, u, t_f, scn.params, 2)
    rng = np.random.default_rng(7)
    pf = full.assemble(disc, z, 1.0, 500.0, scn, sc)
    assert full.row_ids.tolist() == list(range(full.m))
    masks = [rng.random((N, NC)) < 0.5 for _ in range(2)]
    tpls = [SubproblemTemplate(N, True, m.reshape(-1)) for m in masks]
    for tpl in tpls:
        pm = tpl.assemble(disc, z, 1.0, 500.0, scn, sc)
        assert tpl.m < full.m and len(set(tpl.row_ids.tolist())) == tpl.m
        np.testing.assert_array_equal(pm.A.toarray(), pf.A.toarray()[tpl.row_ids])
        np.testing.assert_array_equal(pm.b, pf.b[tpl.row_ids])
    # an answer of the full problem (numbered rows) carried to a mask and on to another
    answer = conic.ConicSolution(
        "solved", z, np.arange(full.m, dtype=float), -np.arange(full.m, dtype=float), 0.0, 9, 0.0
    )
    a, b = tpls
    on_a = carry_solution(answer, full, a)
    np.testing.assert_array_equal(on_a.s, a.row_ids)
    np.testing.assert_array_equal(on_a.z, -a.row_ids)
    assert on_a.x is z
    on_b = carry_solution(on_a, a, b)
    both = np.isin(b.row_ids, a.row_ids)
    np.testing.assert_array_equal(on_b.s[both], b.row_ids[both])
    # a row only b keeps starts at its cone's identity (s = e, z = 0)
    fresh = b.soc_rows[next(key for key in b.soc_rows if not a.mask[key])]
    assert not both[fresh] and on_b.s[fresh] == 1.0 and on_b.z[fresh] == 0.0
    assert not on_b.s[fresh + 1 :][:2].any()
    assert carry_solution(on_a, a, a) is on_a


def test_settings_take_numpy_scalars_and_refuse_numbers_beyond_a_float() -> None:
    """numpy scalars were refused ("iter_max must be an integer within 1..100, got
    np.int64(5)") while scenarios take them; an integer beyond a float (lam = 10**400) passed
    and crashed each backend differently (OverflowError, scipy's dtype object). Now the
    scalars are taken as the Python numbers they stand for, and such integers are refused."""
    st = SCvxSettings(iter_max=np.int64(5), eta_init=np.float32(0.5), socp_warm_start=np.bool_(1))
    assert st == SCvxSettings(iter_max=5, eta_init=0.5, socp_warm_start=True)
    assert (type(st.iter_max), type(st.eta_init), type(st.socp_warm_start)) == (int, float, bool)
    for name in ("lam", "prox_u", "eta_ub"):
        with pytest.raises(InputError, match=f"{name} must be finite, got an integer of 401"):
            SCvxSettings(**{name: 10**400})
    with pytest.raises(InputError, match="lam must be a number"):
        SCvxSettings(lam=np.bool_(True))


def test_iteration_cap_gives_a_subproblem_what_is_left_of_the_budget() -> None:
    """socp_max_iter at most; what is left of socp_max_iter_total, half of it when the
    subproblem is warm-started (a failed warm run is run again cold with the same limit, and
    both count); a single iteration left is run cold; nothing once the budget is spent."""
    st = SCvxSettings(socp_max_iter=200, socp_max_iter_total=500)
    assert iteration_cap(st, 0, True) == (200, True)
    assert iteration_cap(st, 150, True) == (175, True)
    assert iteration_cap(st, 150, False) == (200, False)
    assert iteration_cap(st, 490, True) == (5, True)
    assert iteration_cap(st, 490, False) == (10, False)
    assert iteration_cap(st, 499, True) == (1, False)
    assert iteration_cap(st, 500, True) == (0, False)
    assert iteration_cap(st, 520, False) == (0, False)
    with pytest.raises(InputError, match="socp_max_iter_total must be an integer within"):
        SCvxSettings(socp_max_iter_total=0)


def test_the_guard_puts_back_only_what_the_subproblem_dropped() -> None:
    """T-SCvx's full-constraint guard (step 5 of Algorithm 2): a candidate violating a
    constraint the subproblem left out is rejected and the constraint put back; a violated
    T_min (always kept, its buffer penalized) or a constraint already put back is not counted
    again (review of 26 Nov: the guard reading the prediction instead of the subproblem's
    mask failed no test). A synthetic candidate: the first subproblem's, its h edited."""
    N = SCN.params.N
    solver = SCvxSolver(SCN, SCvxSettings())
    s = solver._start(None)
    assert s is not None
    tmin, glide = 6, 1  # constraint columns (constraints.CONSTRAINT_NAMES)
    pred = np.ones((N, NC), bool)
    pred[:, tmin] = False  # the network left T_min out: the subproblem keeps it anyway
    pred[5, glide] = pred[9, glide] = False  # two glideslope rows left out ...
    s.forced[9 * NC + glide] = True  # ... one of them put back by an earlier rejection
    mask = pred.reshape(-1) | s.forced
    tpl = solver.template(mask)
    prob, sol = solver._solve_subproblem(s, tpl)
    cand = solver._candidate(s, tpl, prob, sol)
    assert not isinstance(cand, str)
    h = np.full((N, NC), -1.0)
    h[:, tmin] = 1.0  # T_min violated everywhere
    h[9, glide] = 1.0  # the constraint already back in the subproblem
    record, _ = solver._judge(s, tpl, replace(cand, h=h), sol, mask, pred.reshape(-1), True)
    assert record.restored == 0
    h[5, glide] = 1.0  # the one the subproblem dropped
    # a step rho accepts (J fell) is retried at the same radius: the mask failed, not the
    # linearization
    good = replace(cand, h=h, J=s.J - 0.5 * (s.J - cand.L))
    record, eta = solver._judge(s, tpl, good, sol, mask, pred.reshape(-1), True)
    assert record.rho >= solver.st.rho0
    assert (record.restored, record.accepted, eta) == (1, False, s.eta)
    assert s.forced[5 * NC + glide]
    # one rho rejects too (J rose) at the radius contracted by alpha, as step 5 of Algorithm
    # 2 rejects it (until 28 Nov at the same radius, where the retry was mostly rejected again)
    s.forced[5 * NC + glide] = False
    bad = replace(cand, h=h, J=s.J + 1.0)
    record, eta = solver._judge(s, tpl, bad, sol, mask, pred.reshape(-1), True)
    assert record.rho < solver.st.rho0
    assert (record.restored, record.accepted, eta) == (1, False, s.eta / solver.st.alpha)
    s.eta = solver.st.eta_lb  # never below the smallest radius
    record, eta = solver._judge(s, tpl, bad, sol, mask, pred.reshape(-1), True)
    assert (record.restored, eta) == (1, solver.st.eta_lb)
