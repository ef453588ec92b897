"""Starting SCvx from a given trajectory (``guidance solve --guess``, ``guidance.solve(guess=)``):
re-planning a landing from a neighbouring landing's plan.

- the given trajectory is projected onto the new landing's boundary conditions and convex path
  constraints before SCvx starts from it (checked against the constraint functions);
- from a neighbour's plan the Python reference on Clarabel and the C library solve the new
  landing to the same trajectory, in fewer subproblems than from the cubic guess, and the
  file passes the independent open-loop check; the file records the guess it started from;
- a guess that does not fit (other N, not finite, with T-SCvx) is refused with the reason.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from c_library import needs_c_library

from guidance.agreement import same_trajectory
from guidance.api import solve
from guidance.cli import main
from guidance.constraints import path_constraint_values
from guidance.errors import InputError
from guidance.guess import given_guess
from guidance.params import InitialState, Params, Scenario
from guidance.scenario import scenario_to_dict
from guidance.trajectory_io import read_trajectory
from guidance.verify import audit

pytestmark = needs_c_library

NEAR = Scenario(InitialState(r0=(4.3, 3.7, 0.1), v0=(0.0, -1.0, -2.0)))
CONVEX = [0, 1, 2, 3, 4, 5]  # every path constraint but T_min (nonconvex), DESIGN.md order


@pytest.fixture(scope="module")
def default_plan(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("plan") / "default.npz"
    assert main(["solve", "--backend", "c", "--out", str(path)]) == 0
    return path


def test_the_guess_is_projected_onto_the_new_landing(default_plan: Path) -> None:
    data = read_trajectory(default_plan)
    x, u, t_f = given_guess(NEAR, data["x"], data["u"], data["t_f"])
    p = NEAR.params
    np.testing.assert_array_equal(x[0], NEAR.x0)
    assert np.abs(x[0] - data["x"][0]).max() > 0.2  # the plan started elsewhere
    target = NEAR.x_final_target()
    for part in (slice(0, 3), slice(3, 6), slice(10, 13)):  # r, v, omega at touchdown
        np.testing.assert_allclose(x[-1, part], target[part], atol=1e-12)
    assert path_constraint_values(x, u, p)[:, CONVEX].max() <= 1e-9
    assert t_f == float(data["t_f"])


def test_a_neighbours_plan_replans_the_landing_in_both_loops(
    default_plan: Path, tmp_path: Path
) -> None:
    data = read_trajectory(default_plan)
    guess = (data["x"], data["u"], data["t_f"])
    cold = solve(NEAR, backend="c")
    ref = solve(NEAR, guess=guess)  # Python on Clarabel
    c = solve(NEAR, backend="c", guess=guess)
    assert ref.status == c.status == cold.status == "solved", (ref.reason, c.reason)
    assert same_trajectory(c, ref)
    assert c.subproblems_solved < 0.7 * cold.subproblems_solved, (
        c.subproblems_solved,
        cold.subproblems_solved,
    )
    # through the command line, into a file that flies and says where it started
    scn_file = tmp_path / "near.json"
    scn_file.write_text(json.dumps(scenario_to_dict(NEAR)))
    out = tmp_path / "near.npz"
    args = ["solve", str(scn_file), "--backend", "c", "--guess", str(default_plan)]
    assert main([*args, "--out", str(out)]) == 0
    written = read_trajectory(out)
    assert float(written["x"][-1, 13]) == pytest.approx(c.m_f, rel=1e-12)
    check = audit(written["x"], written["u"], written["t_f"], Params())
    assert check.landing_position_error <= 1e-3 and check.max_path_violation <= 1e-6
    recorded = written["provenance"]["files"]["initial_guess"]
    assert recorded["sha256"] == hashlib.sha256(default_plan.read_bytes()).hexdigest()
    assert "c_library" in written["provenance"]["files"]  # the build that solved it


def test_a_guess_that_does_not_fit_is_refused(default_plan: Path, tmp_path: Path, capsys) -> None:
    data = dict(np.load(default_plan))
    short = tmp_path / "short.npz"
    np.savez(short, **{**data, "x": data["x"][:30], "u": data["u"][:30]})
    nan = tmp_path / "nan.npz"
    u = data["u"].copy()
    u[3, 1] = np.nan
    np.savez(nan, **{**data, "u": u})
    cases = [
        (["--guess", str(short)], f"--guess {short}: x is (30, 14), the params ask for (50, 14)"),
        (["--guess", str(nan)], f"--guess {nan}: u: holds no trajectory (values not finite)"),
        (
            ["--guess", str(default_plan), "--method", "tscvx"],
            f"--guess {default_plan}: applies to --method scvx only",
        ),
        (["--guess", str(tmp_path / "none.npz")], f"--guess {tmp_path / 'none.npz'}: "),
    ]
    for extra, message in cases:
        assert main(["solve", "--backend", "c", *extra]) == 2
        assert message in capsys.readouterr().err
    with pytest.raises(InputError, match="guess: give"):
        solve(guess=(data["x"], data["u"]))
    with pytest.raises(InputError, match="T-SCvx starts from its solution network"):
        solve(method="tscvx", guess=(data["x"], data["u"], data["t_f"]))
