"""RAD750 budget check of one complete guidance call (DESIGN.md, "The RAD750 budget model").

    python -m guidance.budget [--no-build] [--json] [--check-noalloc] [--nodes N [N ...]]
                              [--landings K [--seed S]]

Builds ``build/pdg_budget_driver`` (c_runtime/examples/pdg_budget_driver.c: the default
scenario, workspace set up before the measured call, then one ``pdg_solve``), and measures:

- time: host instructions of ``pdg_solve`` counted by ``valgrind --tool=callgrind
  --toggle-collect=pdg_solve``; RAD750-equivalent seconds = 1.3 x instructions /
  (0.5 x 200e6) (RISC expansion 1.3, 0.5 instructions per cycle at 200 MHz). Budget 1 s.
- memory: code + static data (``size`` of the static libraries the flight image links:
  libtscvx_gnc.a, libtscvx.a and SuiteSparse's libamd.a, libldl.a, libsuitesparseconfig.a;
  libc/libm are the flight OS's) + the guidance arena as reserved (the size query's answer;
  the library's high-water report is printed beside it) + the static worst-case stack bound
  of the call (guidance/stack_bound.py: GCC's frames over the call graph, no recursion; the
  stack high-water measured by painting in the driver is printed beside it, and must not
  exceed it) + the caller's answer arrays x and u at N. Budget:
  DESIGN.md's 60 MB of SRAM, read as 60 MiB (2^20 bytes, as memory parts are sized); every
  figure printed in MiB.

The driver also counts heap allocations inside the call (malloc interposition): it must be 0.

Grids: ``--nodes N [N ...]`` measures the SCvx call of the same landing on N nodes instead,
one row per grid (the trade of RAD750 time and memory against the grid's resolution); the
T-SCvx and network rows need the networks' N = 50 and are not measured then.

T-SCvx rows: the same driver with ``--tscvx build/models/solution.tnn [--masks
build/models/constraint.tnn]`` measures one complete on-board T-SCvx call (``pdg_solve_tscvx``:
solution-network inference, projection of the prediction, SCvx from the reduced radius 0.01,
and with masks one constraint-network inference per iteration), counted with
``--toggle-collect=pdg_solve_tscvx``, network inference included; its memory adds the weight
blobs (read in place) and the network arenas. The comparison table puts SCvx, T-SCvx (warm
start) and T-SCvx (Algorithm 2, masks) side by side in the same columns.

Campaign: ``--landings K [--seed S]`` measures, after the default landing, K landings drawn
from the networks' training distribution by the T-SCvx benchmark's sampler
(bench_tscvx.sample_landings: guidance/sampling.py's ranges, each turned about the up axis; its
seed by default, so none was trained on, and the same landings as the first K of ``guidance
dispersion``'s), each given to the driver with ``--landing`` and measured as above in all three
variants. Per variant it reports the median, the 90th percentile (nearest rank: a landing's
figure) and the largest RAD750-equivalent time and which landing took it, the statuses, the
T-SCvx / SCvx ratio of instructions landing by landing (median and range), and the memory
over the landings (the arena and the stack bound are fixed by N and the networks; the report
says whether anything varied). A timing budget is judged on a campaign's worst case, and the
default landing lies outside the training distribution.

Network rows: ``build/nn_budget_driver`` (c_runtime/nn/tests/nn_budget_driver.c) runs one
``tscvx_nn_run`` of each shipped network (build/models/*.tnn, the default scenario's theta,
k = 1), counted with ``--toggle-collect=tscvx_nn_run``; budget 5 M host instructions per
inference (issue 5). Memory: the weight file (read in place) + the net's arena + the static
stack bound of the call (its painted high-water beside it).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from guidance import callgrind, stack_bound
from guidance.argtypes import at_least
from guidance.errors import InputError, LibraryNotBuiltError
from guidance.nn.conventions import CONSTRAINT, KINDS, SOLUTION, TNN_SUFFIX, network_file
from guidance.params import N_MAX, N_MIN, Params, Scenario
from guidance.paths import BUILD_DIR, ROOT

DRIVER = BUILD_DIR / "pdg_budget_driver"
LIBS = [BUILD_DIR / "libtscvx_gnc.a", BUILD_DIR / "libtscvx.a"]
SUITESPARSE = ["libamd.a", "libldl.a", "libsuitesparseconfig.a"]
SYSTEM_LIB_DIRS = [Path("/usr/lib/x86_64-linux-gnu"), Path("/usr/lib")]

# The planning model (DESIGN.md). Printed with every report.
RISC_EXPANSION = 1.3
IPC = 0.5
CLOCK_HZ = 200e6
TIME_BUDGET_S = 1.0
MEMORY_BUDGET_B = 60 * 2**20
# Networks (tscvx_nn.h): one inference each; 5 M host instructions per inference (issue 5).
NN_DRIVER = BUILD_DIR / "nn_budget_driver"
NN_MODELS = {kind: BUILD_DIR / "models" / network_file(kind, TNN_SUFFIX) for kind in KINDS}
NN_INSTRUCTION_BUDGET = 5_000_000
# Planning estimate of host (x86-64) instructions per multiply-accumulate of the C inference
# (c_runtime/nn, scalar double code), calibrated on its callgrind count: 2.8 to 2.9 on the
# networks of the first shipped set (3.22 M for 1.14 M MACs, 3.69 M for 1.27 M). It ranks the
# candidates at export (guidance export); the model card prints the callgrind count of the
# shipped files.
INSTR_PER_MAC = 3.0
NN_CONSTRAINT_CALLS = 20  # T-SCvx: one mask per SCvx iteration, iter_max = 20 (Table 1)


# The driver's exit codes for a call made: 0 solved, 3 another status (printed, and judged by
# the report); 1 is a failure before the call.
DRIVER_OK = (0, 3)
# The figures every driver run prints (``key value`` lines)
DRIVER_KEYS = ("nodes", "status", "iterations", "subproblems", "socp_iterations", "m_f",
               "arena_bytes", "arena_high_water", "stack_high_water",
               "heap_allocations_in_solve", "wall_s_min", "result_bytes")  # fmt: skip
# The parts of a guidance call: function (inclusive cost) -> key in the report. The SOCP
# runtime's work outside its solves is its own parts: each subproblem's new numbers
# (tscvx_update_data, with their Ruiz equilibration) and the warm start's point.
PARTS = {"tscvx_solve": "socp_solve", "tscvx_update_data": "socp_data_update",
         "tscvx_warm_start": "socp_warm_start", "discretize": "discretization",
         "tscvx_nn_run": "network_inference"}  # fmt: skip
# What the report's "rest" is: the call less the parts above.
REST = "rest: subproblem assembly, SCvx's decisions, reading answers"

VARIANTS = {  # name -> (driver arguments, function counted by callgrind)
    "SCvx": ([], "pdg_solve"),
    "T-SCvx warm start": (["--tscvx", "{solution}"], "pdg_solve_tscvx"),
    "T-SCvx (Algorithm 2)": (["--tscvx", "{solution}", "--masks", "{constraint}"],
                             "pdg_solve_tscvx"),
}  # fmt: skip


@dataclass
class Budget:
    status: str
    iterations: int
    subproblems: int
    socp_iterations: int
    m_f: float
    instructions: int
    instructions_by_part: dict[str, int]
    rad750_s: float
    code_bytes: int  # `size`'s text: code with the read-only data (.rodata) and unwind tables
    const_data_bytes: int  # data + bss: the writable static data (the name kept for --json)
    arena_bytes: int
    arena_high_water: int
    stack_high_water: int  # measured: the painted stack of this call
    heap_allocations_in_solve: int
    host_wall_s: float
    variant: str = "SCvx"
    nn_weights_bytes: int = 0  # weight blobs of the networks the call runs (read in place)
    nn_arena_bytes: int = 0  # their arenas
    result_bytes: int = 0  # the caller's answer arrays x (N x 14) and u (N x 3)
    nodes: int = 50  # the grid's N
    stack_bound: int = 0  # static worst case of the call (stack_bound.py): what memory counts

    @property
    def memory_bytes(self) -> int:
        return (
            self.code_bytes
            + self.const_data_bytes
            + self.arena_bytes  # reserved in the flight image, not only its high-water
            + self.stack_bound  # the worst case, not this call's high-water
            + self.nn_weights_bytes
            + self.nn_arena_bytes
            + self.result_bytes
        )

    @property
    def instruction_budget(self) -> float:
        return TIME_BUDGET_S * IPC * CLOCK_HZ / RISC_EXPANSION

    def within_time(self) -> bool:
        return self.rad750_s <= TIME_BUDGET_S

    def within_memory(self) -> bool:
        return self.memory_bytes <= MEMORY_BUDGET_B


@dataclass
class NetBudget:
    """One inference of one network (tscvx_nn_run)."""

    name: str
    architecture: str
    instructions: int
    rad750_s: float
    weights_bytes: int  # the weight file, read in place (float64 values + header + probes)
    arena_bytes: int
    stack_high_water: int
    heap_allocations_in_run: int
    host_wall_s: float
    stack_bound: int = 0  # static worst case of tscvx_nn_run

    @property
    def memory_bytes(self) -> int:
        return self.weights_bytes + self.arena_bytes + self.stack_bound

    def within_budget(self) -> bool:
        return self.instructions <= NN_INSTRUCTION_BUDGET


def est_instructions(macs: int) -> float:
    """Planning estimate of host instructions per inference of a network of ``macs``
    multiply-accumulates (today's INSTR_PER_MAC: reports written under an older factor are
    re-estimated, not read back)."""
    return INSTR_PER_MAC * macs


def fits_budget(macs: int) -> bool:
    """Whether a network of ``macs`` multiply-accumulates fits NN_INSTRUCTION_BUDGET, by the
    planning estimate."""
    return est_instructions(macs) <= NN_INSTRUCTION_BUDGET


def rad750_seconds(instructions: float) -> float:
    return RISC_EXPANSION * instructions / (IPC * CLOCK_HZ)


def build(quiet: bool = True, stack: bool = True) -> None:
    """The library, the drivers and (with `stack`) the static stack analysis's units."""
    cmd = ["make", "-s", "-C", str(ROOT), "lib", str(DRIVER.relative_to(ROOT)),
           str(NN_DRIVER.relative_to(ROOT))]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=quiet)
    if stack:
        stack_bound.build(quiet)
    _BOUNDS.clear()  # build/stack may have changed


