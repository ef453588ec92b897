"""guidance agreement: the scoring of final masses across conic solvers, counted by hand."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from c_library import needs_c_library

from guidance import agreement
from guidance.agreement import (
    CONVERGED,
    REFERENCE,
    VARIANTS,
    Outcome,
    landings,
    same_trajectory,
    score,
    summary_table,
)
from guidance.catalog import SCENARIOS
from guidance.cli import main
from guidance.scenario import scenario_to_dict


def test_same_trajectory_is_issue_3s_figure() -> None:
    ref = Outcome(2.0, 11, "solved")
    assert same_trajectory(Outcome(2.0 * (1 + 0.9e-6), 11, "solved"), ref)
    assert not same_trajectory(Outcome(2.0 * (1 + 1.1e-6), 11, "solved"), ref)
    assert not same_trajectory(Outcome(2.0, 12, "solved"), ref)  # iterations must be equal
    assert not same_trajectory(Outcome(2.0, 11, "max_iterations"), ref)


def test_score_counts_and_gaps() -> None:
    gaps = [0.0, 2e-7, 5e-6, 1e-3]  # two within 1e-6, two beyond
    results = [
        {REFERENCE: Outcome(2.0, 10, "solved"), "C library": Outcome(2.0 * (1 + g), 10, "solved")}
        for g in gaps
    ]
    s = score(results, "C library", REFERENCE)
    assert (s.same, s.total) == (2, 4)
    assert s.median_gap == pytest.approx((2e-7 + 5e-6) / 2)
    assert s.max_gap == pytest.approx(1e-3)


def test_summary_has_every_variant_against_both_baselines() -> None:
    one = {v: Outcome(2.0, 10, "solved") for v in VARIANTS}
    table = summary_table([one, one])
    for v in VARIANTS:
        assert f"| {v} |" in table
    assert table.count("2 of 2") == 2 * (len(VARIANTS) - 2) + 2  # baselines skip themselves
    assert CONVERGED in VARIANTS and REFERENCE in VARIANTS


def test_landings_reject_unknown_catalog_names() -> None:
    with pytest.raises(ValueError, match="nowhere"):
        landings(["nowhere"], 0)
    assert main(["agreement", "--catalog", "nowhere"]) == 2  # bad input, nothing solved
    names = [n for n, _ in landings(["default"], 2)]
    assert names == ["default", "sampled 0", "sampled 1"]


@needs_c_library
def test_cli_on_a_landing_every_solver_resolves(capsys: pytest.CaptureFixture[str]) -> None:
    """`overhead` is determined well below 1e-6 by each solver (measured 3e-8 .. 2.5e-7):
    every variant is the reference's trajectory there, through the command line."""
    assert main(["agreement", "--catalog", "overhead", "--landings", "0", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("overhead"))
    assert "*" not in row, row
    assert out.count("1 of 1") == 2 * (len(VARIANTS) - 2) + 2


@needs_c_library
def test_cli_on_a_scenario_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A user's scenario file alone: one landing named by the file, every variant solved."""
    path = tmp_path / "my_landing.json"
    path.write_text(json.dumps(scenario_to_dict(SCENARIOS["overhead"])))
    assert main(["agreement", str(path), "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "tolerances, 1 landing (subproblems: prox_u = 0.02)\n" in out
    assert out.count("of 1 |") == 2 * (len(VARIANTS) - 2) + 2
    assert any(line.startswith("my_landing") for line in out.splitlines())
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"m0": -1.0}))
    assert main(["agreement", str(bad)]) == 2


