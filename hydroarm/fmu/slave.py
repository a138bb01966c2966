"""The FMI 2.0 co-simulation slaves that an exported FMU runs (pythonfmu's ``Fmi2Slave``).

An FMU built by :func:`hydroarm.fmu.export_fmu` holds, as resources, the configuration file
it was exported from (a scenario file of the paper's joint, or an arm file), the files it
refers to, ``hydroarm_fmu.json`` (which slave, which file) and a one-class script whose
class derives from :class:`JointSlave` or :class:`ArmSlave` here. The slave reads the
configuration with hydroarm's own readers and steps it with the steppers
(:class:`~hydroarm.model.stepper.JointStepper`, :class:`~hydroarm.arm.stepper.ArmStepper`):
one physics, the same trajectory as ``hydroarm simulate`` / ``hydroarm arm`` at the same
internal step, whatever communication step the master takes.

Parameters (causality ``parameter``, variability ``fixed``) are read when the master leaves
initialisation mode: the joint is rebuilt from them with its own validation (a bad value is
an FMI error whose log message is hydroarm's one-line error). The FMU state (get/set and
serialisation) is the stepper's complete state plus the parameters and inputs, as JSON.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real

from ..arm.config import load_arm
from ..arm.stepper import ARM_OUTPUTS, JOINT_OUTPUTS, ArmStepper
from ..errors import HydroarmError
from ..integrators import registry
from ..io.schema import load_scenario
from ..io.sections import FIELD_DIMENSIONS
from ..model.joint import Load, ServoJoint
from ..model.scenario import Scenario
from ..model.stepper import OUTPUTS, JointStepper

META_FILE = "hydroarm_fmu.json"
# FMI unit names of the dimensions of hydroarm's file fields (hydroarm.io.units.SI_UNITS)
# and their SI base-unit exponents (None: not expressible with whole exponents)
DIMENSION_UNITS: dict[str, str] = {
    "area": "m2",
    "flow_coefficient": "m2/(s.Pa0.5)",
    "length": "m",
    "leakage": "m3/(s.Pa)",
    "volume": "m3",
    "pressure": "Pa",
    "angle": "rad",
    "force": "N",
    "viscous": "N.s/m",
    "torque": "N.m",
    "inertia": "kg.m2",
    "time": "s",
    "flow": "m3/s",
}
BASE_UNITS: dict[str, dict[str, int] | None] = {
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m2": {"m": 2},
    "m3": {"m": 3},
    "m3/s": {"m": 3, "s": -1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "s": {"s": 1},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "kg.m2": {"kg": 1, "m": 2},
    "m3/(s.Pa)": {"kg": -1, "m": 4, "s": 1},
    "m2/(s.Pa0.5)": None,  # Pa^-1/2: a half power of kg, not a whole exponent
}
# the joint's float fields a parameter of the FMU sets (the kernel's; ``backlash`` is a
# post-processing of a whole trace and ``static_friction`` appears as breakaway_friction)
JOINT_PARAMETERS = (
    "piston_area",
    "flow_coefficient",
    "valve_saturation",
    "leakage_coefficient",
    "trapped_volume",
    "bulk_modulus",
    "supply_pressure",
    "crank_radius",
    "gear_ratio",
    "horizontal_angle",
    "transition_pressure",
    "atmospheric_pressure",
    "coulomb_friction",
    "static_friction",
    "viscous_friction",
    "gearbox_friction_torque",
    "gearbox_loss_at_stall",
    "gearbox_loss_exponent",
    "end_stop_angle",
    "null_leakage_coefficient",
)
LOAD_PARAMETERS = ("weight", "arm", "inertia")


def field_descriptions(cls) -> dict[str, str]:
    """The first sentence of each field's description in a numpydoc ``Parameters`` list of
    ``cls``'s docstring (one source: the dataclass documents its fields)."""
    doc = cls.__doc__ or ""
    out = {}
    for m in re.finditer(r"^    (\w+) : [^\n]*\n((?:        [^\n]*\n?)+)", doc, re.M):
        text = " ".join(line.strip() for line in m.group(2).splitlines())
        first = re.split(r"(?<=[.;])\s", text, maxsplit=1)[0].rstrip(".;")
        out[m.group(1)] = first
    return out


def _read_meta(resources) -> tuple[dict, Path]:
    folder = Path(resources)
    meta = json.loads((folder / META_FILE).read_text(encoding="utf-8"))
    return meta, folder / meta["config"]


