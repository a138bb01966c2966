"""Lever (valve spool) input kernels: y(t) from a piecewise-linear table plus a sine.

An input is a table of (t, y) (a step is two points at the same time; a ramp two points; a
measured lever trace any number), optionally plus a sine ``(amplitude, frequency, start)``.
The table form keeps the compiled kernels to one input evaluator.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, error_model="numpy")
def evaluate(t, tab_t, tab_y, sine):
    """y(t) [m]: piecewise-linear table (held at the ends) plus optional sine."""
    n = tab_t.shape[0]
    if t >= tab_t[n - 1]:
        y = tab_y[n - 1]
    elif t < tab_t[0]:
        y = tab_y[0]
    else:
        i = np.searchsorted(tab_t, t, side="right") - 1
        dt = tab_t[i + 1] - tab_t[i]
        if dt > 0.0:
            y = tab_y[i] + (tab_y[i + 1] - tab_y[i]) * (t - tab_t[i]) / dt
        else:
            y = tab_y[i + 1]
    if sine[0] != 0.0 and t >= sine[2]:
        y += sine[0] * np.sin(2.0 * np.pi * sine[1] * (t - sine[2]))
    return y


@njit(cache=True)
def evaluate_many(ts, tab_t, tab_y, sine):
    out = np.empty(ts.shape[0])
    for i in range(ts.shape[0]):
        out[i] = evaluate(ts[i], tab_t, tab_y, sine)
    return out


def play_operator(theta, backlash: float, initial: float | None = None) -> np.ndarray:
    """Backlash (play) operator: the driven side follows ``theta`` with a dead band.

    The output stays put while the input moves inside a gap of total width ``backlash``
    [rad] and is pushed along at ±backlash/2 once the gap is taken up (Tao & Kokotović,
    *Adaptive control of systems with actuator and sensor nonlinearities*, 1996, ch. 2):
    out_k = min(max(out_{k−1}, θ_k − b/2), θ_k + b/2). It models a driven side held by its
    own friction; gravity that keeps the gap closed on one side shifts the output by b/2.
    """
    th = np.asarray(theta, dtype=float)
    out = np.empty_like(th)
    if th.size == 0:
        return out
    h = 0.5 * backlash
    prev = th[0] if initial is None else initial
    for k, v in enumerate(th):
        prev = min(max(prev, v - h), v + h)
        out[k] = prev
    return out
