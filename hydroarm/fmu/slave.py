"""The FMI 2.0 co-simulation slaves that an exported FMU runs (pythonfmu's ``Fmi2Slave``).

An FMU built by [`hydroarm.fmu.export_fmu`][hydroarm.export_fmu] holds, as resources, the
configuration file it was exported from (a scenario file of the paper's joint, an arm file, a
component servo file or a circuit file), the files it refers to, ``hydroarm_fmu.json`` (which slave,
which file) and a one-class script whose class derives from `JointSlave`,
`ArmSlave`, `ServoSlave` or `CircuitSlave` here. The slave reads the
configuration with hydroarm's own readers, registers the variables of
`hydroarm.fmu.variables` and steps the model with the steppers
([`JointStepper`][hydroarm.JointStepper], `ArmStepper`,
`ServoStepper`,
`CircuitStepper`): one physics, the same trajectory
as ``hydroarm simulate`` / ``hydroarm arm`` at the same internal step, whatever
communication step the master takes.

Parameters (causality ``parameter``, variability ``fixed``) are read when the master leaves
initialisation mode: the joint is rebuilt from them with its own validation (a bad value is
an FMI error whose log message is hydroarm's one-line error). The FMU state (get/set and
serialisation) is the stepper's complete state plus the parameters and inputs, as JSON.

Statuses (issue 31). pythonfmu 0.7 turns every Python exception into ``fmi2Fatal`` and frees
the instance's Python object (its C++ wrapper, ``handle_py_exception``), and a ``do_step``
that returns False into ``fmi2Discard``; no Python slave can return ``fmi2Error``. So what
leaves the instance usable is refused without an exception: ``doStep`` returns
``fmi2Discard`` (nothing of the step is taken, ``fmi2LastSuccessfulTime`` is the step's
start) with hydroarm's one-line error logged at status ``fmi2Error`` (category
``logStatusError``) for a communication step that is not finite, negative or needs more than
`MAX_STEPS_PER_DO_STEP` internal steps, an input that is not finite, a run that left
the physical bounds, a model that cannot be built, and after a serialized state that could
not be read (a corrupt one: one logged line, the instance kept as it was, every ``doStep``
discarded until a good state is set). A bad parameter found when the master leaves
initialisation mode is still ``fmi2Fatal``: FMI 2.0 lets no fixed parameter change after
that, so the instance cannot go on.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from typing import Any

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real
from pythonfmu.enums import Fmi2Status

from ..arm.model import ArmScenario
from ..arm.stepper import ARM_OUTPUTS, ArmStepper
from ..batch.servo_sweep import check_servo_changes
from ..errors import HydroarmError
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

# internal fixed steps one doStep may take: 10⁷ are 100 s of model time at the default
# 10 µs step and seconds to a minute of compute; a master's larger communication step
# (doStep(h = 1e7 s) took 10¹² steps, issue 31) is refused with fmi2Discard (module doc)
MAX_STEPS_PER_DO_STEP = 10**7
ERROR_CATEGORY = "logStatusError"  # FMI 2.0's category for messages of status fmi2Error
CORRUPT = "__hydroarm_corrupt_state__"  # the key of a serialized state that could not be read

CAUSALITY = {
    "parameter": (Fmi2Causality.parameter, Fmi2Variability.fixed),
    "input": (Fmi2Causality.input, Fmi2Variability.continuous),
    "output": (Fmi2Causality.output, Fmi2Variability.continuous),
}


class _Slave(Fmi2Slave):
    """What both slaves share: the variables of `hydroarm.fmu.variables`, their values
    in dictionaries, the stepper built from the parameters."""

    author = "hydroarm"
    description = "hydroarm hydraulic servo (UCL arm prosthesis model)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.model = read_model(self.resources)
        self._values: dict[str, float] = {}  # parameters and inputs
        self._start_values: dict[str, float] = {}  # their start values (the file's)
        self._outputs: dict[str, float] = {}
        self._input_names: set[str] = set()
        self._inputs_set: set[str] = set()  # inputs the master has set
        self._stepper: Any = None  # the JointStepper or ArmStepper, built from the parameters
        self._t_start = 0.0
        self._state_problem = ""  # why the last state set could not be (a corrupt one)
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
            self._start_values[name] = v.start
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
                try:
                    self._apply_inputs()
                except HydroarmError as exc:  # logged now; the next doStep is refused
                    self._refuse(str(exc))
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

    def _refuse(self, problem: str) -> bool:
        """Log hydroarm's one-line error at status fmi2Error; False: doStep's fmi2Discard
        (the closest status to fmi2Error that pythonfmu lets a slave return; module doc)."""
        self.log(f"hydroarm: error: {problem}", Fmi2Status.error, ERROR_CATEGORY)
        return False

    def _step_problem(self, step_size) -> str:
        """Why a communication step cannot be taken ('' if it can): not a finite time ≥ 0,
        more than MAX_STEPS_PER_DO_STEP internal steps, an input that is not finite."""
        if not (isinstance(step_size, (int, float)) and math.isfinite(step_size)):
            return f"doStep: communicationStepSize: {step_size!r} is not a finite time"
        if step_size < 0:
            return f"doStep: communicationStepSize: {step_size!r} s is negative"
        h = self._values.get("solver.step", math.nan)
        if math.isfinite(h) and h > 0 and step_size / h > MAX_STEPS_PER_DO_STEP:
            return (
                f"doStep: communicationStepSize: {step_size:g} s would take "
                f"{step_size / h:.3g} internal steps of {h:g} s, above the budget of "
                f"{MAX_STEPS_PER_DO_STEP:.0e}: take smaller communication steps"
            )
        for name in sorted(self._input_names):
            v = self._values[name]
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                return f"{name}: {v!r} is not a finite number"
        return ""

    def do_step(self, current_time, step_size):
        if self._state_problem:
            return self._refuse(self._state_problem)
        problem = self._step_problem(step_size)
        if problem:
            return self._refuse(problem)
        try:
            if self._stepper is None:
                self._start()
            self._apply_inputs()
            self._stepper.advance_to(current_time + step_size - self._t_start)
        except HydroarmError as exc:  # the run left the bounds, a time before the last...
            return self._refuse(str(exc))
        self._read_outputs()
        return True

    def _start(self) -> None:
        self._stepper = self._build()  # a bad parameter raises: fmi2Fatal (module doc)
        try:
            self._apply_inputs()
        except HydroarmError as exc:  # a bad input: logged; the next doStep is refused
            self._refuse(str(exc))
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

    @staticmethod
    def _fmu_state_from_bytes(state: bytes):
        """A serialized state read back; a corrupt one (not UTF-8 JSON) is not an exception
        (pythonfmu would make it fmi2Fatal and free the instance) but a marker that
        `_set_fmu_state` reports."""
        try:
            return json.loads(bytes(state).decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as exc:
            return {CORRUPT: f"{type(exc).__name__}: {exc}"}

    def _set_fmu_state(self, state):
        kept = (dict(self._values), set(self._inputs_set), self._t_start, self._stepper)
        try:
            if not isinstance(state, dict) or CORRUPT in state:
                raise ValueError(state.get(CORRUPT) if isinstance(state, dict) else "not a state")
            values = {k: float(v) for k, v in dict(state["values"]).items()}
            if set(values) != set(self._values):
                raise ValueError("its variables are not this FMU's")
            self._values = values
            self._inputs_set = set(state["inputs_set"]) & self._input_names
            self._t_start = float(state["t_start"])
            self._start()
            self._stepper.set_state(state["stepper"])
        except (HydroarmError, KeyError, TypeError, ValueError, AttributeError) as exc:
            self._values, self._inputs_set, self._t_start, self._stepper = kept
            self._state_problem = (
                f"fmi2SetFMUstate: the FMU state is corrupt or not this FMU's ({exc}); the "
                "instance is kept as it was, and every doStep is refused until a good state "
                "is set"
            )
            self._refuse(self._state_problem)
            return
        self._state_problem = ""
        self._read_outputs()

    def _build(self):
        raise NotImplementedError

    def _apply_inputs(self) -> None:
        raise NotImplementedError

    def _read_outputs(self) -> None:
        raise NotImplementedError


class JointSlave(_Slave):
    """The paper's joint of a scenario file as a co-simulation slave (variables:
    `hydroarm.fmu.variables.joint_variables`)."""

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
            # a lever that is not finite is refused by the next doStep (module doc), not
            # here, where an exception would be fmi2Fatal: the stepper starts at the file's
            lever=v["lever"] if math.isfinite(v["lever"]) else self._start_values["lever"],
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
    `hydroarm.fmu.variables.arm_variables`)."""

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
    `hydroarm.fmu.variables.circuit_variables`): the inputs its components declare,
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
    co-simulation slave (variables: `hydroarm.fmu.variables.servo_variables`): the
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
