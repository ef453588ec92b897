"""guidance.ccoverage (the table of `make coverage`) against programs whose executed lines
and branches are known by construction."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from guidance import ccoverage

pytestmark = pytest.mark.skipif(
    shutil.which("gcc") is None or shutil.which("gcov") is None, reason="needs gcc and gcov"
)

HEADER = """static inline int sign(int x) {
    if (x > 0)
        return 1;
    return -1;
}
"""
# one.c calls sign() with a positive number only, two.c with a negative one only: each object
# alone covers half of the header's branches, the two together all of them.
ONE = """#include "sign.h"
int unused(int a) {
    return a * 2;
}
int main(void) {
    return sign(3) - 1;
}
"""
TWO = """#include "sign.h"
int main(void) {
    return sign(-3) + 1;
}
"""


def _build_and_run(root: Path) -> Path:
    (root / "src").mkdir()
    (root / "src" / "sign.h").write_text(HEADER)
    (root / "src" / "one.c").write_text(ONE)
    (root / "src" / "two.c").write_text(TWO)
    obj = root / "obj"
    obj.mkdir()
    for name in ("one", "two"):
        o = f"obj/{name}.o"
        subprocess.run(
            ["gcc", "-O0", "--coverage", "-c", f"src/{name}.c", "-o", o], cwd=root, check=True
        )
        subprocess.run(["gcc", "--coverage", o, "-o", f"obj/{name}"], cwd=root, check=True)
        subprocess.run([f"obj/{name}"], cwd=root, check=True)
    return obj


def test_lines_branches_and_functions_of_known_runs(tmp_path: Path) -> None:
    obj = _build_and_run(tmp_path)
    files = ccoverage.collect(obj, root=tmp_path, prefix="src/")
    assert set(files) == {"src/one.c", "src/two.c", "src/sign.h"}
    one = files["src/one.c"]
    assert one.functions == {"unused": False, "main": True}
    assert one.lines[3] is False and one.lines[6] is True
    assert one.uncovered_ranges() == [(2, 3, "unused")]
    header = files["src/sign.h"]
    assert all(header.lines.values())  # line 3 by one.c, line 4 by two.c
    assert ccoverage._ratio(header.branches) == (2, 2)


def test_an_object_that_never_ran_counts_as_not_executed(tmp_path: Path) -> None:
    obj = _build_and_run(tmp_path)
    for gcda in obj.glob("two.gcda"):
        gcda.unlink()
    files = ccoverage.collect(obj, root=tmp_path, prefix="src/")
    assert files["src/two.c"].functions == {"main": False}
    assert ccoverage._ratio(files["src/sign.h"].branches) == (1, 2)
    assert files["src/sign.h"].lines[4] is False


def test_table_totals_and_report_files(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    obj = _build_and_run(tmp_path)
    files = ccoverage.collect(obj, root=tmp_path, prefix="src/")
    total = ccoverage.table(files).splitlines()[-1].split()
    lines = sum(len(f.lines) for f in files.values())
    covered = sum(sum(f.lines.values()) for f in files.values())
    assert total[:2] == ["total", f"{covered}/{lines}"]
    assert ccoverage.main([str(tmp_path / "missing")]) == 2
    assert "no *.gcno" in capsys.readouterr().err
