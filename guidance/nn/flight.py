"""Flight networks: the ``.tnn`` weight file of the C inference (c_runtime/include/tscvx_nn.h)
and ctypes bindings to it.

    python -m guidance.nn.flight models/constraint.onnx build/models/constraint.tnn

``tnn_bytes(onnx_path)`` reads the shipped ONNX file (its initializers, found through the graph
from the named biases of each linear layer, and its ``tscvx`` metadata), checks the weights by
re-running the recorded probes with a float64 NumPy forward pass of the architecture, and
returns the blob: a 128-byte little-endian header (magic, format version, kind, token mode,
dimensions, LayerNorm epsilon, threshold, counts, CRC-32) followed by float64 arrays (layout:
c_runtime/nn/nn_internal.h). Same ONNX file, same bytes.

Why float64 for float32 weights: the conversion is exact (the C arithmetic is the same as
widening float32 at run time), and it buys time, the scarce resource of the RAD750 budget,
for memory, the plentiful one. Scalar x86-64 code at -O2 widens a float32 operand with two
instructions (a dependency-breaking ``pxor`` and ``cvtss2sd``) where a double needs one
``movsd``: the unrolled dot product takes 36 instead of 28 instructions per 8 multiply-adds.
Measured: 3.22 M / 3.69 M host instructions per inference (constraint / solution) with float64;
float32 would add about 1 per multiply-add (0.88 M / 1.01 M MACs), i.e. about 4.1 M / 4.7 M --
a first float32 build with a 4-way unroll measured 4.53 M / 5.19 M, over the 5 M budget. The
constraint network runs up to 20 times per trajectory. The cost is 8.8 + 9.8 MB of weight
files instead of 4.4 + 4.9 MB, of the 60 MB memory budget. (On the PowerPC 750 ``lfs`` and
``lfd`` cost the same, so the float64 count is also the closer model of the target.)

``FlightNet(blob)`` runs the blob (its path, or any bytes-like object) in the C library
(build/libtscvx_gnc.so); a blob the library refuses, or a file that cannot be read, raises
``FlightNetError`` (an ``InputError``) with the status name and message.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import struct
import sys
import threading
import zlib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from guidance.atomic import write_bytes_atomic
from guidance.errors import InputError
from guidance.nn.conventions import CONSTRAINT, PROBE_RTOL, SOLUTION

MAGIC = b"TSCVXNN\0"
FORMAT_VERSION = 2  # 2: the trained-for problem parameters after the probes
HEADER_BYTES = 128
CRC_OFFSET = 124
KIND_CODES = {CONSTRAINT: 1, SOLUTION: 2}  # the blob header's kind field (tscvx_nn.h)
TOKENS = {"single": 0, "scalar": 1}
_HEADER = struct.Struct("<8sIIII8IIIddQQ")  # up to the reserved bytes (96 bytes)
COPY_WEIGHTS = 1
MESSAGE_LEN = 160  # TSCVX_NN_MESSAGE_LEN (tscvx_nn.h)

# tscvx_nn_status, in the order of the C enum
STATUS_NAMES = (
    "ok", "null_argument", "bad_magic", "bad_version", "truncated", "bad_checksum",
    "bad_dimensions", "bad_weights", "bad_alignment", "arena_too_small", "not_ready",
    "bad_size", "bad_input", "numerical_error", "self_test_failed", "bad_flags", "bad_buffer",
)  # fmt: skip


class OnnxLayoutError(InputError):
    """The file is not an ONNX model, or its graph is not the architecture of
    guidance/nn/model.py (or its weights do not reproduce the recorded probes)."""


# ---- ONNX -> arrays ---------------------------------------------------------------------------


@dataclass
class FlightWeights:
    kind: str
    tokens: str
    d_in: int
    d_out: int
    d_model: int
    n_heads: int
    n_layers: int
    d_ff: int
    N: int
    ln_eps: float
    threshold: float
    arrays: list[tuple[str, np.ndarray]]  # float32, in the blob's order
    probe_in: np.ndarray  # (n_probes, d_in) float32
    probe_out: np.ndarray  # (n_probes, d_out) float32
    trained: np.ndarray  # float64: the problem parameters trained for (infer.trained_vector)

    @property
    def seq_len(self) -> int:
        return self.d_in if self.tokens == "scalar" else 1

    def array(self, name: str) -> np.ndarray:
        return dict(self.arrays)[name]


def _linear(graph, inits: dict[str, np.ndarray], bias: str, n_out: int, n_in: int) -> np.ndarray:
    """Weight [n_out][n_in] of the linear layer whose bias initializer is ``bias``."""
    from onnx import helper

    producers = {o: n for n in graph.node for o in n.output}
    users = [n for n in graph.node if bias in n.input]
    if len(users) != 1:
        raise OnnxLayoutError(f"bias {bias!r} is used by {len(users)} nodes, expected 1")
    node = users[0]
    if node.op_type == "Gemm" and list(node.input[2:]) == [bias]:
        attrs = {a.name: helper.get_attribute_value(a) for a in node.attribute}
        if attrs.get("alpha", 1.0) != 1.0 or attrs.get("beta", 1.0) != 1.0 or attrs.get("transA"):
            raise OnnxLayoutError(f"Gemm of {bias!r} is not y = x W^T + b")
        w = inits[node.input[1]]
        w = w if attrs.get("transB", 0) else w.T
    elif node.op_type == "Add":
        other = [i for i in node.input if i != bias]
        mm = producers.get(other[0]) if len(other) == 1 else None
        if mm is None or mm.op_type != "MatMul" or mm.input[1] not in inits:
            raise OnnxLayoutError(f"bias {bias!r} is not added to a MatMul with a weight")
        w = inits[mm.input[1]].T
    else:
        raise OnnxLayoutError(f"bias {bias!r} feeds a {node.op_type}, expected Gemm or Add")
    if w.shape != (n_out, n_in):
        raise OnnxLayoutError(f"weight of {bias!r} has shape {w.shape}, expected {(n_out, n_in)}")
    return np.ascontiguousarray(w, np.float32)


ALLOWED_OPS = {
    "Sub", "Mul", "Add", "Div", "Gemm", "MatMul", "Unsqueeze", "Squeeze", "Reshape",
    "Transpose", "Slice", "Softmax", "LayerNormalization", "Relu", "Flatten", "Constant",
    "Expand", "Shape", "Gather", "Concat",
}  # fmt: skip


def load_onnx(path: str | Path, load_external_data: bool = True) -> Any:
    """The onnx.ModelProto of a file; OnnxLayoutError when the file is not one."""
    import onnx
    from google.protobuf.message import DecodeError

    try:
        return onnx.load(str(path), load_external_data=load_external_data)
    except DecodeError as exc:
        raise OnnxLayoutError(f"{path}: not an ONNX model file ({exc})") from exc
    except OSError as exc:  # a folder or an unreadable file: the user's path
        raise InputError(f"{path}: cannot read it ({exc.strerror or exc})") from None


def read_onnx(path: str | Path) -> FlightWeights:
    """The weights of a T-SCvx ONNX export in the blob's order, checked against the probes
    recorded in its metadata; OnnxLayoutError when the file is not such an export."""
    model = load_onnx(path)
    meta = _tscvx_metadata(path, model)
    try:
        return _weights_of(path, model, meta)
    except (KeyError, TypeError) as exc:  # a hand-edited or foreign metadata entry
        raise OnnxLayoutError(f"{path}: 'tscvx' metadata without a valid {exc}") from None


def _weights_of(path: str | Path, model: Any, meta: dict[str, Any]) -> FlightWeights:
    arch = meta["arch"]
    _check_operators(path, model.graph)
    inits = _Initializers(path, model.graph)
    d_in, d_out, d, ff = arch["d_in"], arch["d_out"], arch["d_model"], arch["d_ff"]
    H, n_layers, tokens = arch["n_heads"], arch["n_layers"], arch["tokens"]
    if (d_in, d_out) != (meta["d_in"], meta["d_out"]) or meta["kind"] not in KIND_CODES:
        raise OnnxLayoutError(f"{path}: metadata sizes or kind inconsistent")
    ln_eps = _layer_norm_eps(path, model.graph, n_layers)
    arrays = _weight_arrays(inits, arch)
    fw = FlightWeights(
        kind=meta["kind"], tokens=tokens, d_in=d_in, d_out=d_out, d_model=d, n_heads=H,
        n_layers=n_layers, d_ff=ff, N=int(meta["N"]), ln_eps=ln_eps,
        threshold=_threshold(path, meta), arrays=arrays,
        probe_in=np.asarray(meta["probe_input"], np.float32).reshape(-1, d_in),
        probe_out=np.asarray(meta["probe_output"], np.float32).reshape(-1, d_out),
        trained=_trained(path, meta),
    )  # fmt: skip
    _check_probes(path, fw)
    return fw


def _tscvx_metadata(path: str | Path, model: Any) -> dict[str, Any]:
    props = {p.key: p.value for p in model.metadata_props}
    if "tscvx" not in props:
        raise OnnxLayoutError(f"{path}: no 'tscvx' metadata: not a T-SCvx model export")
    try:
        meta = json.loads(props["tscvx"])
    except json.JSONDecodeError as exc:
        raise OnnxLayoutError(f"{path}: 'tscvx' metadata is not JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise OnnxLayoutError(f"{path}: 'tscvx' metadata is not a JSON object")
    return meta


def _check_operators(path: str | Path, graph: Any) -> None:
    ops = {n.op_type for n in graph.node} - ALLOWED_OPS
    if ops:
        raise OnnxLayoutError(f"{path}: operators outside the architecture: {sorted(ops)}")


class _Initializers:
    """A graph's initializers, taken by name with the shape the architecture expects."""

    def __init__(self, path: str | Path, graph: Any) -> None:
        from onnx import numpy_helper

        self.path, self.graph = path, graph
        self.arrays = {t.name: numpy_helper.to_array(t) for t in graph.initializer}

    def get(self, name: str, shape: tuple[int, ...]) -> np.ndarray:
        if name not in self.arrays:
            raise OnnxLayoutError(f"{self.path}: initializer {name!r} missing")
        a = np.asarray(self.arrays[name], np.float32)
        if a.size != int(np.prod(shape)):
            raise OnnxLayoutError(f"{self.path}: {name!r} has shape {a.shape}, expected {shape}")
        return a.reshape(shape)

    def linear(self, bias: str, n_out: int, n_in: int) -> np.ndarray:
        """Weight [n_out][n_in] of the linear layer whose bias initializer is ``bias``."""
        return _linear(self.graph, self.arrays, bias, n_out, n_in)


