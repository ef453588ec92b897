"""Flight C inference of the networks (c_runtime/include/tscvx_nn.h, guidance/nn/flight.py):
equal to onnxruntime on the shipped networks and on other architectures, reproducible weight
files, refusal of corrupt or mismatched models and of bad inputs, no heap allocation inside
tscvx_nn_run."""

from __future__ import annotations

import ctypes
import json
import re
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

from guidance import cgnc
from guidance.errors import InputError
from guidance.nn import flight
from guidance.nn.flight import FlightNet, FlightNetError

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
BUILD_MODELS = ROOT / "build" / "models"
DRIVER = ROOT / "build" / "nn_budget_driver"
KINDS = ("constraint", "solution")
TOL = 1e-5  # |C - onnxruntime| <= TOL * max(1, |onnxruntime|), element-wise (float32 graph)

needs_lib = pytest.mark.skipif(not cgnc.available(), reason="build/libtscvx_gnc.so: run make lib")
needs_shipped = pytest.mark.skipif(
    not (MODELS / "constraint.onnx").exists(), reason="no shipped models"
)
needs_built = pytest.mark.skipif(
    not (BUILD_MODELS / "constraint.tnn").exists(), reason="build/models: run make lib"
)


def _ort_session(path: Path):
    ort = pytest.importorskip("onnxruntime")
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = 1
    return ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])


def _random_inputs(meta: dict, n: int, seed: int) -> np.ndarray:
    """Raw inputs around the training distribution (float32, as the ONNX graph takes them)."""
    rng = np.random.default_rng(seed)
    mean, std = np.asarray(meta["in_mean"]), np.asarray(meta["in_std"])
    return (mean + rng.standard_normal((n, len(mean))) * std).astype(np.float32)


def _compare(c: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(c - ref) / np.maximum(1.0, np.abs(ref))))


@pytest.fixture(scope="module")
def blobs() -> dict[str, bytes]:
    return {k: flight.tnn_bytes(MODELS / f"{k}.onnx") for k in KINDS}


# ---- shipped networks ---------------------------------------------------------------------------


@needs_shipped
@needs_lib
@pytest.mark.parametrize("kind", KINDS)
def test_c_equals_onnxruntime_on_1000_inputs(kind: str, blobs: dict[str, bytes]) -> None:
    sess = _ort_session(MODELS / f"{kind}.onnx")
    meta = json.loads(sess.get_modelmeta().custom_metadata_map["tscvx"])
    X = _random_inputs(meta, 1000, seed=11)
    want = sess.run(None, {"inputs": X})[0].astype(np.float64)
    net = FlightNet(blobs[kind])
    got = net.run(X.astype(np.float64))
    assert got.shape == want.shape == (1000, meta["d_out"])
    rel = _compare(got, want)
    abs_err = float(np.max(np.abs(got - want)))
    print(f"\n{kind}: max |C - onnxruntime| = {abs_err:.3e} (relative {rel:.3e}), 1000 inputs")
    assert rel <= TOL
    # the C code is the float64 NumPy forward pass of the same weights, to rounding
    assert _compare(got[:50], flight.forward(flight.read_onnx(MODELS / f"{kind}.onnx"),
                                             X[:50].astype(np.float64))) < 1e-11  # fmt: skip
    assert net.self_test() < 1e-5


@needs_shipped
@needs_built
@needs_lib
def test_c_mask_equals_the_onnx_models_mask(blobs: dict[str, bytes]) -> None:
    from guidance.catalog import SCENARIOS
    from guidance.nn.infer import load_model
    from guidance.sampling import theta_of

    cm = load_model(MODELS / "constraint.onnx", "constraint")
    net = flight.load_flight_model(BUILD_MODELS / "constraint.tnn", "constraint")
    assert net.info.threshold == pytest.approx(cm.threshold, rel=0, abs=0)
    theta = theta_of(SCENARIOS["default"])
    agree = total = 0
    for k in range(1, 21):
        logits = net.run(np.concatenate([theta, [k]]))[0]
        mask_c = net.tight_mask(logits)
        p = 1.0 / (1.0 + np.exp(-logits))
        clear = np.abs(p - cm.threshold) > 1e-4  # away from the decision boundary
        agree += int(np.sum(mask_c[clear] == cm.mask(theta, k)[clear]))
        total += int(np.sum(clear))
    assert agree == total and total > 20 * 340


