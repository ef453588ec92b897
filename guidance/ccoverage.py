"""Structural coverage of the flight C code, from gcov's JSON (``make coverage``).

    python -m guidance.ccoverage build/coverage/obj [--out build/coverage]

Reads every ``*.gcno`` under the object folder (an object whose code never ran has no
``.gcda``: gcov counts it as not executed) and prints, per source file, the lines, branches
and functions run at least once. A line of a header compiled into several objects counts as
run if any object ran it; its branches are matched by position. Writes ``coverage.txt`` (the
table) and ``uncovered.txt`` (each never-run range of lines with its function) to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

from guidance.paths import ROOT

SOURCES = "c_runtime/"  # the hand-written flight code (not the generated model's header)


@dataclass
class FileCoverage:
    """Per line: was it run; per (line, branch index): was it taken; per function: called."""

    lines: dict[int, bool] = field(default_factory=dict)
    branches: dict[tuple[int, int], bool] = field(default_factory=dict)
    functions: dict[str, bool] = field(default_factory=dict)
    function_of: dict[int, str] = field(default_factory=dict)

    def add(self, record: dict) -> None:
        """Merge one gcov JSON ``files[]`` entry (one object's view of this source)."""
        for line in record["lines"]:
            n = line["line_number"]
            self.lines[n] = self.lines.get(n, False) or line["count"] > 0
            self.function_of.setdefault(n, line.get("function_name", "?"))
            for i, br in enumerate(line["branches"]):
                key = (n, i)
                self.branches[key] = self.branches.get(key, False) or br["count"] > 0
        for fn in record["functions"]:
            name = fn["name"]
            self.functions[name] = self.functions.get(name, False) or fn["execution_count"] > 0

    def uncovered_ranges(self) -> list[tuple[int, int, str]]:
        """Maximal runs of never-run lines (consecutive among the lines with code)."""
        ranges: list[tuple[int, int, str]] = []
        for n in sorted(self.lines):
            if self.lines[n]:
                continue
            fn = self.function_of[n]
            if ranges and ranges[-1][2] == fn and self._adjacent(ranges[-1][1], n):
                ranges[-1] = (ranges[-1][0], n, fn)
            else:
                ranges.append((n, n, fn))
        return ranges

    def _adjacent(self, last: int, n: int) -> bool:
        """No line with code, run, between ``last`` and ``n``."""
        return not any(self.lines.get(k, False) for k in range(last + 1, n))


def _ratio(flags: dict) -> tuple[int, int]:
    return sum(flags.values()), len(flags)


def _gcov_json(gcno: Path, root: Path) -> list[dict]:
    """gcov's JSON records of one object (run from ``root``, where the objects were compiled:
    the sources' paths are relative to it)."""
    out = subprocess.run(
        ["gcov", "--json-format", "--stdout", "--branch-probabilities", str(gcno)],
        cwd=root,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return [json.loads(doc) for doc in out.splitlines() if doc.strip()]


def collect(obj_dir: Path, root: Path = ROOT, prefix: str = SOURCES) -> dict[str, FileCoverage]:
    """Coverage of every source under ``prefix`` compiled into the objects of ``obj_dir``."""
    files: dict[str, FileCoverage] = defaultdict(FileCoverage)
    for gcno in sorted(obj_dir.glob("*.gcno")):
        for doc in _gcov_json(gcno.resolve(), root):
            for record in doc["files"]:
                if record["file"].startswith(prefix):
                    files[record["file"]].add(record)
    return dict(files)


def _cell(covered: int, total: int) -> str:
    pct = f"{100 * covered / total:5.1f} %" if total else "    – "
    return f"{covered:>5}/{total:<5} {pct}"


def table(files: dict[str, FileCoverage]) -> str:
    """One row per source file and a total: lines, branches, functions run at least once."""
    w = max(len("total"), *map(len, files))
    head = f"{'file':<{w}} {'lines':>19} {'branches':>19} {'functions':>19}"
    rows, totals = [head, "-" * len(head)], [[0, 0], [0, 0], [0, 0]]
    for path in sorted(files):
        fc = files[path]
        parts = (_ratio(fc.lines), _ratio(fc.branches), _ratio(fc.functions))
        for t, (c, n) in zip(totals, parts, strict=True):
            t[0] += c
            t[1] += n
        rows.append(f"{path:<{w}} " + " ".join(f"{_cell(c, n):>19}" for c, n in parts))
    rows.append("-" * len(head))
    rows.append(f"{'total':<{w}} " + " ".join(f"{_cell(c, n):>19}" for c, n in totals))
    return "\n".join(rows)


def uncovered(files: dict[str, FileCoverage]) -> str:
    lines = []
    for path in sorted(files):
        for a, b, fn in files[path].uncovered_ranges():
            where = f"{a}" if a == b else f"{a}-{b}"
            lines.append(f"{path}:{where} ({fn})")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m guidance.ccoverage", description=__doc__.split("\n")[0]
    )
    ap.add_argument("obj_dir", type=Path, help="folder of the instrumented objects (*.gcno)")
    ap.add_argument("--out", type=Path, help="write coverage.txt and uncovered.txt here")
    args = ap.parse_args(argv)
    if shutil.which("gcov") is None:
        print("ccoverage: gcov not found (it comes with gcc)", file=sys.stderr)
        return 2
    if not any(args.obj_dir.glob("*.gcno")):
        print(
            f"ccoverage: no *.gcno in {args.obj_dir} (`make coverage` builds them)", file=sys.stderr
        )
        return 2
    files = collect(args.obj_dir)
    report = table(files)
    print(report)
    if args.out is not None:
        (args.out / "coverage.txt").write_text(report + "\n")
        (args.out / "uncovered.txt").write_text(uncovered(files) + "\n")
        print(f"never-run lines: {args.out / 'uncovered.txt'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
