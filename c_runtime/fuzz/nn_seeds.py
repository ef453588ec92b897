"""Tiny network blobs for the network fuzz harness's seed corpus (`make fuzz`).

Each is a valid blob (guidance.nn.flight.pack: the exporter's own writer) of a small
architecture: both kinds, both token modes, two heads, no layer, one probe with the
recorded output of guidance.nn.flight.forward, so the self-test passes. A few hundred bytes
to a few KB each, where the shipped networks are 10 MB: the fuzzer mutates these quickly.

Usage: python c_runtime/fuzz/nn_seeds.py OUT_DIR
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from guidance.nn.flight import CONSTRAINT, SOLUTION, FlightWeights, forward, pack


def _blob(kind: str, tokens: str, d: int, heads: int, layers: int, ff: int, N: int) -> bytes:
    rng = np.random.default_rng(7)
    d_in = 17 if kind == CONSTRAINT else 16
    d_out = 7 * N if kind == CONSTRAINT else 17 * N + 1
    L = d_in if tokens == "scalar" else 1

    def r(*shape: int) -> np.ndarray:
        return rng.normal(0.0, 0.5, shape).astype(np.float32)

    arrays = [
        ("in_mean", r(d_in)),
        ("in_scale", np.abs(r(d_in)) + np.float32(0.5)),
        ("out_mean", r(d_out)),
        ("out_std", np.abs(r(d_out)) + np.float32(0.5)),
    ]
    if tokens == "single":
        arrays += [("enc_w", r(d, d_in)), ("enc_b", r(d))]
    else:
        arrays += [("enc_w", r(L, d)), ("enc_b", r(L, d))]
    arrays.append(("pos", r(L, d)))
    for i in range(layers):
        p = f"net.layers.{i}."
        arrays += [
            (p + "W_qkv", r(3 * d, d)), (p + "b_qkv", r(3 * d)), (p + "W_o", r(d, d)),
            (p + "b_o", r(d)), (p + "ln1_g", r(d)), (p + "ln1_b", r(d)), (p + "W_1", r(ff, d)),
            (p + "b_1", r(ff)), (p + "W_2", r(d, ff)), (p + "b_2", r(d)), (p + "ln2_g", r(d)),
            (p + "ln2_b", r(d)),
        ]  # fmt: skip
    arrays += [("W_d", r(d_out, L * d)), ("b_d", r(d_out))]
    fw = FlightWeights(
        kind=kind, tokens=tokens, d_in=d_in, d_out=d_out, d_model=d, n_heads=heads,
        n_layers=layers, d_ff=ff, N=N, ln_eps=1e-5, threshold=0.5, arrays=arrays,
        probe_in=r(1, d_in), probe_out=np.zeros((1, d_out), np.float32),
        trained=np.array([1.0, 2.0]),
    )  # fmt: skip
    fw.probe_out = forward(fw, fw.probe_in.astype(np.float64)).astype(np.float32)
    return pack(fw)


def main(argv: list[str]) -> int:
    out = Path(argv[1])
    out.mkdir(parents=True, exist_ok=True)
    seeds = {
        "tiny_constraint_single": _blob(CONSTRAINT, "single", 2, 2, 1, 2, 1),
        "tiny_solution_single": _blob(SOLUTION, "single", 2, 1, 1, 2, 1),
        "tiny_constraint_scalar": _blob(CONSTRAINT, "scalar", 2, 2, 1, 1, 1),
        "tiny_solution_nolayer": _blob(SOLUTION, "single", 1, 1, 0, 1, 1),
    }
    for name, blob in seeds.items():
        (out / f"{name}.tnn").write_bytes(blob)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
