"""`guidance dispersion`: sampled landings in the C library, each checked open loop."""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import numpy as np
import pytest

from guidance import cgnc, cli, dispersion
from guidance.file_check import verify_file
from guidance.params import InitialState, Scenario, SCvxSettings
from guidance.scenario import load_scenario
from guidance.trajectory_io import write_trajectory

pytestmark = pytest.mark.skipif(not cgnc.LIB_PATH.exists(), reason="run `make lib` first")

# A heavy vehicle on a long flight (t_f 13.5): solved, but its converged defects grow open
# loop past verify's 1e-3 at the pad (27 Nov: 2.0e-3)
HEAVY = Scenario(InitialState(r0=(12.0, 6.0, 0.0), v0=(0.0, -1.0, -2.0), m0=6.0))


def _strict(text: str) -> dict:
    """JSON without NaN or Infinity, as other readers than Python's take it."""

    def refuse(name: str) -> None:
        raise ValueError(f"{name} is not JSON")

    return json.loads(text, parse_constant=refuse)


def _run(argv: list[str], capsys) -> tuple[int, str]:
    code = cli.main(["dispersion", "--workers", "1", *argv])
    return code, capsys.readouterr().out


def test_a_landing_that_misses_open_loop_is_told_as_verify_tells_it(tmp_path: Path) -> None:
    """The campaign's verdict on a solved landing is the file check's on its trajectory."""
    from guidance.cguidance import solve_c

    for index, scenario in enumerate((Scenario(), HEAVY)):
        row = dispersion.solve_landing((index, scenario, SCvxSettings(), "scvx"))
        result = solve_c(scenario)
        path = tmp_path / f"{index}.npz"
        write_trajectory(path, result, scenario.params, scenario, "scvx", "c")
        verdict = verify_file(path)
        assert row.status == "solved" and row.verified == verdict.ok
        failed = [c.name for c in verdict.checks if not c.ok]
        assert row.failed_checks == ", ".join(failed)
        assert row.landing_error == verdict.audit.landing_position_error
        assert row.ipm_iterations == sum(h.solver_iterations for h in result.history)
    assert not row.verified and "landing position" in row.failed_checks  # HEAVY


def test_spread_is_median_nearest_rank_percentile_and_largest() -> None:
    assert dispersion.spread([3.0, 1.0, 2.0]) == (2.0, 3.0, 3.0)
    assert dispersion.spread(list(range(1, 21))) == (10.5, 19.0, 20.0)  # the 19th of 20
    assert all(np.isnan(v) for v in dispersion.spread([]))


def test_the_budget_it_reports_leaves_every_landing_as_it_is(capsys) -> None:
    """Given as --ipm-budget, the reported budget changes no landing; the largest IPM count
    alone (what the report said before) is too small: a warm-started subproblem is given
    half of what is left."""
    base = ["--landings", "5", "--nodes", "10", "--json"]
    code, out = _run(base, capsys)
    rows = _strict(out)["landings"]
    need = max(r["untouched_budget"] for r in rows)
    largest = max(r["ipm_iterations"] for r in rows)
    assert code == 0 and need > largest

    def outcome(budget: int) -> list[tuple]:
        landings = _strict(_run([*base, "--ipm-budget", str(budget)], capsys)[1])["landings"]
        return [(r["status"], r["iterations"], r["ipm_iterations"], r["m_f"]) for r in landings]

    unbudgeted = [(r["status"], r["iterations"], r["ipm_iterations"], r["m_f"]) for r in rows]
    assert outcome(need) == unbudgeted
    assert outcome(largest) != unbudgeted


def test_untouched_budget_by_hand() -> None:
    assert dispersion.untouched_budget([]) == 0
    assert dispersion.untouched_budget([17]) == 17  # the first subproblem starts cold
    assert dispersion.untouched_budget([17, 12, 5]) == max(17, 17 + 24, 29 + 10)


