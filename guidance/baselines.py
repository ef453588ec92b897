"""Lookup-table baselines (paper, "Benchmarking with Table Lookup Approaches").

Same data, split and outputs as the networks (``guidance.nn.train``): the constraint task maps
(theta, k) to the 7N tight bits, the solution task maps theta to the standardized
(x, u, t_f). Two tables:

- KD-tree nearest neighbour (``scipy.spatial.cKDTree``) on the standardized inputs, full
  training split; the prediction is the neighbour's output.
- Linear interpolation over the Delaunay triangulation of the inputs reduced to 10 principal
  components (``sklearn.decomposition.PCA``), evaluated per query by a small linear program
  (see :class:`PCALinearTable`), on a random subset of the training rows as in the paper (the
  paper: 100 training and 10 test rows; here 1,000 and 100 by default, options); test points
  outside the convex hull fall back to the nearest neighbour (their count is reported).

Metrics: mean time of one single-query inference; MSE against the test outputs (for the
constraint task against the 0/1 labels; the network's is its probability MSE); the same on the
OOD test rows (Mahalanobis distance above the training 95th percentile); peak memory, measured
the same way for every method: in a fresh process, after the imports, the peak resident set is
reset (Linux ``/proc/self/clear_refs``) and its rise over the current resident set is recorded
while the process loads the table or model and answers the queries.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import resource
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from guidance.dataset import Dataset
from guidance.errors import InputError
from guidance.nn.conventions import KINDS, TEST_FRACTION, network_file
from guidance.nn.train import dataset_digest, ood_flags, split_bases, standardization, xy
from guidance.scenario import params_from_dict

METHODS = ("Linear Interpolation", "KDTree", "T-SCvx")


@dataclass
class TaskData:
    kind: str
    X_tr: np.ndarray  # standardized inputs
    Y_tr: np.ndarray  # standardized outputs (0/1 labels for the constraint task)
    X_te: np.ndarray
    Y_te: np.ndarray
    X_te_raw: np.ndarray  # raw inputs (for the ONNX models)
    ood: np.ndarray  # bool per test row
    out_mean: np.ndarray
    out_std: np.ndarray


def task_data(
    ds: Dataset, kind: str, test_fraction: float = TEST_FRACTION, seed: int = 0
) -> TaskData:
    solved = ds.solved()
    X, Y, bid, theta = xy(solved, kind)
    trv_b, te_b = split_bases(solved.base_id, test_fraction, seed)
    tr, te = np.isin(bid, trv_b), np.isin(bid, te_b)
    in_mean, in_std = standardization(X[tr])
    if kind == "solution":
        out_mean, out_std = standardization(Y[tr])
    else:
        out_mean, out_std = np.zeros(Y.shape[1]), np.ones(Y.shape[1])
    Xs, Ys = (X - in_mean) / in_std, (Y - out_mean) / out_std
    ood, _ = ood_flags(theta[tr], theta[te])
    return TaskData(kind, Xs[tr], Ys[tr], Xs[te], Ys[te], X[te], ood, out_mean, out_std)


# ---- the two tables -----------------------------------------------------------------------
class KDTreeTable:
    def __init__(self, X: np.ndarray, Y: np.ndarray) -> None:
        from scipy.spatial import cKDTree

        self.tree = cKDTree(X)
        self.Y = Y

    def predict(self, X: np.ndarray) -> np.ndarray:
        _, i = self.tree.query(np.atleast_2d(X), k=1)
        return self.Y[i]


class PCALinearTable:
    """Piecewise-linear (Delaunay) interpolation on the 10-component PCA inputs.

    Building the Delaunay triangulation of even 100 points in 10 dimensions takes minutes and
    gigabytes (the paper reports 1.6 GB), so the containing simplex is found per query instead:
    by the lifting property of the Delaunay triangulation, the barycentric weights of query z
    in the Delaunay simplex that contains it solve the linear program

        min sum_i l_i |z_i|^2   s.t.   sum_i l_i z_i = z,  sum_i l_i = 1,  l >= 0,

    whose optimal vertex has at most d + 1 nonzero weights: exactly those of the simplex. The
    interpolant is sum_i l_i y_i, the same as ``scipy.interpolate.LinearNDInterpolator``. A
    query outside the convex hull (infeasible program) gets the nearest neighbour.
    """

    def __init__(self, X: np.ndarray, Y: np.ndarray, n_components: int = 10) -> None:
        from sklearn.decomposition import PCA

        n = min(n_components, X.shape[1], len(X) - 1)
        self.pca = PCA(n_components=n).fit(X)
        self.Z = self.pca.transform(X)
        self.Y = Y
        self.cost = np.sum(self.Z**2, axis=1)
        self.A_eq = np.vstack([self.Z.T, np.ones(len(self.Z))])
        self.nearest = KDTreeTable(self.Z, Y)
        self.outside = 0

    def weights(self, z: np.ndarray) -> np.ndarray | None:
        from scipy.optimize import linprog

        b = np.concatenate([z, [1.0]])
        r = linprog(self.cost, A_eq=self.A_eq, b_eq=b, bounds=(0, None), method="highs")
        return r.x if r.status == 0 else None

    def predict(self, X: np.ndarray) -> np.ndarray:
        Z = self.pca.transform(np.atleast_2d(X))
        out = np.empty((len(Z), self.Y.shape[1]))
        for i, z in enumerate(Z):
            w = self.weights(z)
            if w is None:
                self.outside += 1
                out[i] = self.nearest.predict(z[None])[0]
            else:
                out[i] = w @ self.Y
        return out


# ---- measurement --------------------------------------------------------------------------
def _status_mb(key: str) -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) / 1024.0  # kB
    raise KeyError(key)


def _reset_peak() -> float:
    """Resets the peak resident set (Linux clear_refs 5) and returns the current one (MB)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return _status_mb("VmRSS")
    except OSError:  # no reset possible: fall back to the process's peak so far
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _peak_mb() -> float:
    try:
        return _status_mb("VmHWM")
    except (OSError, KeyError):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _run_method(spec: dict[str, Any]) -> dict[str, Any]:
    """In a fresh process: load the table/model, answer single queries, report time/memory."""
    # imports first, so that the peak-memory baseline includes them
    import onnxruntime  # noqa: F401
    import scipy.optimize
    import scipy.spatial  # noqa: F401
    import sklearn.decomposition  # noqa: F401

    base = _reset_peak()
    with np.load(spec["data"]) as f:
        d = {k: f[k] for k in f.files}
    t0 = time.perf_counter()
    table: KDTreeTable | PCALinearTable | None = None
    predict: Callable[[np.ndarray], np.ndarray]
    if spec["method"] == "KDTree":
        table = KDTreeTable(d["X_tr"], d["Y_tr"])
        predict = table.predict
    elif spec["method"] == "Linear Interpolation":
        table = PCALinearTable(d["X_tr"], d["Y_tr"])
        predict = table.predict
    else:
        from guidance.nn.infer import load_model

        # the problem of the data it is measured on (a model for another one is refused)
        params = params_from_dict(spec["params"]) if spec.get("params") else None
        model = load_model(spec["model"], spec["kind"], params)
        predict = model.run
    build_s = time.perf_counter() - t0
    X = d["X_query"]
    preds, times = [], []
    for i in range(len(X)):
        t = time.perf_counter()
        preds.append(np.asarray(predict(X[i : i + 1]), dtype=np.float64)[0])
        times.append(time.perf_counter() - t)
    out = {
        "pred": np.array(preds),
        "time_ms": 1e3 * float(np.mean(times)),
        "time_ms_std": 1e3 * float(np.std(times)),
        "build_s": build_s,
        "peak_mb": _peak_mb() - base,
    }
    if isinstance(table, PCALinearTable):
        out["outside_hull"] = table.outside
    return out


