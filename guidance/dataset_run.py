"""Training data, step 2: the base samples solved by SCvx into a run folder, and read back.

(Paper, "Data Sampling Strategy"; the overview is guidance.dataset's.) Every base sample
(guidance.sampling) is solved by SCvx in a pool of worker processes (one thread each,
guidance.pool). Each finished sample is written atomically to ``OUT/samples/NNNNNN.npz`` (its
id: 6 digits, more from 1,000,000) with the record of its run (seed, ranges, parameters, SCvx
settings, backend); a restart skips the ids already there that fit the run, so an interrupted
run loses at most the solves in flight.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from guidance.atomic import atomic_write, set_aside
from guidance.errors import UNREADABLE_NPZ, InputError, npz_damage
from guidance.json_files import ANY, read_json_object
from guidance.params import (
    NC,
    NU,
    NX,
    Params,
    Scenario,
    SCvxSettings,
    rk4_steps_per_interval,
)
from guidance.pool import limit_threads, pool_results
from guidance.provenance import code_version
from guidance.runs import record_code_version
from guidance.sampling import N_THETA, SamplingRanges, base_scenario, theta_of
from guidance.scenario import params_from_dict


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
            f"sample file {path} {problem}: run `guidance dataset` again with the run's options "
            "and without --pack-only, which sets the file aside (as .unreadable) and solves "
            "its sample again, then packs"
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
        raise SampleError(path, f"is {npz_damage(exc)}") from None
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


def read_run(out_dir: Path) -> dict:
    """The record of the run in ``out_dir`` (as _read_run_config), to pack its samples;
    InputError when the folder holds no run."""
    if not _run_config_path(out_dir).is_file():
        raise InputError(
            f"{out_dir} is not a dataset run directory (no run.json): run `guidance dataset` "
            "without --pack-only to make one"
        )
    return _read_run_config(out_dir)


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
    limit_threads()

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


def _progress(total: int, enabled: bool, already: int):
    from tqdm import tqdm

    return tqdm(
        total=total,
        disable=not enabled,
        desc=f"solving ({already} done before)",
        unit="landing",
        file=sys.stderr,
    )
