"""Training data: sampled landings solved by SCvx, with the eight 45-degree rotations.

Pipeline (paper, "Data Sampling Strategy"):

1. Base samples. Sample ``i`` of a run is drawn from its own generator seeded by
   ``(seed, i)`` over :class:`SamplingRanges` (positive east/north only), redrawn until
   :func:`guidance.scenario.validate` accepts it. A dataset of n samples is therefore the
   prefix of any larger one with the same seed and ranges.
2. Solve. Every base sample is solved by the reference SCvx in a pool of worker processes
   (one thread each). Each finished sample is written atomically to
   ``OUT/samples/NNNNNN.npz`` (its id: 6 digits, more from 1,000,000) with the record of its
   run (seed, ranges, parameters, SCvx settings, backend); a restart skips the ids already
   there that fit the run, so an interrupted run loses at most the solves in flight.
3. Augment and pack. The solved base samples are rotated about the up axis by 0, 45, ..., 315
   degrees (``guidance.symmetry``: rotated r, v and q; same omega_B, T_B, m, t_f and masks) and
   written as one versioned ``.npz`` with a JSON header (ranges, seed, SCvx settings,
   parameters, provenance: the code versions that solved the samples and the one that packed
   them, solver package versions, host, creation time).

theta (16) = r0 (3), v0 (3), q0 (4), w0 (3, rad/U_T), m0, glideslope_deg, tilt_max_deg.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import os
import signal
import sys
import time
from collections.abc import Callable, Generator, Iterator, Sequence
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from guidance.atomic import atomic_write, set_aside
from guidance.errors import UNREADABLE_NPZ, InputError
from guidance.json_files import ANY, read_json_object
from guidance.params import (
    NC,
    NU,
    NX,
    InitialState,
    Params,
    Scenario,
    SCvxSettings,
    rk4_steps_per_interval,
)
from guidance.provenance import code_version, provenance, record_code_version
from guidance.scenario import ScenarioError, params_from_dict, validate

FORMAT = "tscvx-dataset"
FORMAT_VERSION = 1
N_THETA = 16
THETA_NAMES = (
    "r0_1",
    "r0_2",
    "r0_3",
    "v0_1",
    "v0_2",
    "v0_3",
    "q0_0",
    "q0_1",
    "q0_2",
    "q0_3",
    "w0_1",
    "w0_2",
    "w0_3",
    "m0",
    "glideslope_deg",
    "tilt_max_deg",
)
N_ROTATIONS = 8
ROTATION_DEG = tuple(45.0 * j for j in range(N_ROTATIONS))
STATUSES = ("solved", "infeasible", "max_iterations", "solver_error", "error")
MAX_DRAWS = 1000


@dataclass(frozen=True)
class SamplingRanges:
    """Uniform ranges of the base samples (the paper's Table 5 made physical).

    The paper samples r0 up to 10 and 13.8 U_L, |v0| up to 2.8 U_L/U_T and m0 down to 0.003;
    with this vehicle (I_sp = 30, m_dry = 2, m0 <= 3) most such starts cannot land. These
    ranges keep the draws mostly feasible around the default landing (r0 = (4, 4, 0),
    v0 = (0, -1, -2), m0 = 3, about 76 % of the propellant burnt). Draws below the glideslope,
    beyond the tilt limit or the rate limit are redrawn (``validate``).
    """

    altitude: tuple[float, float] = (2.0, 6.0)  # r0_1, U_L
    horizontal: tuple[float, float] = (0.0, 4.0)  # r0_2, r0_3 (positive east/north), U_L
    v_up: tuple[float, float] = (-1.2, 0.0)  # v0_1, U_L/U_T
    v_horizontal: tuple[float, float] = (-1.5, 0.5)  # v0_2, v0_3, U_L/U_T
    m0: tuple[float, float] = (2.6, 3.0)  # U_M, within (m_dry, 3]
    glideslope_deg: tuple[float, float] = (5.0, 40.0)
    tilt_max_deg: tuple[float, float] = (45.0, 90.0)
    tilt0_deg: tuple[float, float] = (0.0, 30.0)  # initial tilt (capped by tilt_max)
    omega0: tuple[float, float] = (-0.4, 0.4)  # w0_2, w0_3 in rad/U_T; w0_1 = 0 (no roll rate)

    def to_json_dict(self) -> dict[str, list[float]]:
        return {f.name: list(getattr(self, f.name)) for f in dataclasses.fields(self)}

    @classmethod
    def from_json_dict(cls, d: dict[str, Any]) -> SamplingRanges:
        return cls(**{k: tuple(v) for k, v in d.items()})


def _quaternion_from(roll: float, tilt: float, tilt_axis: float) -> np.ndarray:
    """q_B<-I of a vehicle turned by ``roll`` about the up axis then tilted by ``tilt``.

    The tilt axis is horizontal at angle ``tilt_axis`` from east. Scalar first; the result has
    |(q2, q3)| = sin(tilt / 2), so its tilt from vertical is exactly ``tilt``.
    """
    # C_IB = R_tilt(axis a) R_roll(e1); q_I<-B = q_tilt (x) q_roll; q_B<-I is its conjugate.
    a = np.array([0.0, math.cos(tilt_axis), math.sin(tilt_axis)])
    qt = np.concatenate([[math.cos(tilt / 2)], math.sin(tilt / 2) * a])
    qr = np.array([math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0])
    w1, x1, y1, z1 = qt
    w2, x2, y2, z2 = qr
    q_ib = np.array(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )
    q = q_ib * np.array([1.0, -1.0, -1.0, -1.0])
    return q / np.linalg.norm(q)


def draw_scenario(
    rng: np.random.Generator, ranges: SamplingRanges, params: Params | None = None
) -> tuple[Scenario, int]:
    """One physical base scenario and the number of rejected draws before it."""
    base = params or Params()
    for rejected in range(MAX_DRAWS):
        u = rng.uniform
        gs = u(*ranges.glideslope_deg)
        tilt_max = u(*ranges.tilt_max_deg)
        r0 = (u(*ranges.altitude), u(*ranges.horizontal), u(*ranges.horizontal))
        v0 = (u(*ranges.v_up), u(*ranges.v_horizontal), u(*ranges.v_horizontal))
        tilt0 = math.radians(min(u(*ranges.tilt0_deg), tilt_max))
        q0 = _quaternion_from(u(-math.pi, math.pi), tilt0, u(0.0, 2 * math.pi))
        w0 = (0.0, u(*ranges.omega0), u(*ranges.omega0))
        m0 = u(*ranges.m0)
        scenario = Scenario(
            InitialState(r0=r0, v0=v0, q0=tuple(q0), w0=w0, m0=m0),
            base.replace(glideslope_deg=gs, tilt_max_deg=tilt_max),
        )
        try:
            validate(scenario)
        except ScenarioError:
            continue
        return scenario, rejected
    raise RuntimeError(f"no valid scenario in {MAX_DRAWS} draws: check the sampling ranges")


def base_scenario(seed: int, i: int, ranges: SamplingRanges, params: Params | None = None):
    """Base sample ``i`` of the run with ``seed`` (deterministic, independent of the others)."""
    return draw_scenario(np.random.default_rng([seed, i]), ranges, params)


def theta_of(scenario: Scenario) -> np.ndarray:
    s, p = scenario.initial, scenario.params
    return np.concatenate(
        [s.r0, s.v0, s.q0, s.w0, [s.m0, p.glideslope_deg, p.tilt_max_deg]]
    ).astype(np.float64)


def scenario_of(theta: np.ndarray, params: Params | None = None) -> Scenario:
    """Inverse of :func:`theta_of` (other parameters from ``params``)."""
    t = [float(v) for v in theta]
    base = params or Params()
    initial = InitialState(
        r0=tuple(t[0:3]),  # type: ignore[arg-type]
        v0=tuple(t[3:6]),  # type: ignore[arg-type]
        q0=tuple(t[6:10]),  # type: ignore[arg-type]
        w0=tuple(t[10:13]),  # type: ignore[arg-type]
        m0=t[13],
    )
    return Scenario(initial, base.replace(glideslope_deg=t[14], tilt_max_deg=t[15]))


# ---- solving ------------------------------------------------------------------------------
def _limit_threads() -> None:
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "RAYON_NUM_THREADS"):
        os.environ[var] = "1"


def solve_sample(job: tuple[int, int, dict, dict, dict, str]) -> dict[str, Any]:
    """Worker: draw base sample ``i``, solve it, return the record (never raises)."""
    i, seed, ranges_d, params_d, settings_d, backend = job

    ranges = SamplingRanges.from_json_dict(ranges_d)
    params = params_from_dict(params_d)
    settings = SCvxSettings(**settings_d)
    scenario, rejected = base_scenario(seed, i, ranges, params)
    N = params.N
    rec: dict[str, Any] = {"id": i, "theta": theta_of(scenario), "rejected_draws": rejected}
    t0 = time.perf_counter()
    try:
        r = scvx_solver(backend)(scenario, settings)
        rec.update(
            status=r.status,
            reason=r.reason,
            x=r.x,
            u=r.u,
            t_f=r.t_f,
            iterations=r.iterations,
            subproblems=r.subproblems_solved,
            solve_time_s=r.solve_time_s,
            masks=r.masks.astype(np.uint8),
        )
    except Exception as exc:  # a crashed solve is a data point, not a lost run
        rec.update(
            status="error",
            reason=f"{type(exc).__name__}: {exc}",
            x=np.full((N, NX), np.nan),
            u=np.full((N, NU), np.nan),
            t_f=float("nan"),
            iterations=0,
            subproblems=0,
            solve_time_s=time.perf_counter() - t0,
            masks=np.zeros((0, NC * N), np.uint8),
        )
    return rec


def default_backend() -> str:
    """The C library when it is built (issue 5: the flight solver makes the data), else the
    Python reference with Clarabel."""
    from guidance.cguidance import LIB_PATH

    return "c" if LIB_PATH.exists() else "clarabel"


def scvx_solver(backend: str) -> Callable[[Scenario, SCvxSettings], Any]:
    """solve(scenario, settings) of one backend: "c" (the C library), "clarabel", "c-socp"."""
    if backend == "c":
        from guidance.cguidance import solve_c

        return solve_c
    from guidance.scvx import solve_scvx

    return lambda scenario, settings: solve_scvx(scenario, settings, backend)


def _sample_name(i: int) -> str:
    return f"{i:06d}.npz"  # 6 digits, more from id 1,000,000


def sample_path(out_dir: Path, i: int) -> Path:
    return out_dir / "samples" / _sample_name(i)


def _sample_id(path: Path) -> int | None:
    """The id of a file named as sample files are named, else None (a temporary file, one set
    aside, one named by hand such as 0000001.npz)."""
    stem = path.name.removesuffix(".npz")
    if stem == path.name or not (stem.isascii() and stem.isdigit()):
        return None
    return int(stem) if _sample_name(int(stem)) == path.name else None


def run_record(config: dict) -> str:
    """What defines a run's samples (RUN_KEYS of its run.json), as JSON; each sample file
    carries it, so that a sample of another run is recognized without run.json."""
    return json.dumps({k: config[k] for k in RUN_KEYS}, sort_keys=True)


def write_sample(out_dir: Path, rec: dict[str, Any]) -> None:
    path = sample_path(out_dir, rec["id"])
    with atomic_write(path) as f:
        # numpy's stubs read ** as possibly its allow_pickle flag
        np.savez(f, **{k: np.asarray(v) for k, v in rec.items()})  # type: ignore[arg-type]


class SampleError(InputError):
    """A sample file that is unreadable or does not fit its run; ``problem`` says which."""

    def __init__(self, path: Path, problem: str) -> None:
        super().__init__(
            f"sample file {path} {problem}: run `guidance dataset` with the same settings "
            "again, which solves it again"
        )
        self.problem = problem


def read_sample(path: Path, run: dict | None = None) -> dict[str, Any]:
    """A sample file's arrays; with the run's record (run.json), also checked to fit the run
    (keys, shapes, its id, the run it records): a readable sample of another run is refused
    as an unreadable one is."""
    try:
        with np.load(path, allow_pickle=False) as f:
            rec = {k: f[k] for k in f.files}
    except UNREADABLE_NPZ as exc:
        raise SampleError(path, f"is unreadable ({exc})") from None
    if run is not None:
        i = _sample_id(path)
        misfit = "its name is no sample id" if i is None else _sample_misfit(rec, run, i)
        if misfit:
            raise SampleError(path, f"does not fit this run ({misfit})")
    return rec


_SAMPLE_SCALARS = ("t_f", "status", "iterations", "subproblems", "solve_time_s", "id")


def _sample_misfit(rec: dict[str, Any], run: dict, i: int) -> str | None:
    """Why a readable sample cannot be sample ``i`` of the run of this record, or None."""
    return _layout_misfit(rec, int(run["params"]["N"]), i) or _run_misfit(rec, run, i)


def _layout_misfit(rec: dict[str, Any], N: int, i: int) -> str | None:
    """Why a readable sample cannot be sample ``i`` of a run of this N, or None."""
    shapes = {"theta": (N_THETA,), "x": (N, NX), "u": (N, NU)}
    missing = [k for k in (*shapes, "masks", *_SAMPLE_SCALARS) if k not in rec]
    if missing:
        return f"no {', '.join(missing)}"
    for key, shape in shapes.items():
        if rec[key].shape != shape:
            return f"{key} is {rec[key].shape}, the run asks for {shape}"
    if rec["masks"].ndim != 2 or rec["masks"].shape[1] != NC * N:
        return f"masks is {rec['masks'].shape}, the run asks for (iterations, {NC * N})"
    if any(rec[k].size != 1 for k in _SAMPLE_SCALARS) or int(rec["id"]) != i:
        return f"its id or one of {', '.join(_SAMPLE_SCALARS)} is not sample {i}'s"
    return None


def _run_misfit(rec: dict[str, Any], run: dict, i: int) -> str | None:
    """Why a sample of the right layout was not solved in this run, or None. A sample written
    before samples recorded their run is kept when its theta is this run's draw ``i`` (seed,
    ranges and parameters agree; settings and backend only run.json records)."""
    if "run" not in rec:
        return _theta_misfit(rec, run, i)
    try:
        recorded = json.loads(str(rec["run"]))
    except (ValueError, RecursionError):
        recorded = None
    if not isinstance(recorded, dict):
        return "its run record is not a JSON object"
    recorded = with_rk4_steps(recorded)
    wanted = json.loads(run_record(run))
    differ = [k for k in RUN_KEYS if not _same_run_value(k, recorded.get(k), wanted[k])]
    if not differ:
        return None
    seed = f" (seed {recorded.get('seed')!r}, not {run['seed']!r})" if "seed" in differ else ""
    return f"solved in a run with another {', '.join(differ)}{seed}"


def _theta_misfit(rec: dict[str, Any], run: dict, i: int) -> str | None:
    """Why a sample that records no run is not draw ``i`` of this run, or None."""
    ranges = SamplingRanges.from_json_dict(run["ranges"])
    scenario, _ = base_scenario(run["seed"], i, ranges, params_from_dict(run["params"]))
    # a tolerance, not equality: another machine's libm may round the quaternion otherwise
    if np.allclose(rec["theta"], theta_of(scenario), rtol=1e-9, atol=1e-12):
        return None
    return f"it records no run, and its theta is not draw {i} of this run's seed and ranges"


def done_ids(
    out_dir: Path, set_aside_unreadable: bool = False, run: dict | None = None
) -> set[int]:
    """The ids solved in ``out_dir``. Writes are atomic, but a file can still be damaged
    later (a full disk, a copy cut short): with ``set_aside_unreadable`` (a run resuming)
    such a file, or (given the run's record) one that does not fit the run, is renamed
    ``*.unreadable`` (``*.unreadable.1``, ... when that name is taken) and its sample solved
    again."""
    d = out_dir / "samples"
    if not d.is_dir():
        return set()
    ids = set()
    for p in d.glob("*.npz"):  # not a fixed number of digits: ids past 999,999 have more
        i = _sample_id(p)
        if i is None:
            continue
        if set_aside_unreadable:
            try:
                read_sample(p, run)
            except SampleError as exc:
                aside = set_aside(p)
                print(f"{p} {exc.problem}: set aside as {aside}, solved again", file=sys.stderr)
                continue
        ids.add(i)
    return ids


def _run_config_path(out_dir: Path) -> Path:
    return out_dir / "run.json"


def _read_run_config(out_dir: Path, infer: bool = True) -> dict:
    """The run's run.json: a JSON object with the keys of RUN_KEYS; InputError naming the file
    otherwise (a damaged or hand-edited one). ``infer``: RK4_KEY of a record made before it
    filled in (with_rk4_steps); False: the record as written."""
    required = {k: ANY for k in RUN_KEYS if k != RK4_KEY}  # before 27 Nov: no RK4_KEY
    config = read_json_object(
        _run_config_path(out_dir),
        "a dataset run's record",
        "restore it from a copy, or start the run in another --run-dir",
        required,
    )
    return with_rk4_steps(config) if infer else config


# The RK4 steps per FOH interval the run's samples were solved with: a code rule, not a
# setting (params.rk4_steps_per_interval, since 27 Nov). Runs recorded before it have none
# and took rk4_substeps on every grid: the same steps as now at N = 50, fewer on a coarser
# grid, whose samples solved before and after the change must not be packed together.
RK4_KEY = "rk4_steps_per_interval"
RUN_KEYS = ("seed", "ranges", "params", "scvx_settings", "backend", RK4_KEY)


def with_rk4_steps(record: dict) -> dict:
    """A run record (run.json, or the one a sample carries) with RK4_KEY: as recorded, or,
    when it was recorded before the key, the steps of the rule then (rk4_substeps)."""
    if RK4_KEY in record:
        return record
    settings = record.get("scvx_settings")
    substeps = settings.get("rk4_substeps") if isinstance(settings, dict) else None
    return {**record, RK4_KEY: substeps}


# Settings added to SCvxSettings whose default keeps what the code before them did: a run
# (or sample) recorded without one is taken as recorded with its default. Not prox_u (22 Nov:
# runs before it solved the paper's objective) nor socp_warm_start (25 Nov: a cold IPM).
SETTINGS_ADDED_AS_BEFORE = ("socp_max_iter_total",)


def _same_run_value(key: str, recorded: object, wanted: object) -> bool:
    """Whether a run's recorded RUN_KEYS value is ``wanted``, a setting of
    SETTINGS_ADDED_AS_BEFORE missing on either side taken at its default: a run recorded
    before it resumes, and its samples solved before and after the resume pack together."""
    if key == "scvx_settings" and isinstance(recorded, dict) and isinstance(wanted, dict):
        added = {k: getattr(SCvxSettings, k) for k in SETTINGS_ADDED_AS_BEFORE}  # defaults
        recorded, wanted = {**added, **recorded}, {**added, **wanted}
    return recorded == wanted


def _check_run_config(out_dir: Path, config: dict) -> None:
    """A restart must use the same seed, ranges, parameters, settings and backend. The code
    versions that solved into the run are listed in run.json ("code_versions")."""
    path = _run_config_path(out_dir)
    if not path.exists():
        record_code_version(path, config)
        return
    as_written = _read_run_config(out_dir, infer=False)
    old = with_rk4_steps(as_written)
    for key in RUN_KEYS:
        if not _same_run_value(key, old.get(key), config[key]):
            new = config[key]
            given = "" if isinstance(new, dict) else f" ({old.get(key)!r}, not {new!r})"
            raise InputError(
                f"{out_dir} holds samples made with a different {key}{given}; rerun with the "
                "options that made it to resume, or use another --run-dir"
            )
    record_code_version(path, as_written)  # an inferred RK4_KEY is not written as recorded


class WorkerDiedError(RuntimeError):
    """A worker process died (killed by a signal: a crash in a C solver, out of memory)."""


def worker_died(kept: int, total: int, run_dir: Path | None) -> WorkerDiedError:
    """The error of a run stopped by a dead worker: what is kept and how to go on."""
    where = (
        f"{kept} of {total} are kept in {run_dir}; run the same command again to resume"
        if run_dir is not None
        else "nothing is kept without a run directory"
    )
    return WorkerDiedError(
        "a worker process died (killed by a signal: a crash in the solver or out of memory); "
        + where
    )


def generate(
    out_dir: str | Path,
    n_base: int,
    seed: int = 0,
    ranges: SamplingRanges | None = None,
    params: Params | None = None,
    settings: SCvxSettings | None = None,
    workers: int | None = None,
    progress: bool = True,
    backend: str | None = None,
) -> dict[str, int]:
    """Solve base samples 0..n_base-1 not yet in ``out_dir``; returns status counts."""
    out = Path(out_dir)
    (out / "samples").mkdir(parents=True, exist_ok=True)
    ranges = ranges or SamplingRanges()
    params = params or Params()
    settings = settings or SCvxSettings()
    config = {
        "seed": seed,
        "ranges": ranges.to_json_dict(),
        "params": params.to_json_dict(),
        "scvx_settings": dataclasses.asdict(settings),
        "backend": backend or default_backend(),
        RK4_KEY: rk4_steps_per_interval(settings.rk4_substeps, params.N),
    }
    _check_run_config(out, config)
    version, record = code_version(), run_record(config)
    done = done_ids(out, set_aside_unreadable=True, run=config)
    todo = [i for i in range(n_base) if i not in done]
    jobs = [
        (i, seed, config["ranges"], config["params"], config["scvx_settings"], config["backend"])
        for i in todo
    ]
    workers = workers or os.cpu_count() or 1
    counts: dict[str, int] = {}
    bar = _progress(len(jobs), progress, n_base - len(jobs))
    _limit_threads()

    def kept() -> int:
        return len([i for i in done_ids(out) if i < n_base])

    try:
        with pool_results(solve_sample, jobs, workers, kept, n_base, out) as results:
            for rec in results:
                write_sample(out, {**rec, "code_version": version, "run": record})
                counts[str(rec["status"])] = counts.get(str(rec["status"]), 0) + 1
                bar.update(1)
                bar.set_postfix(counts)
    finally:
        bar.close()
    return counts


def _raise_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt  # SIGTERM stops the pool like Ctrl-C: solved samples are kept


def imap_pool(fn: Callable[[Any], Any], jobs: Sequence, workers: int) -> Generator[Any, None, None]:
    """fn over jobs in a pool of single-threaded worker processes, results as they finish (in
    this process when workers <= 1). An exception in the caller (Ctrl-C) stops the pool;
    results already yielded are the caller's to keep. A worker killed by a signal (a crash in
    a C solver, out of memory) raises BrokenProcessPool once the results finished before it
    are yielded."""
    if workers <= 1 or len(jobs) <= 1:
        yield from map(fn, jobs)
        return
    import multiprocessing as mp
    from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait

    ctx = mp.get_context("spawn")  # CasADi/Clarabel state is not fork-safe
    pool = ProcessPoolExecutor(workers, mp_context=ctx, initializer=_worker_init)
    todo = iter(jobs)
    running: set[Future] = set()

    def submit(n: int) -> None:
        for job in itertools.islice(todo, n):
            running.add(pool.submit(fn, job))

    try:
        submit(2 * workers)  # a few queued per worker, not every job at once
        while running:
            done, running = wait(running, return_when=FIRST_COMPLETED)
            submit(len(done))
            failed = [f for f in done if f.exception() is not None]
            for f in done:
                if f.exception() is None:
                    yield f.result()
            if failed:
                raise failed[0].exception()  # type: ignore[misc]
    except BaseException:
        _stop(pool)
        raise
    pool.shutdown()


@contextmanager
def pool_results(
    fn: Callable[[Any], Any],
    jobs: Sequence,
    workers: int,
    kept: Callable[[], int],
    total: int,
    run_dir: Path | None,
) -> Iterator[Generator[Any, None, None]]:
    """``with pool_results(...) as results: for r in results: keep(r)``: imap_pool's results
    for a resumable run that keeps each one as it comes (in ``run_dir``; None: nowhere).
    SIGTERM (a killed job) stops the run as Ctrl-C does, with KeyboardInterrupt in the loop;
    leaving the block stops the pool now, also when the loop fails; a dead worker raises
    WorkerDiedError saying how many of ``total`` are kept (``kept()``) and how to go on."""
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    results = imap_pool(fn, jobs, workers)
    try:
        yield results
    except BrokenProcessPool as exc:
        raise worker_died(kept(), total, run_dir) from exc
    finally:
        results.close()  # stops the pool now, also when the loop fails
        signal.signal(signal.SIGTERM, previous)


def _worker_init() -> None:
    _limit_threads()
    # Ctrl-C reaches the whole process group: the parent stops the workers, which would
    # otherwise each print a KeyboardInterrupt traceback.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _stop(pool: Any) -> None:
    """Ends the workers now, not after their current solve (no public API before 3.14)."""
    for proc in list((pool._processes or {}).values()):
        proc.terminate()
    pool.shutdown(wait=True, cancel_futures=True)


def _progress(total: int, enabled: bool, already: int):
    from tqdm import tqdm

    return tqdm(
        total=total,
        disable=not enabled,
        desc=f"solving ({already} done before)",
        unit="landing",
        file=sys.stderr,
    )


# ---- augmentation and packing -------------------------------------------------------------
def rotate_theta(theta: np.ndarray, psi: float) -> np.ndarray:
    from guidance.symmetry import rotate_states

    out = np.array(theta, dtype=np.float64)
    x0 = np.zeros(NX)
    x0[:13] = theta[:13]
    out[:10] = rotate_states(x0, psi)[:10]
    return out


def pack(out_dir: str | Path, dataset_path: str | Path, n_base: int | None = None) -> dict:
    """Augment the solved base samples of ``out_dir`` and write the dataset; returns header."""
    from guidance.symmetry import rotate_states

    out = Path(out_dir)
    if not _run_config_path(out).is_file():
        raise InputError(
            f"{out} is not a dataset run directory (no run.json): run `guidance dataset` "
            "without --pack-only to make one"
        )
    config = _read_run_config(out)
    ids = sorted(done_ids(out))
    if n_base is not None:
        ids = [i for i in ids if i < n_base]
    if not ids:
        raise InputError(f"no solved samples in {out}: run `guidance dataset` to solve some")
    N = int(config["params"]["N"])
    recs = [read_sample(sample_path(out, i), config) for i in ids]
    it_max = int(config["scvx_settings"]["iter_max"])
    M = len(recs) * N_ROTATIONS
    theta = np.zeros((M, N_THETA))
    x = np.zeros((M, N, NX))
    u = np.zeros((M, N, NU))
    masks = np.zeros((M, it_max, NC * N), np.uint8)
    n_masks = np.zeros(M, np.int16)
    t_f = np.zeros(M)
    status = np.empty(M, dtype="<U16")
    iterations = np.zeros(M, np.int16)
    subproblems = np.zeros(M, np.int16)
    solve_time = np.zeros(M)
    base_id = np.zeros(M, np.int64)  # ids have no upper bound (files packed before: int32)
    rot = np.zeros(M, np.int8)
    for b, rec in enumerate(recs):
        nm = min(len(rec["masks"]), it_max)
        for j, deg in enumerate(ROTATION_DEG):
            m = b * N_ROTATIONS + j
            psi = math.radians(deg)
            theta[m] = rotate_theta(rec["theta"], psi)
            x[m] = rotate_states(rec["x"], psi)
            u[m] = rec["u"]
            masks[m, :nm] = rec["masks"][:nm]
            n_masks[m] = nm
            t_f[m] = rec["t_f"]
            status[m] = str(rec["status"])
            iterations[m] = rec["iterations"]
            subproblems[m] = rec["subproblems"]
            solve_time[m] = rec["solve_time_s"]
            base_id[m] = rec["id"]
            rot[m] = j
    base_status = [str(r["status"]) for r in recs]
    # samples solved before the code version was recorded with each one say so
    versions = sorted({str(r.get("code_version", "unrecorded")) for r in recs})
    counts = {s: base_status.count(s) for s in sorted(set(base_status))}
    header = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "code_version": code_version(),  # of the packing; guidance.nn.card reads it
        "code_versions": versions,  # of the solves in this file
        "provenance": provenance(),
        "seed": config["seed"],
        "sampling_ranges": config["ranges"],
        "params": config["params"],
        "scvx_settings": config["scvx_settings"],
        RK4_KEY: config[RK4_KEY],
        "solver_backend": config.get("backend", "clarabel"),
        "theta_names": list(THETA_NAMES),
        "rotations_deg": list(ROTATION_DEG),
        "n_base": len(recs),
        "n_samples": M,
        "base_status_counts": counts,
        "feasible_fraction": counts.get("solved", 0) / len(recs),
        "mean_rejected_draws": float(np.mean([int(r["rejected_draws"]) for r in recs])),
        "mask_rule": "bit 7k + c, tight at the accepted subproblem of iteration k (scvx.py)",
    }
    path = Path(dataset_path)
    with atomic_write(path) as f:
        np.savez_compressed(
            f,
            header=np.array(json.dumps(header)),
            theta=theta,
            x=x,
            u=u,
            t_f=t_f,
            masks=masks,
            n_masks=n_masks,
            status=status,
            iterations=iterations,
            subproblems=subproblems,
            solve_time_s=solve_time,
            base_id=base_id,
            rotation=rot,
        )
    return header


@dataclass
class Dataset:
    header: dict
    theta: np.ndarray  # (M, 16)
    x: np.ndarray  # (M, N, 14)
    u: np.ndarray  # (M, N, 3)
    t_f: np.ndarray  # (M,)
    masks: np.ndarray  # (M, iter_max, 7N) uint8, valid rows [: n_masks]
    n_masks: np.ndarray  # (M,)
    status: np.ndarray  # (M,) str
    iterations: np.ndarray
    subproblems: np.ndarray
    solve_time_s: np.ndarray
    base_id: np.ndarray
    rotation: np.ndarray

    @property
    def N(self) -> int:
        return int(self.x.shape[1])

    def subset(self, idx: np.ndarray) -> Dataset:
        fields = {
            f.name: getattr(self, f.name)[idx]
            for f in dataclasses.fields(self)
            if f.name != "header"
        }
        return Dataset(header=self.header, **fields)

    def solved(self) -> Dataset:
        return self.subset(np.flatnonzero(self.status == "solved"))

    def solution_targets(self) -> np.ndarray:
        """(M, 17N + 1): x (N*14, node-major), u (N*3), t_f."""
        M = len(self.theta)
        return np.concatenate(
            [self.x.reshape(M, -1), self.u.reshape(M, -1), self.t_f[:, None]], axis=1
        )

    def constraint_pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows (theta, k) -> mask for every recorded iteration; also the row's sample index."""
        rows, idx = [], []
        for m in range(len(self.theta)):
            for k in range(int(self.n_masks[m])):
                rows.append(np.concatenate([self.theta[m], [k + 1.0]]))
                idx.append((m, k))
        if not rows:
            return np.zeros((0, N_THETA + 1)), np.zeros((0, NC * self.N), np.uint8), np.zeros(0)
        ii = np.array(idx)
        return np.array(rows), self.masks[ii[:, 0], ii[:, 1]], ii[:, 0]