def _in_fresh_process(spec: dict[str, Any]) -> dict[str, Any]:
    ctx = mp.get_context("spawn")
    with ctx.Pool(1) as pool:
        return pool.apply(_run_method, (spec,))


def _mse(pred: np.ndarray, Y: np.ndarray) -> float:
    return float(np.mean((pred - Y) ** 2)) if len(Y) else float("nan")


def evaluate_task(
    td: TaskData,
    model_path: str | Path | None,
    interp_train: int = 1000,
    interp_test: int = 100,
    max_queries: int = 2000,
    seed: int = 0,
    params: dict[str, Any] | None = None,
) -> dict[str, dict[str, Any]]:
    """Scores the tables and, when ``model_path`` is a file, the network (for the problem
    ``params``, the data's: default Params when None)."""
    rng = np.random.default_rng(seed)
    q = np.sort(rng.permutation(len(td.X_te))[:max_queries])
    # the constraint tables store bits as bytes, not doubles
    Y_tr = td.Y_tr.astype(np.uint8) if td.kind == "constraint" else td.Y_tr
    results: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        # KD-tree: full training split
        path = Path(tmp) / "kd.npz"
        np.savez(path, X_tr=td.X_tr, Y_tr=Y_tr, X_query=td.X_te[q])
        r = _in_fresh_process({"method": "KDTree", "data": str(path)})
        r.update(rows_train=len(td.X_tr), rows_test=len(q))
        results["KDTree"] = _scored(r, td, q)
        # linear interpolation: the paper's subsets
        tr = rng.permutation(len(td.X_tr))[:interp_train]
        qi = np.sort(rng.permutation(len(td.X_te))[:interp_test])
        path = Path(tmp) / "li.npz"
        np.savez(path, X_tr=td.X_tr[tr], Y_tr=Y_tr[tr], X_query=td.X_te[qi])
        r = _in_fresh_process({"method": "Linear Interpolation", "data": str(path)})
        r.update(rows_train=len(tr), rows_test=len(qi))
        results["Linear Interpolation"] = _scored(r, td, qi)
        if model_path is not None and Path(model_path).is_file():
            path = Path(tmp) / "nn.npz"
            np.savez(path, X_query=td.X_te_raw[q].astype(np.float32))
            spec: dict[str, Any] = {"method": "T-SCvx", "data": str(path), "model": str(model_path)}
            spec.update(kind=td.kind, params=params)
            r = _in_fresh_process(spec)
            raw = r["pred"]
            if td.kind == "constraint":
                r["pred"] = 1.0 / (1.0 + np.exp(-raw))  # probabilities
            else:
                r["pred"] = (raw - td.out_mean) / td.out_std  # standardized
            r.update(rows_train=len(td.X_tr), rows_test=len(q))
            results["T-SCvx"] = _scored(r, td, q)
    return results


