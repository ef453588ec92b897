"""`guidance dispersion`: sampled landings in the C library, each checked open loop."""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import numpy as np
import pytest
from c_library import needs_c_library

from guidance import cli, dispersion
from guidance.file_check import verify_file
from guidance.params import PARAM_NAMES, InitialState, Scenario, SCvxSettings
from guidance.scenario import load_scenario
from guidance.trajectory_io import write_trajectory

pytestmark = needs_c_library

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
    # every parameter, not only those off today's defaults: solved again the same whatever
    # the defaults become (audit of 28 Nov)
    assert set(PARAM_NAMES) <= set(json.loads(written[0].read_text()))
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


# ---- interruption and resume (--run-dir) ----------------------------------------------------
ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ["--landings", "6", "--nodes", "10"]
SOLVE_LANDING = dispersion.solve_landing  # the worker's job, before any test replaces it


def _main(argv: list[str]) -> int:
    """cli.main, with a Ctrl-C escaping it (a traceback and an exit by the signal, before
    the command handled it) failing the test instead of stopping pytest."""
    try:
        return cli.main(argv)
    except KeyboardInterrupt:
        pytest.fail("KeyboardInterrupt escaped guidance's main: a traceback, not exit 130")


def _counting(monkeypatch, stop_at: int | None = None) -> list[int]:
    """The landings solved from now on (in this process: --workers 1), in order; landing
    ``stop_at`` raises KeyboardInterrupt instead, as Ctrl-C during its solve."""
    solved: list[int] = []
    real = SOLVE_LANDING

    def solve(job):
        if job[0] == stop_at:
            raise KeyboardInterrupt
        solved.append(job[0])
        return real(job)

    monkeypatch.setattr(dispersion, "solve_landing", solve)
    return solved


def _landings(out: str) -> list[dict]:
    """Each landing's figures of a --json campaign, the host's wall time aside."""
    return [{k: v for k, v in r.items() if k != "wall_s"} for r in _strict(out)["landings"]]


def _report(out: str) -> list[str]:
    return [line for line in out.splitlines() if "host wall time" not in line]


@pytest.fixture(scope="module")
def uninterrupted() -> dict[str, object]:
    """The campaign run through at once, without a run directory: its JSON and its report."""
    import contextlib
    import io

    out = {}
    for key, extra in (("json", ["--json"]), ("report", [])):
        text = io.StringIO()
        with contextlib.redirect_stdout(text):
            assert cli.main(["dispersion", "--workers", "1", *CAMPAIGN, *extra]) == 0
        out[key] = text.getvalue()
    return {"json": _landings(out["json"]), "report": _report(out["report"])}


def test_an_interrupted_campaign_resumes_solving_only_what_is_missing(
    tmp_path: Path, monkeypatch, capsys, uninterrupted
) -> None:
    """Ctrl-C at landing 3: landings 0-2 are kept in the run directory, the command printed
    goes on with 3-5 only, and its campaign is the uninterrupted one, landing by landing."""
    run_dir = tmp_path / "run"
    solved = _counting(monkeypatch, stop_at=3)
    argv = ["dispersion", "--workers", "1", *CAMPAIGN, "--json", "--run-dir", str(run_dir)]
    assert _main(argv) == 130
    out, err = capsys.readouterr()
    assert solved == [0, 1, 2] and out == ""
    assert f"interrupted: 3 of 6 landings are kept in {run_dir}; to resume: " in err
    names = sorted(p.name for p in (run_dir / "results").iterdir())
    assert names == ["000000.json", "000001.json", "000002.json"]
    record = json.loads((run_dir / "run.json").read_text())  # the campaign's parameters
    assert (record["landings"], record["nodes"], record["seed"]) == (6, 10, 20261122)
    assert record["code_versions"] and record["scvx_settings"]["socp_max_iter_total"] == 24000

    resume = shlex.split(err.split("to resume: ")[1].strip())
    assert resume[:2] == ["guidance", "dispersion"] and "--json" in resume
    solved = _counting(monkeypatch)
    assert _main(resume[1:]) == 0
    assert solved == [3, 4, 5]
    assert _landings(capsys.readouterr().out) == uninterrupted["json"]
    # the report, once all is kept: the uninterrupted one, nothing solved again
    assert _main(["dispersion", *CAMPAIGN, "--run-dir", str(run_dir)]) == 0
    assert solved == [3, 4, 5]
    assert _report(capsys.readouterr().out) == uninterrupted["report"]
    # a damaged result is set aside, and its landing alone solved again
    (run_dir / "results" / "000004.json").write_text('{"id": 4, "run": ')
    assert _main(argv) == 0
    assert solved == [3, 4, 5, 4]
    out, err = capsys.readouterr()
    assert _landings(out) == uninterrupted["json"]
    assert "set aside as" in err and (run_dir / "results" / "000004.unreadable").exists()


