"""Subcommands of the learning half (dataset, train, export, baselines)."""

from __future__ import annotations

import argparse


def add_commands(sub: argparse._SubParsersAction) -> None:
    """Registers the learning subcommands on the main parser."""
