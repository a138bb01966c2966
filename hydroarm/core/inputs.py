"""Lever (valve spool) input y(t) in jack coordinates [m].

An input is a piecewise-linear table of (t, y) (a step is two points at the same time; a
ramp two points; a measured lever trace any number), optionally plus a sine. The table form
keeps the compiled kernels to one input evaluator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from ..errors import HydroarmError


@dataclass(frozen=True)
class LeverInput:
    """y(t) = table(t) + amplitude·sin(2π·frequency·(t − t_sine)) for t ≥ t_sine.

    Parameters
    ----------
    times : array [s], non-decreasing; a repeated time is a step
    positions : array [m], lever position in jack coordinates
    sine_amplitude : [m]
    sine_frequency : [Hz]
    sine_start : [s]
    description : label
    """

    times: np.ndarray
    positions: np.ndarray
    sine_amplitude: float = 0.0
    sine_frequency: float = 0.0
    sine_start: float = 0.0
    description: str = "input"
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        t = np.asarray(self.times, dtype=float)
        y = np.asarray(self.positions, dtype=float)
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "positions", y)
        if t.ndim != 1 or t.size == 0 or t.shape != y.shape:
            raise HydroarmError("input", "times and positions must be 1-D arrays of equal length")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
            raise HydroarmError("input", "times and positions must be finite numbers")
        if np.any(np.diff(t) < 0):
            raise HydroarmError("input.time", "times must not decrease")

    @property
    def sine(self) -> np.ndarray:
        return np.array([self.sine_amplitude, self.sine_frequency, self.sine_start])

    def __call__(self, t):
        return evaluate_many(
            np.atleast_1d(np.asarray(t, float)), self.times, self.positions, self.sine
        )

    @property
    def final(self) -> float:
        return float(self.positions[-1])


def step(y0: float, y1: float, t0: float = 0.0) -> LeverInput:
    """Lever moved instantly from y0 to y1 [m] at t0 [s] (the saturation tests)."""
    return LeverInput(np.array([t0, t0]), np.array([y0, y1]), description="step")


def ramp(y0: float, y1: float, t0: float, t1: float) -> LeverInput:
    """Lever moved at constant speed from y0 at t0 to y1 at t1."""
    if not t1 > t0:
        raise HydroarmError("input.end", "ramp end time must be after its start")
    return LeverInput(np.array([t0, t1]), np.array([y0, y1]), description="ramp")


def sine(offset: float, amplitude: float, frequency: float, t0: float = 0.0) -> LeverInput:
    """y = offset + amplitude·sin(2π f (t − t0)) for t ≥ t0."""
    if not frequency > 0 or not math.isfinite(frequency):
        raise HydroarmError("input.frequency", f"must be positive, got {frequency!r}")
    return LeverInput(
        np.array([t0]), np.array([offset]), amplitude, frequency, t0, description="sine"
    )


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