# The static bounds of build/stack, analysed once per process (about a second each time; a
# campaign measures 3 calls a landing) until build() runs again.
_BOUNDS: dict[str, stack_bound.Bound] = {}


def flight_bounds() -> dict[str, stack_bound.Bound]:
    if not _BOUNDS:
        _BOUNDS.update(stack_bound.flight_bounds(do_build=False))
    return _BOUNDS


def static_stack(function: str, measured: int) -> int:
    """The static stack bound of a public function (stack_bound.py, build/stack as built),
    checked against the high-water `measured` by painting: a bound below it is wrong."""
    bound = flight_bounds()[function].bytes
    if bound < measured:
        raise RuntimeError(
            f"the static stack bound of {function} ({bound} B) is below its measured "
            f"high-water ({measured} B): the analysis misses a frame"
        )
    return bound


def _variant_args(variant: str) -> tuple[list[str], str]:
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r} (one of {', '.join(VARIANTS)})")
    args, function = VARIANTS[variant]
    paths = {k: str(v) for k, v in NN_MODELS.items()}
    return [a.format(**paths) for a in args], function


def landing_arg(scenario: Scenario) -> str:
    """The driver's ``--landing`` value of a landing of the default vehicle: its theta
    (sampling.theta_of), each number as Python's repr, which strtod reads back to the same
    double."""
    from guidance.sampling import scenario_of, theta_of

    theta = theta_of(scenario)
    if scenario_of(theta, Params()) != scenario:
        raise ValueError("--landing carries theta only: the scenario's vehicle must be the default")
    return ",".join(repr(float(v)) for v in theta)