class _Slave(Fmi2Slave):
    """What both slaves share: variables kept in dictionaries, units for the export."""

    author = "hydroarm"
    description = "hydroarm hydraulic servo joint (UCL arm prosthesis model)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.units: dict[str, str] = {}  # variable name -> FMI unit (the export adds them)
        self._values: dict[str, float] = {}  # parameters and inputs
        self._outputs: dict[str, float] = {}
        self._inputs_set: set[str] = set()  # inputs the master has set
        self._stepper: Any = None  # the JointStepper or ArmStepper, built from the parameters
        self._t_start = 0.0

    def start_values(self) -> dict[str, float]:
        """The start value of every parameter and input (Reals and the method code)."""
        return dict(self._values)

    def _real(self, name, causality, unit, description, value=None) -> None:
        if causality == Fmi2Causality.output:
            var = Real(
                name,
                causality=causality,
                variability=Fmi2Variability.continuous,
                description=description,
                getter=lambda: self._output(name),
            )
        else:
            self._values[name] = float(value)
            var = Real(
                name,
                causality=causality,
                variability=(
                    Fmi2Variability.continuous
                    if causality == Fmi2Causality.input
                    else Fmi2Variability.fixed
                ),
                description=description,
                getter=lambda: self._values[name],
                setter=lambda v: self._set(name, v),
            )
        if unit:
            self.units[name] = unit
        self.register_variable(var, nested=False)

    def _method_parameter(self, method: str) -> None:
        codes = {m.name: m.code for m in registry.METHODS.values() if m.fixed_step}
        self._values["solver.method"] = codes[method]
        self.register_variable(
            Integer(
                "solver.method",
                causality=Fmi2Causality.parameter,
                variability=Fmi2Variability.fixed,
                description="fixed-step method: " + ", ".join(f"{c} {n}" for n, c in codes.items()),
                getter=lambda: self._values["solver.method"],
                setter=lambda v: self._set("solver.method", v),
            ),
            nested=False,
        )

    def _method_name(self) -> str:
        code = int(self._values["solver.method"])
        for m in registry.METHODS.values():
            if m.fixed_step and m.code == code:
                return m.name
        codes = ", ".join(str(m.code) for m in registry.METHODS.values() if m.fixed_step)
        raise HydroarmError("solver.method", f"must be one of {codes}, got {code}")

    def _set(self, name, v) -> None:
        self._values[name] = v
        if name in self._inputs():
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

    def _inputs(self) -> tuple[str, ...]:
        raise NotImplementedError

    def _build(self):
        raise NotImplementedError

    def _apply_inputs(self) -> None:
        raise NotImplementedError

    def _read_outputs(self) -> None:
        raise NotImplementedError


