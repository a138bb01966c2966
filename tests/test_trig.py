"""The kernels' inlined sin/cos (hydroarm.core.trig) against libm.

Tolerance: fdlibm's kernels are accurate to < 1 ulp; with the three-part Cody–Waite
reduction the result may differ from the correctly rounded value by at most 1 ulp, so we
allow 1 ulp of the larger of |f(x)| and 2⁻¹ (near a zero of f the absolute error of the
reduction, ~1e-16, dominates).
"""

import math

import numpy as np
import pytest
from numba import njit

from hydroarm.core.trig import cos, sin, sin_cos


@njit(cache=True)
def _both(xs):
    out = np.empty((xs.size, 2))
    for i in range(xs.size):
        s, c = sin_cos(xs[i])
        out[i, 0] = s
        out[i, 1] = c
    return out


@pytest.mark.parametrize("span", [0.7, math.pi, 50.0, 9.9e4, 1e6])
def test_within_one_ulp_of_libm(span):
    xs = np.random.default_rng(7).uniform(-span, span, 200_000)
    got = _both(xs)
    for j, ref in enumerate((np.sin(xs), np.cos(xs))):
        scale = np.spacing(np.maximum(np.abs(ref), 0.5))
        assert np.max(np.abs(got[:, j] - ref) / scale) <= 1.0


def test_quadrant_signs():
    # multiples of π/4 and points just around the quadrant boundaries
    xs = np.array([k * math.pi / 4 + d for k in range(-12, 13) for d in (-1e-9, 0.0, 1e-9)])
    got = _both(xs)
    assert np.allclose(got[:, 0], np.sin(xs), atol=3e-16, rtol=0)
    assert np.allclose(got[:, 1], np.cos(xs), atol=3e-16, rtol=0)


def test_exact_values_and_special_arguments():
    assert sin(0.0) == 0.0 and cos(0.0) == 1.0
    # far beyond the exact reduction (k·π/2 with |k| > 2²⁰) the documented loss of digits
    assert abs(sin(1e9) - math.sin(1e9)) < 1e-6 and abs(cos(1e9) - math.cos(1e9)) < 1e-6
    assert math.isnan(sin(math.nan)) and math.isnan(cos(math.inf))
