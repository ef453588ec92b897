"""The reference SCvx gives the same trajectory with the flight C runtime (``--backend c``)
as with Clarabel: final mass within 1e-6 relative, same iteration count."""

from __future__ import annotations

import pytest

scvx = pytest.importorskip("guidance.scvx")
params = pytest.importorskip("guidance.params")


def test_scvx_backend_c_matches_clarabel() -> None:
    scenario = params.Scenario()
    ref = scvx.solve_scvx(scenario, backend="clarabel")
    got = scvx.solve_scvx(scenario, backend="c")
    assert ref.status == got.status == "solved"
    assert got.iterations == ref.iterations
    m_ref, m_got = ref.x[-1, 13], got.x[-1, 13]
    assert abs(m_got - m_ref) <= 1e-6 * abs(m_ref)
