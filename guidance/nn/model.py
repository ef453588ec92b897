"""The paper's transformer (section "Transformer Neural Network Architecture").

linear encoder -> learned positional encoding -> L encoder layers (multi-head self-attention,
dropout, residual + LayerNorm, feed-forward, dropout, residual + LayerNorm; post-norm as in
``torch.nn.TransformerEncoderLayer``) -> linear decoder.

How the input vector becomes a sequence is left open by the paper. Two token layouts:

- ``"scalar"``: every input component is one token (sequence length = input size; the linear
  encoder maps each scalar to d_model with its own weights). Attention then mixes the
  parameters of the problem; the decoder reads the flattened sequence.
- ``"single"``: the whole input is one token (sequence length 1). Attention over one token is
  the identity on the value path, so this is a residual MLP; it is what the paper's parameter
  counts imply (384-d, 4 layers, feed-forward 2048: 8.9 M parameters for the constraint net).

The layers are written out (no ``nn.TransformerEncoderLayer``) so that the ONNX graph has only
MatMul/Add/Softmax/LayerNorm-level operators that the C runtime can mirror one to one.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import torch
from torch import nn


@dataclass(frozen=True)
class ArchConfig:
    d_in: int
    d_out: int
    d_model: int = 64
    n_heads: int = 2
    n_layers: int = 2
    d_ff: int = 128
    dropout: float = 0.1
    tokens: str = "scalar"  # "scalar" | "single"

    def __post_init__(self) -> None:
        if self.tokens not in ("scalar", "single"):
            raise ValueError(f"tokens must be 'scalar' or 'single', got {self.tokens!r}")
        if self.d_model % self.n_heads:
            raise ValueError("d_model must be a multiple of n_heads")

    @property
    def seq_len(self) -> int:
        return self.d_in if self.tokens == "scalar" else 1

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    def macs(self) -> int:
        """Multiply-accumulates of one inference (matrix products; softmax/LN not counted)."""
        L, d, f = self.seq_len, self.d_model, self.d_ff
        enc = L * d if self.tokens == "scalar" else self.d_in * d
        per_layer = L * (4 * d * d + 2 * d * f) + 2 * L * L * d
        dec = L * d * self.d_out
        return enc + self.n_layers * per_layer + dec

    def label(self) -> str:
        return f"{self.tokens}-d{self.d_model}-L{self.n_layers}-h{self.n_heads}-ff{self.d_ff}"


class EncoderLayer(nn.Module):
    def __init__(self, d: int, heads: int, d_ff: int, dropout: float) -> None:
        super().__init__()
        self.heads = heads
        self.qkv = nn.Linear(d, 3 * d)
        self.proj = nn.Linear(d, d)
        self.ff1 = nn.Linear(d, d_ff)
        self.ff2 = nn.Linear(d_ff, d)
        self.norm1 = nn.LayerNorm(d)
        self.norm2 = nn.LayerNorm(d)
        self.drop = nn.Dropout(dropout)

    def forward(self, h: torch.Tensor) -> torch.Tensor:  # h: (B, L, d)
        B, L, d = h.shape
        dh = d // self.heads
        q, k, v = self.qkv(h).reshape(B, L, 3, self.heads, dh).permute(2, 0, 3, 1, 4)
        att = torch.softmax(q @ k.transpose(-1, -2) / math.sqrt(dh), dim=-1)  # (B, H, L, L)
        o = (att @ v).transpose(1, 2).reshape(B, L, d)  # Eq. (attention), heads concatenated
        h = self.norm1(h + self.drop(self.proj(o)))
        return self.norm2(h + self.drop(self.ff2(self.drop(torch.relu(self.ff1(h))))))


class Transformer(nn.Module):
    """Maps standardized inputs (B, d_in) to standardized outputs / logits (B, d_out)."""

    def __init__(self, cfg: ArchConfig) -> None:
        super().__init__()
        self.cfg = cfg
        L, d = cfg.seq_len, cfg.d_model
        if cfg.tokens == "scalar":
            # per-token linear encoder: token i = x_i * W_i + b_i
            self.enc_w = nn.Parameter(torch.randn(L, d) / math.sqrt(d))
            self.enc_b = nn.Parameter(torch.zeros(L, d))
        else:
            self.encoder = nn.Linear(cfg.d_in, d)
        self.pos = nn.Parameter(0.02 * torch.randn(L, d))  # learned positional encoding
        self.layers = nn.ModuleList(
            EncoderLayer(d, cfg.n_heads, cfg.d_ff, cfg.dropout) for _ in range(cfg.n_layers)
        )
        self.decoder = nn.Linear(L * d, cfg.d_out)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.cfg.tokens == "scalar":
            h = x.unsqueeze(-1) * self.enc_w + self.enc_b
        else:
            h = self.encoder(x).unsqueeze(1)
        h = h + self.pos
        for layer in self.layers:
            h = layer(h)
        return self.decoder(h.flatten(1))


class Normalized(nn.Module):
    """The network with its standardization folded in: raw inputs -> raw outputs.

    For the solution network the output is de-standardized (physical x, u, t_f); for the
    constraint network ``out_mean = 0, out_std = 1`` and the output stays logits.
    """

    in_mean: torch.Tensor  # the registered buffers
    in_scale: torch.Tensor
    out_mean: torch.Tensor
    out_std: torch.Tensor

    def __init__(
        self,
        net: Transformer,
        in_mean: torch.Tensor,
        in_std: torch.Tensor,
        out_mean: torch.Tensor,
        out_std: torch.Tensor,
    ) -> None:
        super().__init__()
        self.net = net
        self.register_buffer("in_mean", in_mean.float())
        self.register_buffer("in_scale", 1.0 / in_std.float())
        self.register_buffer("out_mean", out_mean.float())
        self.register_buffer("out_std", out_std.float())

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net((x - self.in_mean) * self.in_scale) * self.out_std + self.out_mean


def n_params(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