def _driver_cmd(
    variant: str, repeat: int, nodes: int | None = None, landing: str | None = None
) -> list[str]:
    args, _ = _variant_args(variant)
    grid = [] if nodes is None else ["--nodes", str(nodes)]
    other = [] if landing is None else ["--landing", landing]
    return [str(DRIVER), "--repeat", str(repeat), *grid, *other, *args]


def _run_driver(
    variant: str = "SCvx", nodes: int | None = None, landing: str | None = None, repeat: int = 3
) -> dict[str, str]:
    """``repeat`` native guidance calls: the driver's ``key value`` lines."""
    cmd = _driver_cmd(variant, repeat, nodes, landing)
    out = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if out.returncode not in DRIVER_OK:
        raise RuntimeError(f"budget driver failed ({out.returncode}): {out.stderr[-2000:]}")
    kv = {}
    for line in out.stdout.splitlines():
        key, _, value = line.partition(" ")
        kv[key] = value
    missing = [k for k in DRIVER_KEYS if k not in kv]
    if missing:  # a driver built before this tool (`--no-build`), or one that stopped early
        raise RuntimeError(
            f"{DRIVER} printed no {', '.join(missing)}: it is older than this tool or stopped "
            "early; rebuild it (run without --no-build)"
        )
    return kv


def count_instructions(
    variant: str = "SCvx", nodes: int | None = None, landing: str | None = None
) -> tuple[int, dict[str, int]]:
    """Instructions inside the guidance call (callgrind): pdg_solve, or pdg_solve_tscvx for
    the T-SCvx variants, with the SOCP / discretization / network-inference split."""
    _, function = _variant_args(variant)
    cmd = _driver_cmd(variant, 1, nodes, landing)
    with callgrind.collect(cmd, function, ok_codes=DRIVER_OK) as run:
        parts = callgrind.inclusive_costs(run.out_file, PARTS)
    if parts:
        parts["rest"] = run.instructions - sum(parts.values())
    return run.instructions, parts


def measured_files() -> dict[str, object]:
    """The --json output's provenance: the code version, and the sha256 of what was measured
    (the libraries, the driver, the networks' blobs), so that figures name their binaries."""
    from guidance.provenance import provenance

    files = {p.name: p for p in (*LIBS, DRIVER, NN_DRIVER, *NN_MODELS.values()) if p.exists()}
    return provenance(files)


def measure_networks(do_build: bool = True) -> list[NetBudget]:
    """One tscvx_nn_run of each shipped network: instructions (callgrind) and memory."""
    if do_build:
        build()
    rows = []
    for name, path in NN_MODELS.items():
        out = subprocess.run(
            [str(NN_DRIVER), str(path), "--repeat", "20"], capture_output=True, text=True
        )
        if out.returncode != 0:
            raise RuntimeError(f"nn budget driver failed on {path}: {out.stderr[-2000:]}")
        kv = dict(line.split(" ", 1) for line in out.stdout.splitlines() if " " in line)
        instr = callgrind.total([str(NN_DRIVER), str(path), "--repeat", "1"], "tscvx_nn_run")
        stack = int(kv["stack_high_water"])
        rows.append(
            NetBudget(
                name=name,
                architecture=f"{kv['tokens']} tokens, d {kv['d_model']}, {kv['n_layers']} "
                f"layers, {kv['n_heads']} heads, ff {kv['d_ff']}",
                instructions=instr,
                rad750_s=rad750_seconds(instr),
                weights_bytes=int(kv["blob_bytes"]),
                arena_bytes=int(kv["arena_bytes"]),
                stack_high_water=stack,
                heap_allocations_in_run=int(kv["heap_allocations_in_run"]),
                host_wall_s=float(kv["wall_s_min"]),
                stack_bound=static_stack("tscvx_nn_run", stack),
            )
        )
    return rows