def _layer_norm_eps(path: str | Path, graph: Any, n_layers: int) -> float:
    """The epsilon all LayerNorms share (the C inference has one; 1e-5 without layers)."""
    from onnx import helper

    eps = {
        float(helper.get_attribute_value(a))
        for n in graph.node
        if n.op_type == "LayerNormalization"
        for a in n.attribute
        if a.name == "epsilon"
    }
    if len(eps) > 1 or (n_layers and len(eps) != 1):
        raise OnnxLayoutError(f"{path}: LayerNorm epsilons {sorted(eps)}")
    return eps.pop() if eps else 1e-5


def _weight_arrays(w: _Initializers, arch: dict[str, Any]) -> list[tuple[str, np.ndarray]]:
    """The named arrays of the blob, in its order (c_runtime/nn/nn_internal.h)."""
    d_in, d_out, d, ff = arch["d_in"], arch["d_out"], arch["d_model"], arch["d_ff"]
    L = d_in if arch["tokens"] == "scalar" else 1
    arrays: list[tuple[str, np.ndarray]] = [
        ("in_mean", w.get("in_mean", (d_in,))),
        ("in_scale", w.get("in_scale", (d_in,))),
        ("out_mean", w.get("out_mean", (d_out,))),
        ("out_std", w.get("out_std", (d_out,))),
    ]
    if arch["tokens"] == "single":
        arrays += [
            ("enc_w", w.linear("net.encoder.bias", d, d_in)),
            ("enc_b", w.get("net.encoder.bias", (d,))),
        ]
    else:
        arrays += [("enc_w", w.get("net.enc_w", (L, d))), ("enc_b", w.get("net.enc_b", (L, d)))]
    arrays.append(("pos", w.get("net.pos", (L, d))))
    for i in range(arch["n_layers"]):
        arrays += _layer_arrays(w, f"net.layers.{i}.", d, ff)
    arrays += [
        ("W_d", w.linear("net.decoder.bias", d_out, L * d)),
        ("b_d", w.get("net.decoder.bias", (d_out,))),
    ]
    return arrays


