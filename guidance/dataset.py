"""Training data: sampled landings solved by SCvx, with the eight 45-degree rotations.

Pipeline (paper, "Data Sampling Strategy"):

1. Base samples (``guidance.sampling``). Sample ``i`` of a run is drawn from its own generator
   seeded by ``(seed, i)`` over SamplingRanges, redrawn until it is a valid landing.
2. Solve (``guidance.dataset_run``). Every base sample is solved by SCvx in a pool of worker
   processes and written to ``OUT/samples/NNNNNN.npz`` with the record of its run; a restart
   skips the ids already there that fit the run.
3. Augment and pack (here). The solved base samples are rotated about the up axis by 0, 45,
   ..., 315 degrees (``guidance.symmetry``: rotated r, v and q; same omega_B, T_B, m, t_f and
   masks) and written as one versioned ``.npz`` with a JSON header (ranges, seed, SCvx
   settings, parameters, provenance: the code versions that solved the samples and the one
   that packed them, solver package versions, host, creation time). ``load_dataset`` reads
   it back, checked whole.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from guidance.atomic import atomic_write
from guidance.dataset_run import RK4_KEY, done_ids, read_run, read_sample, sample_path
from guidance.errors import UNREADABLE_NPZ, InputError
from guidance.params import NC, NU, NX, SCvxSettings
from guidance.provenance import code_version, provenance
from guidance.sampling import (
    N_ROTATIONS,
    N_THETA,
    ROTATION_DEG,
    THETA_NAMES,
    SamplingRanges,
    draw_scenario,
    rotate_theta,
    theta_of,
)

FORMAT = "tscvx-dataset"
FORMAT_VERSION = 1


def pack(out_dir: str | Path, dataset_path: str | Path, n_base: int | None = None) -> dict:
    """Augment the solved base samples of ``out_dir`` and write the dataset; returns header."""
    from guidance.symmetry import rotate_states

    out = Path(out_dir)
    config = read_run(out)
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