@needs_shipped
def test_weight_files_are_reproducible(blobs: dict[str, bytes]) -> None:
    from guidance.nn.model_files import check_model_files

    check_model_files(MODELS, BUILD_MODELS)  # the files metrics.json records, when it does
    for kind in KINDS:
        again = flight.tnn_bytes(MODELS / f"{kind}.onnx")
        assert again == blobs[kind]
        built = BUILD_MODELS / f"{kind}.tnn"
        if built.exists():
            assert built.read_bytes() == blobs[kind], f"{built} is stale: run make lib"
        fw = flight.read_onnx(MODELS / f"{kind}.onnx")
        head = struct.unpack_from("<8sII", blobs[kind])
        assert head == (flight.MAGIC, flight.FORMAT_VERSION, flight.HEADER_BYTES)
        n_values = struct.unpack_from("<Q", blobs[kind], 80)[0]
        assert len(blobs[kind]) == flight.HEADER_BYTES + 8 * n_values
        assert fw.tokens == "single" and fw.d_model == 256


@needs_shipped
@needs_built
@needs_lib
def test_model_for_another_problem_is_refused() -> None:
    from guidance.nn.infer import ModelMismatchError
    from guidance.params import Params

    path = BUILD_MODELS / "constraint.tnn"
    with pytest.raises(ModelMismatchError, match="trained for N = 50, the problem has N = 40"):
        flight.load_flight_model(path, "constraint", Params(N=40))
    with pytest.raises(ModelMismatchError, match="'constraint' network"):
        flight.load_flight_model(path, "solution")
    with pytest.raises(ModelMismatchError, match="file not found"):
        flight.load_flight_model(path.with_name("missing.tnn"), "solution")


# ---- refusals -----------------------------------------------------------------------------------


def _edit(blob: bytes, offset: int, fmt: str, value, seal: bool = True) -> bytes:
    b = bytearray(blob)
    struct.pack_into(fmt, b, offset, value)
    return flight.seal(b) if seal else bytes(b)


