"""Small laws shared by several circuit components (one home each).

Pure numba functions on SI floats, used by the component modules of
`hydroarm.core.circuit.components`; the heavier single-component laws (orifice edges,
the relief valve, air in oil, the accumulator, the PID) live in
`hydroarm.core.components`, shared with the component servo.
"""

from __future__ import annotations

import math
from typing import Any

from numba import njit

from ..equations import stick_or_slide

#: the decorator of every law and of the system kernel: compiled, cached, and free of
#: reference counting (numba's ``_nrt=False``): a law allocates nothing and only reads and
#: writes the arrays it is given, and without it the reference counts of the ten-odd arrays
#: passed to every law cost about 90 % of a right-hand side (benchmarks/circuit_speed.py)
_OPTIONS: dict[str, Any] = {"cache": True, "nogil": True, "error_model": "numpy", "_nrt": False}
kernel = njit(**_OPTIONS)
#: `kernel` compiled into each caller (numba's ``inline="always"``): for the system
#: kernel's parts on the step's path, which take the whole net and work tuples. A call copies
#: its arguments, a tuple of arrays as all their fields: some 500 words for the net and the
#: work, which took over half the time of a step when the parts were called
#: (benchmarks/circuit_throughput.py); inlined, they share the caller's unpacked arrays.
inlined_kernel = njit(**_OPTIONS, inline="always")


#: the share of a step by which a projection's velocity change moves the position
#: (`dry_friction`): 1 for the semi-implicit Euler, whose positions advance with the
#: step's final velocity, ½ for a Runge–Kutta step (the friction impulse grows linearly
#: over the step) and for the adaptive integrator's
POSITION_SHARE_EULER = 1.0
POSITION_SHARE_RUNGE_KUTTA = 0.5


def orifice_coefficient(discharge_coefficient, area, density):
    """k = C_d·A·√(2/ρ) [m³ s⁻¹ Pa⁻¹ᐟ²] of a turbulent orifice of flow area A (Merritt 1967
    eq. 3-7): a `Derived` formula of the orifice and the check valve."""
    return discharge_coefficient * area * math.sqrt(2.0 / density)


@kernel
def signal_or(port_index, sig, value):
    """The signal at ``port_index`` of an optional signal input, or ``value`` when the port
    is unconnected (index −1)."""
    if port_index >= 0:
        return sig[port_index]
    return value


@kernel
def first_order_rate(u, y, time_constant):
    """ẏ of a first-order lag τ·ẏ = u − y [unit/s]; 0 when τ = 0 (the output is u)."""
    if time_constant > 0.0:
        return (u - y) / time_constant
    return 0.0


@kernel
def filtered(u, y, time_constant):
    """The output of a first-order lag: its state y, or u itself when τ = 0."""
    return y if time_constant > 0.0 else u


@kernel
def clip(x, lo, hi):
    """x limited to [lo, hi]."""
    return min(max(x, lo), hi)


@kernel
def end_stop(s, ix, iv, lo, hi):
    """An inelastic end stop on the mechanical node whose position and velocity are
    s[ix], s[iv]: the position held in [lo, hi], the velocity into the stop removed."""
    if s[ix] < lo:
        s[ix] = lo
        s[iv] = max(s[iv], 0.0)
    elif s[ix] > hi:
        s[ix] = hi
        s[iv] = min(s[iv], 0.0)


@kernel
def dry_friction(s_old, s, ix, iv, h, coulomb, breakaway, inertia, share):
    """Dry friction on the mechanical node whose position and velocity are s[ix], s[iv], as
    the step's projection (the paper joint's time-stepping rule,
    `hydroarm.core.equations.stick_or_slide`): the node sticks if the velocity v* the
    smooth step reached is within h·F/M (breakaway F_s from rest, else sliding F_c; M the
    node's whole mass or inertia), and otherwise slides with v* reduced by h·F_c/M. The
    position takes the friction impulse as the stepper moves positions with velocities
    (``share``, `POSITION_SHARE_EULER` and the next): by h·(v − v*) after the
    semi-implicit Euler step, whose positions advance with the step's final velocity (the
    paper's eq. (7)), and by ½·h·(v − v*) after a Runge–Kutta step, over which the impulse
    grows linearly. A node that sticks from rest stays where it was. Forces in N or N m.
    Nothing at h = 0 (the start) or without friction."""
    if h <= 0.0 or (coulomb <= 0.0 and breakaway <= 0.0):
        return
    slide = h * coulomb / inertia
    hold = h * max(breakaway, coulomb) / inertia
    v_old = s_old[iv]
    v_star = s[iv]
    v = stick_or_slide(v_old, v_star, slide, hold if v_old == 0.0 else slide)
    if v == 0.0 and v_old == 0.0:
        s[ix] = s_old[ix]
    else:
        s[ix] += share * h * (v - v_star)
    s[iv] = v