def _layer_arrays(w: _Initializers, p: str, d: int, ff: int) -> list[tuple[str, np.ndarray]]:
    """The arrays of the encoder layer whose names start with ``p``."""
    return [
        (p + "W_qkv", w.linear(p + "qkv.bias", 3 * d, d)),
        (p + "b_qkv", w.get(p + "qkv.bias", (3 * d,))),
        (p + "W_o", w.linear(p + "proj.bias", d, d)),
        (p + "b_o", w.get(p + "proj.bias", (d,))),
        (p + "ln1_g", w.get(p + "norm1.weight", (d,))),
        (p + "ln1_b", w.get(p + "norm1.bias", (d,))),
        (p + "W_1", w.linear(p + "ff1.bias", ff, d)),
        (p + "b_1", w.get(p + "ff1.bias", (ff,))),
        (p + "W_2", w.linear(p + "ff2.bias", d, ff)),
        (p + "b_2", w.get(p + "ff2.bias", (d,))),
        (p + "ln2_g", w.get(p + "norm2.weight", (d,))),
        (p + "ln2_b", w.get(p + "norm2.bias", (d,))),
    ]


def _check_probes(path: str | Path, fw: FlightWeights) -> None:
    got = forward(fw, fw.probe_in.astype(np.float64))
    want = fw.probe_out.astype(np.float64)
    if np.any(np.abs(got - want) > PROBE_RTOL * np.maximum(np.abs(want), 1.0)):
        raise OnnxLayoutError(f"{path}: the extracted weights do not reproduce the probes")


