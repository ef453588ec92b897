"""`guidance bench`'s comparison with the reference (guidance/bench.py): the speed-up is the
ratio of mean wall times over the scenarios both backends ran, "same trajectory" is
issue 3's figure, and the C library's line says whether issue 4's target is met."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from guidance.bench import TARGET_SECONDS, TARGET_SPEED_UP, against_reference


@dataclass(frozen=True)
class Run:  # what the comparison reads of an SCvxResult
    status: str
    iterations: int
    m_f: float
    solve_time_s: float


def _runs(times: list[float], m_f: float = 2.0, iterations: int = 14) -> dict[str, Run]:
    return {f"s{i}": Run("solved", iterations, m_f, t) for i, t in enumerate(times)}


def _verdict(lines: list[str]) -> str:
    return next(line for line in lines if "issue 4" in line)


def _row(lines: list[str], backend: str) -> list[str]:
    return next(line.split() for line in lines if line.startswith(backend + " "))


def test_speed_up_is_the_ratio_of_mean_times_and_the_target_is_judged() -> None:
    ref = _runs([0.6, 0.7, 1.4])
    slow = _runs([0.15, 0.2, 0.25])  # means 0.9 s and 0.2 s (medians 0.7 and 0.2)
    lines = against_reference({"clarabel": ref, "c": slow})
    row = _row(lines, "c")
    assert row[1:4] == ["3", "of", "3"]
    assert float(row[4]) == pytest.approx(0.2)
    assert row[5] == "4.50x"  # not the median ratio 4.00x nor the ratio of medians 3.50x
    # each figure says which statistic it is: the ratio of means beside the median time
    assert _verdict(lines).endswith(
        "this run 4.500x (ratio of means) and 0.2000 s (median): not met"
    )
    legend = next(line for line in lines if "speed-up:" in line)
    assert "median[s]: the backend's median" in legend and "ratio of means" in legend
    fast = _runs([t / (TARGET_SPEED_UP + 1) for t in (0.6, 0.7, 0.8)])  # 31x, 23 ms
    assert float(fast["s1"].solve_time_s) < TARGET_SECONDS
    assert _verdict(against_reference({"clarabel": ref, "c": fast})).endswith(": met")
    # fast enough relative to the reference, but not under the absolute time
    slow_ref = _runs([3.0, 3.5, 4.0])
    too_slow = _runs([0.09, 0.1, 0.11])
    assert _verdict(against_reference({"clarabel": slow_ref, "c": too_slow})).endswith("not met")


def test_same_trajectory_needs_the_final_mass_to_1e_6_and_the_iterations() -> None:
    ref = _runs([0.6, 0.7, 0.8, 0.9])
    other = dict(ref)
    other["s0"] = Run("solved", 14, 2.0 * (1 + 2e-6), 0.2)  # final mass 2e-6 apart
    other["s1"] = Run("solved", 15, 2.0, 0.2)  # one iteration more
    other["s2"] = Run("infeasible", 14, 2.0, 0.2)
    other["s3"] = Run("solved", 14, 2.0 * (1 + 5e-7), 0.2)  # within 1e-6: the same
    lines = against_reference({"clarabel": ref, "c-socp": other})
    assert _row(lines, "c-socp")[1:4] == ["1", "of", "4"]
    assert not any("issue 4" in line for line in lines)  # the target is the C library's


def test_nothing_to_compare_without_the_reference_or_another_backend() -> None:
    runs = _runs([0.1, 0.2])
    assert against_reference({"c": runs}) == []
    assert against_reference({"clarabel": runs}) == []
    assert against_reference({"clarabel": runs, "c": {}}) == []


def test_backends_take_turns_on_each_scenario(monkeypatch: pytest.MonkeyPatch) -> None:
    """`guidance bench` solves each scenario on every backend in turn (and repeat), not one
    backend's phase after another's: a slow spell of a shared machine then meets every
    backend alike, and the speed-up is measured in pairs. The best time of the repeats is
    kept."""
    import guidance.api
    from guidance import bench
    from guidance.catalog import SCENARIOS

    calls: list[tuple[str, str]] = []
    clock = iter(range(10_000))

    def fake_solve(scenario: object, method: str, backend: str, settings: object) -> Run:
        name = next(n for n, s in SCENARIOS.items() if s is scenario)
        calls.append((name, backend))
        return Run("solved", 14, 2.0, 1.0 / (1 + next(clock)))  # later solves faster

    monkeypatch.setattr(guidance.api, "solve", fake_solve)
    results, failures = bench.solve_interleaved(["clarabel", "c"], repeats=2, method="scvx")
    assert failures == {}
    names = list(SCENARIOS)
    expected = [(n, b) for n in names for _ in range(2) for b in ("clarabel", "c")]
    assert calls == expected
    # the second repeat is the faster one: its time is kept
    assert results["c"][names[0]].solve_time_s == pytest.approx(1.0 / 4)
    assert list(results["clarabel"]) == names


@dataclass(frozen=True)
class _Step:  # what the table reads of an iteration
    subproblem_time_s: float = 0.02


@dataclass(frozen=True)
class _Solved(Run):  # what the per-backend table reads of an SCvxResult
    subproblems_solved: int = 20
    t_f: float = 6.9
    history: tuple[_Step, ...] = (_Step(),)


def test_a_failing_backend_leaves_the_others_figures(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A backend that raises (its library not built) leaves the rotation; the others' tables
    are printed, and the command still fails, naming the backend and the scenario."""
    import guidance.api
    from guidance import bench
    from guidance.catalog import SCENARIOS

    def fake_solve(scenario: object, method: str, backend: str, settings: object) -> _Solved:
        if backend == "c":
            raise RuntimeError("C library not built")
        return _Solved("solved", 14, 2.0, 0.5)

    monkeypatch.setattr(guidance.api, "solve", fake_solve)
    with pytest.raises(RuntimeError, match=f"backend c failed on scenario {next(iter(SCENARIOS))}"):
        bench.run_scvx_bench(["clarabel", "c"])
    out = capsys.readouterr().out
    assert "backend: clarabel" in out and "backend: c\n" not in out