def load_dataset(path: str | Path) -> Dataset:
    """A packed dataset, checked whole: its header, every member readable, every array of
    the shape the header's sizes give and of its kind, and of values pack writes (0/1 masks,
    counts and ids in range, finite theta and solved trajectories). InputError names the
    file and member."""
    f = _open_dataset(path)
    with f:
        header = _dataset_header(path, f)
        names = {fd.name for fd in dataclasses.fields(Dataset)} - {"header"}
        if set(f.files) - {"header"} != names:
            missing, extra = names - set(f.files), set(f.files) - names - {"header"}
            raise InputError(
                f"{path}: arrays do not match the {FORMAT} layout (missing "
                f"{sorted(missing) or 'none'}, unknown {sorted(extra) or 'none'})"
            )
        arrays = {k: _member(path, f, k) for k in sorted(names)}
    _check_arrays(path, header, arrays)
    _check_values(path, arrays)
    return Dataset(header=header, **arrays)


def _open_dataset(path: str | Path) -> Any:
    if not Path(path).is_file():
        raise InputError(f"dataset {path}: no such file (`guidance dataset` makes one)")
    try:
        f = np.load(path, allow_pickle=False)
    except UNREADABLE_NPZ as exc:
        raise InputError(f"{path} is not a {FORMAT} file (not a readable .npz)") from exc
    if not isinstance(f, np.lib.npyio.NpzFile):
        raise InputError(f"{path} is not a {FORMAT} file (a single array, not an .npz)")
    return f


