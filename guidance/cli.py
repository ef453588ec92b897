"""Command line: ``guidance solve | scenario | verify | bench | agreement | dispersion |
closed-loop | budget`` (the learning tools register theirs from ``guidance.cli_learning``)."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from guidance import file_check, interrupts
from guidance.api import BACKENDS, METHODS, solve
from guidance.argtypes import add_workers_option, at_least, worker_count
from guidance.atomic import check_folder, check_outputs
from guidance.errors import InputError, Interrupted, LibraryNotBuiltError, WorkerDiedError
from guidance.guess import plan_remainder
from guidance.interrupts import exit_code, sigterm_as_interrupt
from guidance.nn.conventions import KINDS, MODELS_DIR, network_file
from guidance.params import IM, PROX_U_MAX, Params, Scenario, SCvxSettings
from guidance.scenario import read_scenario_data, scenario_from_dict, scenario_to_dict
from guidance.tscvx import REDUCED_ETA_INIT

if TYPE_CHECKING:
    from guidance.scvx import SCvxResult

EXIT_FAILED = 1  # the command ran and failed (a worker process of its run died)
EXIT_BAD_INPUT = 2
# No trajectory to write (the solve stopped before its first subproblem). Any status with a
# trajectory exits 0: an infeasible landing is a normal answer, not an error (DESIGN.md).
EXIT_NO_TRAJECTORY = 3
EXIT_BROKEN_PIPE = 141  # as a shell reports a command killed by SIGPIPE (128 + 13)
EXIT_INTERRUPTED = interrupts.EXIT_INTERRUPTED  # 130: Ctrl-C (128 + SIGINT)
EXIT_TERMINATED = interrupts.EXIT_TERMINATED  # 143: SIGTERM (128 + SIGTERM), stopped as Ctrl-C


def _load(path: str | None, pin_final_attitude: bool) -> Scenario:
    data = read_scenario_data(path) if path else None
    scenario = scenario_from_dict(data) if data is not None else Scenario()
    if pin_final_attitude:
        if data is not None and data.get("final_roll_free") is True:
            print(f'note: --pin-final-attitude overrides {path}\'s "final_roll_free": true',
                  file=sys.stderr)  # fmt: skip
        scenario = Scenario(scenario.initial, scenario.params.replace(final_roll_free=False))
    return scenario


def _setting(name: str, cast: Callable[[str], float] = float) -> Callable[[str], float]:
    """argparse type of an SCvxSettings field, checked by SCvxSettings itself: a bad value
    exits 2 with its message (--prox-u, --eta-init, --iter-max)."""

    def parse(text: str) -> float:
        try:
            return getattr(SCvxSettings().replace(**{name: cast(text)}), name)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return parse


def add_prox_u(parser: argparse.ArgumentParser, about_zero: str) -> None:
    """--prox-u: SCvxSettings.prox_u, the weight of the subproblems' proximal term."""
    parser.add_argument(
        "--prox-u",
        type=_setting("prox_u"),
        default=SCvxSettings().prox_u,
        help="weight of the subproblems' proximal term on the scaled thrust, within "
        f"[0, {PROX_U_MAX:g}] (default "
        f"%(default)s; 0: the paper's linear objective, {about_zero})",
    )


def positive_float(text: str) -> float:
    """argparse type of a tolerance: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def _check_plot_format(path: str) -> None:
    """Refuse a figure name matplotlib cannot write before solving, not after."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backend_bases import FigureCanvasBase

    suffix = Path(path).suffix.lstrip(".").lower()
    formats = FigureCanvasBase.get_supported_filetypes()
    if suffix not in formats:
        raise InputError(
            f"--plot {path}: unknown figure format {suffix!r} (use one of "
            f"{', '.join(sorted(formats))})"
        )


