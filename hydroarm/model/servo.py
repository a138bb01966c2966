"""A servo built from components: scenario, run and result (issue 14; docs/components.md).

[`ServoScenario`][hydroarm.ServoScenario] holds the servo's named SI parameters (the names of
`hydroarm.core.servo.PARAMETERS`), its initial state, its reference input and the
solver; [`ServoScenario.run`][hydroarm.ServoScenario.run] steps the circuit the servo stands for
([`ServoScenario.circuit`][hydroarm.ServoScenario.circuit], with its energy account) on the system
kernel (`hydroarm.integrators.system`) and reads the servo's states back
(`servo_states`); what that circuit has no form for is refused, before work, with one
line naming the field (`hydroarm.model.servo_circuit.scenario_circuit`). The servo's own
hand-fused kernel is a test oracle only (`hydroarm.reference.servo`).
[`ServoResult`][hydroarm.ServoResult] gives the time series, a CSV, a pandas frame, the energy
account and a plot. [`run_servos`][hydroarm.run_servos] runs many scenarios (the same servo with
parameters varied) on the batch path: every row the single run's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from ..core.components import relief_flows
from ..core.servo import (
    FEEDBACK_MECHANICAL,
    LOAD_CRANK,
    LOAD_MASS,
    N_STATES,
    P_F_COULOMB,
    P_F_STATIC,
    P_FEEDBACK,
    P_GB_LOSS,
    P_GB_T0,
    P_LOAD,
    P_P_TANK,
    P_P_TRANS,
    P_SUPPLY,
    PARAMETER_INDEX,
    PARAMETERS,
    S_E_ACT,
    S_E_COMP,
    S_E_LEAK,
    S_E_RELIEF,
    S_E_SUPPLY,
    S_E_THROTTLE,
    S_INT,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    S_V,
    S_VV,
    S_XR,
    S_XV,
    STATE_INDEX,
    STATES,
    SUPPLY_PUMP,
    default_parameters,
)
from ..display import Summarised, fmt, span
from ..errors import HydroarmError, check_number
from ..integrators import registry
from ..metrics import power
from ..metrics.servo import (
    DEFAULT_BAND,
    metric_columns,
    step_of,
)
from ..plotting.servo import servo_figure
from .circuit import Circuit, CircuitResult, CompiledCircuit, build, simulate_many
from .circuit import simulate as simulate_circuit
from .lever import LeverInput
from .quantities import plain
from .result import csv_lines
from .servo_circuit import circuit_step_limit, scenario_circuit
from .servo_observers import servo_metrics_many
from .servo_rows import (
    add_energy_terms,
    check_same_run,
    same_net,
)

SERVO_METHODS = registry.method_names()
# the unit of every column a ServoResult may have (`ServoResult.display_units`)
COLUMN_UNITS: dict[str, str] = {
    "t_s": "s",
    "position_m": "m",
    "velocity_m_s": "m/s",
    "angle_deg": "deg",
    "angular_velocity_deg_s": "deg/s",
    "lever_m": "m",
    "reference_m": "m",
    "reference_deg": "deg",
    "spool_m": "m",
    "pressure_a_bar": "bar",
    "pressure_b_bar": "bar",
    "supply_bar": "bar",
    "relief_flow_l_min": "L/min",
    "relief_opening": "m**3/s/Pa**0.5",
}

# each parameter's SI unit (pint quantities in ServoScenario.replace)
PARAMETER_UNITS = {name: unit for name, unit, _ in PARAMETERS}


@dataclass(frozen=True)
class ServoScenario:
    """One run of a component servo.

    Parameters
    ----------
    parameters : dict
        {name: value} in SI units, names of `hydroarm.core.servo.PARAMETERS` (those not given
        keep `default_parameters`).
    reference : LeverInput
        The reference input r(t): the lever position [m] in actuator coordinates for
        mechanical feedback, the sensor's reference for electronic feedback.
    initial : dict
        {state name: value} (SI), names of `hydroarm.core.servo.STATES` (pressures not given
        start at the tank pressure, the supply at its ``supply_pressure``).
    method : str
        Integration method (``"rk4"``, ``"euler"``, ...).
    step : float
        Fixed step [s].
    duration : float
        Simulated time [s].
    record_every : int
        Keep every K-th step [-].
    name : str
        Label.
    check_stability : bool
        Refuse, before the run, a fixed step too large for the servo.
    electric : dict, optional
        The supply's electric side: ``pump_efficiency``, ``motor_efficiency`` [-],
        ``usable_battery_energy`` [J] or None, ``cycles`` (task cycles the run performs);
        reported by [`ServoResult.summary`][hydroarm.ServoResult.summary] through
        `hydroarm.metrics.power.electric_summary`; None: not reported.
    """

    parameters: dict
    reference: LeverInput
    initial: dict = field(default_factory=dict)
    method: str = "rk4"
    step: float = 1e-5
    duration: float = 1.0
    record_every: int = 1
    name: str = "servo"
    check_stability: bool = True
    # the supply's electric side: {pump_efficiency, motor_efficiency, usable_battery_energy
    # [J] or None, cycles (task cycles the run performs)}; None: not reported
    electric: dict | None = None

    def __post_init__(self):
        for k in self.parameters:
            if k not in PARAMETER_INDEX:
                raise HydroarmError(f"parameters.{k}", "is not a servo parameter")
        for k in self.initial:
            if k not in STATE_INDEX:
                raise HydroarmError(f"initial.{k}", "is not a servo state")
        registry.method(self.method)
        check_number("solver.step", self.step, positive=True)
        check_number("solver.duration", self.duration, positive=True)
        if self.step > self.duration:
            raise HydroarmError("solver.step", "is longer than the duration")

    # -------------------------------------------------------------- circuit ---
    @cached_property
    def circuit(self) -> Circuit:
        """The circuit this servo stands for (`hydroarm.model.servo_circuit.scenario_circuit`: the
        system kernel's components at the nodes T, supply, A, B, rod, joint), built once per
        scenario (a [`replace`][hydroarm.ServoScenario.replace]d copy builds its own). What has no
        circuit form yet is refused with one line naming the field."""
        return scenario_circuit(self)

    @cached_property
    def compiled_circuit(self) -> CompiledCircuit:
        """[`circuit`][hydroarm.ServoScenario.circuit] compiled for the system kernel
        (`hydroarm.model.circuit.build`), once per scenario."""
        return build(self.circuit)

    def __getstate__(self) -> dict:
        # the cached circuit is rebuilt where the scenario is unpickled (a worker)
        return {k: v for k, v in self.__dict__.items() if k not in _CACHED}

    # -------------------------------------------------------------- vectors ---
    def vector(self) -> np.ndarray:
        """The kernel's parameter vector."""
        P = default_parameters()
        for k, v in self.parameters.items():
            P[PARAMETER_INDEX[k]] = v
        return P

    def initial_state(self) -> np.ndarray:
        """The kernel's initial state vector."""
        P = self.vector()
        s = np.zeros(N_STATES)
        s[S_PA] = s[S_PB] = P[P_P_TANK]
        s[S_PS] = self.parameters.get("supply_pressure", P[P_P_TANK])
        for k, v in self.initial.items():
            s[STATE_INDEX[k]] = v
        return s

    def replace(self, **kw) -> ServoScenario:
        """A copy with solver fields or servo parameters (by name) changed: numbers in SI, or
        pint quantities (converted to the parameter's SI unit; another dimension is refused)."""
        own = {k: kw.pop(k) for k in list(kw) if k in self.__dataclass_fields__}
        for k in ("step", "duration"):
            if k in own:
                own[k] = plain(f"solver.{k}", own[k], "s")
        kw = {k: plain(k, v, PARAMETER_UNITS.get(k, "-")) for k, v in kw.items()}
        if kw:
            own["parameters"] = {**self.parameters, **kw}
        return replace(self, **own)

    @property
    def nsteps(self) -> int:
        return int(round(self.duration / self.step))

    def step_limit(self) -> float | None:
        """None if the fixed step is stable for the kernel the run steps, else the largest
        stable step [s] (linearised, docs/errors.md): its circuit's on the system kernel
        (`hydroarm.model.servo_circuit.circuit_step_limit`). None for the adaptive
        reference."""
        if not registry.method(self.method).fixed_step:
            return None
        return circuit_step_limit(self)

    def check_step(self) -> None:
        """Refuse a fixed step above the servo's stability limit
        ([`step_limit`][hydroarm.ServoScenario.step_limit])."""
        limit = self.step_limit()
        if limit is not None:
            raise HydroarmError(
                "solver.step",
                f"{self.step:.3g} s is above the stable limit {limit:.3g} s of "
                f"'{self.method}' for this servo; use a smaller step",
            )

    def step_reference(self) -> tuple[float, float]:
        """(time, from) of the reference's last step (NaN, NaN: not a step reference);
        `hydroarm.metrics.servo.step_of`."""
        ref = self.reference
        if ref.description not in ("steps", "step"):
            return math.nan, math.nan
        return step_of(ref.times, ref.positions, ref.sine_amplitude)

    def metrics_vector(self, band: float = DEFAULT_BAND) -> np.ndarray:
        """The run's on-the-fly metrics (`hydroarm.metrics.servo.METRICS`, SI): the servo's
        circuit observed on the system kernel (`hydroarm.model.servo_observers`); what a
        sweep computes per row."""

        return servo_metrics_many([self], band)[0]

    # ------------------------------------------------------------------ run ---
    @cached_property
    def energy_circuit(self) -> CompiledCircuit:
        """[`circuit`][hydroarm.ServoScenario.circuit] compiled with its energy account, pressures
        counted from the tank (`CompiledCircuit`, ``energy=True``): what
        [`run`][hydroarm.ServoScenario.run] steps."""
        return build(self.circuit, energy=True, energy_reference_pressure=self.vector()[P_P_TANK])

    def initial_state_default(self, name: str) -> float:
        """The value state ``name`` starts at when `initial` does not give it."""
        saved = {k: v for k, v in self.initial.items() if k != name}
        return float(replace(self, initial=saved).initial_state()[STATE_INDEX[name]])

    def run(self) -> ServoResult:
        """Integrate the servo; a fixed step is checked for stability first. The servo's
        circuit runs on the system kernel
        ([`run_on_system_kernel`][hydroarm.ServoScenario.run_on_system_kernel]); what has no
        circuit form is refused first, with one line naming the field."""
        self.circuit  # noqa: B018 (built first: what has no circuit form is refused here)
        if self.check_stability:
            self.check_step()
        return self.run_on_system_kernel()

    def run_on_system_kernel(self) -> ServoResult:
        """Run [`energy_circuit`][hydroarm.ServoScenario.energy_circuit] on the system kernel
        (`hydroarm.model.circuit.simulate`) and read its states back into the servo's
        (`servo_states`); no stability check. The adaptive method is Radau on the circuit's
        right-hand side (`hydroarm.integrators.adaptive.integrate_circuit_adaptive`, the
        stops and the cavitation floor projected at each record), refused with dry friction
        as on the servo kernel."""
        self._refuse_adaptive_friction()
        res = simulate_circuit(self.energy_circuit)
        if res.bad_step >= 0:
            raise HydroarmError(
                "solver.step",
                f"the run left the physical bounds at t = {res.bad_step * self.step:.6g} s (a "
                "state not finite): reduce the step",
            )
        return ServoResult(self, res.t, servo_states(self, res), self.reference(res.t))

    def _refuse_adaptive_friction(self) -> None:
        """The adaptive method with dry friction (non-smooth: a stick-slip law), refused."""
        P = self.vector()
        # dry friction in its circuit: the piston's (the cylinder's, through the crank) or a
        # crank's gearbox (`hydroarm.model.servo_circuit`'s crank_spec and actuator_spec)
        gearbox = P[P_LOAD] == LOAD_CRANK and (P[P_GB_T0] > 0.0 or P[P_GB_LOSS] > 0.0)
        dry = P[P_F_COULOMB] > 0.0 or P[P_F_STATIC] > 0.0 or gearbox
        if not registry.method(self.method).fixed_step and dry:
            raise HydroarmError(
                "solver.method",
                "'adaptive' cannot integrate dry friction (non-smooth); use euler or rk4",
            )


_CACHED = ("circuit", "compiled_circuit", "energy_circuit")  # ServoScenario's cached properties
_ENERGY_STATES = (S_E_SUPPLY, S_E_RELIEF, S_E_THROTTLE, S_E_ACT, S_E_LEAK, S_E_COMP)


def circuit_stems(P: np.ndarray) -> dict[int, str]:
    """Servo state index (`hydroarm.core.servo.STATES`) → the state of its circuit
    (`hydroarm.model.servo_circuit.scenario_circuit`) that stands for it, for the servo's
    parameter vector ``P``: the load's node, the chambers', the supply's, the spool, the
    relief valve's opening and (electronic feedback) the controller's integral."""
    rod = P[P_LOAD] == LOAD_MASS
    pairs = {
        S_Q: "rod.position" if rod else "joint.angle",
        S_V: "rod.velocity" if rod else "joint.angular_velocity",
        S_PA: "A.pressure",
        S_PB: "B.pressure",
        S_PS: "supply.pressure",
        S_XV: "valve.spool",
        S_VV: "valve.spool_velocity",
        S_XR: "relief.opening",
    }
    if P[P_FEEDBACK] != FEEDBACK_MECHANICAL:
        pairs[S_INT] = "controller.integral"
    return pairs


#: the servo's energy terms as sums of its circuit's (`servo_states`; actuator work:
#: every other term, the piston's rest and the load's, the crank's)
def servo_states(scenario: ServoScenario, res: CircuitResult) -> np.ndarray:
    """The servo kernel's states (records × N_STATES, `hydroarm.core.servo.STATES`)
    of a run of the scenario's [`energy_circuit`][hydroarm.ServoScenario.energy_circuit]: the load's
    node, the chambers', the supply's, the spool, the controller's integral (0: mechanical
    feedback), the relief valve's opening and the energy terms (`ENERGY_TERMS`, measured from
    the tank as the servo kernel's)."""
    cc = res.compiled
    index = {stem: j for j, (stem, _) in enumerate(cc.state_names)}
    S = res.states
    out = np.zeros((S.shape[0], N_STATES))
    P = scenario.vector()
    for i, stem in circuit_stems(P).items():
        if stem in index:
            out[:, i] = S[:, index[stem]]
    add_energy_terms({k: S[:, j] for k, j in cc.energy_states.items()}, out)
    # what no circuit state carries starts where the servo kernel's does: a mechanical
    # feedback's integral (held: nothing integrates it) and each energy's offset
    held = (S_INT,) if P[P_FEEDBACK] == FEEDBACK_MECHANICAL else ()
    for i in (*held, *_ENERGY_STATES):
        v = scenario.initial.get(STATES[i][0], 0.0)
        if v != 0.0:
            out[:, i] += v
    return out


def servo_metrics_table(scenarios: list[ServoScenario], band: float = DEFAULT_BAND) -> np.ndarray:
    """On-the-fly metrics (rows × `N_METRICS`, SI) of servos that differ only in parameters
    and initial state, on the batch path (`hydroarm.model.servo_observers.servo_metrics_many`:
    the system kernel's observers);
    row i is ``scenarios[i].metrics_vector(band)`` bit for bit. Nothing grows with the steps."""

    return servo_metrics_many(scenarios, band)


def run_servos(scenarios: list[ServoScenario]) -> list[ServoResult]:
    """Run servos together on the batch path.

    Their circuits run on the system kernel's batch path (`hydroarm.model.circuit.simulate_many`)
    when they share one net, else one by one. Each result is the scenario's single
    [`run`][hydroarm.ServoScenario.run], bit for bit.

    Parameters
    ----------
    scenarios : list of ServoScenario
        Servos that differ only in parameters and initial state (the same reference and
        solver).

    Returns
    -------
    list of ServoResult
        One result per scenario, in their order.
    """
    if not scenarios:
        return []
    first = scenarios[0]
    check_same_run(scenarios)
    m = registry.method(first.method)
    if not m.fixed_step:
        return [sc.run() for sc in scenarios]
    for sc in scenarios:
        sc.circuit  # noqa: B018 (what has no circuit form is refused before any run)
    for sc in scenarios:
        if sc.check_stability:
            sc.check_step()
    nets = [sc.energy_circuit.net for sc in scenarios]
    if all(same_net(nets[0], net) for net in nets[1:]):
        return _run_circuits(scenarios)
    return [sc.run_on_system_kernel() for sc in scenarios]


def _run_circuits(scenarios: list[ServoScenario]) -> list[ServoResult]:
    """Servos whose circuits share one net, on the system kernel's batch path
    (`hydroarm.model.circuit.simulate_many`: a row is the single run, bit for bit)."""
    first = scenarios[0].energy_circuit
    table = np.array([sc.energy_circuit.P for sc in scenarios])
    S0 = np.array([sc.energy_circuit.s0 for sc in scenarios])
    t, states, bad = simulate_many(first, table, S0)
    if np.any(bad >= 0):
        i = int(np.argmax(bad >= 0))
        raise HydroarmError(
            "solver.step", f"scenario {i} left the physical bounds: reduce the step"
        )
    out = []
    for i, sc in enumerate(scenarios):
        res = CircuitResult(sc.energy_circuit, t, states[i], -1, table[i])
        out.append(ServoResult(sc, res.t, servo_states(sc, res), sc.reference(res.t)))
    return out


@dataclass(frozen=True, repr=False)
class ServoResult(Summarised):
    """Time series of a component servo run.

    Parameters
    ----------
    scenario : ServoScenario
        The scenario run.
    t : numpy.ndarray
        Times [s].
    states : numpy.ndarray
        len(t) × N_STATES, the columns of `hydroarm.core.servo.STATES` (SI).
    reference : numpy.ndarray
        The reference at each time (the lever [m], or the sensor's unit).
    """

    scenario: ServoScenario
    t: np.ndarray
    states: np.ndarray
    reference: np.ndarray

    def _summary(self) -> list[tuple[str, str]]:
        sc = self.scenario
        cols = self.columns()
        rows = [
            ("servo", sc.name),
            ("run", f"{span(self.t)}, {sc.method}, step {fmt(sc.step * 1e6)} us"),
        ]
        for name in ("position_m", "angle_deg", "reference_m", "reference_deg"):
            if name in cols:
                rows.append((f"final {name}", fmt(cols[name][-1])))
        rows.append(("columns", str(len(cols))))
        return rows

    def _trace_columns(self):
        return {k: v for k, v in self.columns().items() if k != "t_s"}, {}

    def state(self, name: str) -> np.ndarray:
        return self.states[:, STATE_INDEX[name]]

    @property
    def linear(self) -> bool:
        """Whether the load moves along a line (positions in m) or turns (in rad)."""
        return int(self.scenario.vector()[P_LOAD]) == LOAD_MASS

    def columns(self) -> dict:
        """The CSV's columns: name → array (pressures in bar absolute)."""
        s = self.states
        P = self.scenario.vector()
        if self.linear:
            pos = {"position_m": s[:, S_Q], "velocity_m_s": s[:, S_V]}
        else:
            pos = {
                "angle_deg": np.degrees(s[:, S_Q]),
                "angular_velocity_deg_s": np.degrees(s[:, S_V]),
            }
        electronic = P[P_FEEDBACK] != 0.0
        ref = self.reference
        if not electronic:
            ref_name = "lever_m"  # in the actuator's coordinates
        elif self.linear:
            ref_name = "reference_m"
        else:
            ref_name, ref = "reference_deg", np.degrees(ref)
        relief = np.zeros(s.shape[0])
        if P[P_SUPPLY] == SUPPLY_PUMP:  # the circuit's relief_valve law (its flow output)
            relief = relief_flows(
                np.ascontiguousarray(s[:, S_XR]),
                np.ascontiguousarray(s[:, S_PS]),
                P[P_P_TANK],
                P[P_P_TRANS],
            )
        return {
            "t_s": self.t,
            **pos,
            ref_name: ref,
            "spool_m": s[:, S_XV],
            "pressure_a_bar": s[:, S_PA] / 1e5,
            "pressure_b_bar": s[:, S_PB] / 1e5,
            "supply_bar": s[:, S_PS] / 1e5,
            "relief_flow_l_min": relief * 6e4,
            "relief_opening": s[:, S_XR],
        }

    def display_units(self) -> dict[str, str]:
        """Each column's unit in pint's syntax, the unit its values are in (``bar``,
        ``L/min``, ``deg``; the relief valve's opening in SI)."""
        return {k: COLUMN_UNITS[k] for k in self.columns()}

    def to_csv(self, path) -> None:
        """Write the columns ([`columns`][hydroarm.ServoResult.columns]) to a CSV file, all at
        once."""
        cols = self.columns()
        rows = np.column_stack(list(cols.values()))
        Path(path).write_text(csv_lines(list(cols), rows))

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self.columns())

    def energies(self) -> dict:
        """The run's energy account [J] (states integrated with the method): supplied
        (a pump: at its shaft, hydraulic), dissipated in the relief valve, the valve's
        metering edges and leakage, stored by compression, and the work on the piston;
        ``balance`` is what they leave over (round-off and the step's projections)."""
        e = self.states[-1] - self.states[0]
        out = {
            "supply_energy_j": float(e[S_E_SUPPLY]),
            "relief_energy_j": float(e[S_E_RELIEF]),
            "throttle_energy_j": float(e[S_E_THROTTLE]),
            "leakage_energy_j": float(e[S_E_LEAK]),
            "compression_energy_j": float(e[S_E_COMP]),
            "actuator_work_j": float(e[S_E_ACT]),
        }
        out["balance_j"] = out["supply_energy_j"] - sum(
            v for k, v in out.items() if k != "supply_energy_j"
        )
        return out

    def metrics(self, band: float = DEFAULT_BAND) -> dict:
        """The run's on-the-fly metrics (`hydroarm.metrics.servo`: final state, energies,
        peak and lowest pressures, peak speed, settling time within ±``band`` of the last
        step, overshoot, failure), observed at every step whatever the run kept: the
        scenario is run again as a sweep runs a row
        ([`metrics_vector`][hydroarm.ServoScenario.metrics_vector]: its circuit's observers on
        the system kernel), so that a sweep's row
        and this are equal bit for bit. Pressures in bar, names with units. A run of the
        adaptive method has no fixed steps to observe: refused with one line
        (``solver.method``); its [`summary`][hydroarm.ServoResult.summary] is computed from
        the records."""
        M = self.scenario.metrics_vector(band)
        return {
            k: (bool(v[0]) if v.dtype == bool else float(v[0]))
            for k, v in metric_columns(M[None, :], self.linear).items()
        }

    def summary(self) -> dict:
        """Final state, peak pressures, steady error and the energy account."""
        s = self.states
        q = s[:, S_Q]
        final = float(q[-1])
        ref = float(self.reference[-1])
        unit = "m" if self.linear else "rad"
        # the reference in its own coordinates (as `columns`): a mechanical feedback's
        # lever in the actuator's [m], an electronic one's in the load's (m or rad)
        electronic = self.scenario.vector()[P_FEEDBACK] != 0.0
        ref_unit = unit if electronic else "m"
        out = {
            f"final_position_{unit}": final,
            f"final_reference_{ref_unit}": ref,
            "peak_pressure_bar": float(max(s[:, S_PA].max(), s[:, S_PB].max()) / 1e5),
            "peak_supply_bar": float(s[:, S_PS].max() / 1e5),
            f"peak_speed_{unit}_s": float(np.abs(s[:, S_V]).max()),
        }
        out.update(self.energies())
        el = self.scenario.electric
        if el is not None:
            e = power.electric_summary(
                out["supply_energy_j"],
                float(self.t[-1] - self.t[0]),
                pump_efficiency=el["pump_efficiency"],
                motor_efficiency=el["motor_efficiency"],
                usable_battery_energy=el["usable_battery_energy"],
                cycles=el["cycles"],
            )
            for k, v in e.items():
                suffix = power.ELECTRIC_UNITS[k]
                out[f"{k}_{suffix}" if suffix else k] = v
        return {k: (v if math.isfinite(v) else float("nan")) for k, v in out.items()}

    def plot(self):
        return servo_figure(self)