def code_size() -> tuple[int, int]:
    """(text, data + bss) of the static libraries of the flight image."""
    files = [str(p) for p in LIBS]
    for name in SUITESPARSE:
        for d in SYSTEM_LIB_DIRS:
            if (d / name).exists():
                files.append(str(d / name))
                break
    out = subprocess.run(["size", "-t", *files], capture_output=True, text=True, check=True)
    text = data = 0
    for line in out.stdout.splitlines():
        if line.rstrip().endswith("(TOTALS)"):
            f = line.split()
            text += int(f[0])
            data += int(f[1]) + int(f[2])
    return text, data


def measure(
    do_build: bool = True,
    variant: str = "SCvx",
    nodes: int | None = None,
    landing: str | None = None,
    repeat: int = 3,
) -> Budget:
    """One complete guidance call of ``variant`` (a key of VARIANTS), on ``nodes`` nodes
    (None: the default scenario's N), of ``landing`` (the driver's --landing; None: the
    default landing); the host wall time is the fastest of ``repeat`` native calls."""
    if do_build:
        build()
    native = _run_driver(variant=variant, nodes=nodes, landing=landing, repeat=repeat)
    _, function = _variant_args(variant)
    bound = static_stack(function, int(native["stack_high_water"]))
    instr, parts = count_instructions(variant, nodes, landing)
    text, data = code_size()
    return Budget(
        status=native["status"],
        iterations=int(native["iterations"]),
        subproblems=int(native["subproblems"]),
        socp_iterations=int(native["socp_iterations"]),
        m_f=float(native["m_f"]),
        instructions=instr,
        instructions_by_part=parts,
        rad750_s=rad750_seconds(instr),
        code_bytes=text,
        const_data_bytes=data,
        arena_bytes=int(native["arena_bytes"]),
        arena_high_water=int(native["arena_high_water"]),
        stack_high_water=int(native["stack_high_water"]),
        heap_allocations_in_solve=int(native["heap_allocations_in_solve"]),
        host_wall_s=float(native["wall_s_min"]),
        variant=variant,
        nn_weights_bytes=int(native.get("nn_weights_bytes", 0)),
        nn_arena_bytes=int(native.get("nn_arena_bytes", 0)),
        result_bytes=int(native["result_bytes"]),
        nodes=int(native["nodes"]),
        stack_bound=bound,
    )


def measure_variants(do_build: bool = True) -> list[Budget]:
    """SCvx, T-SCvx (warm start) and T-SCvx (Algorithm 2): one complete call each."""
    if do_build:
        build()
    return [measure(do_build=False, variant=v) for v in VARIANTS]


def _solve_head() -> str:
    """The columns of a call's solve, shared by the comparison tables."""
    return f"{'status':>14s} {'iter.':>5s} {'subpr.':>6s} {'IPM':>5s}"


def _solve_cells(b: Budget) -> str:
    return f"{b.status:>14s} {b.iterations:5d} {b.subproblems:6d} {b.socp_iterations:5d}"


def report_variants(rows: list[Budget]) -> str:
    """The complete guidance calls side by side, network inference included."""
    lines = [
        "One complete guidance call, default scenario: SCvx against T-SCvx on board "
        "(pdg_solve_tscvx, network inference included)",
        f"  {'call':22s} {_solve_head()} {'host instr.':>12s} {'of which NN':>11s} "
        f"{'RAD750 s':>9s} {'memory':>10s} {'of which NN':>11s} {'heap':>5s} {'m_f':>9s}",
    ]
    for b in rows:
        nn = b.instructions_by_part.get("network_inference", 0)
        nn_mem = b.nn_weights_bytes + b.nn_arena_bytes
        lines.append(
            f"  {b.variant:22s} {_solve_cells(b)} "
            f"{b.instructions / 1e6:10.1f} M {nn / 1e6:9.2f} M "
            f"{b.rad750_s:9.2f} {b.memory_bytes / 2**20:6.2f} MiB {nn_mem / 2**20:7.2f} MiB "
            f"{b.heap_allocations_in_solve:5d} {b.m_f:9.6f}"
        )
    if rows and rows[0].variant == "SCvx":
        base = rows[0]
        for b in rows[1:]:
            lines.append(
                f"  {b.variant}: {b.instructions / base.instructions:.2f}x the instructions of "
                f"SCvx, {b.subproblems - base.subproblems:+d} subproblems, "
                f"{b.socp_iterations - base.socp_iterations:+d} IPM iterations"
            )
    lines.append(
        "  memory: code + static data + guidance arena + static stack bound + answer arrays "
        "+ network weights (read in place) + network arenas; budget "
        f"{_mb(MEMORY_BUDGET_B).strip()} and {TIME_BUDGET_S:.0f} s RAD750"
    )
    return "\n".join(lines)


