"""Inference of the shipped networks through onnxruntime, with the checks that refuse a model
that does not fit the problem (input/output size, trained parameters, normalization).

    cm = load_model("models/constraint.onnx", "constraint", scenario.params)
    sm = load_model("models/solution.onnx", "solution", scenario.params)
    theta = theta_of(scenario)
    solve_tscvx(scenario, lambda s: sm.solution(theta), lambda s, k: cm.mask(theta, k))
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from guidance.errors import InputError
from guidance.nn.conventions import PROBE_RTOL
from guidance.params import N_MAX, N_MIN, NC, NU, NX, PARAM_NAMES, Params, Scenario
from guidance.sampling import N_THETA, THETA_NAMES

META_KEY = "tscvx"
META_FORMAT = "tscvx-onnx"
META_VERSION = 1
# Parameters that are network inputs (theta); every other parameter must match the model's.
INPUT_PARAMS = ("glideslope_deg", "tilt_max_deg")
TRAINED_PARAMS = tuple(name for name in PARAM_NAMES if name not in INPUT_PARAMS)


def _metadata_object(path: str | Path, raw: str) -> dict[str, Any]:
    """The model's metadata entry as a JSON object, or ModelMismatchError."""
    try:
        meta = json.loads(raw)
    except json.JSONDecodeError as exc:
        raise _fail(path, f"its '{META_KEY}' metadata is not JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise _fail(path, f"its '{META_KEY}' metadata is not a JSON object")
    return meta


def checked_inputs(inputs: object, d_in: int, dtype: type) -> np.ndarray:
    """Network inputs as a (B, d_in) array of ``dtype``: one input (d_in,) or a batch
    (B, d_in) of finite numbers; InputError otherwise. The onnxruntime and flight-library
    paths take the same inputs through it. Raw bytes are refused: numpy would read each byte
    as one number (16 bytes, two doubles, as 16 inputs)."""
    if _is_raw_bytes(inputs):
        raise InputError(
            f"network inputs: raw bytes ({type(inputs).__name__}), not numbers; give the "
            "values (np.frombuffer(data, np.float64) for the bytes of float64 values)"
        )
    a = np.asarray(inputs)
    if a.ndim not in (1, 2) or a.shape[-1] != d_in or a.dtype.kind not in "biuf":
        raise InputError(
            f"network inputs: expected ({d_in},) or (B, {d_in}) numbers, got {a.shape} "
            f"{a.dtype} values"
        )
    if not np.isfinite(a).all():
        raise InputError("network inputs: not finite (NaN or infinity)")
    with np.errstate(over="ignore"):  # beyond float32: inf, and the output says so
        return np.atleast_2d(a).astype(dtype)


def _is_raw_bytes(inputs: object) -> bool:
    """bytes, bytearray or a memoryview of bytes (format B, b or c): data, not numbers."""
    if isinstance(inputs, memoryview):
        return inputs.format in ("B", "b", "c")
    return isinstance(inputs, (bytes, bytearray))


class ModelMismatchError(InputError):
    """The model file cannot serve this problem; the message says why."""


def expected_sizes(kind: str, N: int) -> tuple[int, int]:
    if kind == "constraint":
        return N_THETA + 1, NC * N
    if kind == "solution":
        return N_THETA, (NX + NU) * N + 1
    raise ValueError(f"unknown model kind {kind!r}")


def grid_mismatch(kind: str, trained_N: object, N: int) -> str | None:
    """Why a ``kind`` network trained on ``trained_N`` nodes cannot serve a problem of N nodes
    (None when it can): the one wording of this refusal, whichever runs the network
    (onnxruntime, or the C library from a .tnn or a converted ONNX file). Its outputs are per
    node, so T-SCvx runs only on the grid its networks were trained for."""
    if trained_N == N:
        return None
    return (
        f"the {kind} network is trained for N = {trained_N}, the problem has N = {N} (T-SCvx "
        f"runs on its networks' grid; SCvx solves any N in [{N_MIN}, {N_MAX}])"
    )


def _fail(path: str | Path, msg: str) -> ModelMismatchError:
    return ModelMismatchError(f"model {path}: {msg}")


def _load_reason(exc: Exception, path: Path) -> str:
    """onnxruntime's reason for refusing a file without the phrase that repeats its path
    ("Load model from PATH failed:"): _fail names the path once. Only that phrase goes (a
    short path such as "O" also occurs inside the reason's own words)."""
    reason = str(exc).replace(f"Load model from {path} failed:", "")
    return reason.strip() or type(exc).__name__


def trained_vector(values: dict[str, Any]) -> np.ndarray:
    """The problem parameters a network was trained for (``Params.to_json_dict`` form), flat
    in TRAINED_PARAMS order, booleans as 0/1: what a .tnn blob records and the C library
    compares with the scenario's (pdg_tscvx.c, the same order)."""
    missing = [name for name in TRAINED_PARAMS if name not in values]
    if missing:
        raise InputError(f"no trained-for value of {', '.join(missing)}")
    return np.concatenate([np.ravel(np.asarray(values[name], float)) for name in TRAINED_PARAMS])


def trained_dict(vector: Sequence[float]) -> dict[str, Any]:
    """trained_vector read back (a blob's record), by name; {} when it has another length."""
    sizes = [int(np.size(Params().to_json_dict()[name])) for name in TRAINED_PARAMS]
    if len(vector) != sum(sizes):
        return {}
    out, i = {}, 0
    for name, n in zip(TRAINED_PARAMS, sizes, strict=True):
        out[name] = list(vector[i : i + n]) if n > 1 else vector[i]
        i += n
    return out


def decision_threshold(meta: dict[str, Any], kind: str) -> float:
    """The decision threshold a model's metadata records: a number in (0, 1), as the flight
    library requires of every blob (tscvx_nn.h). A constraint network must record its own
    (the calibrated one of `guidance train`): read as 0.5 it would miss about one tight bit in
    eight on the shipped network instead of one in a hundred. ValueError saying why otherwise."""
    value = meta.get("threshold")
    if value is None and kind != "constraint":
        return 0.5  # unused: the solution network has no decision
    if value is None:
        raise ValueError("no decision threshold ('threshold') in its metadata")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"decision threshold {value!r} is not a number")
    if not 0.0 < value < 1.0:
        raise ValueError(f"decision threshold {value!r} is outside (0, 1)")
    return float(value)