def _member(path: str | Path, f: Any, name: str) -> np.ndarray:
    """One array of the file; a damaged one (zlib.error, a bad CRC, an object array...) is
    InputError naming it, not numpy's or zipfile's error naming nothing."""
    try:
        return f[name]
    except UNREADABLE_NPZ as exc:
        raise InputError(
            f"{path}: member {name} is unreadable ({type(exc).__name__}: {exc})"
        ) from exc


def _dataset_header(path: str | Path, f: Any) -> dict:
    raw = _member(path, f, "header") if "header" in f.files else np.array("{}")
    try:
        header = json.loads(str(raw))
    except (ValueError, RecursionError) as exc:
        raise InputError(f"{path}: its header is not JSON ({exc})") from exc
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise InputError(f"{path} is not a {FORMAT} file")
    if header.get("format_version") != FORMAT_VERSION:
        raise InputError(
            f"{path} has format version {header.get('format_version')}, "
            f"this code reads version {FORMAT_VERSION}"
        )
    return header


# Each array's dtype kinds, as pack writes them (masks may also be booleans).
_KINDS = {
    **dict.fromkeys(("theta", "x", "u", "t_f", "solve_time_s"), "f"),
    **dict.fromkeys(("n_masks", "iterations", "subproblems", "base_id", "rotation"), "iu"),
    "masks": "biu",
    "status": "U",
}
_KIND_WORDS = {"f": "floats", "iu": "integers", "biu": "integers or booleans", "U": "strings"}