def _threshold(path: str | Path, meta: dict[str, Any]) -> float:
    from guidance.nn.infer import decision_threshold

    try:
        return decision_threshold(meta, meta["kind"])
    except ValueError as exc:
        raise OnnxLayoutError(f"{path}: metadata: {exc}") from None


def _trained(path: str | Path, meta: dict[str, Any]) -> np.ndarray:
    from guidance.nn.infer import trained_vector

    try:
        return trained_vector(meta.get("params", {}))
    except InputError as exc:
        raise OnnxLayoutError(f"{path}: metadata: {exc}") from None


def forward(fw: FlightWeights, x: np.ndarray) -> np.ndarray:
    """float64 NumPy forward pass of the extracted weights (the C library's equations)."""
    a = {k: v.astype(np.float64) for k, v in fw.arrays}
    x = np.atleast_2d(x)
    B, L, d, H = len(x), fw.seq_len, fw.d_model, fw.n_heads
    dh = d // H
    z = (x - a["in_mean"]) * a["in_scale"]
    if fw.tokens == "single":
        h = (z @ a["enc_w"].T + a["enc_b"])[:, None, :]
    else:
        h = z[:, :, None] * a["enc_w"] + a["enc_b"]
    h = h + a["pos"]

    def ln(v: np.ndarray, g: np.ndarray, b: np.ndarray) -> np.ndarray:
        mu = v.mean(-1, keepdims=True)
        var = ((v - mu) ** 2).mean(-1, keepdims=True)
        return (v - mu) / np.sqrt(var + fw.ln_eps) * g + b

    for i in range(fw.n_layers):
        p = f"net.layers.{i}."
        qkv = (h @ a[p + "W_qkv"].T + a[p + "b_qkv"]).reshape(B, L, 3, H, dh)
        q, k, v = (qkv[:, :, j].transpose(0, 2, 1, 3) for j in range(3))  # (B, H, L, dh)
        s = q @ k.transpose(0, 1, 3, 2) / np.sqrt(dh)
        s = np.exp(s - s.max(-1, keepdims=True))
        o = ((s / s.sum(-1, keepdims=True)) @ v).transpose(0, 2, 1, 3).reshape(B, L, d)
        h = ln(h + o @ a[p + "W_o"].T + a[p + "b_o"], a[p + "ln1_g"], a[p + "ln1_b"])
        f = np.maximum(h @ a[p + "W_1"].T + a[p + "b_1"], 0.0)
        h = ln(h + f @ a[p + "W_2"].T + a[p + "b_2"], a[p + "ln2_g"], a[p + "ln2_b"])
    y = h.reshape(B, L * d) @ a["W_d"].T + a["b_d"]
    return y * a["out_std"] + a["out_mean"]