@needs_c_library
def test_the_proximal_term_is_what_makes_the_solvers_agree(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`crossing` with the paper's linear objective: Clarabel and the C SOCP stop on different
    points of flat optimal faces and SCvx ends 4.7e-4 apart (measured since 21 Nov); with the
    default proximal term every variant is the reference's trajectory."""
    rows = {}
    for prox in ("0", "0.02"):
        args = ["agreement", "--catalog", "crossing", "--landings", "0", "--workers", "1"]
        assert main([*args, "--prox-u", prox]) == 0
        out = capsys.readouterr().out
        rows[prox] = next(line for line in out.splitlines() if line.startswith("crossing"))
    c_library = rows["0"].split("|")[3]
    assert "*" in c_library, rows["0"]
    assert "*" not in rows["0.02"], rows["0.02"]


# ---- interruption and resume (--run-dir) ----------------------------------------------------
# Two catalog landings and two sampled ones, each "solved" by stand-ins for the variants
# (figures of the scenario: the reference's mass, the others off by 1e-9 k), in this process.
RUN = ["agreement", "--catalog", "overhead", "crossing", "--landings", "2", "--workers", "1"]
SOLVE_LANDING = agreement.solve_landing


def _main(argv: list[str]) -> int:
    """main, with a Ctrl-C escaping it (a traceback and an exit by the signal, before the
    command handled it) failing the test instead of stopping pytest."""
    try:
        return main(argv)
    except KeyboardInterrupt:
        pytest.fail("KeyboardInterrupt escaped guidance's main: a traceback, not exit 130")


def _stand_ins(monkeypatch, stop_at: int | None = None) -> list[int]:
    """The landings solved from now on, in order; the solve after ``stop_at`` of them raises
    KeyboardInterrupt instead, as Ctrl-C during it."""
    for k, variant in enumerate(VARIANTS):
        monkeypatch.setitem(
            VARIANTS,
            variant,
            lambda s, st, k=k: Outcome(s.initial.m0 * (1 + 1e-9 * k), 10 + k % 2, "solved"),
        )
    solved: list[int] = []

    def solve(job):
        if len(solved) == stop_at:  # the landings are solved in their order (--workers 1)
            raise KeyboardInterrupt
        solved.append(job[0])
        return SOLVE_LANDING(job)

    monkeypatch.setattr(agreement, "solve_landing", solve)
    return solved


@needs_c_library
def test_an_interrupted_run_resumes_solving_only_what_is_missing(
    tmp_path: Path, monkeypatch, capsys: pytest.CaptureFixture[str]
) -> None:
    solved = _stand_ins(monkeypatch)
    assert _main(RUN) == 0
    whole = capsys.readouterr().out
    assert solved == [0, 1, 2, 3] and "4 of 4" in whole

    run = [*RUN, "--run-dir", str(tmp_path / "run")]
    solved = _stand_ins(monkeypatch, stop_at=2)
    assert _main(run) == 130
    out, err = capsys.readouterr()
    assert solved == [0, 1] and out == ""
    assert f"interrupted: 2 of 4 landings are kept in {tmp_path / 'run'}; run the same" in err
    solved = _stand_ins(monkeypatch)
    assert _main(run) == 0
    assert solved == [2, 3]
    assert capsys.readouterr().out == whole
    record = json.loads((tmp_path / "run" / "run.json").read_text())
    assert record["landings"] == ["overhead", "crossing", "sampled 0", "sampled 1"]
    assert record["code_versions"] and record["scvx_settings"]["prox_u"] == 0.02


@needs_c_library
def test_a_resume_with_other_landings_or_settings_is_refused(
    tmp_path: Path, monkeypatch, capsys: pytest.CaptureFixture[str]
) -> None:
    run = [*RUN, "--run-dir", str(tmp_path / "run")]
    _stand_ins(monkeypatch, stop_at=0)
    assert _main(run) == 130
    capsys.readouterr()
    for extra, said in (
        (["--landings", "3"], "(different landings, scenarios_sha256)"),
        (["--prox-u", "0"], "(different scvx_settings)"),
    ):
        assert _main([*run, *extra]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: {tmp_path / 'run'} holds landings of another run"), err
        assert said in err, err


@needs_c_library
def test_ctrl_c_without_a_run_directory_says_nothing_was_kept(
    monkeypatch, capsys: pytest.CaptureFixture[str]
) -> None:
    solved = _stand_ins(monkeypatch, stop_at=3)
    assert _main(RUN) == 130
    out, err = capsys.readouterr()
    assert solved == [0, 1, 2] and out == ""
    assert "interrupted: 3 of 4 landings were finished; nothing is kept without --run-dir" in err