def report_grids(rows: list[Budget]) -> str:
    """The SCvx call on several grids: what a coarser grid saves in time and memory."""
    lines = [
        "One complete guidance call (pdg_solve), the default landing on N nodes: RAD750 time "
        "and memory against the grid",
        f"  {'N':>4s} {_solve_head()} {'host instr.':>12s} {'per IPM it.':>11s} "
        f"{'discretiz.':>11s} {'RAD750 s':>9s} {'memory':>10s} {'heap':>5s} {'m_f':>9s}",
    ]
    for b in rows:
        disc = b.instructions_by_part.get("discretization", 0)
        per_ipm = b.instructions / b.socp_iterations if b.socp_iterations else float("nan")
        lines.append(
            f"  {b.nodes:4d} {_solve_cells(b)} "
            f"{b.instructions / 1e6:10.1f} M {per_ipm / 1e6:9.2f} M "
            f"{disc / 1e6:9.1f} M {b.rad750_s:9.2f} {b.memory_bytes / 2**20:6.2f} MiB "
            f"{b.heap_allocations_in_solve:5d} {b.m_f:9.6f}"
        )
    lines += [
        "  per IPM it.: the call's instructions over its IPM iterations (discretization and "
        "assembly included); memory as in the budget table",
        "  T-SCvx and the networks: not measured on other grids (the shipped networks are "
        "trained for N = 50)",
    ]
    return "\n".join(lines)


def _mb(b: float) -> str:
    return f"{b / 2**20:8.3f} MiB"


def report(b: Budget) -> str:
    lines = [
        "RAD750 budget, default scenario, one complete guidance call "
        + (
            "(pdg_solve)"
            if b.variant == "SCvx"
            else f"(pdg_solve_tscvx, {b.variant}, network inference included)"
        ),
        f"  solve: {b.status}, {b.iterations} iterations, {b.subproblems} subproblems, "
        f"{b.socp_iterations} IPM iterations, m_f = {b.m_f:.9f}",
        f"  model: RAD750 s = {RISC_EXPANSION:g} x instructions / ({IPC:g} x "
        f"{CLOCK_HZ / 1e6:g}e6); budget {TIME_BUDGET_S:g} s = "
        f"{b.instruction_budget / 1e6:.1f} M host instructions",
        "",
        f"  {'item':48s} {'measured':>16s} {'budget':>14s}  ok",
        f"  {'host instructions (callgrind)':48s} {b.instructions / 1e6:14.1f} M "
        f"{b.instruction_budget / 1e6:12.1f} M  {'yes' if b.within_time() else 'NO'}",
    ]
    counted = {key: function for function, key in PARTS.items()}
    for key, val in b.instructions_by_part.items():
        label = f"  of which {key}" + (f" ({counted[key]})" if key in counted else "")
        lines.append(f"  {label:48s} {val / 1e6:14.1f} M")
    lines += [
        f"  {'RAD750-equivalent time':48s} {b.rad750_s:14.3f} s {TIME_BUDGET_S:12.3f} s  "
        f"{'yes' if b.within_time() else 'NO'}",
        f"  {'code + read-only data (library text)':48s} {_mb(b.code_bytes):>16s}",
        f"  {'writable static data (data + bss)':48s} {_mb(b.const_data_bytes):>16s}",
        f"  {'guidance arena (as sized and reserved)':48s} {_mb(b.arena_bytes):>16s}"
        f"   ({b.arena_bytes} B; high-water {b.arena_high_water} B, library report)",
        f"  {'stack, static worst case (stack_bound.py)':48s} {_mb(b.stack_bound):>16s}"
        f"   ({b.stack_bound} B; high-water of this call {b.stack_high_water} B, painted)",
        f"  {'answer arrays x, u (the caller, at N)':48s} {_mb(b.result_bytes):>16s}"
        f"   ({b.result_bytes} B)",
        *(
            [
                f"  {'network weights (blobs read in place)':48s} {_mb(b.nn_weights_bytes):>16s}",
                f"  {'network arenas':48s} {_mb(b.nn_arena_bytes):>16s}",
            ]
            if b.nn_weights_bytes
            else []
        ),
        f"  {'memory total':48s} {_mb(b.memory_bytes):>16s} {_mb(MEMORY_BUDGET_B):>14s}  "
        f"{'yes' if b.within_memory() else 'NO'}",
        f"  {'heap allocations inside the call':48s} {b.heap_allocations_in_solve:16d} "
        f"{0:14d}  {'yes' if b.heap_allocations_in_solve == 0 else 'NO'}",
        f"  {'host wall time (not the model)':48s} {b.host_wall_s * 1e3:14.1f} ms",
    ]
    if "rest" in b.instructions_by_part:
        lines.append(f"  {REST}")
    return "\n".join(lines)