@needs_shipped
@needs_lib
def test_corrupt_or_mismatched_blob_is_refused_with_the_message(blobs: dict[str, bytes]) -> None:
    good = blobs["constraint"]
    n_values = struct.unpack_from("<Q", good, 80)[0]
    cases = {
        "bad_magic": b"XSCVXNN\0" + good[8:],
        "bad_version": _edit(good, 8, "<I", 1),  # format 1: no trained-for parameters
        "truncated": good[:-8],
        "bad_checksum": _edit(good, len(good) // 2, "<d", 0.123, seal=False),
        "bad_dimensions": _edit(good, 28, "<I", 351),  # d_out no longer matches the weights
        "bad_weights": _edit(good, flight.HEADER_BYTES + 8 * 1000, "<d", float("nan")),
    }
    messages = {
        "bad_magic": "bad magic",
        "bad_version": "format version",
        "truncated": "length does not match",
        "bad_checksum": "CRC-32",
        "bad_dimensions": "dimensions",
        "bad_weights": "NaN/inf",
    }
    # and what tscvx_nn_check_blob says of the field at fault
    fields = {
        "bad_magic": "the first 8 bytes are not",
        "bad_version": "format 1 with a 128-byte header",
        "truncated": f"n_values = {n_values} asks for 128 + 8 x {n_values}",
        "bad_checksum": "CRC-32 of the blob is",
        "bad_dimensions": "d_in = 17, d_out = 351 do not fit a constraint network of N = 50",
        "bad_weights": f"value 1000 of {n_values} is NaN or infinite",
    }
    for status, blob in cases.items():
        with pytest.raises(FlightNetError, match=messages[status]) as info:
            FlightNet(blob)
        assert info.value.status == status
        assert fields[status] in str(info.value)
    assert n_values > 1000
    # heads that do not divide d_model
    with pytest.raises(FlightNetError, match="bad_dimensions") as info:
        FlightNet(_edit(good, 36, "<I", 3))
    assert "d_model = 256 is not a multiple of n_heads = 3" in str(info.value)
    # a reserved byte set: a later format's field this library does not know
    with pytest.raises(FlightNetError, match="format version"):
        FlightNet(_edit(good, 100, "<B", 1))


@needs_shipped
@needs_lib
def test_a_network_trained_for_other_parameters_is_refused_naming_them() -> None:
    """The blob records the problem parameters the network was trained for (every one that
    is not a network input); the C library compares each with the scenario's and names the
    first that differs. Each of the 35 values is changed in turn, so the order written by
    guidance/nn/infer.py and the one read by pdg_tscvx.c must be the same."""
    import dataclasses

    from guidance import cguidance
    from guidance.catalog import SCENARIOS
    from guidance.nn.infer import TRAINED_PARAMS, trained_vector
    from guidance.params import Params

    fw = flight.read_onnx(MODELS / "solution.onnx")
    np.testing.assert_array_equal(fw.trained, trained_vector(Params().to_json_dict()))
    fields = [
        name if np.size(value) == 1 else f"{name}[{k}]"
        for name in TRAINED_PARAMS
        for value in [Params().to_json_dict()[name]]
        for k in range(np.size(value))
    ]
    assert len(fields) == fw.trained.size == 35
    for i, field in enumerate(fields):
        trained = fw.trained.copy()
        trained[i] = 2.0 * trained[i] + 0.5  # differs from every default, zeros included
        net = FlightNet(flight.pack(dataclasses.replace(fw, trained=trained)))
        with pytest.raises(cguidance.FlightNetsError, match=re.escape(f"parameters: {field} (")):
            cguidance.solve_tscvx_c(SCENARIOS["default"], masks=False, nets=(net, None))


@needs_shipped
@needs_lib
def test_bad_inputs_are_refused(blobs: dict[str, bytes]) -> None:
    net = FlightNet(blobs["solution"], copy_weights=True)
    assert net.info.weights_in_arena == 1
    x = np.zeros(16)
    x[6] = 1.0
    assert np.all(np.isfinite(net.run(x)))
    # the wrapper refuses these before the C call, as the onnxruntime path does (the C
    # library's own bad_size and bad_input refusals: c_runtime/nn/tests/test_nn.c)
    with pytest.raises(InputError, match=r"expected \(16,\) or \(B, 16\) numbers, got \(17,\)"):
        net.run(np.zeros(17))
    for bad in (np.nan, np.inf):
        x[3] = bad
        with pytest.raises(InputError, match="not finite"):
            net.run(x)
    with pytest.raises(FlightNetError, match="bad_size"):
        net.tight_mask(np.zeros(851))  # a solution network has no mask


@needs_lib
def test_a_cut_off_magic_is_truncated_not_bad_magic() -> None:
    """Review of 27 Nov: the first 1 to 7 bytes of a blob were `bad_magic` ("the first 8 bytes
    are not ..."), a cut-off file taken for a foreign one. Bytes that begin the magic (none
    too) are `truncated` now, with their length; other short bytes are still `bad_magic`."""
    for n in range(8):
        with pytest.raises(FlightNetError, match="length does not match") as info:
            FlightNet(flight.MAGIC[:n])
        assert info.value.status == "truncated"
        assert f"({n} bytes, shorter than the 8-byte magic and the 128-byte header)" in str(
            info.value
        )
    with pytest.raises(FlightNetError, match="bad magic") as info:
        FlightNet(b"TSCVYNN")
    assert info.value.status == "bad_magic"
    assert "the first 7 bytes are not those of" in str(info.value)


@needs_shipped
@needs_lib
def test_an_output_in_the_networks_arena_is_refused_by_name(blobs: dict[str, bytes]) -> None:
    """Review of 27 Nov: tscvx_nn_run wrote an output that overlaps the net's arena (its
    activations, the net itself) without a word. It is `bad_buffer` now (the C cases, input,
    output over the input or over the blob, init: c_runtime/nn/tests/test_nn.c), a status the
    wrapper names: STATUS_NAMES is in step with the C enum."""
    n = len(flight.STATUS_NAMES)
    assert flight.status_message(n - 1) != "unknown tscvx_nn_status"
    assert flight.status_message(n) == "unknown tscvx_nn_status"
    net = FlightNet(blobs["constraint"])
    x = np.zeros(net.d_in)
    want = net.run(x)
    end = ctypes.addressof(net._arena) + net.arena_bytes
    inside = ctypes.cast((end - 8 * net.d_out) // 8 * 8, flight._dp)  # the arena's last bytes
    st = flight.library().tscvx_nn_run(
        net._net, x.ctypes.data_as(flight._dp), net.d_in, inside, net.d_out
    )
    error = FlightNetError(st, flight.status_message(st), "tscvx_nn_run")
    assert error.status == "bad_buffer" and "overlapping buffers" in str(error)
    np.testing.assert_array_equal(net.run(x), want)  # the net untouched


def test_onnx_that_is_not_a_tscvx_export_is_refused(tmp_path: Path) -> None:
    onnx = pytest.importorskip("onnx")
    from onnx import TensorProto, helper, numpy_helper

    W = numpy_helper.from_array(np.zeros((16, 3), np.float32), "W")
    graph = helper.make_graph(
        [helper.make_node("MatMul", ["inputs", "W"], ["y"])], "g",
        [helper.make_tensor_value_info("inputs", TensorProto.FLOAT, [1, 16])],
        [helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 3])], [W],
    )  # fmt: skip
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    onnx.save(model, str(tmp_path / "plain.onnx"))
    with pytest.raises(flight.OnnxLayoutError, match="no 'tscvx' metadata"):
        flight.read_onnx(tmp_path / "plain.onnx")
    assert flight.main([str(tmp_path / "plain.onnx"), str(tmp_path / "x.tnn")]) == 2
    assert not (tmp_path / "x.tnn").exists()