def cmd_solve(args: argparse.Namespace) -> int:
    scenario = _load(args.scenario, args.pin_final_attitude)
    _check_method_options(args)
    guess = _read_guess(args.guess, scenario.params)
    if guess is not None and args.at is not None:  # in-flight re-planning
        guess = plan_remainder(scenario, *guess, args.at)
    _check_output_files(args.out, args.plot, args.scenario)
    settings = SCvxSettings(
        iter_max=args.iter_max,
        tau_r_update=args.trust_update != "alg1",
        prox_u=args.prox_u,
        socp_warm_start=not args.cold_ipm,
        socp_max_iter_total=args.ipm_budget,
        polish=args.polish,
    )
    _print_problem(args, scenario, settings)
    result = solve(
        scenario,
        args.method,
        args.backend,
        settings,
        Path(args.models),
        print,
        args.eta_init,
        guess,
    )
    print()
    print(f"status        {result.status} ({result.reason})")
    print(f"iterations    {result.iterations} (subproblems solved: {result.subproblems_solved})")
    if not np.isfinite(result.t_f):  # stopped before its first subproblem
        print("no trajectory: nothing written")
        return EXIT_NO_TRAJECTORY
    _print_landing(result, scenario, args.at)
    if args.out:
        _write_trajectory(args, result, scenario)
    if args.plot:
        _write_figure(args, result, scenario.params)
    return 0


def _check_method_options(args: argparse.Namespace) -> None:
    """Refuse the options the chosen method has no use for."""
    if args.trust_update is not None and args.method != "tscvx":
        raise InputError("--trust-update: applies to --method tscvx only (SCvx has no masks)")
    if args.at is not None and not args.guess:
        raise InputError(
            "--at: applies with --guess only (the plan whose remainder starts the solve)"
        )
    if args.guess and args.method != "scvx":
        raise InputError(
            f"--guess {args.guess}: applies to --method scvx only (T-SCvx starts from its network)"
        )
    if args.method == "tscvx" and not Path(args.models).is_dir():  # before anything is printed
        raise InputError(f"--models {args.models}: no such folder")
    if args.method == "tscvx":  # the networks its metrics.json records, not stale blobs
        from guidance.nn.model_files import check_model_files

        check_model_files(Path(args.models))


def _read_guess(path: str | None, p: Params) -> tuple[np.ndarray, np.ndarray, float] | None:
    """--guess: the file's (x, u, t_f), checked here to name the file (solve projects it)."""
    if not path:
        return None
    from guidance.trajectory_io import read_trajectory
    from guidance.verify import checked_trajectory

    try:  # the flag named in every refusal: the file alone does not say which input it was
        data = read_trajectory(path)
        return checked_trajectory(data["x"], data["u"], data["t_f"], p)
    except InputError as exc:
        raise InputError(f"--guess {path}: {exc}") from None


def _check_output_files(out: str | None, plot: str | None, scenario: str | None) -> None:
    """Refuse, before solving, an output the solve could not write, two outputs that are one
    file (the figure would overwrite the trajectory) or an output that is the scenario file;
    no folder is made until written. (--out may replace the --guess file: a re-planning loop.)"""
    if plot:
        _check_plot_format(plot)
    check_outputs(("--out", out), ("--plot", plot), inputs=(("scenario file", scenario),))
    if out and not out.lower().endswith(".npz"):  # README.md would become a zip archive
        raise InputError(f"--out {out}: a trajectory file's name ends in .npz")


def _print_problem(args: argparse.Namespace, scenario: Scenario, settings: SCvxSettings) -> None:
    print(f"scenario: {json.dumps(scenario_to_dict(scenario, changed_only=True))}")
    objective = "paper's linear" if settings.prox_u == 0 else f"proximal weight {settings.prox_u:g}"
    print(
        f"method: {args.method}, backend: {args.backend}, N = {scenario.params.N}, "
        f"subproblem objective: {objective}"
    )
    if args.guess:
        part = "" if args.at is None else f", its remainder from t = {args.at:g} U_T"
        print(
            f"initial guess: {args.guess}{part} (projected onto the boundary and path constraints)"
        )


