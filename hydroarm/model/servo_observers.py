"""A component servo's on-the-fly metrics as observers over the circuit it stands for
(issue 28; `hydroarm.metrics.servo`, `hydroarm.integrators.observers`).

The servo's own kernel (a test oracle: `hydroarm.reference.servo`) keeps its metrics as it
steps (`hydroarm.reference.servo_metrics.row_metrics`); the same metrics are statistics of
the outputs of its circuit
([`energy_circuit`][hydroarm.ServoScenario.energy_circuit], the circuit with its energy account),
observed at every step of the system kernel:

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
energies                   ``final`` of each energy state of the circuit's energy account
                           ([`energy_circuit`][hydroarm.ServoScenario.energy_circuit]) minus
                           its start, summed into the servo's six terms by
                           `hydroarm.model.servo_rows.add_energy_terms` (as the single run's)
=========================  ================================================================

Each is the servo kernel's to the two codings' round-off (tests/test_servo_circuit.py: 1e-9
of a trace's range; an energy to 1e-9 of the supplied energy): the values to that, a settling
time to the steps where the measurement crosses the band's edge within that round-off.

`servo_metrics_many` gives the metrics of many servos (a sweep's rows, the same reference and
solver): the rows whose circuits share one net and one settling window run together on
`hydroarm.integrators.observers.observe_many` (a row equal to the row alone, bit for bit).
[`metrics`][hydroarm.ServoResult.metrics] is this for one row.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..core.servo import (
    LOAD_MASS,
    N_STATES,
    PARAMETER_INDEX,
    S_E_ACT,
    S_E_COMP,
    S_E_LEAK,
    S_E_RELIEF,
    S_E_SUPPLY,
    S_E_THROTTLE,
)
from ..errors import HydroarmError
from ..integrators.observers import ONLINE_STATISTICS, SOURCE_STATE, TARGET_STATISTICS
from ..integrators.observers import observe_many as run_observers
from ..integrators.system import stepper
from ..metrics.servo import DEFAULT_BAND, METRIC_INDEX, N_METRICS
from .circuit import CompiledCircuit, output_sources
from .servo_rows import add_energy_terms, check_metrics_request, check_same_run, same_net

if TYPE_CHECKING:
    from .servo import ServoScenario

_STATISTICS = ONLINE_STATISTICS | TARGET_STATISTICS
_WHOLE = (-math.inf, math.inf, 0.0, 0.0)
_ENERGY = (  # the servo's energy terms: (metric, state of `hydroarm.core.servo.STATES`)
    ("supply_energy", S_E_SUPPLY),
    ("relief_energy", S_E_RELIEF),
    ("throttle_energy", S_E_THROTTLE),
    ("leakage_energy", S_E_LEAK),
    ("compression_energy", S_E_COMP),
    ("actuator_work", S_E_ACT),
)

Spec = tuple[str, str, tuple[float, float, float, float]]


def servo_circuit_metrics(scenario: ServoScenario, band: float = DEFAULT_BAND) -> np.ndarray:
    """A servo's `METRICS` (SI, the layout of
    [`metrics_vector`][hydroarm.ServoScenario.metrics_vector]) observed over its circuit
    (module doc)."""
    if scenario.method not in ("euler", "rk4"):
        raise HydroarmError("solver.method", "the observers run fixed-step methods only")
    return _circuit_rows([scenario], band)[0]


def servo_metrics_many(scenarios: list[ServoScenario], band: float = DEFAULT_BAND) -> np.ndarray:
    """The `METRICS` (rows × `N_METRICS`, SI) of servos that differ only in parameters and
    initial state (module doc): each row's circuit observed on the system kernel (what has
    no circuit form is refused before any row runs). Row i equals
    ``servo_metrics_many([scenarios[i]])`` bit for bit."""
    if not scenarios:
        return np.empty((0, N_METRICS))
    check_same_run(scenarios)
    check_metrics_request(scenarios[0].method, band)
    for sc in scenarios:
        sc.circuit  # noqa: B018 (what has no circuit form is refused before any row runs)
    return _circuit_rows(scenarios, band)


def _circuit_rows(scenarios: list[ServoScenario], band: float) -> np.ndarray:
    """The metrics of servos observed over their circuits: rows grouped by their circuit's
    net (one `observe_many` runs only rows whose nets are equal), then by their settling
    window (a step from the start: from each row's initial measurement)."""
    M = np.empty((len(scenarios), N_METRICS))
    groups: list[list[int]] = []
    for i, sc in enumerate(scenarios):
        net = sc.energy_circuit.net
        for g in groups:
            if same_net(scenarios[g[0]].energy_circuit.net, net):
                g.append(i)
                break
        else:
            groups.append([i])
    first = scenarios[0]
    t_step, step_from = first.step_reference()
    for g in groups:
        rows = [scenarios[i] for i in g]
        if math.isnan(t_step):
            sizes = np.zeros(len(g))
        else:
            target = float(first.reference.positions[-1])
            if math.isnan(step_from):  # from each row's measurement at the start
                start = _observe(rows, [("measurement_signal", "initial", _WHOLE)], 0)[0][:, 0]
            else:
                start = np.full(len(g), step_from)
            sizes = target - start
        for size in dict.fromkeys(sizes.tolist()):
            sel = [k for k in range(len(g)) if sizes[k] == size]
            M[[g[k] for k in sel]] = _observed([rows[k] for k in sel], size, t_step, band)
    return M


def _observed(rows: list[ServoScenario], size: float, t_step: float, band: float) -> np.ndarray:
    """The metrics of servos sharing one net and one step's size (module doc)."""
    sc = rows[0]
    cc = sc.energy_circuit
    known = output_sources(cc)
    mass = sc.vector()[PARAMETER_INDEX["load_kind"]] == LOAD_MASS
    pos, vel = ("rod_position_m", "rod_velocity_m_s")
    if not mass:
        pos, vel = ("joint_angle_deg", "joint_angular_velocity_rad_s")
    spool = "valve_spool_m" if "valve_spool_m" in known else None
    specs: list[Spec] = [
        (pos, "final", _WHOLE),
        (vel, "final", _WHOLE),
        ("A_pressure_bar", "final", _WHOLE),
        ("B_pressure_bar", "final", _WHOLE),
        ("supply_pressure_bar", "final", _WHOLE),
        ("A_pressure_bar", "max", _WHOLE),
        ("B_pressure_bar", "max", _WHOLE),
        ("A_pressure_bar", "min", _WHOLE),
        ("B_pressure_bar", "min", _WHOLE),
        ("supply_pressure_bar", "max", _WHOLE),
        (vel, "max_abs", _WHOLE),
    ]
    if spool:
        specs.append((spool, "final", _WHOLE))
    energies = list(cc.energy_states)
    specs += [(_energy_output(k), "final", _WHOLE) for k in energies]
    if size != 0.0:
        target = float(sc.reference.positions[-1])
        near = (t_step, math.inf, target, band * abs(size))
        specs.append(("measurement_signal", "settled_at", near))
        specs.append(("measurement_signal", "overshoot_past", (t_step, math.inf, target, size)))
    values, bad = _observe(rows, specs, sc.nsteps)
    M = np.full((len(rows), N_METRICS), math.nan)
    column = {(o, st): j for j, (o, st, _) in enumerate(specs)}
    for r, row in enumerate(rows):
        if bad[r] >= 0:
            M[r, METRIC_INDEX["failed"]] = 1.0
            M[r, METRIC_INDEX["failure_time"]] = bad[r] * sc.step
            continue
        v = {key: values[r, j] for key, j in column.items()}
        m = M[r]
        m[METRIC_INDEX["failed"]] = 0.0
        m[METRIC_INDEX["final_position"]] = v[pos, "final"]
        m[METRIC_INDEX["final_velocity"]] = v[vel, "final"]
        m[METRIC_INDEX["final_pressure_a"]] = v["A_pressure_bar", "final"]
        m[METRIC_INDEX["final_pressure_b"]] = v["B_pressure_bar", "final"]
        m[METRIC_INDEX["final_supply_pressure"]] = v["supply_pressure_bar", "final"]
        if spool:
            m[METRIC_INDEX["final_spool"]] = v[spool, "final"]
        a, b = v["A_pressure_bar", "max"], v["B_pressure_bar", "max"]
        m[METRIC_INDEX["peak_pressure"]] = max(a, b)
        a, b = v["A_pressure_bar", "min"], v["B_pressure_bar", "min"]
        m[METRIC_INDEX["min_pressure"]] = min(a, b)
        m[METRIC_INDEX["peak_supply_pressure"]] = v["supply_pressure_bar", "max"]
        m[METRIC_INDEX["peak_speed"]] = v[vel, "max_abs"]
        # the energy account: each term's final minus its start, as the single run's
        s0 = row.energy_circuit.s0
        e = np.zeros(N_STATES)
        add_energy_terms(
            {k: v[_energy_output(k), "final"] - s0[cc.energy_states[k]] for k in energies}, e
        )
        for name, i in _ENERGY:
            m[METRIC_INDEX[name]] = e[i]
        if size != 0.0:
            m[METRIC_INDEX["settling_time"]] = v["measurement_signal", "settled_at"]
            over = v["measurement_signal", "overshoot_past"]
            if t_step > sc.nsteps * sc.step:  # no sample after the step: never past it
                over = 0.0  # (the servo kernel's 0)
            m[METRIC_INDEX["overshoot"]] = over
    return M


def _energy_output(term: str) -> str:
    """The observers' name of an energy state (no output of `output_sources`)."""
    return f"energy {term}"


def _sources(cc: CompiledCircuit) -> dict[str, tuple[int, int, int]]:
    """The kernel quantity every output and energy state reads: (what, i, k)."""
    out = {name: src[:3] for name, src in output_sources(cc).items()}
    for k, j in cc.energy_states.items():
        out[_energy_output(k)] = (SOURCE_STATE, j, 0)
    return out


def _observe(
    rows: list[ServoScenario], specs: list[Spec], nsteps: int
) -> tuple[np.ndarray, np.ndarray]:
    """The observers ``specs`` (output, statistic, (after, before, target, scale)) over
    ``nsteps`` steps of the circuits of ``rows`` (one net), in SI (each output's factor 1):
    (values rows × specs, each row's bad step)."""
    cc = rows[0].energy_circuit
    known = _sources(cc)
    names = list(dict.fromkeys(o for o, _, _ in specs))
    sources = np.array([known[o] for o in names], np.int64).reshape(-1, 3)
    # SI: the raw kernel quantity, an angle in rad, a pressure in Pa
    factors = np.ones(len(names))
    metrics = np.array([(names.index(o), _STATISTICS[st]) for o, st, _ in specs], np.int64)
    windows = np.array([w for _, _, w in specs], float).reshape(-1, 4)
    code, A, b, c = stepper(cc.circuit.method)
    S0 = np.array([sc.energy_circuit.s0 for sc in rows])
    table = np.array([sc.energy_circuit.P for sc in rows])
    values, bad = run_observers(
        code, A, b, c, S0, 0.0, rows[0].step, nsteps, table, cc.net, sources, factors,
        metrics.reshape(-1, 2), windows, 1, np.zeros(0, np.int64), np.zeros((len(rows), 0, 0)),
    )  # fmt: skip
    return values, np.asarray(bad, np.int64)