def _params_diff(trained: dict[str, Any], problem: Params) -> list[str]:
    cur = problem.to_json_dict()
    diff = []
    for key, value in cur.items():
        if key in INPUT_PARAMS:
            continue
        old = trained.get(key)
        same = (
            old is not None
            and np.shape(old) == np.shape(value)
            and np.allclose(np.asarray(old, float), np.asarray(value, float), rtol=1e-12, atol=0)
        )
        if not same:
            diff.append(f"{key} (model {old!r}, problem {value!r})")
    return diff


class OnnxModel:
    """One network loaded and checked. ``run`` takes raw inputs (B, d_in)."""

    def __init__(self, path: str | Path, kind: str, params: Params | None = None) -> None:
        import onnxruntime as ort

        self.path = path = Path(path)
        params = params or Params()
        if not path.is_file():
            raise _fail(
                path,
                "file not found (the shipped networks are in models/; "
                "`make models` trains them again)",
            )
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = 1
        opts.inter_op_num_threads = 1
        try:
            self.session = ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
        except Exception as exc:
            raise _fail(path, f"onnxruntime cannot load it: {_load_reason(exc, path)}") from exc
        raw = self.session.get_modelmeta().custom_metadata_map.get(META_KEY)
        if raw is None:
            raise _fail(path, f"no '{META_KEY}' metadata: not a T-SCvx model export")
        meta = _metadata_object(path, raw)
        if meta.get("format") != META_FORMAT or meta.get("format_version") != META_VERSION:
            raise _fail(path, f"unsupported metadata format {meta.get('format')!r}")
        if meta.get("kind") != kind:
            raise _fail(path, f"is a {meta.get('kind')!r} network, a {kind!r} one was asked for")
        d_in, d_out = expected_sizes(kind, params.N)
        inp = self.session.get_inputs()[0]
        self._check_sizes(meta, kind, params.N, inp.shape[-1], self.session.get_outputs()[0])
        names = [*THETA_NAMES, "k"] if kind == "constraint" else list(THETA_NAMES)
        if meta.get("input_names") != names:
            raise _fail(path, f"inputs {meta.get('input_names')} differ from {names}")
        diff = _params_diff(meta.get("params", {}), params)
        if diff:
            raise _fail(path, "trained for other problem parameters: " + "; ".join(diff))
        self._check_normalization(meta, d_in, d_out)
        self.threshold = self._recorded_threshold(meta, kind)
        self.meta = meta
        self.kind = kind
        self.N = params.N
        self.input_name = inp.name
        self._check_probe()

    def _check_sizes(self, meta: dict, kind: str, N: int, g_in: object, out: Any) -> None:
        """The graph's input size ``g_in`` and output ``out``, and the metadata's sizes and
        grid, those of a ``kind`` network for N nodes."""
        d_in, d_out = expected_sizes(kind, N)
        if g_in != d_in or meta.get("d_in") != d_in:
            raise _fail(
                self.path,
                f"input size {g_in} does not match the problem's {d_in} "
                f"({'theta (16) and the iteration k' if kind == 'constraint' else 'theta (16)'})",
            )
        grid = grid_mismatch(kind, meta.get("N"), N)
        if grid:
            raise _fail(self.path, grid)
        g_out = out.shape[-1]
        if g_out != d_out or meta.get("d_out") != d_out:
            raise _fail(
                self.path, f"output size {g_out} does not match the problem's {d_out} (N = {N})"
            )

    def _check_normalization(self, meta: dict, d_in: int, d_out: int) -> None:
        for key, size in (("in_mean", d_in), ("in_std", d_in), ("out_mean", d_out)):
            v = np.asarray(meta.get(key, []), float)
            if v.shape != (size,) or not np.all(np.isfinite(v)):
                raise _fail(self.path, f"normalization '{key}' has not {size} finite values")
        for key, size in (("in_std", d_in), ("out_std", d_out)):
            v = np.asarray(meta.get(key, []), float)
            if v.shape != (size,) or not np.all(np.isfinite(v)) or np.any(v <= 0):
                raise _fail(self.path, f"normalization '{key}' must be {size} positive values")

    def _recorded_threshold(self, meta: dict, kind: str) -> float:
        try:
            return decision_threshold(meta, kind)
        except ValueError as exc:
            raise _fail(self.path, str(exc)) from None

    def _check_probe(self) -> None:
        """The graph must reproduce the outputs recorded at export: catches a graph whose
        weights or folded normalization are not the exported ones. The statistics of the
        metadata are a record (checked for their sizes and signs by _check_normalization):
        the graph's own are the ones applied, and the probe cannot compare the two."""
        x = np.asarray(self.meta["probe_input"], np.float32)
        want = np.asarray(self.meta["probe_output"], np.float64)
        got = self.run(x).astype(np.float64)
        scale = np.maximum(np.abs(want), 1.0)
        if got.shape != want.shape or np.any(np.abs(got - want) > PROBE_RTOL * scale):
            raise _fail(
                self.path,
                "the graph does not reproduce its recorded probe outputs: its normalization "
                "or weights do not match the metadata",
            )

    def run(self, inputs: np.ndarray) -> np.ndarray:
        a = checked_inputs(inputs, self.meta["d_in"], np.float32)
        return self.session.run(None, {self.input_name: a})[0]