def _print_landing(result: SCvxResult, scenario: Scenario, at: float | None = None) -> None:
    """The figures of a solve that has a trajectory: time, mass, accuracy, run time. A re-plan
    from time ``at`` of a plan (--at) counts its t_f from there; its touchdown is on the
    plan's clock too."""
    fuel = scenario.initial.m0 - result.x[-1, IM]
    propellant = scenario.initial.m0 - scenario.params.m_dry
    sub_times = [h.subproblem_time_s for h in result.history]
    if at is None:
        print(f"t_f           {result.t_f:.6f} U_T")
    else:
        print(f"t_f           {result.t_f:.6f} U_T from the re-plan (touchdown at t = "
              f"{at + result.t_f:.6f} U_T of the plan's clock)")  # fmt: skip
    print(f"final mass    {result.m_f:.6f} U_M")
    print(f"fuel          {fuel:.6f} U_M ({100 * fuel / propellant:.1f} % of the propellant)")
    print(  # the defect of the subproblems' own model: guidance verify integrates the dynamics
        f"max defect    {result.max_defect:.2e} (x_k+1 against the RK4 discretization of "
        f"interval k; the RK4 error comes on top)"
    )
    print(  # the largest h: <= 0 when every path constraint holds
        f"max path h    {result.max_violation:.2e} (largest path-constraint value at the nodes; "
        f"<= 0: all met)"
    )
    if result.settings is not None and result.settings.polish and result.status == "solved":
        print(f"polish        {result.polish.describe(result.max_defect, result.m_f)}")
    print(
        f"total time    {result.solve_time_s:.3f} s "
        f"(conic solves {sum(sub_times):.3f} s, median {1e3 * np.median(sub_times):.1f} ms)"
    )


def _write_trajectory(args: argparse.Namespace, result: SCvxResult, scenario: Scenario) -> None:
    from guidance.trajectory_io import write_trajectory

    write_trajectory(
        args.out,
        result,
        scenario.params,
        scenario,
        args.method,
        args.backend,
        _solve_inputs(args, result),
    )
    print(f"wrote {args.out}")


def _solve_inputs(args: argparse.Namespace, result: SCvxResult) -> dict[str, Path] | None:
    """The files the solve started from, for the trajectory file's provenance, and the C
    library that solved it (which build exactly: its sha256 beside the code version), or
    that discretized the Python loop's subproblems (its generated C: result.settings)."""
    files: dict[str, Path] = {}
    if args.guess:  # SCvx only (_check_method_options)
        name = "initial_guess" if args.at is None else f"initial_guess from t = {args.at:g}"
        files[name] = Path(args.guess)
    elif args.method == "tscvx":  # the files the networks were read from
        files.update(_network_files(Path(args.models), args.backend))
    if args.backend == "c":
        from guidance.cgnc import LIB_PATH

        files["c_library"] = LIB_PATH
    elif args.backend == "c-socp":
        from guidance.csocp import library_path

        files["c_library"] = library_path()
    if args.backend != "c" and result.settings and result.settings.discretization == "c":
        from guidance.cgnc import LIB_PATH

        files["c_discretization"] = LIB_PATH
    return files or None


def _write_figure(args: argparse.Namespace, result: SCvxResult, p: Params) -> None:
    from guidance.plots import landing_figure

    title = (
        f"{args.method} / {args.backend}: {result.status}, t_f = {result.t_f:.3f}, "
        f"m_f = {result.m_f:.4f}"
    )
    landing_figure(result.x, result.u, result.t_f, p, args.plot, title)
    print(f"wrote {args.plot}")


def _network_files(models: Path, backend: str) -> dict[str, Path]:
    """The network files a T-SCvx solve reads: the ONNX files for onnxruntime, for the C
    library the flight blob (.tnn) when the folder has one, else the ONNX it converts."""
    if backend == "c":
        from guidance.cguidance import net_source

        return {kind: net_source(models, kind) for kind in KINDS}
    return {kind: models / network_file(kind) for kind in KINDS}


def cmd_scenario(args: argparse.Namespace) -> int:
    scenario = _load(args.scenario, False)
    # --all: every parameter a scenario file may set, with its value
    print(json.dumps(scenario_to_dict(scenario, changed_only=not args.all), indent=2))
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from guidance.bench import run_scvx_bench

    run_scvx_bench(backends=args.backend, repeats=args.repeats, method=args.method)
    if args.tscvx_landings > 0:
        from guidance import bench_tscvx

        print()
        bench_tscvx.main(args.tscvx_landings, args.tscvx_backend)
    if not args.skip_socp:
        try:
            from guidance import bench_socp
        except ImportError:
            print("\n(conic solver benchmark unavailable: guidance.bench_socp not found)")
        else:
            bench_socp.main(["--callgrind"] if args.callgrind else [])
    return 0