def _scored(r: dict[str, Any], td: TaskData, q: np.ndarray) -> dict[str, Any]:
    pred = r.pop("pred")
    Y = td.Y_te[q]
    ood = td.ood[q]
    r["mse"] = _mse(pred, Y)
    r["ood_mse"] = _mse(pred[ood], Y[ood])
    r["ood_rows"] = int(ood.sum())
    return r


def format_table(kind: str, res: dict[str, dict[str, Any]]) -> str:
    title = {
        "constraint": "Tight Constraints Prediction Performance",
        "solution": "Solution Prediction Performance",
    }[kind]
    cols = [m for m in METHODS if m in res]
    rows = [
        ("Inference Time (ms)", "time_ms", "{:.4f}"),
        ("MSE", "mse", "{:.4f}"),
        ("OOD MSE", "ood_mse", "{:.4f}"),
        ("Peak Memory Usage (MB)", "peak_mb", "{:.3f}"),
        ("train / test rows", None, ""),
    ]
    w = 22
    lines = [title, "Metric".ljust(w) + "".join(c.rjust(w) for c in cols)]
    for name, key, fmt in rows:
        if key is None:
            cells = [f"{res[c]['rows_train']} / {res[c]['rows_test']}" for c in cols]
        else:
            cells = [fmt.format(res[c][key]) for c in cols]
        lines.append(name.ljust(w) + "".join(x.rjust(w) for x in cells))
    if res.get("T-SCvx", {}).get("data_warning"):
        lines.append(res["T-SCvx"]["data_warning"])
    li = res.get("Linear Interpolation", {})
    if li.get("outside_hull"):
        lines.append(
            f"(linear interpolation: {li['outside_hull']} of {li['rows_test']} test points "
            "outside the hull, answered by the nearest neighbour)"
        )
    return "\n".join(lines)


def run_baselines(
    ds: Dataset,
    models_dir: str | Path | None,
    interp_train: int = 1000,
    interp_test: int = 100,
    max_queries: int = 2000,
    seed: int = 0,
    kinds: tuple[str, ...] = KINDS,
) -> dict[str, dict[str, dict[str, Any]]]:
    """The tables' and, with ``models_dir``, the networks' scores on each task of ``kinds``.
    A network of ``kinds`` missing from ``models_dir`` is an InputError, before any work:
    scoring only the tables would look like a network-free run."""
    models = {kind: Path(models_dir) / network_file(kind) for kind in kinds} if models_dir else {}
    missing = [str(path) for path in models.values() if not path.is_file()]
    if missing:
        raise InputError(
            f"{' and '.join(missing)}: no such network to score beside the tables (`guidance "
            "export` writes them): give the models folder that holds them, or leave their "
            "kind out (guidance baselines --kind)"
        )
    out = {}
    digest = dataset_digest(ds)
    for kind in kinds:
        td = task_data(ds, kind, seed=seed)
        model = models.get(kind)
        out[kind] = evaluate_task(
            td, model, interp_train, interp_test, max_queries, seed, ds.header.get("params")
        )
        if model is not None and "T-SCvx" in out[kind]:
            out[kind]["T-SCvx"]["data_warning"] = training_data_warning(model, digest, seed)
    return out


def training_data_warning(model: Path, digest: str, seed: int) -> str | None:
    """Why the network may have trained on the test rows it is scored on here (None when its
    export records this dataset, by :func:`dataset_digest`, and this split seed)."""
    from guidance.nn.flight import load_onnx

    props = {p.key: p.value for p in load_onnx(model, load_external_data=False).metadata_props}
    meta = json.loads(props.get("tscvx", "{}"))
    trained, split = meta.get("dataset_content_sha256"), meta.get("split_seed")
    reasons = []
    if trained != digest:
        reasons.append("was trained on another dataset" if trained else "records no dataset")
    if split != seed:
        reasons.append(f"was split with seed {split}, not {seed}")
    if not reasons:
        return None
    return (
        f"WARNING: the T-SCvx network {model.name} {' and '.join(reasons)}: its rows are "
        "scored on test rows it may have trained on"
    )


def results_json(res: dict) -> str:
    return json.dumps(res, indent=1, default=float)
