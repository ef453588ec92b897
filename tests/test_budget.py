"""RAD750 budget check (guidance/budget.py): the figures are produced, memory fits with a wide
margin, and the time budget is reported honestly (an expected failure while it does not fit,
with the measured figure in the reason -- never a pretended pass). While it does not fit, a
slower call is caught against QOCO counted in the same run."""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import shutil

import pytest

from guidance import budget

needs_tools = pytest.mark.skipif(
    shutil.which("valgrind") is None or not budget.LIBS[0].exists(),
    reason="valgrind or the built library missing",
)


def test_planning_model_matches_design() -> None:
    # DESIGN.md: 1 s is about 77 million host instructions
    assert budget.rad750_seconds(77e6) == pytest.approx(1.001, abs=1e-3)
    assert budget.rad750_seconds(1e8) == pytest.approx(1.3)


needs_tscvx = pytest.mark.skipif(
    shutil.which("valgrind") is None
    or not budget.LIBS[0].exists()
    or not all(p.exists() for p in budget.NN_MODELS.values()),
    reason="valgrind, the built library or build/models/*.tnn missing (make lib)",
)


@pytest.fixture(scope="module")
def calls() -> list[budget.Budget]:
    """One complete call each: SCvx, T-SCvx warm start, T-SCvx (Algorithm 2)."""
    return budget.measure_variants(do_build=True)


@pytest.fixture(scope="module")
def figures(calls: list[budget.Budget]) -> budget.Budget:
    return calls[0]


@needs_tscvx
def test_figures_are_produced(figures: budget.Budget) -> None:
    assert figures.status == "solved"
    assert figures.instructions > 1e6
    assert figures.code_bytes > 10_000
    assert 0 < figures.arena_high_water <= figures.arena_bytes
    assert 0 < figures.stack_high_water < 1 << 20
    # memory counts the static worst case, which covers the painted high-water
    assert figures.stack_high_water <= figures.stack_bound < 1 << 16
    assert figures.heap_allocations_in_solve == 0
    text = budget.report(figures)
    for item in ("RAD750-equivalent time", "guidance arena", "stack, static worst case",
                 "high-water of this call", "1.3 x"):  # fmt: skip
        assert item in text
    _check_parts(figures)
    # the SOCP runtime's work outside its solves is its own part, not hidden in "rest"
    parts = figures.instructions_by_part
    assert parts["socp_data_update"] > 0 and parts["socp_warm_start"] > 0
    assert parts["rest"] < parts["socp_solve"] / 20
    assert "rest: subproblem assembly" in text


def _check_parts(c: budget.Budget) -> None:
    """The named parts are disjoint pieces of the call: each counted, together within it
    ("rest" is what they leave, so a part counted twice would make it negative)."""
    parts = c.instructions_by_part
    assert min(parts.values()) >= 0, parts
    assert sum(v for k, v in parts.items() if k != "rest") <= c.instructions
    assert parts["socp_solve"] > c.instructions / 2  # the conic solves are most of the call


@needs_tscvx
def test_memory_within_budget_with_margin(figures: budget.Budget) -> None:
    assert figures.memory_bytes <= budget.MEMORY_BUDGET_B / 4  # 15 MB of 60


needs_qoco = pytest.mark.skipif(
    importlib.util.find_spec("qoco") is None, reason="QOCO (the bench extra) not installed"
)


@pytest.fixture(scope="module")
def qoco_subproblem() -> tuple[int, int]:
    """Instructions of this runtime and of QOCO (callgrind, this run) on the flight call's
    first subproblem: the default landing from the built-in guess, with the proximal term."""
    from guidance import bench_socp
    from guidance.params import SCvxSettings

    prob = bench_socp.landing_set(limit=1, prox_u=SCvxSettings().prox_u)[0]
    ours = bench_socp.instructions_ours(prob, flops=False)
    qoco = bench_socp.instructions_qoco(prob)
    assert ours is not None and qoco is not None, "callgrind gave no count"
    return ours.instructions, qoco.instructions