# ---- arrays -> blob ---------------------------------------------------------------------------


def pack(fw: FlightWeights) -> bytes:
    weights = np.concatenate([np.ravel(v) for _, v in fw.arrays]).astype("<f8")
    probes = np.concatenate([np.ravel(fw.probe_in), np.ravel(fw.probe_out)]).astype("<f8")
    trained = np.asarray(fw.trained, "<f8")
    payload = weights.tobytes() + probes.tobytes() + trained.tobytes()
    head = _HEADER.pack(
        MAGIC, FORMAT_VERSION, HEADER_BYTES, KIND_CODES[fw.kind], TOKENS[fw.tokens],
        fw.d_in, fw.d_out, fw.d_model, fw.n_heads, fw.n_layers, fw.d_ff, fw.seq_len, fw.N,
        len(fw.probe_in), trained.size, fw.ln_eps, fw.threshold,
        weights.size + probes.size + trained.size, weights.size,
    )  # fmt: skip
    head += bytes(CRC_OFFSET - len(head))
    crc = zlib.crc32(payload, zlib.crc32(head))
    return head + struct.pack("<I", crc) + payload


def seal(blob: bytes | bytearray) -> bytes:
    """The blob with its CRC-32 recomputed (tests: a blob edited on purpose but not corrupt)."""
    b = bytes(blob)
    crc = zlib.crc32(b[HEADER_BYTES:], zlib.crc32(b[:CRC_OFFSET]))
    return b[:CRC_OFFSET] + struct.pack("<I", crc) + b[HEADER_BYTES:]


def tnn_bytes(onnx_path: str | Path) -> bytes:
    return pack(read_onnx(onnx_path))


def write_tnn(onnx_path: str | Path, out_path: str | Path) -> bool:
    """Writes the blob; an identical existing file is left untouched. Returns True if written."""
    blob = tnn_bytes(onnx_path)
    out = Path(out_path)
    if out.is_file() and out.read_bytes() == blob:
        return False
    write_bytes_atomic(out, blob)
    return True


# ---- ctypes bindings --------------------------------------------------------------------------


class FlightNetError(InputError):
    """The C library refused a blob, an input or a call (``status`` its status name), or the
    wrapper refused the weights before it (``status`` UNREADABLE or NOT_BYTES). An
    InputError: a weight file or an input the user gave, the CLI prints it and exits 2."""

    def __init__(self, status: int | str, message: str, where: str) -> None:
        if isinstance(status, str):
            self.status = status
        else:
            known = 0 <= status < len(STATUS_NAMES)
            self.status = STATUS_NAMES[status] if known else str(status)
        super().__init__(f"{where}: {self.status}: {message}")


UNREADABLE = "unreadable"  # FlightNetError.status of a weight file that cannot be read
NOT_BYTES = "not_bytes"  # of weights that are neither a path nor a bytes-like object