class ConstraintModel(OnnxModel):
    def __init__(self, path: str | Path, params: Params | None = None) -> None:
        super().__init__(path, "constraint", params)

    def probabilities(self, theta: np.ndarray, k: np.ndarray | int) -> np.ndarray:
        theta = np.atleast_2d(theta)
        kk = np.broadcast_to(np.asarray(k, float), (len(theta),))[:, None]
        logits = self.run(np.concatenate([theta, kk], axis=1))
        return 1.0 / (1.0 + np.exp(-logits.astype(np.float64)))

    def mask(self, theta: np.ndarray, k: int) -> np.ndarray | None:
        """Predicted tight mask (7N bools) of iteration k for one scenario; None (the full
        problem, as the flight library takes a failed inference) when the network's output
        is not finite (an overflow inside it), where every bit would read "drop"."""
        p = self.probabilities(theta, k)[0]
        return p >= self.threshold if np.isfinite(p).all() else None

    def mask_fn(self, theta: np.ndarray) -> Callable[[int], np.ndarray | None]:
        """The ``masks`` argument of ``SCvxSolver.solve``: k -> predicted mask."""
        return lambda k: self.mask(theta, k)


class SolutionModel(OnnxModel):
    def __init__(self, path: str | Path, params: Params | None = None) -> None:
        super().__init__(path, "solution", params)

    def solution(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """Warm start (x (N,14), u (N,3), t_f) for one scenario."""
        y = self.run(theta)[0].astype(np.float64)
        N = self.N
        x = y[: N * NX].reshape(N, NX)
        u = y[N * NX : N * (NX + NU)].reshape(N, NU)
        return x, u, float(y[-1])

    def warm_start(self, scenario: Scenario) -> tuple[np.ndarray, np.ndarray, float]:
        """The ``guess`` for ``SCvxSolver.solve``: the prediction with the boundary conditions
        and the convex path constraints made exact (``guess.project_guess``, as on board)."""
        from guidance.guess import project_guess
        from guidance.sampling import theta_of

        return project_guess(scenario, *self.solution(theta_of(scenario)))


def load_model(path: str | Path, kind: str, params: Params | None = None) -> OnnxModel:
    cls = {"constraint": ConstraintModel, "solution": SolutionModel}.get(kind)
    if cls is None:
        raise ValueError(f"unknown model kind {kind!r}")
    return cls(path, params)