def _check_arrays(path: str | Path, header: dict, arrays: dict[str, np.ndarray]) -> None:
    """Every array of the shape the header's sizes give and of its kind: a file cut or
    patched by hand fails here, by name, not later in training with numpy's broadcast error."""
    shapes = _dataset_shapes(path, header)
    for name, a in arrays.items():
        shape, kinds = shapes[name], _KINDS[name]
        fits = a.ndim == len(shape) and all(
            w is None or w == n for w, n in zip(shape, a.shape, strict=True)
        )
        if not fits or a.dtype.kind not in kinds:
            want = ", ".join("any" if w is None else str(w) for w in shape)
            raise InputError(
                f"{path}: member {name} holds {a.shape} {a.dtype}, the header's sizes ask "
                f"for ({want}) {_KIND_WORDS[kinds]}"
            )


def _check_values(path: str | Path, arrays: dict[str, np.ndarray]) -> None:
    """The values pack writes (arrays of checked shapes and kinds): a file patched by hand
    or written by other code fails here, by member and sample, not in training as a NaN loss
    or a mask row past the recorded ones. NaN is the padding of x, u and t_f in a sample that
    was not solved (a crashed or failed solve), so only the solved samples' must be finite."""
    K = arrays["masks"].shape[1]  # the header's iter_max (checked by _check_arrays)
    ranges: dict[str, tuple[int, int | None, str]] = {
        "masks": (0, 1, "mask bits 0 or 1"),
        "n_masks": (0, K, f"mask counts within 0..{K} (iter_max)"),
        "iterations": (0, K, f"iteration counts within 0..{K} (iter_max)"),
        "subproblems": (0, None, "non-negative subproblem counts"),
        "base_id": (0, None, "non-negative sample ids"),
        "rotation": (0, N_ROTATIONS - 1, f"rotation indices within 0..{N_ROTATIONS - 1}"),
    }
    for name, (lo, hi, want) in ranges.items():
        a = arrays[name]
        if a.size and (a.min() < lo or (hi is not None and a.max() > hi)):
            bad = (a < lo) | (a > hi) if hi is not None else a < lo
            _bad_value(path, name, a, bad, want)
    solved = arrays["status"] == "solved"
    finite = {
        "theta": None,
        "solve_time_s": None,
        "x": solved,
        "u": solved,
        "t_f": solved,
    }
    for name, rows in finite.items():
        a = arrays[name]
        ok = np.isfinite(a) if rows is None else np.isfinite(a) | ~_along(rows, a)
        if not ok.all():
            where = "finite values" if rows is None else "finite values in solved samples"
            _bad_value(path, name, a, ~ok, where)


