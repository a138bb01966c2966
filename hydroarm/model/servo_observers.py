"""A component servo's on-the-fly metrics as observers over the circuit it stands for
(issue 28; `hydroarm.metrics.servo`, `hydroarm.integrators.observers`).

The servo's own kernel keeps its metrics as it steps (`hydroarm.metrics.servo.row_metrics`); the
same metrics are statistics of the outputs of its circuit
([`compiled_circuit`][hydroarm.ServoScenario.compiled_circuit]), observed at every step of the
system kernel:

=========================  ================================================================
servo metric               observers over the circuit's outputs (SI)
=========================  ================================================================
final_position, _velocity  ``final`` of ``rod_position``/``rod_velocity`` (a mass load) or
                           ``joint_angle``/``joint_angular_velocity`` (rotary, crank)
final_pressure_a, _b       ``final`` of ``A_pressure``, ``B_pressure``
final_supply_pressure      ``final`` of ``supply_pressure``
final_spool                ``final`` of ``valve_spool`` (NaN: a valve without spool state)
peak_pressure              the larger ``max`` of ``A_pressure`` and ``B_pressure``
min_pressure               the smaller ``min`` of the two
peak_supply_pressure       ``max`` of ``supply_pressure``
peak_speed                 ``max_abs`` of the velocity
settling_time              ``settled_at`` of ``measurement`` (the feedback's measurement
                           signal, in the reference's units) from the last step, target the
                           final reference, within ± band × the step's size
overshoot                  ``overshoot_past`` of ``measurement`` from the last step, past the
                           final reference, over the step's size
failed, failure_time       the run's bad step (every other metric NaN)
energies                   not yet: the system kernel has no energy states (NaN here)
=========================  ================================================================

Each is the servo kernel's to the two codings' round-off (tests/test_servo_circuit.py: 1e-9
of a trace's range): the values to that, a settling time to the steps where the
measurement crosses the band's edge within that round-off.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.servo import LOAD_MASS, PARAMETER_INDEX
from ..errors import HydroarmError
from ..integrators.observers import ONLINE_STATISTICS, TARGET_STATISTICS
from ..integrators.observers import observe_many as run_observers
from ..integrators.system import stepper
from ..metrics.servo import DEFAULT_BAND, METRIC_INDEX, N_METRICS
from .circuit import output_sources
from .servo import ServoScenario

_STATISTICS = ONLINE_STATISTICS | TARGET_STATISTICS


def servo_circuit_metrics(scenario: ServoScenario, band: float = DEFAULT_BAND) -> np.ndarray:
    """A servo's `METRICS` (SI, the layout of
    [`metrics_vector`][hydroarm.ServoScenario.metrics_vector]) observed over its circuit
    (module doc); the energies NaN."""
    if scenario.method not in ("euler", "rk4"):
        raise HydroarmError("solver.method", "the observers run fixed-step methods only")
    cc = scenario.compiled_circuit
    known = output_sources(cc)
    mass = scenario.vector()[PARAMETER_INDEX["load_kind"]] == LOAD_MASS
    pos, vel = ("rod_position_m", "rod_velocity_m_s")
    if not mass:
        pos, vel = ("joint_angle_deg", "joint_angular_velocity_rad_s")
    spool = "valve_spool_m" if "valve_spool_m" in known else None
    whole = (-math.inf, math.inf, 0.0, 0.0)
    specs: list[tuple[str, str, tuple[float, float, float, float]]] = [
        (pos, "final", whole),
        (vel, "final", whole),
        ("A_pressure_bar", "final", whole),
        ("B_pressure_bar", "final", whole),
        ("supply_pressure_bar", "final", whole),
        ("A_pressure_bar", "max", whole),
        ("B_pressure_bar", "max", whole),
        ("A_pressure_bar", "min", whole),
        ("B_pressure_bar", "min", whole),
        ("supply_pressure_bar", "max", whole),
        (vel, "max_abs", whole),
    ]
    if spool:
        specs.append((spool, "final", whole))
    t_step, step_from = scenario.step_reference()
    size = 0.0
    if not math.isnan(t_step):
        target = float(scenario.reference.positions[-1])
        if math.isnan(step_from):  # from the measurement at the start
            step_from = _observe(scenario, [("measurement_signal", "initial", whole)], 0)[0][0]
        size = target - step_from
        if size != 0.0:
            near = (t_step, math.inf, target, band * abs(size))
            specs.append(("measurement_signal", "settled_at", near))
            specs.append(("measurement_signal", "overshoot_past", (t_step, math.inf, target, size)))
    values, bad = _observe(scenario, specs, scenario.nsteps)
    M = np.full(N_METRICS, math.nan)
    if bad >= 0:
        M[METRIC_INDEX["failed"]] = 1.0
        M[METRIC_INDEX["failure_time"]] = bad * scenario.step
        return M
    v = dict(zip([(o, st) for o, st, _ in specs], values, strict=True))
    M[METRIC_INDEX["failed"]] = 0.0
    M[METRIC_INDEX["final_position"]] = v[pos, "final"]
    M[METRIC_INDEX["final_velocity"]] = v[vel, "final"]
    M[METRIC_INDEX["final_pressure_a"]] = v["A_pressure_bar", "final"]
    M[METRIC_INDEX["final_pressure_b"]] = v["B_pressure_bar", "final"]
    M[METRIC_INDEX["final_supply_pressure"]] = v["supply_pressure_bar", "final"]
    if spool:
        M[METRIC_INDEX["final_spool"]] = v[spool, "final"]
    M[METRIC_INDEX["peak_pressure"]] = max(v["A_pressure_bar", "max"], v["B_pressure_bar", "max"])
    M[METRIC_INDEX["min_pressure"]] = min(v["A_pressure_bar", "min"], v["B_pressure_bar", "min"])
    M[METRIC_INDEX["peak_supply_pressure"]] = v["supply_pressure_bar", "max"]
    M[METRIC_INDEX["peak_speed"]] = v[vel, "max_abs"]
    if size != 0.0:
        M[METRIC_INDEX["settling_time"]] = v["measurement_signal", "settled_at"]
        M[METRIC_INDEX["overshoot"]] = v["measurement_signal", "overshoot_past"]
    return M


def _observe(scenario: ServoScenario, specs, nsteps: int) -> tuple[np.ndarray, int]:
    """The circuit's observers ``specs`` (output, statistic, (after, before, target, scale))
    over ``nsteps`` steps, in SI (each output's factor 1): (values, bad step)."""
    cc = scenario.compiled_circuit
    known = output_sources(cc)
    names = list(dict.fromkeys(o for o, _, _ in specs))
    sources = np.array([known[o][:3] for o in names], np.int64).reshape(-1, 3)
    # SI: the raw kernel quantity, an angle in rad, a pressure in Pa
    factors = np.ones(len(names))
    metrics = np.array([(names.index(o), _STATISTICS[st]) for o, st, _ in specs], np.int64)
    windows = np.array([w for _, _, w in specs], float).reshape(-1, 4)
    code, A, b, c = stepper(cc.circuit.method)
    S0, table = cc.s0[None, :], cc.P[None, :]
    values, bad = run_observers(
        code, A, b, c, S0, 0.0, scenario.step, nsteps, table, cc.net, sources, factors,
        metrics.reshape(-1, 2), windows,
    )  # fmt: skip
    return values[0], int(bad[0])
