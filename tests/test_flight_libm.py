"""Which libm functions the flight libraries call, read from their objects (`nm`).

IEEE 754 fixes the result of sqrt, fabs, fmax and fmin to the bit; libm's other functions it
does not (glibc documents errors of up to 1 or 2 ulp, and the RAD750's libm is not glibc), so
each of them makes a landing's last bits depend on the libm linked. The flight code calls them
only where listed below, each for a stated reason, and a new one (or libm's hypot, which
pdg_hypot replaced) needs a decision here first.

The SOCP runtime calls none of them: the centering parameter (1 - alpha)^3 of every IPM
iteration was libm's pow until 28 Nov and is two multiplications since. The change moved the
default landing by its last bits and tipped the undisturbed closed-loop re-plan at t = 5 of
tests/test_closed_loop.py, which crept (J falling by about 1e-6 per accepted step, each step
above step_tol), into max_iterations; it was kept once SCvx's convergence test stopped such a
creep (cost_tol, paper Algorithm 1's dJ <= eps_tol; docs/budget.md, "On a PowerPC").
"""

from __future__ import annotations

import ctypes
import ctypes.util
import shutil
import subprocess
from pathlib import Path

import pytest

from guidance import cgnc

BUILD = cgnc.LIB_PATH.parent
RUNTIME = BUILD / "libtscvx.a"  # the SOCP runtime
GUIDANCE = BUILD / "libtscvx_gnc.a"  # the guidance loop, its generated model and the networks

IEEE_EXACT = {"sqrt", "fabs", "fmax", "fmin"}
# not fixed by IEEE 754, each once per call or outside the IPM: the scenario's constants
# (glide slope, gimbal and tilt limits: tan, cos, sincos, acos), the guess's grid of final
# times and T-SCvx's tau-radius rule (pow), the networks' softmax and mask (exp)
GUIDANCE_ROUNDED_BY_LIBM = {"acos", "cos", "sincos", "tan", "pow", "exp"}

pytestmark = pytest.mark.skipif(
    not (RUNTIME.exists() and GUIDANCE.exists() and shutil.which("nm")),
    reason="run `make lib` first (needs binutils' nm)",
)


def _libm_path() -> Path:
    name = ctypes.util.find_library("m")
    assert name, "libm not found"
    ctypes.CDLL(name)  # mapped into this process: its path is in /proc/self/maps
    maps = Path("/proc/self/maps").read_text().splitlines()
    paths = {line.split()[-1] for line in maps if Path(line.split()[-1]).name == name}
    assert len(paths) == 1, paths
    return Path(paths.pop())


def _nm(*args: str) -> list[str]:
    out = subprocess.run(["nm", *args], capture_output=True, text=True, check=True).stdout
    return out.splitlines()


def _libm_functions() -> set[str]:
    lines = _nm("-D", "--defined-only", str(_libm_path()))
    return {line.split()[-1].split("@")[0] for line in lines if line.strip()}


def _libm_calls(archive: Path) -> set[str]:
    undefined = {line.split()[-1] for line in _nm("-u", str(archive)) if " U " in line}
    return undefined & _libm_functions()


def test_the_socp_runtime_calls_only_the_libm_functions_ieee_754_rounds_exactly() -> None:
    calls = _libm_calls(RUNTIME)
    assert "sqrt" in calls  # the reading works: the cone operations take square roots
    assert calls <= IEEE_EXACT, calls - IEEE_EXACT


def test_the_guidance_calls_libm_only_where_listed() -> None:
    calls = _libm_calls(GUIDANCE)
    assert "sqrt" in calls
    assert "hypot" not in calls  # pdg_hypot (tests/test_hypot.py)
    assert calls - IEEE_EXACT <= GUIDANCE_ROUNDED_BY_LIBM, calls - IEEE_EXACT