def report_networks(nets: list[NetBudget], call: Budget | None = None) -> str:
    lines = [
        "Network inference (tscvx_nn_run, one call each; budget "
        f"{NN_INSTRUCTION_BUDGET / 1e6:.0f} M host instructions per inference)",
        f"  {'network':12s} {'host instr.':>12s} {'RAD750 ms':>10s} {'weights':>10s} "
        f"{'arena':>9s} {'stack: painted / bound':>22s} {'heap':>5s} {'host ms':>8s}  ok",
    ]
    for n in nets:
        lines.append(
            f"  {n.name:12s} {n.instructions / 1e6:10.3f} M {n.rad750_s * 1e3:10.1f} "
            f"{n.weights_bytes / 2**20:6.2f} MiB {n.arena_bytes:7d} B "
            f"{n.stack_high_water:9d} B / {n.stack_bound:6d} B "
            f"{n.heap_allocations_in_run:5d} {n.host_wall_s * 1e3:8.3f}  "
            f"{'yes' if n.within_budget() else 'NO'}"
        )
    for n in nets:
        lines.append(f"  {n.name}: {n.architecture}")
    by = {n.name: n for n in nets}
    if set(KINDS) <= by.keys():
        total = by[SOLUTION].instructions + NN_CONSTRAINT_CALLS * by[CONSTRAINT].instructions
        lines.append(
            f"  T-SCvx trajectory: 1 solution + {NN_CONSTRAINT_CALLS} constraint inferences "
            f"= {total / 1e6:.1f} M host instructions = {rad750_seconds(total):.3f} s "
            f"RAD750-equivalent (budget 1 s per trajectory, SCvx solves not included)"
        )
    if call is not None:  # the T-SCvx call, networks included, with its own stack
        nn = call.nn_weights_bytes + call.nn_arena_bytes
        lines.append(
            f"  flight image with both networks ({call.variant}): code, data, arena, stack, "
            f"answers {_mb(call.memory_bytes - nn).strip()} + weights and arenas "
            f"{_mb(nn).strip()} = "
            f"{_mb(call.memory_bytes).strip()} of {_mb(MEMORY_BUDGET_B).strip()}"
        )
    return "\n".join(lines)


# ---- campaign: sampled landings (--landings K) -------------------------------------------


@dataclass
class CampaignLanding:
    """One landing of the campaign: its index in the sampler's draw, theta and one measured
    call per variant (VARIANTS' order)."""

    index: int
    theta: list[float]
    calls: list[Budget]


@dataclass
class VariantSpread:
    """One variant over the campaign's landings."""

    variant: str
    landings: int
    median_s: float
    p90_s: float  # nearest rank: the figure of a landing
    max_s: float
    largest_landing: int  # the landing of max_s (its index in the draw)
    statuses: dict[str, int]
    median_instructions: float
    # instructions / SCvx's on the same landing (None for SCvx itself)
    ratio_median: float | None
    ratio_min: float | None
    ratio_max: float | None
    memory_bytes: tuple[int, int]  # (least, most) over the landings
    arena_bytes: tuple[int, int]
    stack_bound: tuple[int, int]
    arena_high_water: tuple[int, int]
    stack_high_water: tuple[int, int]  # painted
    heap_allocations: int  # inside the calls, summed over the landings

    @property
    def memory_fixed(self) -> bool:
        """The memory the budget counts is the same on every landing."""
        return self.memory_bytes[0] == self.memory_bytes[1]


def measure_campaign(
    landings: int, seed: int | None = None, progress: bool = True
) -> list[CampaignLanding]:
    """``landings`` landings of the T-SCvx benchmark's sampler (``seed``, default its own),
    each measured in every variant (callgrind; the driver built)."""
    from guidance.bench_tscvx import BENCH_SEED, sample_landings
    from guidance.sampling import theta_of

    out = []
    scenarios = sample_landings(landings, seed=BENCH_SEED if seed is None else seed)
    for i, scenario in enumerate(scenarios):
        arg = landing_arg(scenario)
        calls = [measure(do_build=False, variant=v, landing=arg, repeat=1) for v in VARIANTS]
        out.append(CampaignLanding(i, [float(v) for v in theta_of(scenario)], calls))
        if progress:
            done = ", ".join(f"{c.variant} {c.status} {c.rad750_s:.2f} s" for c in calls)
            print(f"landing {i} ({i + 1} of {len(scenarios)}): {done}", file=sys.stderr, flush=True)
    return out


def _range(values: list[int]) -> tuple[int, int]:
    return (min(values), max(values))