@needs_tscvx
@needs_qoco
def test_a_subproblem_costs_fewer_instructions_than_qoco(
    qoco_subproblem: tuple[int, int],
) -> None:
    """Issue 3 asks for a fifth of QOCO's count (27 Nov: 1/2.3, `make bench`); this guards
    what is reached, with room for the other machine's compiler."""
    ours, qoco = qoco_subproblem
    assert ours < qoco, f"{ours / 1e6:.1f} M instructions against QOCO's {qoco / 1e6:.1f} M"


@needs_tscvx
@needs_qoco
def test_a_guidance_call_costs_less_than_qoco_on_its_subproblems(
    calls: list[budget.Budget], qoco_subproblem: tuple[int, int]
) -> None:
    """The time budget is not met (the expected failures below), so these keep a slower call
    from passing unnoticed: each call, discretization, assembly and networks included, costs
    less than QOCO would on its subproblems alone (27 Nov: 2.4 to 2.8 times less)."""
    _, qoco = qoco_subproblem
    for c in calls:
        assert c.instructions < c.subproblems * qoco, (
            f"{c.variant}: {c.instructions / 1e6:.0f} M instructions for {c.subproblems} "
            f"subproblems; QOCO takes {qoco / 1e6:.0f} M on one"
        )


@needs_tscvx
@pytest.mark.parametrize("variant", list(budget.VARIANTS))
def test_time_within_budget(calls: list[budget.Budget], variant: str) -> None:
    figures = {c.variant: c for c in calls}[variant]
    if not figures.within_time():
        parts = ", ".join(f"{k} {v / 1e6:.0f} M" for k, v in figures.instructions_by_part.items())
        pytest.xfail(
            f"{variant} over the RAD750 time budget: {figures.instructions / 1e6:.0f} M "
            f"instructions = {figures.rad750_s:.1f} s RAD750-equivalent (budget 1 s); {parts}"
        )
    assert figures.rad750_s <= budget.TIME_BUDGET_S


# ---- the complete on-board T-SCvx call (pdg_solve_tscvx), network inference included --------


@needs_tscvx
def test_tscvx_call_figures_are_produced(calls: list[budget.Budget]) -> None:
    assert [c.variant for c in calls] == list(budget.VARIANTS)
    text = budget.report_variants(calls)
    print("\n" + text)
    scvx, warm, alg2 = calls
    weights = {k: p.stat().st_size for k, p in budget.NN_MODELS.items()}
    for c in calls:
        assert c.status == "solved"
        assert c.instructions > 1e6
        assert c.heap_allocations_in_solve == 0
        assert 0 < c.arena_high_water <= c.arena_bytes
        assert 0 < c.stack_high_water <= c.stack_bound < 1 << 20
        _check_parts(c)
        assert c.variant in text
        assert c.result_bytes == 8 * 50 * (14 + 3)  # x and u of the default N = 50
    # the arena the call is given is the one the library sizes for the default landing (the
    # Python bindings ask it the same way); its high-water mark cannot pass it
    from guidance.cguidance import workspace
    from guidance.params import Scenario

    assert scvx.arena_bytes == workspace(Scenario()).arena_bytes
    assert scvx.nn_weights_bytes == scvx.nn_arena_bytes == 0
    assert scvx.instructions_by_part.get("network_inference", 0) == 0
    # the networks the call runs: their weights (in place) and arenas are in its memory
    assert warm.nn_weights_bytes == weights["solution"]
    assert alg2.nn_weights_bytes == weights["solution"] + weights["constraint"]
    assert 0 < warm.nn_arena_bytes < alg2.nn_arena_bytes < 1 << 20
    # network inference is counted inside the call: one solution inference, and one
    # constraint inference per iteration k (a rejected step reuses its k's logits)
    nn_warm = warm.instructions_by_part["network_inference"]
    nn_alg2 = alg2.instructions_by_part["network_inference"]
    assert 1e6 < nn_warm < budget.NN_INSTRUCTION_BUDGET
    assert nn_alg2 > nn_warm + alg2.iterations * 1e6
    for item in ("RAD750 s", "memory", "of which NN", "host instr."):
        assert item in text


