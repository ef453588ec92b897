"""The skip mark of the tests that need the C guidance library (build/libtscvx_gnc.so, or
TSCVX_GNC_LIB), one condition and one reason for every test module."""

from __future__ import annotations

import pytest

from guidance.cgnc import LIB_PATH

needs_c_library = pytest.mark.skipif(
    not LIB_PATH.exists(), reason=f"{LIB_PATH} not built (make lib)"
)