def campaign_spread(rows: list[CampaignLanding]) -> list[VariantSpread]:
    """Per variant: the spread of the RAD750 time over the landings, the largest and its
    landing, statuses, the instruction ratio against SCvx landing by landing, the memory."""
    from guidance.dispersion import spread

    if not rows:
        raise ValueError("a campaign of no landings")
    out = []
    for j, variant in enumerate(VARIANTS):
        calls = [r.calls[j] for r in rows]
        if any(c.variant != variant for c in calls):
            raise ValueError(f"landing calls out of order: expected {variant}")
        med, p90, largest = spread([c.rad750_s for c in calls], q=90)
        worst = max(range(len(rows)), key=lambda i: calls[i].instructions)
        ratios = None
        if j > 0:  # against SCvx (VARIANTS' first) on the same landing
            ratios = [
                c.instructions / r.calls[0].instructions for c, r in zip(calls, rows, strict=True)
            ]
        statuses: dict[str, int] = {}
        for c in calls:
            statuses[c.status] = statuses.get(c.status, 0) + 1
        out.append(
            VariantSpread(
                variant=variant,
                landings=len(rows),
                median_s=med,
                p90_s=p90,
                max_s=largest,
                largest_landing=rows[worst].index,
                statuses=statuses,
                median_instructions=float(np.median([c.instructions for c in calls])),
                ratio_median=None if ratios is None else float(np.median(ratios)),
                ratio_min=None if ratios is None else min(ratios),
                ratio_max=None if ratios is None else max(ratios),
                memory_bytes=_range([c.memory_bytes for c in calls]),
                arena_bytes=_range([c.arena_bytes for c in calls]),
                stack_bound=_range([c.stack_bound for c in calls]),
                arena_high_water=_range([c.arena_high_water for c in calls]),
                stack_high_water=_range([c.stack_high_water for c in calls]),
                heap_allocations=sum(c.heap_allocations_in_solve for c in calls),
            )
        )
    return out


def _bytes_range(r: tuple[int, int]) -> str:
    return f"{r[0]} B" if r[0] == r[1] else f"{r[0]}-{r[1]} B"


def _mib_range(r: tuple[int, int]) -> str:
    lo, hi = (f"{b / 2**20:.2f}" for b in r)
    return f"{lo} MiB" if r[0] == r[1] else f"{lo}-{hi} MiB"