# ---- other architectures (random weights, exported as the shipped models are) --------------------

ARCHS = [
    dict(tokens="scalar", d_model=16, n_heads=2, n_layers=2, d_ff=24),
    dict(tokens="scalar", d_model=12, n_heads=3, n_layers=1, d_ff=20),
    dict(tokens="single", d_model=24, n_heads=4, n_layers=3, d_ff=40),
    dict(tokens="single", d_model=8, n_heads=2, n_layers=0, d_ff=16),
]


@needs_lib
@pytest.mark.parametrize("arch", ARCHS, ids=lambda a: f"{a['tokens']}-d{a['d_model']}")
def test_other_architectures_equal_onnxruntime(arch: dict, tmp_path: Path) -> None:
    torch = pytest.importorskip("torch")
    from guidance.nn.export import export_onnx
    from guidance.nn.model import ArchConfig, Transformer
    from guidance.nn.train import TrainResult
    from guidance.params import Params

    torch.manual_seed(3)
    kind = "constraint" if arch["tokens"] == "single" else "solution"
    d_in, d_out = (17, 350) if kind == "constraint" else (16, 851)
    cfg = ArchConfig(d_in=d_in, d_out=d_out, dropout=0.0, **arch)
    net = Transformer(cfg)
    with torch.no_grad():  # the positional encoding and LayerNorms away from their defaults
        for name, p in net.named_parameters():
            if "pos" in name or "norm" in name:
                p.add_(0.3 * torch.randn_like(p))
    rng = np.random.default_rng(4)
    res = TrainResult(
        kind=kind, arch=cfg, net=net, in_mean=rng.standard_normal(d_in),
        in_std=0.5 + rng.random(d_in), out_mean=rng.standard_normal(d_out),
        out_std=0.5 + rng.random(d_out), threshold=0.2, metrics={},
    )  # fmt: skip
    path = tmp_path / f"{kind}.onnx"
    meta = export_onnx(res, path, Params().to_json_dict())
    c = FlightNet(flight.tnn_bytes(path))
    assert (c.info.tokens, c.info.seq_len) == (flight.TOKENS[arch["tokens"]], cfg.seq_len)
    X = _random_inputs(meta, 200, seed=5)
    want = _ort_session(path).run(None, {"inputs": X})[0].astype(np.float64)
    rel = _compare(c.run(X.astype(np.float64)), want)
    print(f"\n{cfg.label()}: max relative |C - onnxruntime| = {rel:.3e}")
    assert rel <= TOL
    assert c.self_test() < 1e-5
    if cfg.n_layers == 0:  # the exporter writes d_ff without layers too: checked all the same
        with pytest.raises(FlightNetError, match=r"d_ff = 0 is outside 1\.\.65536"):
            FlightNet(_edit(flight.tnn_bytes(path), 44, "<I", 0))


