"""The skip mark of the tests that need the C guidance library (build/libtscvx_gnc.so, or
TSCVX_GNC_LIB), one condition and one reason for every test module."""

from __future__ import annotations

import ctypes
import math
import struct

import pytest

from guidance.cgnc import LIB_PATH

needs_c_library = pytest.mark.skipif(
    not LIB_PATH.exists(), reason=f"{LIB_PATH} not built (make lib)"
)


def nan_output_net():
    """The shipped solution network of build/models with out_mean[0] NaN in its blob (read in
    place: init checked the blob before), so that every prediction has a NaN entry."""
    from guidance.cguidance import BUILD_MODELS_DIR
    from guidance.nn.flight import FlightNet

    net = FlightNet(BUILD_MODELS_DIR / "solution.tnn")
    at = 128 + 8 * 2 * net.d_in  # header, in_mean, in_scale: out_mean[0]
    ctypes.memmove(ctypes.addressof(net._blob) + at, struct.pack("<d", math.nan), 8)
    return net
