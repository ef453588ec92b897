"""The flight path needs no torch: `make lib`, `make demo` and `make budget` install the package
without its extras (Makefile), so code generation, the weight files and the demo's commands
must run with the training stack and the benchmark's solvers absent. Each runs here in a
Python that refuses to import them."""

from __future__ import annotations

import re
import subprocess
import sys
from importlib.metadata import requires
from pathlib import Path

import pytest

from guidance.cguidance import LibraryNotBuiltError, library

ROOT = Path(__file__).resolve().parents[1]
# what only the extras bring (pyproject.toml: train, bench, dev)
EXTRAS_ONLY = ("torch", "onnxscript", "sklearn", "qoco", "ecos", "pytest")
_BLOCKED = (
    "import runpy, sys\n"
    f"for name in {EXTRAS_ONLY!r}:\n"
    "    sys.modules[name] = None  # `import name` now raises ImportError\n"
    "sys.argv = sys.argv[1:]\n"
    "if sys.argv[0] == '-m':\n"
    "    sys.argv = sys.argv[1:]\n"
    "    runpy.run_module(sys.argv[0], run_name='__main__', alter_sys=True)\n"
    "else:\n"
    "    runpy.run_path(sys.argv[0], run_name='__main__')\n"
)


def _run_without_extras(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", _BLOCKED, *argv], cwd=ROOT, capture_output=True, text=True
    )


def _built() -> bool:
    try:
        library()
    except LibraryNotBuiltError:
        return False
    return True


def test_the_package_alone_asks_for_no_extra() -> None:
    """The installed package's requirements (pyproject.toml's, as pip read them)."""
    reqs = requires("guidance") or []
    base = {re.match(r"[\w.-]+", r).group(0) for r in reqs if "extra ==" not in r}
    assert {"casadi", "onnx", "onnxruntime"} <= base  # onnx: nn.flight reads the models
    assert not base & {"torch", "onnxscript", "scikit-learn", "qoco", "ecos", "pytest"}
    assert any(r.startswith("torch==2.13.0") and 'extra == "train"' in r for r in reqs)


def test_the_blocking_works() -> None:
    out = _run_without_extras("-m", "guidance.nn.train", "--help")
    assert out.returncode != 0 and "torch" in out.stderr


def test_code_generation_and_weight_files_need_no_extra(tmp_path: Path) -> None:
    out = _run_without_extras("codegen/generate.py", str(tmp_path))
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "tscvx_model.c").stat().st_size > 10_000
    for name in ("solution", "constraint"):
        out = _run_without_extras(
            "-m", "guidance.nn.flight", f"models/{name}.onnx", str(tmp_path / f"{name}.tnn")
        )
        assert out.returncode == 0, out.stderr
        built = ROOT / "build" / "models" / f"{name}.tnn"
        if built.exists():  # the same ONNX makes the same bytes (nn.mk)
            assert (tmp_path / f"{name}.tnn").read_bytes() == built.read_bytes()


@pytest.mark.skipif(not _built(), reason="make lib builds the flight library")
def test_the_demo_s_commands_need_no_extra(tmp_path: Path) -> None:
    files = []
    for method, backend in (("scvx", "clarabel"), ("tscvx", "c")):
        path = tmp_path / f"{method}_{backend}.npz"
        out = _run_without_extras(
            "-m", "guidance", "solve", "--method", method, "--backend", backend, "--out",
            str(path), "--plot", str(path.with_suffix(".png")),
        )  # fmt: skip
        assert out.returncode == 0, out.stderr
        files.append(str(path))
    out = _run_without_extras("-m", "guidance", "verify", *files)
    assert out.returncode == 0, out.stdout + out.stderr
    assert out.stdout.count("verdict: pass") == 2