@needs_tscvx
def test_tscvx_call_memory_within_budget(calls: list[budget.Budget]) -> None:
    for c in calls:
        assert c.within_memory(), f"{c.variant}: {c.memory_bytes / 2**20:.1f} MB"
        assert c.memory_bytes <= budget.MEMORY_BUDGET_B / 2  # 30 MB of 60, weights included
    report = budget.report(calls[-1])
    assert "network weights" in report and "pdg_solve_tscvx" in report
    # the flight image with both networks is the Algorithm 2 call's own total (its stack)
    line = budget.report_networks([], calls[-1]).splitlines()[-1]
    assert line.startswith("  flight image with both networks (T-SCvx (Algorithm 2))")
    assert line.endswith(f"= {budget._mb(calls[-1].memory_bytes).strip()} of 60.000 MiB")


def test_guidance_budget_takes_the_tool_s_options() -> None:
    """`guidance budget --no-build --json` reaches the budget tool (the CLI used to refuse
    every option; only `python -m guidance.budget` took them)."""
    from guidance.cli import build_parser, cmd_budget

    args = build_parser().parse_args(["budget", "--no-build", "--json"])
    assert args.func is cmd_budget and args.no_build and args.json and not args.check_noalloc


@needs_tscvx
def test_another_grid_is_measured_as_asked(figures: budget.Budget) -> None:
    """`--nodes 5`: the driver solves the default landing on 5 nodes (the C library through
    Python finds the same final mass on that grid), for less time and memory than at 50."""
    from guidance.cguidance import solve_c
    from guidance.params import Params, Scenario

    row = budget.measure(do_build=False, nodes=5)
    assert (row.nodes, row.status, row.heap_allocations_in_solve) == (5, "solved", 0)
    assert row.result_bytes == 8 * 5 * (14 + 3)
    assert row.m_f == pytest.approx(solve_c(Scenario(params=Params(N=5))).m_f, rel=1e-11)
    assert figures.nodes == 50
    assert row.instructions < figures.instructions / 3
    assert row.arena_bytes < figures.arena_bytes / 3
    text = budget.report_grids([row, figures])
    assert "\n     5         solved" in text and "\n    50         solved" in text


def test_a_grid_outside_the_solvers_range_is_refused() -> None:
    from guidance.cli import build_parser

    ap = build_parser()
    assert ap.parse_args(["budget", "--nodes", "3", "400"]).nodes == [3, 400]
    for bad in ("2", "401", "x", "5.0"):
        with pytest.raises(SystemExit) as exc:
            ap.parse_args(["budget", "--nodes", bad])
        assert exc.value.code == 2


@pytest.mark.skipif(not budget.DRIVER.exists(), reason="make budget builds the driver")
def test_the_driver_refuses_a_grid_outside_the_range() -> None:
    import subprocess

    for bad in ("2", "401", "12x"):
        out = subprocess.run([str(budget.DRIVER), "--nodes", bad], capture_output=True, text=True)
        assert out.returncode == 1
        assert f"--nodes {bad}: N must be an integer in [3, 400]" in out.stderr
    # an option without its value, or unknown, is refused too (it ran N = 50 without a word)
    for argv, said in ((["--nodes"], "--nodes: needs a value"),
                       (["--node", "20"], "--node: unknown option")):  # fmt: skip
        out = subprocess.run([str(budget.DRIVER), *argv], capture_output=True, text=True)
        assert out.returncode == 1 and said in out.stderr


# ---- network inference (tscvx_nn_run), issue 5's 5 M instructions per inference -------------

needs_nets = pytest.mark.skipif(
    shutil.which("valgrind") is None or not all(p.exists() for p in budget.NN_MODELS.values()),
    reason="valgrind or build/models/*.tnn missing (make lib)",
)