# ---- no heap allocation inside tscvx_nn_run -----------------------------------------------------


@needs_built
@pytest.mark.skipif(not DRIVER.exists(), reason="build/nn_budget_driver: run make lib ctest")
@pytest.mark.parametrize("kind", KINDS)
def test_no_heap_allocation_inside_run(kind: str) -> None:
    path = BUILD_MODELS / f"{kind}.tnn"
    out = subprocess.run([str(DRIVER), str(path)], capture_output=True, text=True, check=True)
    kv = dict(line.split(" ", 1) for line in out.stdout.splitlines())
    assert kv["status"] == "ok" and kv["kind"] == kind
    assert kv["heap_allocations_in_run"] == "0"
    assert 0 < int(kv["stack_high_water"]) < 16384


# ---- the network wrappers' inputs (adversarial review, 26 Nov) ---------------------------


def test_self_test_takes_turns_with_inferences_on_one_network() -> None:
    """self_test runs an inference in the network's arena but did not take its lock: beside
    run() in another thread it corrupted run's outputs without a word (13 of 200 to all)."""
    import threading

    net = FlightNet((BUILD_MODELS / "constraint.tnn").read_bytes())
    rng = np.random.default_rng(5)
    X = rng.standard_normal((40, net.d_in))
    want = net.run(X)
    stop = threading.Event()

    def keep_testing() -> None:
        while not stop.is_set():
            net.self_test()

    t = threading.Thread(target=keep_testing)
    t.start()
    try:
        got = [net.run(X) for _ in range(10)]
    finally:
        stop.set()
        t.join()
    assert all(np.array_equal(g, want) for g in got)


def test_both_network_paths_refuse_the_same_inputs() -> None:
    """The onnxruntime path took NaN and returned NaN (a mask of all "drop" bits), raised
    onnxruntime's own error for a 3-D input, and the C path flattened 3-D inputs; both now
    take (d_in,) or (B, d_in) finite numbers, and refuse the rest with the same message."""
    from guidance.errors import InputError
    from guidance.nn.infer import load_model

    onnx_net = load_model(MODELS / "constraint.onnx", "constraint")
    c_net = FlightNet((BUILD_MODELS / "constraint.tnn").read_bytes())
    d = c_net.d_in
    good = np.zeros(d)
    for bad in (np.full(d, np.nan), np.zeros((1, d, 1)), np.zeros(d + 1), np.zeros((2, 4, 4))):
        with pytest.raises(InputError) as a:
            onnx_net.run(bad)
        with pytest.raises(InputError) as b:
            c_net.run(bad)
        assert str(a.value) == str(b.value)
    assert onnx_net.run(good).shape == c_net.run(good).shape == (1, c_net.d_out)


def test_a_constraint_mask_from_a_non_finite_output_is_the_full_problem() -> None:
    """A finite input beyond float32 (1e39) overflows in the onnxruntime network: every
    probability NaN, and the mask read every bit as "drop" (0 of 350 kept). It is now None,
    the full problem, as the flight library takes a failed mask inference."""
    from guidance.nn.infer import load_model
    from guidance.params import Scenario
    from guidance.sampling import theta_of

    net = load_model(MODELS / "constraint.onnx", "constraint")
    theta = theta_of(Scenario())
    assert net.mask(theta, 1) is not None
    theta[3] = 1e39
    assert net.mask(theta, 1) is None


@pytest.mark.parametrize("damage", ["not JSON", "no arch"])
def test_a_damaged_metadata_entry_is_refused_by_name(damage: str, tmp_path: Path) -> None:
    """A hand-edited metadata entry raised KeyError or JSONDecodeError from inside the readers
    (the CLI printed a traceback); both paths now refuse the file by name."""
    import onnx

    from guidance.cguidance import FlightNetsError, flight_net
    from guidance.nn.flight import OnnxLayoutError, read_onnx
    from guidance.nn.infer import ModelMismatchError, load_model

    model = onnx.load(str(MODELS / "solution.onnx"))
    entry = next(p for p in model.metadata_props if p.key == "tscvx")
    if damage == "not JSON":
        entry.value = entry.value[:-5]
    else:
        meta = json.loads(entry.value)
        del meta["arch"]
        entry.value = json.dumps(meta)
    path = tmp_path / "solution.onnx"
    onnx.save(model, str(path))
    with pytest.raises(OnnxLayoutError, match="'tscvx' metadata"):
        read_onnx(path)
    with pytest.raises(FlightNetsError, match=r"solution\.onnx"):
        flight_net(tmp_path, "solution")
    if damage == "not JSON":
        with pytest.raises(ModelMismatchError, match="metadata is not JSON"):
            load_model(path, "solution")