def test_a_small_campaign_reports_and_writes_its_failures(tmp_path: Path, capsys) -> None:
    code, out = _run(["--landings", "3", "--nodes", "10", "--json"], capsys)
    record = _strict(out)
    assert code == 0 and (record["count"], record["nodes"], record["method"]) == (3, 10, "scvx")
    rows = record["landings"]
    assert [r["index"] for r in rows] == [0, 1, 2]
    # each landing is the sampler's, on 10 nodes: solved alike by the C library itself
    from guidance.bench_tscvx import BENCH_SEED, sample_landings
    from guidance.cguidance import solve_c

    for r, s in zip(rows, sample_landings(3, BENCH_SEED), strict=True):
        again = solve_c(Scenario(s.initial, s.params.replace(N=10)))
        assert (r["status"], r["iterations"]) == (again.status, again.iterations)
    # a budget too small for any landing: every one stops, and is written as a scenario file
    folder = tmp_path / "f"
    code, out = _run(
        ["--landings", "2", "--nodes", "10", "--ipm-budget", "30", "--failures", str(folder)],
        capsys,
    )
    assert code == 0  # nothing solved, nothing failed the open-loop check
    assert "solved 0 of 2" in out and "max_iterations" in out
    assert "; --ipm-budget 30 stopped 2" in out
    written = sorted(folder.glob("landing_*.json"))
    assert [p.name for p in written] == ["landing_0.json", "landing_1.json"]
    first = sample_landings(1, BENCH_SEED)[0]
    assert load_scenario(written[0]) == Scenario(first.initial, first.params.replace(N=10))
    campaign = _strict((folder / "campaign.json").read_text())
    assert campaign["ipm_budget"] == 30 and campaign["nodes"] == 10
    assert campaign["failures"]["landing_1.json"]["status"] == "max_iterations"
    assert "--ipm-budget 30" in campaign["solve_again"]
    # the command as recorded solves a failure again, from any folder
    again = shlex.split(campaign["solve_again"].replace("<i>", "1"))
    assert again[:2] == ["guidance", "solve"] and again[-1] == str(folder / "landing_1.json")
    capsys.readouterr()
    assert cli.main(again[1:]) == 0
    assert "status        max_iterations" in capsys.readouterr().out
    # the folder now holds a campaign: another one is refused before any work
    assert cli.main(["dispersion", "--landings", "1", "--failures", str(folder)]) == 2
    assert "holds an earlier campaign's landings" in capsys.readouterr().err


def test_a_solved_landing_failing_the_check_fails_the_command(monkeypatch, capsys) -> None:
    fail = dispersion.Landing(0, "solved", "converged", 2.2, 14, 21, 268, 300, 0.1,
                              verified=False, failed_checks="landing position")  # fmt: skip
    monkeypatch.setattr(dispersion, "solve_landing", lambda job: fail)
    code, out = _run(["--landings", "1"], capsys)
    assert code == 1
    assert "landing 0: solved: open loop: landing position" in out


def test_options_outside_their_range_are_refused(tmp_path: Path, capsys) -> None:
    for argv in (["--nodes", "2"], ["--landings", "0"], ["--ipm-budget", "0"],
                 ["--ipm-budget", "500001"]):  # fmt: skip
        with pytest.raises(SystemExit) as exc:
            cli.build_parser().parse_args(["dispersion", *argv])
        assert exc.value.code == 2
    assert cli.main(["dispersion", "--method", "tscvx", "--nodes", "20"]) == 2
    assert "shipped networks are for N = 50, not --nodes 20" in capsys.readouterr().err
    (tmp_path / "file").write_text("")
    assert cli.main(["dispersion", "--failures", str(tmp_path / "file")]) == 2
    assert "is a file, not a folder" in capsys.readouterr().err
    assert cli.main(["dispersion", "--failures", "/proc/no_such_folder"]) == 2
    assert "cannot create it" in capsys.readouterr().err