def cmd_agreement(args: argparse.Namespace) -> int:
    from guidance import agreement

    # defaults: the whole catalog and 20 samples, or only the files when files are given
    files_only = bool(args.scenarios)
    if args.catalog is None:
        catalog: list[str] | None = [] if files_only else None
    else:
        catalog = None if args.catalog == ["all"] else args.catalog
    n = (0 if files_only else 20) if args.landings is None else args.landings
    try:
        settings = SCvxSettings(prox_u=args.prox_u)
        if args.run_dir is not None:
            check_folder("--run-dir", args.run_dir)
        return agreement.main(
            catalog,
            n,
            worker_count(args.workers),
            args.scenarios,
            settings=settings,
            run_dir=args.run_dir,
        )
    except ValueError as exc:  # an unknown catalog name or a bad scenario file
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def cmd_budget(args: argparse.Namespace) -> int:
    try:
        from guidance import budget
    except ImportError:
        print("the budget tool is not available in this build", file=sys.stderr)
        return 1
    return int(budget.run(args) or 0)


def cmd_dispersion(args: argparse.Namespace) -> int:
    from guidance import dispersion

    return dispersion.run(args)


def cmd_verify(args: argparse.Namespace) -> int:
    tol = file_check.Tolerances(
        landing=args.tol_landing,
        path=args.tol_path,
        node_deviation=args.tol_nodes,
        flown_path=args.tol_flown,
    )
    return file_check.main(args.files, tol)


class _PrintVersion(argparse.Action):
    """--version: the package version and git commit (provenance.code_version, asked of git
    only when the option is given)."""

    def __init__(self, option_strings: Sequence[str], dest: str, **kwargs: object) -> None:
        help_text = "print the version (package and git commit) and exit"
        super().__init__(option_strings, dest, nargs=0, help=help_text)

    def __call__(self, parser: argparse.ArgumentParser, *args: object, **kwargs: object) -> None:
        from guidance.provenance import code_version

        print(code_version())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="guidance",
        description="T-SCvx 6-DoF powered-descent guidance: ground tools.",
    )
    parser.add_argument("--version", action=_PrintVersion)
    sub = parser.add_subparsers(dest="command", required=True)
    _add_solve(sub)
    _add_scenario(sub)
    _add_bench(sub)
    _add_agreement(sub)
    _add_verify(sub)
    _add_dispersion(sub)
    _add_closed_loop(sub)
    g = sub.add_parser("budget", help="RAD750 time and memory budget of one C guidance call")
    g.set_defaults(func=cmd_budget)
    try:
        from guidance import budget
    except ImportError:  # cmd_budget says so
        pass
    else:
        budget.add_arguments(g)

    # Learning tools (dataset, train, export, baselines) register their own subcommands.
    from guidance import cli_learning

    cli_learning.add_commands(sub)
    return parser


