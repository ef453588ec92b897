"""A data file's code version says '+dirty' when anything its numbers depend on has uncommitted
changes: the package, and the flight C code, its generator and its build (the c and c-socp
backends' results depend on them as much as the reference's on guidance/)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from guidance import provenance

needs_git = pytest.mark.skipif(shutil.which("git") is None, reason="git not installed")


def _repo(root: Path) -> None:
    files = ["guidance/a.py", "c_runtime/src/b.c", "codegen/generate.py", "Makefile",
             "pyproject.toml", "docs/notes.md"]  # fmt: skip
    for name in files:
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text("0\n")
    for cmd in (["init", "-q"], ["add", "."], ["-c", "user.name=t", "-c", "user.email=t@t",
                                               "commit", "-qm", "c"]):  # fmt: skip
        subprocess.run(["git", "-C", str(root), *cmd], check=True)


@needs_git
@pytest.mark.parametrize(
    ("edited", "dirty"),
    [
        (None, False),
        ("guidance/a.py", True),
        ("c_runtime/src/b.c", True),
        ("codegen/generate.py", True),
        ("Makefile", True),
        ("pyproject.toml", True),
        ("docs/notes.md", False),  # the numbers do not depend on the documents
    ],
)
def test_dirty_covers_what_the_numbers_depend_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, edited: str | None, dirty: bool
) -> None:
    _repo(tmp_path)
    monkeypatch.setattr(provenance, "ROOT", tmp_path)
    if edited:
        (tmp_path / edited).write_text("1\n")
    version = provenance.code_version()
    assert " git " in version
    assert version.endswith("+dirty") == dirty, version


def test_an_input_file_given_relative_is_recorded_by_its_absolute_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Audit of 28 Nov: `guidance solve --guess plan.npz` recorded "plan.npz", which names the
    file only from the folder the solve ran in, which the file does not record. The path is
    recorded absolute (the sha256 says which bytes)."""
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / "plan.npz").write_bytes(b"plan")
    monkeypatch.chdir(tmp_path / "runs")
    files = provenance.provenance({"initial_guess": Path("plan.npz")})["files"]
    assert files == {  # type: ignore[comparison-overlap]
        "initial_guess": {
            "path": str(tmp_path / "runs" / "plan.npz"),
            "sha256": provenance.file_digest(tmp_path / "runs" / "plan.npz"),
        }
    }