def test_ctrl_c_stops_the_workers_and_the_campaign_resumes(
    tmp_path: Path, monkeypatch, capsys, uninterrupted
) -> None:
    """A real Ctrl-C (SIGINT to the process group) once the first landing is kept, two
    worker processes solving: exit 130, no traceback, and the landings kept are read back."""
    import os
    import signal
    import subprocess
    import sys
    import time

    run_dir = tmp_path / "run"
    argv = ["dispersion", *CAMPAIGN, "--json", "--run-dir", str(run_dir)]
    proc = subprocess.Popen(
        [sys.executable, "-m", "guidance", *argv, "--workers", "2"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own group, signalled as a terminal's Ctrl-C is
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # as in a terminal
    )
    t0 = time.monotonic()
    while not (run_dir / "results" / "000000.json").exists() and proc.poll() is None:
        assert time.monotonic() - t0 < 120, "no landing finished"
        time.sleep(0.01)
    assert proc.poll() is None, proc.communicate()[1]  # still solving
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    kept = sorted(int(p.stem) for p in (run_dir / "results").glob("*.json"))
    assert proc.returncode == 130, err
    assert "Traceback" not in err and out == ""
    assert f"interrupted: {len(kept)} of 6 landings are kept in {run_dir}; to resume: " in err
    assert 0 < len(kept) < 6
    solved = _counting(monkeypatch)
    assert _main([*argv, "--workers", "1"]) == 0
    assert solved == [i for i in range(6) if i not in kept]
    assert _landings(capsys.readouterr().out) == uninterrupted["json"]


def test_a_resume_with_other_parameters_is_refused(tmp_path: Path, monkeypatch, capsys) -> None:
    run_dir = tmp_path / "run"
    argv = ["dispersion", "--workers", "1", *CAMPAIGN, "--run-dir", str(run_dir)]
    _counting(monkeypatch, stop_at=0)
    assert _main(argv) == 130  # nothing solved, the run recorded
    capsys.readouterr()
    for option, value, said in (
        ("--nodes", "12", "different nodes, drawn_landings_sha256); it records nodes 10, not 12"),
        ("--seed", "3", "it records seed 20261122, not 3"),
        ("--landings", "7", "it records landings 6, not 7"),
        ("--ipm-budget", "500", "different ipm_budget, scvx_settings"),
    ):
        assert _main([*argv, option, value]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: {run_dir} holds landings of another run"), err
        assert said in err, err
    assert not (run_dir / "results").exists()  # nothing solved into it


def test_ctrl_c_without_a_run_directory_says_nothing_was_kept(monkeypatch, capsys) -> None:
    solved = _counting(monkeypatch, stop_at=2)
    assert _main(["dispersion", "--workers", "1", *CAMPAIGN]) == 130
    out, err = capsys.readouterr()
    assert solved == [0, 1] and out == ""
    assert "interrupted: 2 of 6 landings were finished; nothing is kept without --run-dir" in err


def test_failures_of_a_resumed_campaign_are_written_at_its_end(
    tmp_path: Path, monkeypatch, capsys
) -> None:
    """--failures with --run-dir: written once the campaign is whole, from the landings kept
    before the interruption too; the run directory itself is refused as the folder."""
    run_dir, folder = tmp_path / "run", tmp_path / "failures"
    argv = ["dispersion", "--workers", "1", "--landings", "3", "--nodes", "10",
            "--ipm-budget", "30", "--run-dir", str(run_dir), "--failures", str(folder)]  # fmt: skip
    solved = _counting(monkeypatch, stop_at=2)
    assert _main(argv) == 130
    assert not any(folder.iterdir())  # nothing written before the end
    solved = _counting(monkeypatch)
    assert _main(argv) == 0 and solved == [2]
    written = sorted(p.name for p in folder.glob("landing_*.json"))
    assert written == ["landing_0.json", "landing_1.json", "landing_2.json"]
    campaign = _strict((folder / "campaign.json").read_text())
    assert campaign["failures"]["landing_0.json"]["status"] == "max_iterations"
    capsys.readouterr()
    assert _main([*argv[:-1], str(run_dir)]) == 2
    assert "is the --run-dir folder" in capsys.readouterr().err