@pytest.fixture(scope="module")
def nets() -> list[budget.NetBudget]:
    return budget.measure_networks(do_build=True)


@needs_nets
def test_network_inference_within_5M_instructions(nets: list[budget.NetBudget]) -> None:
    assert [n.name for n in nets] == ["constraint", "solution"]
    text = budget.report_networks(nets)
    print("\n" + text)
    for n in nets:
        figure = (
            f"{n.name} network: {n.instructions / 1e6:.3f} M host instructions per inference "
            f"= {n.rad750_s * 1e3:.1f} ms RAD750-equivalent (budget "
            f"{budget.NN_INSTRUCTION_BUDGET / 1e6:.0f} M)"
        )
        print(figure)
        assert n.instructions > 1e5, figure
        # the figure itself, not only within_budget() (which a `return True` passed here)
        assert n.instructions <= budget.NN_INSTRUCTION_BUDGET, figure
        assert n.rad750_s == pytest.approx(budget.rad750_seconds(n.instructions), rel=1e-12)
        assert n.within_budget(), figure
        assert n.name in text and "RAD750 ms" in text


@needs_nets
def test_network_memory_and_no_allocation(nets: list[budget.NetBudget]) -> None:
    for n in nets:
        assert n.heap_allocations_in_run == 0
        assert 0 < n.arena_bytes < 1 << 20 and 0 < n.stack_high_water <= n.stack_bound < 16384
        assert n.weights_bytes == budget.NN_MODELS[n.name].stat().st_size
        # weights in place + arena + stack, well within the 60 MB of the whole flight image
        assert n.memory_bytes < budget.MEMORY_BUDGET_B / 4


def _budget_with_memory(total: int) -> budget.Budget:
    """A report whose memory parts add up to ``total`` bytes."""
    parts = {
        "code_bytes": 3_000_000,
        "const_data_bytes": 200_000,
        "arena_high_water": 0,
        "stack_bound": 50_000,
        "nn_weights_bytes": 400_000,
        "nn_arena_bytes": 10_000,
    }
    parts["arena_high_water"] = total - sum(parts.values())
    return budget.Budget(
        status="solved", iterations=10, subproblems=12, socp_iterations=200, m_f=2.2,
        instructions=50_000_000, instructions_by_part={}, rad750_s=0.65,
        arena_bytes=parts["arena_high_water"], heap_allocations_in_solve=0, host_wall_s=0.1,
        stack_high_water=40_000,  # measured, not counted: the bound is
        **parts,
    )  # fmt: skip