def blob_bytes(blob: object) -> bytes:
    """The weights as bytes: a path's file content, or a bytes-like object's raw bytes whatever
    its item size (len() of a memoryview or array of doubles counts values, not bytes)."""
    if isinstance(blob, (str, Path)):
        try:
            return Path(blob).read_bytes()
        except OSError as exc:  # a folder, a missing or unreadable file
            why = f"cannot read the weight file ({exc.strerror or exc})"
            raise FlightNetError(UNREADABLE, why, str(blob)) from None
    try:
        return memoryview(blob).tobytes()  # type: ignore[arg-type]
    except TypeError:  # bytes(5) would be 5 zero bytes, bytes([1, 2]) a 2-byte blob
        why = f"expected a .tnn path or its bytes (bytes-like), got {type(blob).__name__}"
        raise FlightNetError(NOT_BYTES, why, "FlightNet") from None


class NetInfo(ctypes.Structure):
    _fields_ = [
        *((name, ctypes.c_int) for name in (
            "kind", "tokens", "d_in", "d_out", "d_model", "n_heads", "n_layers", "d_ff",
            "seq_len", "N", "n_probes")),
        ("threshold", ctypes.c_double),
        ("ln_eps", ctypes.c_double),
        ("n_weights", ctypes.c_size_t),
        ("n_params", ctypes.c_int),
        ("params", ctypes.POINTER(ctypes.c_double)),
        ("arena_bytes", ctypes.c_size_t),
        ("weights_in_arena", ctypes.c_int),
    ]  # fmt: skip


_dp = ctypes.POINTER(ctypes.c_double)


@lru_cache(maxsize=1)
def library() -> ctypes.CDLL:
    from guidance.cgnc import open_library

    lib = open_library()
    vp, sz = ctypes.c_void_p, ctypes.c_size_t
    lib.tscvx_nn_status_message.restype = ctypes.c_char_p
    lib.tscvx_nn_status_message.argtypes = [ctypes.c_int]
    lib.tscvx_nn_check_blob.argtypes = [vp, sz, ctypes.c_char_p]
    lib.tscvx_nn_arena_size.argtypes = [vp, sz, ctypes.c_uint, ctypes.POINTER(sz)]
    lib.tscvx_nn_init.argtypes = [ctypes.POINTER(vp), vp, sz, vp, sz, ctypes.c_uint]
    lib.tscvx_nn_run.argtypes = [vp, _dp, ctypes.c_int, _dp, ctypes.c_int]
    lib.tscvx_nn_tight_mask.argtypes = [vp, _dp, ctypes.c_int, ctypes.c_char_p]
    lib.tscvx_nn_get_info.argtypes = [vp, ctypes.POINTER(NetInfo)]
    lib.tscvx_nn_self_test.argtypes = [vp, _dp]
    for f in ("check_blob", "arena_size", "init", "run", "tight_mask", "get_info", "self_test"):
        getattr(lib, f"tscvx_nn_{f}").restype = ctypes.c_int
    return lib


def status_message(status: int) -> str:
    return library().tscvx_nn_status_message(status).decode()


def _check(status: int, where: str) -> None:
    if status != 0:
        raise FlightNetError(status, status_message(status), where)


