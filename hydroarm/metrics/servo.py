"""On-the-fly metrics of component servo runs (issue 14; docs/batch.md "Component servos").

A sweep of 10⁴–10⁶ servos cannot keep their traces: it keeps per-run summaries, observed
at every step of the servo's circuit on the system kernel
(`hydroarm.model.servo_observers`). This module declares them (`METRICS`, their columns
`metric_columns`, the reference's last step `step_of`); the servo kernel's own compiled
metrics, the tests' oracle, are `hydroarm.reference.servo_metrics`.

Metrics (`METRICS`, SI; positions in m, or rad for an angular load):

* the final state: position, velocity, chamber and supply pressures, spool position, and
  the energies of the run (final minus initial: supplied, relief, throttling, leakage,
  compression, work on the piston);
* the highest and the lowest chamber pressure, the highest supply pressure and the highest
  |velocity| over every step (the initial state included);
* for a step reference: ``settling_time`` [s] after the last step, from which the
  controlled quantity (the feedback's measurement, in the reference's units: the sensor's
  output for electronic feedback, the actuator position for mechanical) stays within
  ±``band`` × the step's size of the final reference (NaN: outside the band at the end), and
  ``overshoot``, the largest excursion past the final reference after the step relative to
  the step's size (0 when it never passes it). Other references: NaN.
* ``failed`` (1.0: a state stopped being finite; every other metric is then NaN) and
  ``failure_time`` [s].
"""

from __future__ import annotations

import math

import numpy as np

DEFAULT_BAND = 0.02  # settling band: ±2 % of the last step's size

# (name, unit kind): "position" is m or rad (rad/s) with the load, "pressure" Pa
METRICS: tuple[tuple[str, str], ...] = (
    ("final_position", "position"),
    ("final_velocity", "velocity"),
    ("final_pressure_a", "pressure"),
    ("final_pressure_b", "pressure"),
    ("final_supply_pressure", "pressure"),
    ("final_spool", "length"),
    ("supply_energy", "energy"),
    ("relief_energy", "energy"),
    ("throttle_energy", "energy"),
    ("leakage_energy", "energy"),
    ("compression_energy", "energy"),
    ("actuator_work", "energy"),
    ("peak_pressure", "pressure"),
    ("min_pressure", "pressure"),
    ("peak_supply_pressure", "pressure"),
    ("peak_speed", "velocity"),
    ("settling_time", "time"),
    ("overshoot", "fraction"),
    ("failed", "flag"),
    ("failure_time", "time"),
)
N_METRICS = len(METRICS)
METRIC_INDEX = {name: i for i, (name, _) in enumerate(METRICS)}


def step_of(times, positions, sine_amplitude: float = 0.0) -> tuple[float, float]:
    """(time, from) of the last step of a reference table (a repeated time whose value
    changes): from = NaN for a single value (a step at the table's start from wherever the
    servo starts). (NaN, NaN) for a reference that is not steps (a ramp, a sine)."""
    t = np.asarray(times, float)
    y = np.asarray(positions, float)
    if sine_amplitude != 0.0:
        return math.nan, math.nan
    if len(t) == 1:
        return float(t[0]), math.nan
    jump = (t[1:] == t[:-1]) & (y[1:] != y[:-1])
    ramp = (t[1:] > t[:-1]) & (y[1:] != y[:-1])
    if np.any(ramp):
        return math.nan, math.nan
    if not np.any(jump):
        return float(t[0]), math.nan
    i = int(np.flatnonzero(jump)[-1]) + 1
    return float(t[i]), float(y[i - 1])


def metric_columns(M: np.ndarray, linear: bool) -> dict:
    """Named columns of a metrics table (rows × N_METRICS): pressures in bar (absolute),
    positions in m (or rad), ``failed`` as bool; the names carry the units."""
    M = np.atleast_2d(M)
    pos, vel = ("m", "m_s") if linear else ("rad", "rad_s")
    suffix = {
        "position": pos,
        "velocity": vel,
        "pressure": "bar",
        "length": "m",
        "energy": "j",
        "time": "s",
        "fraction": "",
        "flag": "",
    }
    cols: dict = {}
    for i, (name, kind) in enumerate(METRICS):
        v = M[:, i]
        if kind == "pressure":
            v = v / 1e5
        elif kind == "flag":
            v = v > 0.5
        key = f"{name}_{suffix[kind]}" if suffix[kind] else name
        cols[key] = v
    return cols