def test_memory_budget_is_60_mb() -> None:
    """DESIGN.md: 60 MB = 60 x 2^20 bytes, all memory parts counted (the stack at its static
    bound, not at one call's painted high-water)."""
    limit = 60 * 1024 * 1024
    at = _budget_with_memory(limit)
    assert at.memory_bytes == limit and at.within_memory()
    assert _budget_with_memory(limit - 1).within_memory()
    assert not _budget_with_memory(limit + 1).within_memory()
    assert not _budget_with_memory(limit + limit // 2).within_memory()  # 90 MB


def test_the_time_budget_is_one_rad750_second() -> None:
    """within_time() decides whether test_time_within_budget fails or is an expected failure.
    While every call is far over budget (27 to 34 s RAD750-equivalent, docs/budget.md) that
    test cannot tell a within_time() that never says yes (`return False`: an expected failure
    either way, nothing else noticed), so the boundary is checked here: 1 s = 1e8 / 1.3."""
    at = dataclasses.replace(_budget_with_memory(10_000_000), rad750_s=1.0)
    assert at.within_time() and dataclasses.replace(at, rad750_s=0.25).within_time()
    assert not dataclasses.replace(at, rad750_s=math.nextafter(1.0, 2.0)).within_time()
    assert not dataclasses.replace(at, rad750_s=30.0).within_time()
    assert at.instruction_budget == pytest.approx(1e8 / 1.3, rel=1e-12)


def test_the_network_budget_is_5m_instructions() -> None:
    """Issue 5: 5 M host instructions per inference, that count included."""
    net = budget.NetBudget(
        name="constraint", architecture="single", instructions=5_000_000,
        rad750_s=budget.rad750_seconds(5e6), weights_bytes=1, arena_bytes=1,
        stack_high_water=1, heap_allocations_in_run=0, host_wall_s=0.0,
    )  # fmt: skip
    assert net.within_budget()
    assert not dataclasses.replace(net, instructions=5_000_001).within_budget()


def test_a_driver_older_than_the_tool_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """`guidance budget --no-build` with a driver built before a figure was added: a clear
    error saying to rebuild, not a KeyError from inside the report."""
    import subprocess

    old = "\n".join(f"{k} 1" for k in budget.DRIVER_KEYS if k != "result_bytes")

    def fake_run(*args: object, **kwargs: object) -> subprocess.CompletedProcess:
        return subprocess.CompletedProcess(args, 0, stdout=old + "\n", stderr="")

    monkeypatch.setattr(budget.subprocess, "run", fake_run)
    with pytest.raises(RuntimeError, match=r"printed no result_bytes.*rebuild it"):
        budget._run_driver()


@pytest.mark.skipif(not budget.LIBS[0].exists(), reason="make lib builds the library")
def test_the_json_figures_name_the_binaries_measured() -> None:
    """`guidance budget --json` carries the code version and the sha256 of the libraries, the
    driver and the networks it measured."""
    import hashlib

    from guidance.provenance import code_version

    prov = budget.measured_files()
    assert prov["generator"] == code_version()
    files = prov["files"]
    assert isinstance(files, dict)
    lib = budget.LIBS[0]
    assert files[lib.name] == {
        "path": str(lib),
        "sha256": hashlib.sha256(lib.read_bytes()).hexdigest(),
    }
    assert {p.name for p in budget.NN_MODELS.values() if p.exists()} <= set(files)


# ---- a landing other than the default, and the campaign (--landings K) ---------------------

needs_driver = pytest.mark.skipif(
    not budget.DRIVER.exists() or not all(p.exists() for p in budget.NN_MODELS.values()),
    reason="make budget builds the driver; make lib the networks",
)


def _fnv1a(x: object, u: object) -> str:
    """The driver's solution_fnv1a, computed here: FNV-1a over x then u, each double's bytes
    least significant first."""
    import numpy as np

    h = 0xCBF29CE484222325
    for a in (x, u):
        for byte in np.ascontiguousarray(a, dtype="<f8").tobytes():
            h = ((h ^ byte) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


@needs_driver
def test_the_driver_solves_the_landing_given_on_its_command_line() -> None:
    from guidance.bench_tscvx import sample_landings
    from guidance.cguidance import solve_c, solve_tscvx_c

    default = budget._run_driver("SCvx", repeat=1)
    scenario = sample_landings(2)[1]
    arg = budget.landing_arg(scenario)
    # the same landing through the library's Python binding: an independent path to the call
    for variant, ref in (
        ("SCvx", solve_c(scenario)),
        ("T-SCvx (Algorithm 2)", solve_tscvx_c(scenario, masks=True)),
    ):
        kv = budget._run_driver(variant, landing=arg, repeat=1)
        assert kv["status"] == ref.status == "solved"
        assert int(kv["iterations"]) == ref.iterations
        assert int(kv["subproblems"]) == ref.subproblems_solved
        assert float(kv["m_f"]) == pytest.approx(ref.m_f, abs=1e-12)
        assert kv["solution_fnv1a"] == _fnv1a(ref.x, ref.u)  # the same answer, to the bit
        assert kv["solution_fnv1a"] != default["solution_fnv1a"]


@needs_driver
def test_the_driver_refuses_a_bad_argument_with_its_usage() -> None:
    import subprocess

    from guidance.params import Scenario
    from guidance.sampling import theta_of

    good = [repr(float(v)) for v in theta_of(Scenario())]
    light = [*good[:13], "1.5", *good[14:]]  # m0 below the dry mass: the library refuses it
    bad = {
        ("--landing", ",".join(good[:15])): "--landing",  # 15 numbers
        ("--landing", ",".join([*good, "1"])): "--landing",  # 17
        ("--landing", ",".join(good) + ","): "--landing",
        ("--landing", ",".join(good).replace(",", ",,", 1)): "--landing",
        ("--landing", ",".join(good).replace(",", ", ", 1)): "--landing",
        ("--landing", ",".join(["4x", *good[1:]])): "--landing",
        ("--landing", ",".join(["nan", *good[1:]])): "--landing",
        ("--landing", ",".join(["1e999", *good[1:]])): "--landing",
        ("--landing", ""): "--landing",
        ("--landing", ",".join(light)): "scenario field 'm0'",
        ("--landing",): "--landing: needs a value",
        ("--repeat", "0"): "--repeat 0: R must be",
        ("--repeat", "3x"): "--repeat 3x: R must be",
        ("--repeat", "1001"): "--repeat 1001: R must be",
        ("--nodes", "12x"): "--nodes 12x: N must be",
        ("--masks", "x.tnn"): "--masks needs --tscvx",
        ("--landings", "2"): "--landings: unknown option",
    }
    for argv, said in bad.items():
        out = subprocess.run([str(budget.DRIVER), *argv], capture_output=True, text=True)
        assert out.returncode == 1, argv
        assert said in out.stderr and "usage: pdg_budget_driver" in out.stderr, argv
        assert out.stdout == "", argv  # no call made
    # the default landing's own numbers, given on the command line, are the default landing
    given = budget._run_driver("SCvx", landing=",".join(good), repeat=1)
    assert given["solution_fnv1a"] == budget._run_driver("SCvx", repeat=1)["solution_fnv1a"]


def test_campaign_options_are_refused_where_they_do_not_apply() -> None:
    from guidance.cli import build_parser
    from guidance.errors import InputError

    ap = build_parser()
    args = ap.parse_args(["budget", "--landings", "3", "--seed", "7"])
    assert (args.landings, args.seed) == (3, 7)
    refused = (
        (["--seed", "7"], "--seed"),
        (["--landings", "2", "--nodes", "20"], "--nodes"),
        (["--landings", "2", "--check-noalloc"], "--check-noalloc"),
    )
    for argv, said in refused:
        with pytest.raises(InputError, match=said):
            budget.run(ap.parse_args(["budget", "--no-build", *argv]))
    for bad in ("0", "x"):
        with pytest.raises(SystemExit):
            ap.parse_args(["budget", "--landings", bad])


def _call(
    variant: str, instructions: int, status: str = "solved", arena: int = 100
) -> budget.Budget:
    return budget.Budget(
        status=status, iterations=10, subproblems=20, socp_iterations=200, m_f=2.2,
        instructions=instructions, instructions_by_part={},
        rad750_s=budget.rad750_seconds(instructions), code_bytes=1000, const_data_bytes=10,
        arena_bytes=arena, arena_high_water=arena - 1, stack_high_water=50,
        heap_allocations_in_solve=0, host_wall_s=0.5, variant=variant, stack_bound=60,
    )  # fmt: skip


def _landing(index: int, scvx: int, warm: int, alg2: int, **kw: object) -> budget.CampaignLanding:
    names = list(budget.VARIANTS)
    return budget.CampaignLanding(
        index, [0.0] * 16,
        [_call(names[0], scvx), _call(names[1], warm), _call(names[2], alg2, **kw)],  # type: ignore[arg-type]
    )  # fmt: skip


def test_the_campaign_spread_is_computed_landing_by_landing() -> None:
    M = 10**6
    # two landings (K = 2): the median is their mean, the 90th percentile and the largest the
    # larger; the ratio pairs each landing with its own SCvx call
    rows = [
        _landing(0, 2000 * M, 1000 * M, 3000 * M),
        _landing(1, 1000 * M, 1500 * M, 1000 * M, status="max_iterations"),
    ]
    scvx, warm, alg2 = budget.campaign_spread(rows)
    assert scvx.median_s == pytest.approx(budget.rad750_seconds(1500 * M))
    assert scvx.p90_s == scvx.max_s == pytest.approx(budget.rad750_seconds(2000 * M))
    assert scvx.largest_landing == 0 and warm.largest_landing == 1 and alg2.largest_landing == 0
    assert scvx.ratio_median is None
    assert (warm.ratio_min, warm.ratio_median, warm.ratio_max) == pytest.approx((0.5, 1.0, 1.5))
    assert (alg2.ratio_min, alg2.ratio_median, alg2.ratio_max) == pytest.approx((1.0, 1.25, 1.5))
    assert scvx.statuses == {"solved": 2} and alg2.statuses == {"solved": 1, "max_iterations": 1}
    assert scvx.memory_fixed and alg2.memory_fixed
    # five landings: the 90th percentile by nearest rank is the 5th value, the median the 3rd;
    # the largest is named by its landing's index in the draw
    times = [5, 1, 4, 2, 3]
    rows = [_landing(10 + i, t * M, t * M, t * M, arena=100 + i) for i, t in enumerate(times)]
    rows[3].calls[0] = _call("SCvx", 9 * M)
    scvx, warm, alg2 = budget.campaign_spread(rows)
    assert scvx.median_s == pytest.approx(budget.rad750_seconds(4 * M))
    assert scvx.p90_s == scvx.max_s == pytest.approx(budget.rad750_seconds(9 * M))
    assert scvx.largest_landing == 13 and warm.largest_landing == 10
    assert warm.median_s == pytest.approx(budget.rad750_seconds(3 * M))
    assert warm.ratio_min == pytest.approx(2 / 9) and warm.ratio_max == 1.0
    assert not alg2.memory_fixed and alg2.arena_bytes == (100, 104) and scvx.memory_fixed
    text = budget.report_campaign(rows, seed=7)
    assert "5 landings" in text and "seed 7" in text
    assert "varies with the landing" in text and "the same on every landing" in text
    with pytest.raises(ValueError):
        budget.campaign_spread([])


@needs_driver
def test_a_campaign_measures_the_sampled_landings(monkeypatch: pytest.MonkeyPatch) -> None:
    """K = 2 end to end, the driver run natively on each landing and variant; callgrind is
    replaced by a count the test knows (1 M per IPM iteration) to keep it fast."""
    from guidance.bench_tscvx import sample_landings

    asked: list[str | None] = []

    def fake_count(variant: str, nodes: int | None = None, landing: str | None = None):
        asked.append(landing)
        kv = budget._run_driver(variant, landing=landing, repeat=1)
        return int(kv["socp_iterations"]) * 10**6, {}

    monkeypatch.setattr(budget, "count_instructions", fake_count)
    monkeypatch.setattr(budget, "static_stack", lambda function, measured: measured)
    rows = budget.measure_campaign(2, seed=5, progress=False)
    args = [budget.landing_arg(s) for s in sample_landings(2, seed=5)]
    assert asked == [args[0]] * 3 + [args[1]] * 3
    ipm = [[c.socp_iterations for c in r.calls] for r in rows]
    assert all(c.instructions == c.socp_iterations * 10**6 for r in rows for c in r.calls)
    spreads = budget.campaign_spread(rows)
    for j, v in enumerate(spreads):
        col = [ipm[0][j], ipm[1][j]]
        assert v.max_s == pytest.approx(budget.rad750_seconds(max(col) * 10**6))
        assert v.median_s == pytest.approx(budget.rad750_seconds(sum(col) / 2 * 10**6))
        assert v.largest_landing == col.index(max(col))
        assert v.memory_fixed  # arena and stack bound fixed by N
        if j:
            r = sorted(ipm[i][j] / ipm[i][0] for i in range(2))
            assert (v.ratio_min, v.ratio_max) == pytest.approx((r[0], r[1]))
