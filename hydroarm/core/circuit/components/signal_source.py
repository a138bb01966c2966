"""Signal source: a constant, steps, a ramp, a sine or a table against time.

    constant   y = offset
    steps      y = values[i] for times[i] ≤ t < times[i+1]; offset before times[0]
    ramp       y = offset + rate·(clip(t, t_start, t_end) − t_start)
    sine       y = offset + amplitude·sin(2π·f·(t − t_start) + φ) for t ≥ t_start, else offset
    table      y linear in t through (times, values), held beyond the ends (a CSV's columns)

Steps and a table add a sine amplitude·sin(2π·f·(t − t_start) + φ) from t_start where the
amplitude is not zero (a lever input's sine on top of its table: `hydroarm.core.lever`).

A signal carries any quantity in SI (a spool demand in m, a pump speed in rad/s, a pressure
in Pa, a position reference in m).
"""

from __future__ import annotations

import math

from ..declare import SIGNAL_OUT, Component, Input, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="signal_source",
    summary="a signal against time: constant, steps, ramp, sine or table",
    parameters=(
        Param(
            "waveform",
            "",
            "constant",
            "",
            "the shape",
            ("constant", "steps", "ramp", "sine", "table"),
            sweepable=False,
        ),
        Param("offset", "*", 0.0, "", "the level (before the steps, the ramp, the sine)"),
        Param("rate", "*", 0.0, "", "ramp: rate of change (unit/s)"),
        Param("start_time", "s", 0.0, "", "ramp and sine: start (the sine's on steps and a table)"),
        Param("end_time", "s", float("inf"), "", "ramp: end"),
        Param("amplitude", "*", 0.0, "", "sine: amplitude (steps and table: of the added sine)"),
        Param("frequency", "Hz", 0.0, ">= 0", "sine: frequency"),
        Param("phase", "rad", 0.0, "", "sine: phase at the start"),
    ),
    arrays=(
        Param("times", "s", None, "", "steps and table: instants, increasing"),
        Param("values", "*", None, "", "steps and table: values"),
    ),
    states=(),
    ports=(Port("out", SIGNAL_OUT, "the signal"),),
    source="",
    inputs=(
        Input(
            "value",
            "offset",
            "the signal, held over each step (once set, in place of the waveform)",
            hold=(("waveform", "constant"),),
            port="out",
        ),
    ),
)
par, st, pt = DECLARATION.indices()
CONSTANT, STEPS, RAMP, SINE, TABLE = range(5)


@kernel
def tabulated(t, P, po, kind):
    """The steps' or the table's value at t (module doc), without the added sine."""
    n = int(P[po + par.times])
    ti = po + par.times + 1
    vi = po + par.values + n + 1  # [n, times…, n, values…]: the values after the times
    if t < P[ti]:
        return P[po + par.offset] if kind == STEPS else P[vi]
    for i in range(n - 1):
        if t < P[ti + i + 1]:
            if kind == STEPS:
                return P[vi + i]
            f = (t - P[ti + i]) / (P[ti + i + 1] - P[ti + i])
            return P[vi + i] + f * (P[vi + i + 1] - P[vi + i])
    return P[vi + n - 1]


@kernel
def with_sine(y, t, P, po):
    """y plus the sine added on top of steps or a table at t (module doc): y itself before
    its start or where its amplitude is 0."""
    a = P[po + par.amplitude]
    t0 = P[po + par.start_time]
    if a == 0.0 or t < t0:
        return y
    return y + a * math.sin(2.0 * math.pi * P[po + par.frequency] * (t - t0) + P[po + par.phase])


@kernel
def value(t, P, po):
    """The source's value at t."""
    kind = P[po + par.waveform]
    y = P[po + par.offset]
    if kind == RAMP:
        t0 = P[po + par.start_time]
        return y + P[po + par.rate] * (min(max(t, t0), P[po + par.end_time]) - t0)
    if kind == SINE:
        t0 = P[po + par.start_time]
        if t < t0:
            return y
        arg = 2.0 * math.pi * P[po + par.frequency] * (t - t0) + P[po + par.phase]
        return y + P[po + par.amplitude] * math.sin(arg)
    if kind == STEPS or kind == TABLE:
        return with_sine(tabulated(t, P, po, kind), t, P, po)
    return y


def corners(P, po):
    """The instants [s] where the source's value or its slope jumps: its steps' and its
    table's times, its ramp's start and end, its sine's start, also on top of steps or a
    table (none for a constant). The
    adaptive method (`hydroarm.integrators.adaptive.integrate_circuit_adaptive`) never
    steps across one."""
    kind = P[po + par.waveform]
    if kind == RAMP:
        return [float(P[po + par.start_time]), float(P[po + par.end_time])]
    if kind == SINE:
        return [float(P[po + par.start_time])]
    if kind == STEPS or kind == TABLE:
        n = int(P[po + par.times])
        found = [float(x) for x in P[po + par.times + 1 : po + par.times + 1 + n]]
        if P[po + par.amplitude] != 0.0:  # a sine on top starts at its start time
            found.append(float(P[po + par.start_time]))
        return found
    return []


@kernel
def signals(t, P, po, s, so, port, pn, xm, vm, sig):
    sig[port[pt.out]] = value(t, P, po)


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    return None
