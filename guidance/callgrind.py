"""Instruction counts with valgrind's callgrind: one run of a program, counting only inside
one function (``--toggle-collect``). Shared by the RAD750 budget (``guidance budget``), the
network card and the SOCP benchmark (``python -m guidance.bench_socp --callgrind``)."""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

# What bench_socp's flop count reads: one cost line per instruction address, uncompressed.
PER_INSTRUCTION = ["--dump-instr=yes", "--compress-pos=no", "--compress-strings=no"]


@dataclass(frozen=True)
class Collected:
    """One run under callgrind: the instructions counted inside the function, and the
    callgrind file (valid only inside the ``collect`` block) for annotation."""

    instructions: int
    out_file: Path


@contextmanager
def collect(
    cmd: list[str],
    function: str,
    *,
    per_instruction: bool = False,
    ok_codes: tuple[int, ...] = (0,),
) -> Iterator[Collected]:
    """Runs ``cmd`` under callgrind from a temporary directory, counting inside ``function``
    (a callgrind pattern: ``pdg_solve``, ``*qoco_solve*``). Raises RuntimeError when valgrind
    is missing, the program exits with a code outside ``ok_codes`` or no total is written."""
    if shutil.which("valgrind") is None:
        raise RuntimeError("valgrind not found (Debian package valgrind)")
    with tempfile.TemporaryDirectory() as tmp:
        out_file = Path(tmp) / "callgrind.out"
        run = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out_file}",
             f"--toggle-collect={function}", *(PER_INSTRUCTION if per_instruction else []),
             *cmd],
            capture_output=True, text=True, cwd=tmp, check=False,
        )  # fmt: skip
        if run.returncode not in ok_codes:
            raise RuntimeError(
                f"{Path(cmd[0]).name} failed under callgrind ({run.returncode}): "
                f"{run.stderr[-2000:]}"
            )
        text = out_file.read_text() if out_file.exists() else ""
        m = re.search(r"^(?:summary|totals):\s*(\d+)", text, re.MULTILINE)
        if not m:
            raise RuntimeError("no instruction total in the callgrind output")
        yield Collected(int(m.group(1)), out_file)


def total(cmd: list[str], function: str) -> int:
    """Instructions inside ``function`` (inclusive) of one run of ``cmd`` under callgrind."""
    with collect(cmd, function) as run:
        return run.instructions


def inclusive_costs(out_file: Path, functions: dict[str, str]) -> dict[str, int]:
    """Inclusive instructions of the named functions (``callgrind_annotate``; {} without it):
    ``functions`` maps a function name to the key it is reported under."""
    if shutil.which("callgrind_annotate") is None:
        return {}
    ann = subprocess.run(
        ["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out_file)],
        capture_output=True, text=True, check=False,
    ).stdout  # fmt: skip
    costs = {}
    for name, key in functions.items():
        m = re.search(rf"^\s*([\d,]+)\s.*:{name}\s", ann, re.MULTILINE)
        if m:
            costs[key] = int(m.group(1).replace(",", ""))
    return costs