class JointSlave(_Slave):
    """The paper's joint of a scenario file as a co-simulation slave.

    Inputs ``lever`` [m], ``supply_pressure`` [Pa], ``external_torque`` [N m]; outputs
    :data:`hydroarm.model.stepper.OUTPUTS`; parameters ``joint.<field>``, ``load.<field>``,
    ``initial.angle``, ``solver.step``, ``solver.method``."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        meta, config = _read_meta(self.resources)
        sc = load_scenario(config)
        if not isinstance(sc, Scenario):
            raise HydroarmError("--config", "a servo built from components has no FMU export yet")
        self._scenario = sc
        method = meta.get("method") or sc.method
        step = float(meta.get("step") or sc.step)
        jd, ld = field_descriptions(ServoJoint), field_descriptions(Load)
        P = Fmi2Causality.parameter
        joint = sc.joint
        for name in JOINT_PARAMETERS:
            v = _default(joint, name)
            dim = FIELD_DIMENSIONS[name]
            self._real(f"joint.{name}", P, DIMENSION_UNITS.get(dim, ""), jd.get(name), v)
        for name in LOAD_PARAMETERS:
            self._real(
                f"load.{name}",
                P,
                DIMENSION_UNITS[FIELD_DIMENSIONS[name]],
                ld.get(name),
                getattr(sc.load, name),
            )
        self._real("initial.angle", P, "rad", "joint angle θ₂ at the start", sc.initial_angle)
        self._real("solver.step", P, "s", "internal fixed step", step)
        self._method_parameter(method)
        I = Fmi2Causality.input
        y0 = float(sc.lever(sc.t0)[0])
        self._real("lever", I, "m", "lever (valve input) position in jack coordinates", y0)
        self._real(
            "supply_pressure",
            I,
            "Pa",
            "momentary supply pressure the valve sees",
            joint.supply_pressure,
        )
        self._real(
            "external_torque",
            I,
            "N.m",
            "external load torque at the joint, added to the load's gravity torque",
            0.0,
        )
        for name, unit, text in OUTPUTS:
            self._real(name, Fmi2Causality.output, unit, text)

    def _inputs(self):
        return ("lever", "supply_pressure", "external_torque")

    def _build(self) -> JointStepper:
        v = self._values
        sc = self._scenario
        changes: dict[str, Any] = {
            n: v[f"joint.{n}"] for n in JOINT_PARAMETERS if v[f"joint.{n}"] != _default(sc.joint, n)
        }
        if "end_stop_angle" in changes and math.isinf(changes["end_stop_angle"]):
            changes["end_stop_angle"] = None
        joint = sc.joint.replace(**changes) if changes else sc.joint
        load = Load(
            weight=v["load.weight"], arm=v["load.arm"], inertia=v["load.inertia"], name=sc.load.name
        )
        # the start pressure holds the (possibly changed) load, as a scenario file's does
        return JointStepper(
            joint,
            load,
            method=self._method_name(),
            step=v["solver.step"],
            initial_angle=v["initial.angle"],
            initial_pressure=sc.initial_pressure,
            lever=v["lever"],
            t0=0.0,
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


def _default(joint: ServoJoint, name: str) -> float:
    v = getattr(joint, name)
    if name == "static_friction" and v is None:
        return joint.breakaway_friction
    if name == "end_stop_angle" and v is None:
        return math.inf
    return v


class ArmSlave(_Slave):
    """The whole arm of an arm file as a co-simulation slave.

    Inputs ``<joint>.lever`` [m]; outputs ``<joint>.<output>``
    (:data:`hydroarm.arm.stepper.JOINT_OUTPUTS`) and the arm's
    (:data:`hydroarm.arm.stepper.ARM_OUTPUTS`); parameters ``solver.step``,
    ``solver.method``, ``power_pack.supply_pressure``, ``power_pack.pump_flow``."""

    description = "hydroarm four-joint hydraulic arm (UCL arm prosthesis model)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        meta, config = _read_meta(self.resources)
        sc = load_arm(config)
        self._scenario = sc
        self._names = [j.name for j in sc.joints]
        P = Fmi2Causality.parameter
        self._real("solver.step", P, "s", "internal fixed step", float(meta.get("step") or sc.step))
        self._method_parameter(meta.get("method") or sc.method)
        pk = sc.power_pack
        self._real(
            "power_pack.supply_pressure", P, "Pa", "relief (supply) pressure of the power pack",
            pk.supply_pressure,
        )  # fmt: skip
        self._real("power_pack.pump_flow", P, "m3/s", "pump flow (INF: unlimited)", pk.pump_flow)
        for n in self._names:
            self._real(
                f"{n}.lever",
                Fmi2Causality.input,
                "m",
                f"{n}: lever (valve input) position in jack coordinates",
                float(sc.inputs[n](0.0)[0]),
            )
        for n in self._names:
            for name, unit, text in JOINT_OUTPUTS:
                self._real(f"{n}.{name}", Fmi2Causality.output, unit, f"{n}: {text}")
        for name, unit, text in ARM_OUTPUTS:
            self._real(name, Fmi2Causality.output, unit, text)

    def _inputs(self):
        return tuple(f"{n}.lever" for n in self._names)

    def _build(self) -> ArmStepper:
        v = self._values
        sc = self._scenario
        pk = replace(
            sc.power_pack,
            supply_pressure=v["power_pack.supply_pressure"],
            pump_flow=v["power_pack.pump_flow"],
        )
        return ArmStepper(
            sc.replace(power_pack=pk), method=self._method_name(), step=v["solver.step"]
        )

    def _apply_inputs(self) -> None:
        self._stepper.levers = {n: self._values[f"{n}.lever"] for n in self._names}

    def _read_outputs(self) -> None:
        o = self._stepper.outputs()
        flat = {f"{n}.{k}": v for n in self._names for k, v in o[n].items()}
        flat.update({name: o[name] for name, _, _ in ARM_OUTPUTS})
        self._outputs = flat
