"""Where a data file came from: the code (package version and git commit), the solvers, and
the model files a result depended on. One definition for every file this package writes."""

from __future__ import annotations

import hashlib
import platform
import subprocess
from datetime import datetime, timezone
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from guidance.paths import ROOT

# What a result's numbers depend on in the repository: the package, the flight C code and its
# generator (the c and c-socp backends, the weight files), and how they are built.
CODE_PATHS = ("guidance", "c_runtime", "codegen", "Makefile", "pyproject.toml")
# The libraries whose arithmetic a trajectory depends on.
SOLVER_PACKAGES = ("numpy", "scipy", "casadi", "clarabel", "onnxruntime")
# The libraries a network's weights (guidance train) and its ONNX file (guidance export,
# torch's exporter writes through onnxscript) depend on.
LEARNING_PACKAGES = ("numpy", "torch", "onnx", "onnxscript")
# What a file made before its writer recorded a version says of it.
UNKNOWN = "unknown"


def _version(package: str) -> str | None:
    try:
        return version(package)
    except PackageNotFoundError:
        return None


def code_version() -> str:
    """'guidance 0.1.0 git 2177901' ('+dirty' when CODE_PATHS have uncommitted changes: a
    result of the C library depends on c_runtime/ as much as one of Python on guidance/)."""
    pkg = _version("guidance") or "unknown"

    def git(*args: str) -> str:
        return subprocess.run(
            ["git", "-C", str(ROOT), *args], capture_output=True, text=True, timeout=5
        ).stdout.strip()

    try:
        rev = git("rev-parse", "--short", "HEAD")
        dirty = git("status", "--porcelain", "--", *CODE_PATHS)
    except (OSError, subprocess.SubprocessError):
        rev, dirty = "", ""
    return f"guidance {pkg}" + (f" git {rev}{'+dirty' if dirty else ''}" if rev else "")


def file_digest(path: Path) -> str:
    """sha256 of a file's bytes (which model file exactly, not only its name)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def provenance(
    files: dict[str, Path] | None = None, packages: tuple[str, ...] = SOLVER_PACKAGES
) -> dict[str, object]:
    """The code, the versions of ``packages`` (default the solvers; those installed), the
    machine and the time; with ``files`` (a name for each input file, such as the networks of
    a T-SCvx solve) their absolute paths and sha256 (a relative path would name the file
    only from the working folder of the run, which nothing records)."""
    out: dict[str, object] = {
        "generator": code_version(),
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "python": platform.python_version(),
        "host": platform.machine(),
        "packages": {name: v for name in packages if (v := _version(name))},
    }
    if files:
        out["files"] = {
            name: {"path": str(Path(path).absolute()), "sha256": file_digest(path)}
            for name, path in files.items()
        }
    return out