def report_campaign(rows: list[CampaignLanding], seed: int) -> str:
    """The campaign's spread per variant (campaign_spread) and one line per landing."""
    spreads = campaign_spread(rows)
    lines = [
        f"Campaign: {len(rows)} landings of the training distribution (bench_tscvx's sampler, "
        f"seed {seed}), one complete guidance call each, RAD750-equivalent seconds",
        f"  {'call':22s} {'median':>8s} {'90th pct':>8s} {'largest':>8s} {'(landing)':>9s} "
        f"{'instr./SCvx: median [range]':>28s} {'memory':>10s}  statuses",
    ]
    for v in spreads:
        ratio = (
            "-"
            if v.ratio_median is None
            else f"{v.ratio_median:.2f} [{v.ratio_min:.2f}, {v.ratio_max:.2f}]"
        )
        stat = ", ".join(f"{n} {k}" for k, n in sorted(v.statuses.items()))
        lines.append(
            f"  {v.variant:22s} {v.median_s:8.2f} {v.p90_s:8.2f} {v.max_s:8.2f} "
            f"{v.largest_landing:9d} {ratio:>28s} {_mib_range(v.memory_bytes):>10s}  {stat}"
        )
    lines.append(
        "  90th pct: nearest rank (a landing's figure); instr./SCvx: the call's instructions "
        "over SCvx's on the same landing"
    )
    for v in spreads:
        fixed = "the same on every landing" if v.memory_fixed else "varies with the landing"
        lines.append(
            f"  {v.variant}: memory {fixed} (arena {_mib_range(v.arena_bytes)}, stack bound "
            f"{_bytes_range(v.stack_bound)}; measured: arena high-water "
            f"{_bytes_range(v.arena_high_water)}, stack painted "
            f"{_bytes_range(v.stack_high_water)}); heap allocations "
            f"{v.heap_allocations}"
        )
    by_index = {r.index: r for r in rows}
    for i in sorted({v.largest_landing for v in spreads}):
        theta = ",".join(repr(t) for t in by_index[i].theta)
        lines.append(f"  landing {i}, the largest of a variant: {DRIVER.name} --landing {theta}")
    lines.append(f"  {'landing':>7s} " + " ".join(f"{v:>30s}" for v in VARIANTS))
    for r in rows:
        cells = [
            f"{c.status[:10]:>10s} {c.subproblems:3d} {c.socp_iterations:4d} {c.rad750_s:7.2f} s"
            for c in r.calls
        ]
        lines.append(f"  {r.index:7d} " + " ".join(f"{x:>30s}" for x in cells))
    lines.append("  per landing: status, subproblems, IPM iterations, RAD750-equivalent time")
    return "\n".join(lines)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options, shared by ``python -m guidance.budget`` and ``guidance budget``."""
    ap.add_argument("--no-build", action="store_true", help="use the built driver as is")
    ap.add_argument("--json", action="store_true", help="print the figures as JSON")
    ap.add_argument(
        "--check-noalloc", action="store_true",
        help="only run the driver natively and fail unless pdg_solve made no heap allocation",
    )  # fmt: skip
    ap.add_argument(
        "--nodes", type=at_least(N_MIN, N_MAX), nargs="+", metavar="N",
        help=f"measure the SCvx call of the default landing on each of these grids instead, N "
        f"in [{N_MIN}, {N_MAX}] (the T-SCvx and network rows need the networks' N = 50)",
    )  # fmt: skip
    ap.add_argument(
        "--landings", type=at_least(1), metavar="K",
        help="also measure K landings drawn from the networks' training distribution, every "
        "variant (about 30 s a landing): median, 90th percentile and largest time",
    )  # fmt: skip
    ap.add_argument(
        "--seed", type=at_least(0), metavar="S",
        help="the campaign's draw seed (default: the T-SCvx benchmark's, never trained on)",
    )  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="guidance budget", description=__doc__.splitlines()[0])
    add_arguments(ap)
    return run(ap.parse_args(argv))


def _json_row(b: Budget) -> dict[str, object]:
    return {**asdict(b), "memory_bytes": b.memory_bytes, "within_time": b.within_time(),
            "within_memory": b.within_memory()}  # fmt: skip


def run(args: argparse.Namespace) -> int:
    """The budget job for parsed options (add_arguments)."""
    _check_campaign_options(args)
    if not args.no_build:
        build(stack=not args.check_noalloc)
    needed = (DRIVER,) if args.check_noalloc else (DRIVER, NN_DRIVER)
    missing = [str(d) for d in needed if not d.is_file()]
    if missing:
        raise LibraryNotBuiltError(
            f"{', '.join(missing)} not found: run `make budget` (or drop --no-build)"
        )
    if args.check_noalloc:
        allocations = 0
        for nodes in args.nodes or [None]:
            kv = _run_driver(nodes=nodes)
            n = int(kv["heap_allocations_in_solve"])
            allocations += n
            print(
                f"heap allocations inside pdg_solve: {n} (N = {kv['nodes']}, status {kv['status']})"
            )
        return 0 if allocations == 0 else 1
    if args.nodes:
        grids = [measure(do_build=False, nodes=n) for n in args.nodes]
        if args.json:
            out = {"grids": [_json_row(b) for b in grids], "provenance": measured_files()}
            print(json.dumps(out, indent=2))
        else:
            print(report_grids(grids))
        return 0
    calls = measure_variants(do_build=False)
    nets = measure_networks(do_build=False)
    campaign = measure_campaign(args.landings, args.seed) if args.landings else None
    if args.json:
        print(json.dumps(_json_figures(calls, nets, campaign, _campaign_seed(args)), indent=2))
    else:
        print(_text_figures(calls, nets))
        if campaign is not None:
            print()
            print(report_campaign(campaign, _campaign_seed(args)))
    return 0


def _json_figures(
    calls: list[Budget],
    nets: list[NetBudget],
    campaign: list[CampaignLanding] | None,
    seed: int,
) -> dict[str, object]:
    """--json: the SCvx call's figures at the top level, the calls, networks and campaign."""
    b = calls[0]
    d = asdict(b)
    d.update(memory_bytes=b.memory_bytes, within_time=b.within_time(),
             within_memory=b.within_memory())  # fmt: skip
    d["networks"] = [
        {**asdict(n), "memory_bytes": n.memory_bytes, "within_budget": n.within_budget()}
        for n in nets
    ]
    d["calls"] = [_json_row(c) for c in calls]
    if campaign is not None:
        d["campaign"] = {
            "seed": seed,
            "variants": [
                {**asdict(v), "memory_fixed": v.memory_fixed} for v in campaign_spread(campaign)
            ],
            "landings": [
                {"index": r.index, "theta": r.theta, "calls": [_json_row(c) for c in r.calls]}
                for r in campaign
            ],
        }
    d["provenance"] = measured_files()
    return d


def _text_figures(calls: list[Budget], nets: list[NetBudget]) -> str:
    """The default landing's reports: SCvx, the variants, Algorithm 2, networks, stack."""
    painted: dict[str, int] = {"tscvx_nn_run": max(n.stack_high_water for n in nets)}
    for c in calls:
        fn = VARIANTS[c.variant][1]
        painted[fn] = max(painted.get(fn, 0), c.stack_high_water)
    parts = [
        report(calls[0]),
        report_variants(calls),
        report(calls[-1]),
        report_networks(nets, calls[-1]),
        stack_bound.summary(flight_bounds(), painted),
    ]
    return "\n\n".join(parts)


def _campaign_seed(args: argparse.Namespace) -> int:
    from guidance.bench_tscvx import BENCH_SEED

    return BENCH_SEED if args.seed is None else int(args.seed)


def _check_campaign_options(args: argparse.Namespace) -> None:
    """--seed belongs to --landings; a campaign is of the networks' grid and of the time."""
    landings = getattr(args, "landings", None)
    if getattr(args, "seed", None) is not None and not landings:
        raise InputError("--seed: the seed of a campaign, give --landings K too")
    if landings and (args.nodes or args.check_noalloc):
        raise InputError(
            "--landings: measured on the networks' grid, not with --nodes or --check-noalloc"
        )


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (LibraryNotBuiltError, InputError) as exc:  # as `guidance budget` reports them
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