class FlightNet:
    """One network in the C library: ``run(inputs)`` for (d_in,) or (B, d_in) raw inputs."""

    def __init__(self, blob: bytes | str | Path, copy_weights: bool = False) -> None:
        lib = library()
        blob = blob_bytes(blob)
        self._blob = ctypes.create_string_buffer(blob, len(blob))  # malloc: aligned
        flags = COPY_WEIGHTS if copy_weights else 0
        size = ctypes.c_size_t()
        status = lib.tscvx_nn_arena_size(self._blob, len(blob), flags, ctypes.byref(size))
        if status != 0:
            message = status_message(status)
            why = ctypes.create_string_buffer(MESSAGE_LEN)
            if lib.tscvx_nn_check_blob(self._blob, len(blob), why) == status:  # the blob's fault
                message += f" ({why.value.decode()})"  # the field at fault and its value
            raise FlightNetError(status, message, "tscvx_nn_arena_size")
        self.arena_bytes = size.value
        self._arena = ctypes.create_string_buffer(size.value)
        self._net = ctypes.c_void_p()
        _check(lib.tscvx_nn_init(ctypes.byref(self._net), self._arena, size.value, self._blob,
                                 len(blob), flags), "tscvx_nn_init")  # fmt: skip
        info = NetInfo()
        _check(lib.tscvx_nn_get_info(self._net, ctypes.byref(info)), "tscvx_nn_get_info")
        self.info = info
        self.d_in, self.d_out = info.d_in, info.d_out
        # an inference writes its activations into the arena: one at a time per network
        # (held by run and by the guidance calls that run this network in C)
        self.lock = threading.Lock()

    def run(self, inputs: np.ndarray) -> np.ndarray:
        from guidance.nn.infer import checked_inputs

        x = checked_inputs(inputs, self.d_in, np.float64)
        out = np.empty((len(x), self.d_out))
        with self.lock:
            for i, row in enumerate(x):
                r = np.ascontiguousarray(row)
                y = out[i]
                st = library().tscvx_nn_run(
                    self._net, r.ctypes.data_as(_dp), r.size, y.ctypes.data_as(_dp), y.size
                )
                _check(st, "tscvx_nn_run")
        return out

    def tight_mask(self, logits: np.ndarray) -> np.ndarray:
        lg = np.ascontiguousarray(logits, np.float64)
        buf = ctypes.create_string_buffer(lg.size)
        _check(library().tscvx_nn_tight_mask(self._net, lg.ctypes.data_as(_dp), lg.size, buf),
               "tscvx_nn_tight_mask")  # fmt: skip
        return np.frombuffer(buf.raw, np.uint8).astype(bool)

    def self_test(self) -> float:
        err = ctypes.c_double()
        with self.lock:  # an inference too: its activations go into the arena
            st = library().tscvx_nn_self_test(self._net, ctypes.byref(err))
        _check(st, "tscvx_nn_self_test")
        return err.value


def load_flight_model(path: str | Path, kind: str, params=None) -> FlightNet:
    """A weight file loaded in the C library and checked against the problem, as
    ``guidance.nn.infer.load_model`` checks an ONNX file: kind, input/output sizes, N and the
    problem parameters it was trained for."""
    from guidance.nn.infer import (
        ModelMismatchError,
        _params_diff,
        expected_sizes,
        grid_mismatch,
        trained_dict,
    )
    from guidance.params import Params

    params = params or Params()
    path = Path(path)
    if not path.is_file():
        raise ModelMismatchError(f"model {path}: file not found (run `make lib`)")
    blob = blob_bytes(path)  # FlightNetError (unreadable) as it is: not the library's refusal
    try:
        net = FlightNet(blob)
    except FlightNetError as exc:
        raise ModelMismatchError(f"model {path}: refused by the C library: {exc}") from exc
    got = {v: k for k, v in KIND_CODES.items()}.get(net.info.kind)
    if got != kind:
        raise ModelMismatchError(
            f"model {path}: is a {got!r} network, a {kind!r} one was asked for"
        )
    d_in, d_out = expected_sizes(kind, params.N)
    if net.d_in != d_in:
        raise ModelMismatchError(
            f"model {path}: input size {net.d_in} does not match the problem's {d_in}"
        )
    grid = grid_mismatch(kind, net.info.N, params.N)
    if grid:
        raise ModelMismatchError(f"model {path}: {grid}")
    if net.d_out != d_out:
        raise ModelMismatchError(
            f"model {path}: output size {net.d_out} does not match the problem's {d_out} "
            f"(N = {params.N})"
        )
    recorded = [net.info.params[i] for i in range(net.info.n_params)]
    diff = _params_diff(trained_dict(recorded), params)
    if diff:
        raise ModelMismatchError(
            f"model {path}: trained for other problem parameters: " + "; ".join(diff)
        )
    return net


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m guidance.nn.flight", description=__doc__.splitlines()[0]
    )
    ap.add_argument("onnx", help="shipped ONNX model (models/*.onnx)")
    ap.add_argument("out", help="weight file to write (build/models/*.tnn)")
    args = ap.parse_args(argv)
    try:
        wrote = write_tnn(args.onnx, args.out)
    except (InputError, KeyError, OSError) as exc:  # OnnxLayoutError, an unreadable file
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"{args.out}: {'written' if wrote else 'unchanged'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
