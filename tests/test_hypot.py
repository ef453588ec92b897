"""The flight library's own hypot (pdg_hypot, c_runtime/guidance/pdg_scenario.c) against exact
rational arithmetic.

The guidance computes its trust-region steps and penalty with pdg_hypot instead of libm's
hypot, whose last bit differs between hosts (Debian's 32-bit PowerPC glibc and x86-64 glibc
disagree on about a third of the default landing's calls), so that a landing is the same to the
bit on the ground and on the RAD750's kind of CPU (`make check-ppc`; the C test
test_libm_hypot checks that the landing no longer depends on libm's hypot). pdg_hypot uses IEEE
operations only; here it must be within one ulp of the exact value everywhere, correctly rounded
almost always, and take IEEE 754's special values as hypot does.
"""

from __future__ import annotations

import ctypes
import math
import random
from fractions import Fraction

import pytest
from c_library import needs_c_library

from guidance import cgnc

pytestmark = needs_c_library


@pytest.fixture(scope="module")
def pdg_hypot() -> ctypes._CFuncPtr:
    fn = cgnc.library().pdg_hypot
    fn.restype = ctypes.c_double
    fn.argtypes = [ctypes.c_double, ctypes.c_double]
    return fn


def _correctly_rounded(a: float, b: float) -> float:
    """sqrt(a^2 + b^2) rounded to nearest: the double whose exact value is closest."""
    s = Fraction(a) ** 2 + Fraction(b) ** 2
    if s == 0:
        return 0.0
    if s >= (Fraction(2) ** 1024 - Fraction(2) ** 970) ** 2:  # past the last rounding midpoint
        return math.inf
    k = max(math.frexp(a)[1], math.frexp(b)[1])  # scaled by 4^k: no under- or overflow
    guess = math.ldexp(math.sqrt(float(s / Fraction(4) ** k)), k)
    cands = [guess]
    for _ in range(3):
        cands = [math.nextafter(cands[0], 0.0), *cands, math.nextafter(cands[-1], math.inf)]
    # |c - sqrt(s)| ordered as |c^2 - s| / (c + sqrt(s)), with the guess for sqrt(s)
    return min(
        (c for c in cands if math.isfinite(c)),
        key=lambda c: abs(Fraction(c) ** 2 - s) / (Fraction(c) + Fraction(guess)),
    )


def _arguments(n: int) -> list[tuple[float, float]]:
    rng = random.Random(20261128)
    out = []
    for i in range(n):
        if i % 4 == 0:  # the guidance's range: scaled state differences
            a, b = (rng.uniform(-1, 1) * 2.0 ** rng.randint(-30, 8) for _ in range(2))
        elif i % 4 == 1:  # very different magnitudes
            a, b = rng.uniform(-1, 1), rng.uniform(-1, 1) * 2.0 ** rng.randint(-60, -20)
        elif i % 4 == 2:  # near overflow and underflow (the scaled paths)
            e = rng.choice([rng.randint(500, 1023), rng.randint(-1074, -500)])
            a, b = (rng.uniform(0.5, 1) * 2.0**e for _ in range(2))
        else:  # any finite doubles
            a, b = (math.ldexp(rng.uniform(-1, 1), rng.randint(-1070, 1023)) for _ in range(2))
        out.append((a, b))
    return out


def test_pdg_hypot_within_one_ulp_and_mostly_correctly_rounded(pdg_hypot):
    args = _arguments(4000)
    wrong = 0
    for a, b in args:
        got, want = pdg_hypot(a, b), _correctly_rounded(a, b)
        assert abs(got - want) <= math.ulp(want), (a, b, got, want)
        assert pdg_hypot(b, a) == got and pdg_hypot(-a, b) == got  # symmetric, sign-blind
        wrong += got != want
    assert wrong <= len(args) // 100, f"{wrong} of {len(args)} not correctly rounded"


def test_pdg_hypot_special_values(pdg_hypot):
    inf, nan = math.inf, math.nan
    assert pdg_hypot(inf, nan) == inf and pdg_hypot(nan, -inf) == inf  # IEEE 754: inf wins
    assert math.isnan(pdg_hypot(nan, 1.0)) and math.isnan(pdg_hypot(0.0, nan))
    assert pdg_hypot(0.0, -0.0) == 0.0 and math.copysign(1.0, pdg_hypot(-0.0, -0.0)) == 1.0
    assert pdg_hypot(3.0, 4.0) == 5.0 and pdg_hypot(-5e-324, 0.0) == 5e-324
    assert pdg_hypot(1.5e308, 1.5e308) == _correctly_rounded(1.5e308, 1.5e308)
    assert pdg_hypot(1.7e308, 1.7e308) == inf  # the exact value overflows
    assert pdg_hypot(3e-320, 4e-320) == _correctly_rounded(3e-320, 4e-320)
