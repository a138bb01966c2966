"""The FMI 2.0 co-simulation slaves that an exported FMU runs (pythonfmu's ``Fmi2Slave``).

An FMU built by :func:`hydroarm.fmu.export_fmu` holds, as resources, the configuration file
it was exported from (a scenario file of the paper's joint, an arm file, a component servo
file or a circuit file), the files it refers to, ``hydroarm_fmu.json`` (which slave, which
file) and a one-class script whose class derives from :class:`JointSlave`,
:class:`ArmSlave`, :class:`ServoSlave` or :class:`CircuitSlave` here. The slave reads the
configuration with hydroarm's own readers, registers the variables of
:mod:`hydroarm.fmu.variables` and steps the model with the steppers
(:class:`~hydroarm.model.stepper.JointStepper`, :class:`~hydroarm.arm.stepper.ArmStepper`,
:class:`~hydroarm.model.servo_stepper.ServoStepper`,
:class:`~hydroarm.model.circuit_stepper.CircuitStepper`): one physics, the same trajectory
as ``hydroarm simulate`` / ``hydroarm arm`` at the same internal step, whatever
communication step the master takes.

Parameters (causality ``parameter``, variability ``fixed``) are read when the master leaves
initialisation mode: the joint is rebuilt from them with its own validation (a bad value is
an FMI error whose log message is hydroarm's one-line error). The FMU state (get/set and
serialisation) is the stepper's complete state plus the parameters and inputs, as JSON.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real

from ..arm.model import ArmScenario
from ..arm.stepper import ARM_OUTPUTS, ArmStepper
from ..batch.servo_sweep import check_servo_changes
from ..model.circuit import Circuit, build
from ..model.circuit_stepper import CircuitStepper
from ..model.joint import Load
from ..model.scenario import Scenario
from ..model.servo import ServoScenario
from ..model.servo_stepper import ServoStepper
from ..model.stepper import JointStepper
from .variables import (
    JOINT_PARAMETERS,
    LOAD_PARAMETERS,
    Variable,
    circuit_parameters,
    default_value,
    method_name,
    model_variables,
    read_model,
    servo_parameters,
)

CAUSALITY = {
    "parameter": (Fmi2Causality.parameter, Fmi2Variability.fixed),
    "input": (Fmi2Causality.input, Fmi2Variability.continuous),
    "output": (Fmi2Causality.output, Fmi2Variability.continuous),
}


class _Slave(Fmi2Slave):
    """What both slaves share: the variables of :mod:`hydroarm.fmu.variables`, their values
    in dictionaries, the stepper built from the parameters."""

    author = "hydroarm"
    description = "hydroarm hydraulic servo (UCL arm prosthesis model)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.model = read_model(self.resources)
        self._values: dict[str, float] = {}  # parameters and inputs
        self._outputs: dict[str, float] = {}
        self._input_names: set[str] = set()
        self._inputs_set: set[str] = set()  # inputs the master has set
        self._stepper: Any = None  # the JointStepper or ArmStepper, built from the parameters
        self._t_start = 0.0
        for v in model_variables(self.model):
            self._register(v)

    def _register(self, v: Variable) -> None:
        causality, variability = CAUSALITY[v.causality]
        kind = Integer if v.integer else Real
        name = v.name
        if v.causality == "output":
            var = kind(
                name,
                causality=causality,
                variability=variability,
                description=v.description,
                getter=lambda: self._output(name),
            )
        else:
            assert v.start is not None
            self._values[name] = v.start
            if v.causality == "input":
                self._input_names.add(name)
            var = kind(
                name,
                causality=causality,
                variability=variability,
                description=v.description,
                getter=lambda: self._values[name],
                setter=lambda x: self._set(name, x),
            )
        self.register_variable(var, nested=False)

    def _set(self, name, v) -> None:
        self._values[name] = v
        if name in self._input_names:
            self._inputs_set.add(name)
            if self._stepper is not None:
                self._apply_inputs()
        else:  # a parameter: the stepper is built again from the parameters
            self._stepper = None

    def _output(self, name):
        if self._stepper is None:
            self._start()
        return self._outputs[name]

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._t_start = float(start_time)

    def exit_initialization_mode(self):
        self._start()

    def do_step(self, current_time, step_size):
        if self._stepper is None:
            self._start()
        self._apply_inputs()
        self._stepper.advance_to(current_time + step_size - self._t_start)
        self._read_outputs()
        return True

    def _start(self) -> None:
        self._stepper = self._build()
        self._apply_inputs()
        self._read_outputs()

    # state: the stepper's plus the parameters and inputs (JSON; floats round-trip exactly)
    def _get_fmu_state(self):
        if self._stepper is None:
            self._start()
        return {
            "values": dict(self._values),
            "inputs_set": sorted(self._inputs_set),
            "t_start": self._t_start,
            "stepper": self._stepper.get_state().tolist(),
        }

    def _set_fmu_state(self, state):
        self._values = dict(state["values"])
        self._inputs_set = set(state["inputs_set"])
        self._t_start = float(state["t_start"])
        self._start()
        self._stepper.set_state(state["stepper"])
        self._read_outputs()

    def _build(self):
        raise NotImplementedError

    def _apply_inputs(self) -> None:
        raise NotImplementedError

    def _read_outputs(self) -> None:
        raise NotImplementedError


class JointSlave(_Slave):
    """The paper's joint of a scenario file as a co-simulation slave (variables:
    :func:`hydroarm.fmu.variables.joint_variables`)."""

    description = "hydroarm hydraulic servo joint (UCL arm prosthesis model)"

    def _build(self) -> JointStepper:
        v = self._values
        sc = self.model.scenario
        assert isinstance(sc, Scenario)
        changes: dict[str, Any] = {
            n: v[f"joint.{n}"]
            for n in JOINT_PARAMETERS
            if v[f"joint.{n}"] != default_value(sc.joint, n)
        }
        if "end_stop_angle" in changes and math.isinf(changes["end_stop_angle"]):
            changes["end_stop_angle"] = None
        joint = sc.joint.replace(**changes) if changes else sc.joint
        load = Load(
            weight=v["load.weight"], arm=v["load.arm"], inertia=v["load.inertia"], name=sc.load.name
        )
        if all(v[f"load.{n}"] == getattr(sc.load, n) for n in LOAD_PARAMETERS):
            load = sc.load
        # the start pressure holds the (possibly changed) load, as a scenario file's does
        return JointStepper(
            joint,
            load,
            method=method_name(v["solver.method"]),
            step=v["solver.step"],
            initial_angle=v["initial.angle"],
            initial_pressure=sc.initial_pressure,
            lever=v["lever"],
        )

    def _apply_inputs(self) -> None:
        st = self._stepper
        if "supply_pressure" not in self._inputs_set:  # until set: the joint's parameter
            self._values["supply_pressure"] = self._values["joint.supply_pressure"]
        st.lever = self._values["lever"]
        st.supply_pressure = self._values["supply_pressure"]
        st.external_torque = self._values["external_torque"]

    def _read_outputs(self) -> None:
        self._outputs = self._stepper.outputs()


class ArmSlave(_Slave):
    """The whole arm of an arm file as a co-simulation slave (variables:
    :func:`hydroarm.fmu.variables.arm_variables`)."""

    description = "hydroarm four-joint hydraulic arm (UCL arm prosthesis model)"

    def _names(self) -> list[str]:
        sc = self.model.scenario
        assert isinstance(sc, ArmScenario)
        return [j.name for j in sc.joints]

    def _build(self) -> ArmStepper:
        v = self._values
        sc = self.model.scenario
        assert isinstance(sc, ArmScenario)
        pk = replace(
            sc.power_pack,
            supply_pressure=v["power_pack.supply_pressure"],
            pump_flow=v["power_pack.pump_flow"],
        )
        return ArmStepper(
            sc.replace(power_pack=pk), method=method_name(v["solver.method"]), step=v["solver.step"]
        )

    def _apply_inputs(self) -> None:
        self._stepper.levers = {n: self._values[f"{n}.lever"] for n in self._names()}

    def _read_outputs(self) -> None:
        o = self._stepper.outputs()
        names = self._names()
        flat = {f"{n}.{k}": v for n in names for k, v in o[n].items()}
        flat.update({name: o[name] for name, _, _ in ARM_OUTPUTS})
        self._outputs = flat


class CircuitSlave(_Slave):
    """A circuit file as a co-simulation slave (variables:
    :func:`hydroarm.fmu.variables.circuit_variables`): the inputs its components declare,
    every output ``simulate`` writes. An input the master has not set leaves its component
    as the file says (a signal source runs its waveform)."""

    description = "hydroarm hydraulic circuit"

    def _build(self) -> CircuitStepper:
        v = self._values
        circuit = self.model.scenario
        assert isinstance(circuit, Circuit)
        if not hasattr(self, "_starts"):
            self._starts = circuit_parameters(circuit)
        starts = self._starts
        changes = {n: v[n] for n, (_, _, start) in starts.items() if v[n] != start}
        if changes:  # rebuilt from the file with its own validation
            circuit = circuit.with_values(changes)
        method = method_name(v["solver.method"], "circuit")
        return CircuitStepper(build(circuit), method=method, step=v["solver.step"])

    def _apply_inputs(self) -> None:
        for name in sorted(self._inputs_set):
            self._stepper.set_input(name, self._values[name])

    def _read_outputs(self) -> None:
        self._outputs = self._stepper.outputs()


class ServoSlave(_Slave):
    """A component servo file (``[actuator] [valve] [feedback] [load] [supply]``) as a
    co-simulation slave (variables: :func:`hydroarm.fmu.variables.servo_variables`): the
    reference and the external force as inputs, the servo's sweepable parameters, every
    column ``simulate`` writes. Until the master sets the reference, the file's runs."""

    description = "hydroarm component hydraulic servo"

    def _build(self) -> ServoStepper:
        v = self._values
        sc = self.model.scenario
        assert isinstance(sc, ServoScenario)
        if not hasattr(self, "_starts"):
            self._starts = servo_parameters(sc)
        changes = {n: v[n] for n, (_, _, start) in self._starts.items() if v[n] != start}
        if changes:  # checked with a sweep row's rules, then the file's servo changed
            check_servo_changes(sc, changes)
            sc = sc.replace(**changes)
        return ServoStepper(sc, method=method_name(v["solver.method"]), step=v["solver.step"])

    def _apply_inputs(self) -> None:
        st = self._stepper
        if "reference" in self._inputs_set:
            st.reference = self._values["reference"]
        st.external_force = self._values["external_force"]

    def _read_outputs(self) -> None:
        self._outputs = self._stepper.outputs()