def _along(rows: np.ndarray, a: np.ndarray) -> np.ndarray:
    """A per-sample (M,) flag broadcast over the other axes of ``a``."""
    return rows.reshape(rows.shape + (1,) * (a.ndim - 1))


def _bad_value(path: str | Path, name: str, a: np.ndarray, bad: np.ndarray, want: str) -> NoReturn:
    first = tuple(int(i) for i in np.argwhere(bad)[0])
    raise InputError(
        f"{path}: member {name} holds {a[first].item()!r} at {first} (sample {first[0]}; "
        f"{int(np.count_nonzero(bad))} such values), pack writes {want}"
    )


def _dataset_shapes(path: str | Path, header: dict) -> dict[str, tuple[int | None, ...]]:
    """Each array's shape from the header: n_samples rows, params.N nodes and, when the header
    records the settings (every packed file does), scvx_settings.iter_max mask rows."""
    M = _header_size(path, header, "n_samples")
    N = _header_size(path, header, "params", "N")
    K = (
        _header_size(path, header, "scvx_settings", "iter_max")
        if "scvx_settings" in header
        else None
    )
    shapes: dict[str, tuple[int | None, ...]] = dict.fromkeys(_KINDS, (M,))
    shapes.update(theta=(M, N_THETA), x=(M, N, NX), u=(M, N, NU), masks=(M, K, NC * N))
    return shapes


