"""sin and cos for the compiled kernels, inlined instead of called from libm.

The step kernels spend most of their time in the three trigonometric functions of eqs. (3)
and (4). A call into the C library cannot be inlined, so it also stops the compiler from
vectorising the batch engine's loop over scenarios (`hydroarm.batch.engine`). These are
the fdlibm kernels (``__kernel_sin``/``__kernel_cos``, Sun Microsystems 1993, the ones in
glibc and musl) after a Cody–Waite reduction by π/2 in three parts, written in plain,
branch-free arithmetic that numba inlines and LLVM vectorises. The error is at most 1 ulp
against the correctly rounded value for |x| ≤ 10⁶ rad (tests/test_trig.py compares them
with libm). Beyond, where k·π/2 no longer fits the 33-bit first part, the reduction loses
digits: absolute errors ~1e-9 at 10⁷ rad, ~6e-8 at 10⁹ rad. Joint angles are a few radians.

They take floats; array code loops over them (e.g.
`hydroarm.core.equations.jack_position_trace`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

# fdlibm k_sin.c / k_cos.c minimax coefficients on [−π/4, π/4]
_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10
_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11
# fdlibm e_rem_pio2.c: 2/π and π/2 split in three parts (33 + 33 + 53 bits)
_INV_PIO2 = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624871116645580e-21


@njit(inline="always", error_model="numpy")
def _kernel_sin(x):
    z = x * x
    r = _S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))
    return x + x * z * (_S1 + z * r)


@njit(inline="always", error_model="numpy")
def _kernel_cos(x):
    z = x * x
    r = z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    hz = 0.5 * z
    w = 1.0 - hz
    return w + (((1.0 - w) - hz) + z * r)


@njit(inline="always", error_model="numpy", cache=True)
def sin_cos(x):
    """(sin x, cos x) of a float x [rad].

    Branch-free, so that a loop over independent scenarios can be vectorised: x = k·π/2 + r
    with |r| ≤ π/4 (Cody–Waite; r = x exactly where |x| < π/4), both kernels on r, and the
    quadrant k mod 4 chosen by selects, not jumps.
    """
    k = np.floor(x * _INV_PIO2 + 0.5)  # a float: no float-to-integer conversion in the loop
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    s = _kernel_sin(r)
    c = _kernel_cos(r)
    q = k - 4.0 * np.floor(0.25 * k)  # k mod 4, in {0, 1, 2, 3}
    odd = (q == 1.0) | (q == 3.0)
    s_out = c if odd else s
    c_out = s if odd else c
    s_out = -s_out if q >= 2.0 else s_out  # quadrants 2 and 3: sin < 0
    c_out = -c_out if (q == 1.0) | (q == 2.0) else c_out  # quadrants 1 and 2: cos < 0
    return s_out, c_out


@njit(inline="always", error_model="numpy", cache=True)
def sin(x):
    """sin x of a float x [rad]."""
    return sin_cos(x)[0]


@njit(inline="always", error_model="numpy", cache=True)
def cos(x):
    """cos x of a float x [rad]."""
    return sin_cos(x)[1]
