"""Lever (valve spool) input y(t) in jack coordinates [m].

An input is a piecewise-linear table of (t, y) (a step is two points at the same time; a
ramp two points; a measured lever trace any number), optionally plus a sine. The table form
keeps the compiled kernels to one input evaluator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.lever import evaluate_many
from ..errors import HydroarmError


@dataclass(frozen=True)
class LeverInput:
    """Lever input y(t) = table(t) + amplitude·sin(2π·frequency·(t − t_sine)) for t ≥ t_sine.

    Parameters
    ----------
    times : numpy.ndarray
        Times of the table [s], non-decreasing; a repeated time is a step.
    positions : numpy.ndarray
        Lever positions [m] in jack coordinates.
    sine_amplitude : float
        Amplitude of the sine [m].
    sine_frequency : float
        Its frequency [Hz].
    sine_start : float
        Its start t_sine [s].
    description : str
        Label.
    meta : dict
        Where the input came from (a file's section), for reports.
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
    """Lever moved instantly from y0 to y1 at t0 (the saturation tests).

    Parameters
    ----------
    y0 : float
        Lever position before the step [m].
    y1 : float
        Lever position after it [m].
    t0 : float
        Time of the step [s].

    Returns
    -------
    LeverInput
        The lever's input.
    """
    return LeverInput(np.array([t0, t0]), np.array([y0, y1]), description="step")


def ramp(y0: float, y1: float, t0: float, t1: float) -> LeverInput:
    """Lever moved at constant speed from y0 at t0 to y1 at t1.

    Parameters
    ----------
    y0 : float
        Lever position before the ramp [m].
    y1 : float
        Lever position after it [m].
    t0 : float
        Start of the ramp [s].
    t1 : float
        End of the ramp [s].

    Returns
    -------
    LeverInput
        The lever's input.
    """
    if not t1 > t0:
        raise HydroarmError("input.end", "ramp end time must be after its start")
    return LeverInput(np.array([t0, t1]), np.array([y0, y1]), description="ramp")


def sine(offset: float, amplitude: float, frequency: float, t0: float = 0.0) -> LeverInput:
    """Lever y = offset + amplitude·sin(2π f (t − t0)) for t ≥ t0.

    Parameters
    ----------
    offset : float
        Mean lever position [m].
    amplitude : float
        Amplitude [m].
    frequency : float
        Frequency f [Hz].
    t0 : float
        Start of the sine [s].

    Returns
    -------
    LeverInput
        The lever's input.
    """
    if not frequency > 0 or not math.isfinite(frequency):
        raise HydroarmError("input.frequency", f"must be positive, got {frequency!r}")
    return LeverInput(
        np.array([t0]), np.array([offset]), amplitude, frequency, t0, description="sine"
    )
