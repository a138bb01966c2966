"""The paper's evaluation methods, as functions on traces (t, x).

They work on simulated and on measured traces alike: no model object is needed. Results are
in the trace's own units (x-units per t-unit for velocities, t-units for times). The
thresholds of the paper, the middle 80 % of motion and 63 % of the rise, are keyword
arguments.

- Saturation velocity: "the average velocity for the middle 80 % of motion" (Table III).
- Time constants: "the time to move 63 % of full valve opening either at the start or at the
  end of travel" (no-load transient test) and "the time constant of the exponential rise to
  this steady velocity can be measured as the time to reach 63 % of full valve opening"
  (Figs. 9–11), read literally: the time the jack takes to *move* 0.63·e_o from where it
  started, the mirror image of the end-of-travel constant (docs/model.md, "Time
  constants"). The time for the velocity to reach 63 % of the full-opening velocity is kept
  as a named alternative. See [`step_metrics`][hydroarm.step_metrics] for the exact definitions.
- End of motion: the commanded target when it is known (a simulation), else the final
  position (a measured trace); the on-the-fly metrics of `hydroarm.metrics.online`
  use the same definitions.
- Stall: the paper notes that under the heaviest load the arm stalls before the end of
  travel and that its raising velocity is then the velocity up to stall; the metrics do the
  same and say so (``stalled``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import HydroarmError, check_number


@dataclass(frozen=True)
class MetricOptions:
    """Thresholds of the paper's step metrics.

    Passed the same way everywhere: to a [`Scenario`][hydroarm.Scenario]
    (``metric_options``), to the batch engine, and from the ``[metrics]`` section of scenario
    and sweep files.

    Parameters
    ----------
    middle : float
        Fraction of the motion over which the saturation velocity is averaged [-] (0.8).
    threshold : float
        Fraction defining the time constants [-] (0.63 ≈ 1 − 1/e).
    stall_tolerance : float
        A motion ending farther than this fraction [-] of the commanded travel short of the
        target has stalled (0.05).
    """

    middle: float = 0.8
    threshold: float = 0.63
    stall_tolerance: float = 0.05

    def __post_init__(self):
        for name in ("middle", "threshold"):
            v = check_number(f"metrics.{name}", getattr(self, name))
            if not 0 < v < 1:
                raise HydroarmError(f"metrics.{name}", f"must lie between 0 and 1, got {v!r}")
        v = check_number("metrics.stall_tolerance", self.stall_tolerance, positive=True)
        if not v < 1:
            raise HydroarmError("metrics.stall_tolerance", f"must be below 1, got {v!r}")

    def as_kwargs(self) -> dict:
        """Keyword arguments of [`step_metrics`][hydroarm.step_metrics] and the batch engine."""
        return asdict(self)


DEFAULT_METRIC_OPTIONS = MetricOptions()

# What each step metric measures, declared once: a result hands a metric to a user under its
# identifier with the unit of this quantity appended (``saturation_velocity_m_s``;
# `with_units`, docs/model.md "Units in names"). None: no unit (a bool, a sign, a text).
# ``peak_pressure``, ``final_x``, ``reach`` and ``failed`` are the on-the-fly kernels' additions
# (`hydroarm.metrics.online`, a sweep file's columns); ``failure``: why a run failed.
METRIC_QUANTITIES: dict[str, str | None] = {
    "saturation_velocity": "velocity",
    "direction": None,
    "time_constant_start": "time",
    "time_constant_start_velocity": "time",
    "time_constant_end": "time",
    "stalled": None,
    "stall_position": "position",
    "t_middle": "time",
    "travel": "position",
    "stall_reason": None,
    "peak_pressure": "pressure",
    "final_x": "position",
    "reach": "position",
    "failed": None,
    "failure": None,
}
# the SI unit of each quantity as a name's suffix, for a jack (positions in m) and for a
# joint measured on its angle (positions in rad)
SI_SUFFIXES = {
    "linear": {"position": "m", "velocity": "m_s", "time": "s", "pressure": "pa"},
    "angular": {"position": "rad", "velocity": "rad_s", "time": "s", "pressure": "pa"},
}


def unit_name(name: str, angular: bool = False) -> str:
    """The name of step metric ``name`` with its SI unit (``saturation_velocity_m_s``;
    ``stalled`` as it is)."""
    quantity = METRIC_QUANTITIES[name]
    if quantity is None:
        return name
    return f"{name}_{SI_SUFFIXES['angular' if angular else 'linear'][quantity]}"


def with_units(m: dict, angular: bool = False) -> dict:
    """A step-metric dictionary keyed by identifier ([`step_metrics`][hydroarm.step_metrics], SI) as
    a result hands it to a user: the same values, each name with its SI unit (`unit_name`)."""
    return {unit_name(k, angular): v for k, v in m.items()}


def _as_trace(t, x):
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if t.ndim != 1 or t.shape != x.shape or t.size < 3:
        raise HydroarmError("trace", "t and x must be 1-D arrays of equal length (at least 3)")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise HydroarmError("trace", "t and x must be finite numbers")
    if np.any(np.diff(t) <= 0):
        raise HydroarmError("trace.t", "times must increase strictly")
    return t, x


def crossing_time(t, x, level, sign, after=-math.inf):
    """First time after ``after`` at which sign·(x − level) becomes ≥ 0 (linear interpolation).

    Returns NaN if it never does.
    """
    g = sign * (x - level)
    idx = np.nonzero((g >= 0) & (t >= after))[0]
    if idx.size == 0:
        return math.nan
    i = int(idx[0])
    if i == 0 or t[i - 1] < after or g[i - 1] >= 0:
        return float(t[i])
    # interpolate between i-1 and i
    f = -g[i - 1] / (g[i] - g[i - 1])
    return float(t[i - 1] + f * (t[i] - t[i - 1]))


def saturation_velocity(
    t, x, *, middle: float = DEFAULT_METRIC_OPTIONS.middle, x_end: float | None = None
) -> float:
    """Average velocity over the middle ``middle`` fraction of the motion.

    Parameters
    ----------
    t : array_like
        Times [s].
    x : array_like
        Positions [m, or rad for a joint angle] of one motion from rest.
    middle : float
        Fraction of the motion averaged over [-].
    x_end : float, optional
        End of the motion [x's unit] (default: the furthest point reached in the direction of
        travel, so a motion that stalls is measured up to the stall).

    Returns
    -------
    float
        |Δx|/Δt over the middle of the motion [x's unit per s].
    """
    return step_metrics(t, x, middle=middle, x_end=x_end)["saturation_velocity"]


def step_metrics(
    t,
    x,
    *,
    valve_opening: float | None = None,
    target: float | None = None,
    t_start: float | None = None,
    middle: float = DEFAULT_METRIC_OPTIONS.middle,
    threshold: float = DEFAULT_METRIC_OPTIONS.threshold,
    stall_tolerance: float = DEFAULT_METRIC_OPTIONS.stall_tolerance,
    onset_fraction: float = 0.01,
    x_end: float | None = None,
    full_opening_velocity: float | None = None,
) -> dict:
    """The paper's evaluation of one full-speed motion.

    Parameters
    ----------
    t, x : array_like
        Time [s] and jack (or joint) position [m or rad] of one motion from rest.
    valve_opening : float, optional
        Full valve opening e_o [x's unit]; needed for the end-of-travel time constant.
    target : float, optional
        Commanded final position [x's unit]; needed to tell a stall from an arrival.
    t_start : float, optional
        Time the input was applied [s] (the lever step). Default: the time the trace first
        leaves x[0] by ``onset_fraction`` of its travel (for measured traces).
    middle : float
        Fraction of the motion over which the saturation velocity is averaged [-] (0.8).
    threshold : float
        Fraction defining the time constants [-] (0.63 = 1 − 1/e).
    stall_tolerance : float
        A motion that ends farther than this fraction [-] of the commanded travel from
        ``target`` has stalled.
    onset_fraction : float
        Fraction of the travel [-] by which the trace leaves x[0] when it starts (without
        ``t_start``).
    x_end : float, optional
        End of the motion [x's unit] (default: the furthest point reached in the direction
        of travel).
    full_opening_velocity : float, optional
        Velocity at full valve opening [x's unit per s], K_q·e_o/A (the no-load saturation
        velocity), for the velocity-based alternative ``time_constant_start_velocity``.
        Default: the trace's own saturation velocity (for measured traces whose valve data
        are unknown).

    Returns
    -------
    dict with
        ``saturation_velocity``: |Δx|/Δt over the middle of the motion (up to the stall if
        it stalled);
        ``direction``: +1 or −1;
        ``time_constant_start``: from ``t_start`` to the time the jack has moved
        ``threshold`` × ``valve_opening`` from x[0] toward the target (the paper's "time to
        move 63 % of full valve opening" at the start of travel; Figs. 9–11); NaN without
        ``valve_opening`` or if it never moves that far;
        ``time_constant_start_velocity``: from ``t_start`` to the time the velocity first
        reaches ``threshold`` × ``full_opening_velocity`` (an alternative reading; NaN if it
        never does, a heavy raise);
        ``time_constant_end``: time to move ``threshold`` of the full valve opening at the
        end of travel, i.e. from ``valve_opening`` to (1 − threshold)·``valve_opening`` short
        of the end of motion (the target when given, else the final position; NaN when it
        stalled, never came that close, or without ``valve_opening``);
        ``stalled``: bool, or None without ``target``;
        ``stall_position``: the furthest point reached if it stalled, else NaN;
        ``t_middle``: (start, end) of the averaging window; ``travel``: x_end − x[0];
        ``stall_reason``: None, or why it counts as stalled. A trace that does not move
        toward ``target`` at all (a joint held by friction or its load) is a stall with
        NaN velocity and time constants, not an error; without ``target`` it is an error.
    """
    if not 0 < middle < 1:
        raise HydroarmError("middle", f"must lie between 0 and 1, got {middle!r}")
    if not 0 < threshold < 1:
        raise HydroarmError("threshold", f"must lie between 0 and 1, got {threshold!r}")
    t, x = _as_trace(t, x)
    x0 = x[0]
    ref = target if target is not None else x[-1]
    sign = 1.0 if ref >= x0 else -1.0
    reach = x0 + sign * float(np.max(sign * (x - x0)))
    stalled = None
    if target is not None:
        commanded = abs(target - x0)
        stalled = bool(sign * (target - reach) > stall_tolerance * commanded)
    # the end of motion: the target when it is known, else the final position (an
    # overshoot is part of the transient, not of the travel); up to the stall if it stalled
    x_stop = x[-1] if target is None else target
    if x_end is None:
        x_end = reach if stalled else x_stop
    travel = x_end - x0
    if abs(travel) <= 0 or not np.any(sign * (x - x0) > 0):
        if not stalled:
            raise HydroarmError("trace", "the trace does not move")
        # held where it started (by friction or the load): a stall with nothing to measure
        return {
            "saturation_velocity": math.nan,
            "direction": int(sign),
            "time_constant_start": math.nan,
            "time_constant_start_velocity": math.nan,
            "time_constant_end": math.nan,
            "stalled": True,
            "stall_position": reach,
            "t_middle": (math.nan, math.nan),
            "travel": 0.0,
            "stall_reason": "the joint does not move toward the target (held by friction "
            "or the load)",
        }
    a = x0 + 0.5 * (1 - middle) * travel
    b = x0 + 0.5 * (1 + middle) * travel
    ta = crossing_time(t, x, a, sign)
    tb = crossing_time(t, x, b, sign, after=ta)
    v_sat = abs(b - a) / (tb - ta) if tb > ta else math.nan

    if t_start is None:
        t_start = crossing_time(t, x, x0 + onset_fraction * travel, sign)
    v = np.gradient(x, t)
    v_ref = v_sat if full_opening_velocity is None else abs(full_opening_velocity)
    t63 = crossing_time(t, sign * v, threshold * v_ref, 1.0, after=t_start)
    tc_velocity = t63 - t_start

    tc_start = tc_end = math.nan
    if valve_opening is not None:
        if not valve_opening > 0:
            raise HydroarmError("valve_opening", f"must be positive, got {valve_opening!r}")
        tc_start = crossing_time(t, x, x0 + sign * threshold * valve_opening, sign, t_start)
        tc_start -= t_start
    if valve_opening is not None and not stalled:
        xf = x_stop
        t1 = crossing_time(t, x, xf - sign * valve_opening, sign, after=ta)
        t2 = crossing_time(t, x, xf - sign * (1 - threshold) * valve_opening, sign, after=t1)
        tc_end = t2 - t1
    return {
        "saturation_velocity": v_sat,
        "direction": int(sign),
        "time_constant_start": tc_start,
        "time_constant_start_velocity": tc_velocity,
        "time_constant_end": tc_end,
        "stalled": stalled,
        "stall_position": reach if stalled else math.nan,
        "t_middle": (ta, tb),
        "travel": travel,
        "stall_reason": "stopped short of the target" if stalled else None,
    }


def time_constants(t, x, *, valve_opening: float, **kwargs) -> dict:
    """Start and end 63 % time constants (see [`step_metrics`][hydroarm.step_metrics]).

    Parameters
    ----------
    t : array_like
        Times [s].
    x : array_like
        Jack (or joint) positions of one motion from rest [m or rad].
    valve_opening : float
        Full valve opening e_o [x's unit].
    **kwargs
        The other options of [`step_metrics`][hydroarm.step_metrics].

    Returns
    -------
    dict
        ``{"start": [s], "end": [s]}``.
    """
    m = step_metrics(t, x, valve_opening=valve_opening, **kwargs)
    return {"start": m["time_constant_start"], "end": m["time_constant_end"]}
