"""ctypes bindings to the generated model and the C discretization (build/libtscvx_gnc.so)."""

from __future__ import annotations

import ctypes
import os
from functools import lru_cache
from pathlib import Path

import numpy as np

from guidance.errors import LibraryNotBuiltError, ModelEvaluationError
from guidance.model import N_AUG, NP
from guidance.params import NU, NX
from guidance.paths import BUILD_DIR

FOH_NOT_FINITE = -2  # pdg_foh_interval's status for a non-finite model evaluation (foh.h)
# The guidance library (the SOCP runtime inside); TSCVX_GNC_LIB points elsewhere (`make
# coverage` runs the suite against an instrumented build). One path for every binding.
LIB_ENV = "TSCVX_GNC_LIB"
LIB_PATH = Path(os.environ.get(LIB_ENV, str(BUILD_DIR / "libtscvx_gnc.so")))
_dp = ctypes.POINTER(ctypes.c_double)


def require_library() -> None:
    """LibraryNotBuiltError unless the guidance library has been built."""
    if not LIB_PATH.exists():
        raise LibraryNotBuiltError(f"{LIB_PATH} not found: run `make lib`")


def open_library() -> ctypes.CDLL:
    """The guidance library, opened for one binding (which declares its own functions)."""
    require_library()
    return ctypes.CDLL(str(LIB_PATH))


@lru_cache(maxsize=1)
def library() -> ctypes.CDLL:
    lib = open_library()
    lib.pdg_foh_interval.restype = ctypes.c_int
    lib.pdg_foh_interval.argtypes = [_dp, _dp, _dp, ctypes.c_double, ctypes.c_double, _dp,
                                     ctypes.c_int, _dp, _dp, _dp]  # fmt: skip
    lib.pdg_foh_all.restype = ctypes.c_int
    lib.pdg_foh_all.argtypes = [ctypes.c_int, _dp, _dp, ctypes.c_double, _dp, ctypes.c_int,
                                _dp, _dp, _dp]  # fmt: skip
    return lib


def available() -> bool:
    return LIB_PATH.exists()


def _ptr(a: np.ndarray) -> ctypes._Pointer[ctypes.c_double]:
    return a.ctypes.data_as(_dp)


def call_generated(name: str, inputs: list[np.ndarray], out_sizes: list[int]) -> list[np.ndarray]:
    """Calls a CasADi-generated function by name; outputs are its nonzeros (column-major)."""
    lib = library()
    fun = getattr(lib, name)
    ins = [np.ascontiguousarray(np.ravel(np.asarray(a, dtype=float), order="F")) for a in inputs]
    outs = [np.zeros(n) for n in out_sizes]
    arg = (_dp * len(ins))(*[_ptr(a) for a in ins])
    res = (_dp * len(outs))(*[_ptr(o) for o in outs])
    fun.restype = ctypes.c_int
    status = fun(arg, res, None, None, 0)
    if status != 0:
        raise RuntimeError(f"{name} returned {status}")
    return outs


def foh_interval(x_k: np.ndarray, u_k: np.ndarray, u_k1: np.ndarray, sigma: float, dtau: float,
                 p: np.ndarray, substeps: int) -> dict[str, np.ndarray]:  # fmt: skip
    """The C discretization of one interval (same outputs as guidance.model's function)."""
    arrays = [np.ascontiguousarray(a, dtype=float) for a in (x_k, u_k, u_k1, p)]
    if arrays[3].size != NP:
        raise ValueError(f"p must have {NP} entries")
    aug, z, work = np.zeros(N_AUG), np.zeros(NX), np.zeros(N_AUG)
    status = library().pdg_foh_interval(
        _ptr(arrays[0]), _ptr(arrays[1]), _ptr(arrays[2]), float(sigma), float(dtau),
        _ptr(arrays[3]), int(substeps), _ptr(aug), _ptr(z), _ptr(work),
    )  # fmt: skip
    if status != 0:
        raise ValueError(f"pdg_foh_interval returned {status}")
    i = np.cumsum([0, NX, NX * NX, NX * NU, NX * NU, NX])
    return {
        "x_next": aug[i[0] : i[1]],
        "A": aug[i[1] : i[2]].reshape(NX, NX, order="F"),
        "Bm": aug[i[2] : i[3]].reshape(NX, NU, order="F"),
        "Bp": aug[i[3] : i[4]].reshape(NX, NU, order="F"),
        "Sigma": aug[i[4] : i[5]],
        "z": z,
    }


def discretize_all(x: np.ndarray, u: np.ndarray, sigma: float, p: np.ndarray,
                   substeps: int) -> dict[str, np.ndarray]:  # fmt: skip
    """All intervals in C; same keys and shapes as guidance.model.discretize."""
    N = x.shape[0]
    xs = np.ascontiguousarray(x, dtype=float)
    us = np.ascontiguousarray(u, dtype=float)
    ps = np.ascontiguousarray(p, dtype=float)
    aug, z, work = np.zeros((N - 1, N_AUG)), np.zeros((N - 1, NX)), np.zeros(N_AUG)
    status = library().pdg_foh_all(
        N, _ptr(xs), _ptr(us), float(sigma), _ptr(ps), int(substeps), _ptr(aug), _ptr(z),
        _ptr(work),
    )  # fmt: skip
    if status == FOH_NOT_FINITE:
        raise ModelEvaluationError(
            "the FOH discretization is not finite or left its structural pattern"
        )
    if status != 0:
        raise ValueError(f"pdg_foh_all returned {status}")
    i = np.cumsum([0, NX, NX * NX, NX * NU, NX * NU, NX])
    return {
        "x_next": aug[:, i[0] : i[1]],
        "A": aug[:, i[1] : i[2]].reshape(N - 1, NX, NX).transpose(0, 2, 1),
        "Bm": aug[:, i[2] : i[3]].reshape(N - 1, NU, NX).transpose(0, 2, 1),
        "Bp": aug[:, i[3] : i[4]].reshape(N - 1, NU, NX).transpose(0, 2, 1),
        "Sigma": aug[:, i[4] : i[5]],
        "z": z,
    }