# ---- weights and inputs given as other types (review of the wrappers, 26 Nov) ------------


@needs_shipped
@needs_lib
def test_a_blob_in_any_bytes_like_container_is_the_same_network(blobs: dict[str, bytes]) -> None:
    """len() of a memoryview or array of doubles counts values, not bytes: FlightNet sized
    its copy of the blob by it and failed with ctypes' "byte string too long". Any bytes-like
    object is now its raw bytes; an object that is not one is refused by name (5 was read as
    5 zero bytes, None raised TypeError)."""
    import array

    blob = blobs["solution"]
    x = np.zeros(16)
    x[6] = 1.0
    want = FlightNet(blob).run(x)
    doubles = memoryview(blob).cast("d")
    for held in (doubles, np.frombuffer(blob, np.float64), array.array("d", doubles)):
        np.testing.assert_array_equal(FlightNet(held).run(x), want)
    for bad in (None, 5, [1.0, 2.0]):
        with pytest.raises(FlightNetError, match="bytes-like") as info:
            FlightNet(bad)  # type: ignore[arg-type]
        assert info.value.status == flight.NOT_BYTES


@needs_lib
def test_a_weight_file_that_cannot_be_read_is_an_input_error(tmp_path: Path) -> None:
    """FlightNet(folder) raised IsADirectoryError, load_onnx(folder) too (the CLI printed a
    traceback): both are now the modules' InputError, naming the path."""
    with pytest.raises(FlightNetError, match="Is a directory") as info:
        FlightNet(tmp_path)
    assert info.value.status == flight.UNREADABLE and str(tmp_path) in str(info.value)
    with pytest.raises(InputError, match="cannot read it"):
        flight.load_onnx(tmp_path)


@needs_shipped
@needs_lib
def test_flight_net_errors_are_input_errors(blobs: dict[str, bytes], tmp_path: Path) -> None:
    """FlightNetError was a plain ValueError, unlike every other refusal of a user's model
    or input (OnnxLayoutError, ModelMismatchError, ScenarioError): code catching InputError,
    as the CLI does to print the message and exit 2, let it through. cguidance still names a
    library refusal as one (FlightNetsError)."""
    from guidance.cguidance import FlightNetsError, flight_net

    assert issubclass(FlightNetError, InputError)
    with pytest.raises(InputError, match="bad_magic"):
        FlightNet(b"XSCVXNN\0" + blobs["solution"][8:])
    with pytest.raises(InputError, match="bad_size"):
        FlightNet(blobs["solution"]).tight_mask(np.zeros(851))
    (tmp_path / "solution.tnn").write_bytes(blobs["solution"][:-8])
    with pytest.raises(FlightNetsError, match=r"refused by the C library: .*truncated"):
        flight_net(tmp_path, "solution")


@needs_shipped
@needs_built
@needs_lib
def test_raw_bytes_are_not_read_as_one_input_per_byte() -> None:
    """numpy reads a bytearray (or a memoryview of format B) as one number per byte: the bytes
    of two doubles passed as the 16 inputs of the solution network, and were run. Both paths
    now refuse raw bytes with the same message; a memoryview of doubles is its values."""
    from guidance.nn.infer import load_model

    onnx_net = load_model(MODELS / "solution.onnx", "solution")
    c_net = FlightNet(BUILD_MODELS / "solution.tnn")
    two_doubles = np.array([0.5, 2.0]).tobytes()  # 16 bytes
    for raw in (bytearray(two_doubles), memoryview(two_doubles), two_doubles):
        with pytest.raises(InputError, match="raw bytes") as a:
            onnx_net.run(raw)
        with pytest.raises(InputError, match="raw bytes") as b:
            c_net.run(raw)
        assert str(a.value) == str(b.value)
    x = np.linspace(-1.0, 1.0, 16)
    np.testing.assert_array_equal(c_net.run(memoryview(x)), c_net.run(x))