def _add_solve(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("solve", help="solve one landing and write the trajectory")
    s.add_argument("scenario", nargs="?", help="scenario JSON (default: the default landing)")
    s.add_argument(
        "--method",
        choices=METHODS,
        default="scvx",
        help="tscvx: warm start and tight-constraint masks from the shipped networks",
    )
    s.add_argument(
        "--backend",
        choices=BACKENDS,
        default="clarabel",
        help="clarabel: Python SCvx + Clarabel; c-socp: Python SCvx + the C SOCP runtime; "
        "c: the whole solve in the C library",
    )
    s.add_argument(
        "--models",
        default=str(MODELS_DIR),
        help="folder of the networks: solution.onnx and constraint.onnx (with --backend c "
        "also the .tnn blobs of make lib, e.g. build/models)",
    )
    s.add_argument("--out", help="trajectory .npz to write")
    s.add_argument("--plot", help="figure (.png) to write")
    s.add_argument(
        "--iter-max",
        type=_setting("iter_max", int),
        default=SCvxSettings().iter_max,
        help="accepted SCvx iterations at most, 1 to 100 (default: Table 1's 20)",
    )
    s.add_argument(
        "--trust-update",
        choices=["tau_r", "alg1"],
        default=None,
        help="T-SCvx trust radius (--method tscvx only): tau_r = Algorithm 2's update (paper, "
        "the default), alg1 = Algorithm 1's Eq. (15) with the masks as well",
    )
    add_prox_u(s, "whose answer depends on the conic solver")
    s.add_argument(
        "--eta-init",
        type=_setting("eta_init"),
        default=None,
        help="initial trust radius, within [eta_lb, eta_ub] = "
        f"[{SCvxSettings().eta_lb:g}, {SCvxSettings().eta_ub:g}] (default: Table 1's, "
        f"{SCvxSettings().eta_init:g} for scvx, {REDUCED_ETA_INIT:g} for tscvx from the "
        "networks' warm start)",
    )
    s.add_argument(
        "--guess",
        metavar="TRAJECTORY",
        help="start SCvx from this trajectory file's x, u and t_f (same N; e.g. an earlier "
        "solve of a neighbouring landing: re-planning) instead of the cubic guess, projected "
        "onto the scenario's boundary conditions and convex path constraints",
    )
    s.add_argument(
        "--at",
        metavar="T",
        type=float,
        help="with --guess: start from that plan's remainder from time T (U_T) on, regridded "
        "over [T, t_f]: in-flight re-planning, the scenario holding the state at T",
    )
    s.add_argument(
        "--pin-final-attitude",
        action="store_true",
        help="require q(t_f) = q_f instead of only an upright touchdown",
    )
    s.add_argument(
        "--ipm-budget",
        type=_setting("socp_max_iter_total", int),
        default=SCvxSettings().socp_max_iter_total,
        metavar="N",
        help="interior-point iterations of the whole solve at most (socp_max_iter_total): the "
        "bound on a guidance call's time; once spent, the solve ends with max_iterations and "
        "the last accepted iterate (default %(default)s: never binds)",
    )
    s.add_argument(
        "--cold-ipm",
        action="store_true",
        help="start every subproblem's interior-point method cold (default with the C "
        "backends: from the last subproblem's answer; Clarabel always starts cold)",
    )
    s.add_argument(
        "--polish",
        action="store_true",
        help="after convergence, one more subproblem without the fuel term that removes the "
        "defects the last trust-region steps left (largest defect 1e-5 -> 1e-10; docs/scvx.md, "
        "'What the defects cost open loop')",
    )
    s.set_defaults(func=cmd_solve)


def _add_scenario(sub: argparse._SubParsersAction) -> None:
    c = sub.add_parser("scenario", help="print a scenario (default: the default) as JSON")
    c.add_argument(
        "scenario",
        nargs="?",
        help="scenario JSON to check and print (parameters only where they differ from the "
        "defaults)",
    )
    c.add_argument(
        "--all",
        action="store_true",
        help="print every parameter a scenario file may set, defaults included",
    )
    c.set_defaults(func=cmd_scenario)


def _add_bench(sub: argparse._SubParsersAction) -> None:
    b = sub.add_parser("bench", help="time the reference SCvx (and the conic solvers)")
    b.add_argument(
        "--backend",
        nargs="+",
        default=["clarabel"],
        choices=BACKENDS,
        help="backends to time, taking turns on each scenario; the speed-ups are against "
        "clarabel when it runs (default: clarabel)",
    )
    b.add_argument(
        "--repeats",
        type=at_least(1),
        default=1,
        help="solves per scenario and backend; the best time counts (default: 1)",
    )
    b.add_argument(
        "--method", choices=METHODS, default="scvx", help="what is timed (default: scvx)"
    )
    b.add_argument("--skip-socp", action="store_true", help="skip the conic solver benchmark")
    b.add_argument(
        "--callgrind",
        action="store_true",
        help="conic solver benchmark: also instructions per solve, ours against QOCO's (valgrind)",
    )
    b.add_argument(
        "--tscvx-landings",
        type=at_least(0),
        default=0,
        help="also compare SCvx and T-SCvx on this many fresh sampled landings",
    )
    b.add_argument(
        "--tscvx-backend",
        default="c",
        choices=BACKENDS,
        help="backend of the --tscvx-landings comparison (default: c)",
    )
    b.set_defaults(func=cmd_bench)


def _add_agreement(sub: argparse._SubParsersAction) -> None:
    a = sub.add_parser(
        "agreement",
        help="final mass of SCvx across conic solvers and tolerances (reference, C library)",
    )
    a.add_argument(
        "scenarios", nargs="*", help="scenario JSON files (given alone: only these landings)"
    )
    a.add_argument(
        "--catalog", nargs="+", help="catalog landings to include, or all (default: all)"
    )
    a.add_argument(
        "--landings", type=at_least(0), help="fresh sampled landings to add (default: 20)"
    )
    add_workers_option(a, "landings solved at once")
    add_prox_u(a, "on which the solvers part")
    a.add_argument(
        "--run-dir",
        type=Path,
        help="folder keeping each landing's outcomes as it finishes (run.json: the run's "
        "landings and settings); the same command again resumes, solving only what is missing",
    )
    a.set_defaults(func=cmd_agreement, interrupted=_agreement_interrupted)


def _agreement_interrupted(args: argparse.Namespace) -> str:
    from guidance import agreement

    return agreement.interrupted(args.run_dir)


def _add_verify(sub: argparse._SubParsersAction) -> None:
    v = sub.add_parser(
        "verify",
        help="fly trajectory files open loop (scipy) and check landing and path constraints",
    )
    v.add_argument("files", nargs="+", help="trajectory .npz files (DESIGN.md contract)")
    tol = file_check.Tolerances()
    v.add_argument(
        "--tol-landing",
        type=positive_float,
        default=tol.landing,
        help=f"|r(t_f) - r_f| and |v(t_f) - v_f| of the propagation (default {tol.landing:g})",
    )
    v.add_argument(
        "--tol-path",
        type=positive_float,
        default=tol.path,
        help=f"largest path-constraint value h at the nodes (default {tol.path:g})",
    )
    v.add_argument(
        "--tol-nodes",
        type=positive_float,
        default=tol.node_deviation,
        help=f"node states against the propagation (default {tol.node_deviation:g})",
    )
    v.add_argument(
        "--tol-flown",
        type=positive_float,
        default=tol.flown_path,
        help="largest state-constraint value h (mass, glideslope, tilt, rate) on the flown "
        f"trajectory's nodes; between them reported, not checked (default {tol.flown_path:g})",
    )
    v.set_defaults(func=cmd_verify)


def _add_dispersion(sub: argparse._SubParsersAction) -> None:
    from guidance import dispersion

    d = sub.add_parser(
        "dispersion",
        help="many sampled landings in the C library, each checked open loop: statuses and "
        "the spread of iterations per call",
        description=dispersion.__doc__.split("\n\n")[0].replace("\n", " "),
    )
    dispersion.add_arguments(d)
    d.set_defaults(func=cmd_dispersion, interrupted=dispersion.interrupted)


def _add_closed_loop(sub: argparse._SubParsersAction) -> None:
    from guidance import closed_loop

    c = sub.add_parser(
        "closed-loop",
        help="fly a landing through a disturbance, re-planning in flight, against open loop",
        description=closed_loop.__doc__.split("\n\n")[0].replace("\n", " "),
    )
    closed_loop.add_arguments(c)
    c.set_defaults(func=cmd_closed_loop)


def cmd_closed_loop(args: argparse.Namespace) -> int:
    from guidance import closed_loop

    return closed_loop.run(args)


def main(argv: Sequence[str] | None = None) -> int:
    args = None
    try:
        with sigterm_as_interrupt():  # SIGTERM stops the command as Ctrl-C does
            args = build_parser().parse_args(argv)
            code = int(args.func(args))
            sys.stdout.flush()  # here, not at exit: a reader that left is then caught below
        return code
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM at any point: exit 130 or 143
        print(f"\ninterrupted{_what_is_kept(args, exc)}", file=sys.stderr)
        return exit_code(exc)
    except (InputError, LibraryNotBuiltError) as exc:  # input that cannot be used, or a C
        print(f"error: {exc}", file=sys.stderr)  # library the command needs is not built
        return EXIT_BAD_INPUT
    except WorkerDiedError as exc:  # the message says what the run kept and how to go on
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except BrokenPipeError:  # the reader of stdout left (`guidance solve | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no error at exit
        return EXIT_BROKEN_PIPE


def _what_is_kept(args: argparse.Namespace | None, exc: KeyboardInterrupt) -> str:
    """ ": what is kept and how to go on" of an interrupted command: its Interrupted's message
    (it knew how far it got), else what its ``interrupted`` default (a function of the
    options) says of any point of the command; "" for a command that sets none."""
    if isinstance(exc, Interrupted):
        return f": {exc}"
    note: Callable[[argparse.Namespace], str] | None = getattr(args, "interrupted", None)
    return f": {note(args)}" if args is not None and note is not None else ""


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
