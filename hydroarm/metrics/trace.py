"""Statistics of one named output's trace (t, y): the metrics of studies on any system.

A study names a metric by an output and a statistic (docs/batch.md "Studies of a circuit")::

    peak_pressure = { output = "A_pressure_bar", statistic = "max" }
    settling = { output = "load_position_m", statistic = "settling_time", after = "1 s" }

The window ``[after, before]`` [s] selects the part of the run the statistic reads (default:
all of it). The step-response statistics (``settling_time``, ``rise_time``, ``overshoot``,
``peak_time``) are python-control's `control.step_info` on the window, its times
counted from the window's start: a step applied at ``after`` from the value the output has
there (python-control's thresholds are relative to the final value; the trace is taken from
its first value so that they are relative to the step's size). Their thresholds are
keywords: ``band`` (settling: within ± band of the step's size of the final value, 0.02)
and ``rise`` ((0.1, 0.9) of the step). Results are in the output's units, times in
seconds, the overshoot in per cent of the step.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import HydroarmError

#: statistic → (unit of the result: "same" the output's, "s", "pct", "same*s"; description)
STATISTICS: dict[str, tuple[str, str]] = {
    "max": ("same", "largest value"),
    "min": ("same", "smallest value"),
    "mean": ("same", "time average (trapezoid rule)"),
    "rms": ("same", "root mean square over time (trapezoid rule)"),
    "final": ("same", "value at the window's end"),
    "initial": ("same", "value at the window's start"),
    "peak_to_peak": ("same", "largest minus smallest value"),
    "max_abs": ("same", "largest magnitude"),
    "integral": ("same*s", "time integral (trapezoid rule)"),
    "time_of_max": ("s", "time of the largest value"),
    "time_of_min": ("s", "time of the smallest value"),
    "settling_time": (
        "s",
        "time after the window's start to stay within ± band of the final value",
    ),
    "rise_time": ("s", "time from rise[0] to rise[1] of the step"),
    "overshoot": ("pct", "overshoot in per cent of the step"),
    "peak_time": ("s", "time after the window's start of the response's peak"),
}
STEP_STATISTICS = ("settling_time", "rise_time", "overshoot", "peak_time")
DEFAULT_BAND = 0.02
DEFAULT_RISE = (0.1, 0.9)


def window(t, y, after: float = -math.inf, before: float = math.inf):
    """The samples of (t, y) with ``after <= t <= before``."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    keep = (t >= after) & (t <= before)
    return t[keep], y[keep]


def _trapezoid(t, y) -> float:
    return float(np.trapezoid(y, t)) if len(t) > 1 else 0.0


def trace_statistic(
    t,
    y,
    statistic: str,
    *,
    after: float = -math.inf,
    before: float = math.inf,
    band: float = DEFAULT_BAND,
    rise: tuple[float, float] = DEFAULT_RISE,
) -> float:
    """One statistic (`STATISTICS`) of the trace (t [s], y) in its window; NaN when
    the window holds no sample or the trace is not finite."""
    if statistic not in STATISTICS:
        raise HydroarmError("statistic", f"{statistic!r}: one of {', '.join(STATISTICS)}")
    t, y = window(t, y, after, before)
    if len(t) == 0 or not np.all(np.isfinite(y)):
        return math.nan
    if statistic == "max":
        return float(np.max(y))
    if statistic == "min":
        return float(np.min(y))
    if statistic == "final":
        return float(y[-1])
    if statistic == "initial":
        return float(y[0])
    if statistic == "peak_to_peak":
        return float(np.max(y) - np.min(y))
    if statistic == "max_abs":
        return float(np.max(np.abs(y)))
    if statistic == "time_of_max":
        return float(t[int(np.argmax(y))])
    if statistic == "time_of_min":
        return float(t[int(np.argmin(y))])
    span = t[-1] - t[0]
    if statistic == "integral":
        return _trapezoid(t, y)
    if statistic == "mean":
        return _trapezoid(t, y) / span if span > 0 else float(y[0])
    if statistic == "rms":
        return math.sqrt(_trapezoid(t, y * y) / span) if span > 0 else abs(float(y[0]))
    return step_statistics(t, y, band=band, rise=rise)[statistic]


def step_statistics(t, y, *, band: float = DEFAULT_BAND, rise=DEFAULT_RISE) -> dict:
    """``settling_time``, ``rise_time``, ``overshoot`` [%] and ``peak_time`` of a step
    response (t [s], y), times from t[0] (python-control's `control.step_info`);
    NaN for a trace that does not move."""
    import control

    t = np.asarray(t, float)
    y = np.asarray(y, float)
    nan = dict.fromkeys(STEP_STATISTICS, math.nan)
    if len(t) < 3 or not np.all(np.isfinite(y)) or y[-1] == y[0]:
        return nan
    # from the window's first value: python-control takes its thresholds relative to the
    # final value, which is the step's size only for a response that starts at zero
    info = control.step_info(
        y - y[0], t - t[0], SettlingTimeThreshold=band, RiseTimeLimits=tuple(rise)
    )
    return {
        "settling_time": float(info["SettlingTime"]),
        "rise_time": float(info["RiseTime"]),
        "overshoot": float(info["Overshoot"]),
        "peak_time": float(info["PeakTime"]),
    }


def statistic_unit(statistic: str, output_unit: str) -> str:
    """The unit suffix of a statistic's column from its output's (``bar`` → ``bar``; a time
    → ``s``; an integral of ``lpm`` → ``lpm_s``)."""
    kind = STATISTICS[statistic][0]
    if kind == "same":
        return output_unit
    if kind == "same*s":
        return f"{output_unit}_s" if output_unit else "s"
    return kind