def _header_size(path: str | Path, header: dict, *keys: str) -> int:
    value: Any = header
    for key in keys:
        value = value.get(key) if isinstance(value, dict) else None
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise InputError(f"{path}: its header gives no {'.'.join(keys)} count ({value!r})")
    return value


def summary(header: dict) -> str:
    c = header["base_status_counts"]
    return (
        f"{header['n_base']} base samples x {len(header['rotations_deg'])} rotations = "
        f"{header['n_samples']} samples; base status {c}; feasible fraction "
        f"{100 * header['feasible_fraction']:.1f} %"
    )


def random_dataset(n_base: int = 12, N: int = 50, seed: int = 0, iters: int = 5) -> Dataset:
    """A synthetic (not physical) dataset with the real layout, for tests of the learning code.

    theta from the default ranges; targets are smooth functions of theta plus noise; masks are
    thresholds of such functions, so that there is something to learn.
    """
    rng = np.random.default_rng(seed)
    ranges = SamplingRanges()
    theta = np.array([theta_of(draw_scenario(rng, ranges)[0]) for _ in range(n_base)])
    theta = np.concatenate(
        [[rotate_theta(t, math.radians(d)) for d in ROTATION_DEG] for t in theta]
    )
    M = len(theta)
    W = rng.standard_normal((N_THETA, N * (NX + NU) + 1)) / 4
    y = np.tanh(theta @ W) + 0.01 * rng.standard_normal((M, W.shape[1]))
    Wm = rng.standard_normal((N_THETA + 1, NC * N))
    masks = np.zeros((M, SCvxSettings().iter_max, NC * N), np.uint8)
    for k in range(iters):
        z = np.concatenate([theta, np.full((M, 1), k + 1.0)], axis=1) @ Wm
        masks[:, k] = z > 2.0 * z.std()
    header = {"format": FORMAT, "format_version": FORMAT_VERSION, "n_base": n_base}
    return Dataset(
        header=header,
        theta=theta,
        x=y[:, : N * NX].reshape(M, N, NX),
        u=y[:, N * NX : N * (NX + NU)].reshape(M, N, NU),
        t_f=y[:, -1],
        masks=masks,
        n_masks=np.full(M, iters, np.int16),
        status=np.array(["solved"] * M),
        iterations=np.full(M, iters, np.int16),
        subproblems=np.full(M, iters, np.int16),
        solve_time_s=np.ones(M),
        base_id=np.repeat(np.arange(n_base), N_ROTATIONS).astype(np.int64),
        rotation=np.tile(np.arange(N_ROTATIONS), n_base).astype(np.int8),
    )
