"""The variables of hydroarm's FMUs, in one place: the slaves register them
(`hydroarm.fmu.slave`), the export completes the model description from them (units,
exact start values; `hydroarm.fmu.export`). No pythonfmu here.

A `Variable` is a name, a causality (``parameter``, ``input``, ``output``), an FMI
unit, a description and, for a parameter or an input, its start value (SI).
"""

from __future__ import annotations

import difflib
import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

from ..arm.config import load_arm
from ..arm.model import ArmScenario
from ..arm.stepper import ARM_OUTPUTS, JOINT_OUTPUTS, ArmStepper
from ..core.circuit.system import SYSTEM
from ..core.servo import (
    FEEDBACK_MECHANICAL,
    LOAD_MASS,
    P_FEEDBACK,
    P_FORCE,
    P_LOAD,
    PARAMETER_INDEX,
    PARAMETERS,
)
from ..errors import HydroarmError
from ..integrators import registry
from ..io.circuit import load_circuit
from ..io.components import SWEEP_PARAMETERS, check_sweep_name, sweep_dimension
from ..io.schema import load_scenario
from ..io.sections import FIELD_DIMENSIONS
from ..io.units import SI_UNITS
from ..model.circuit import Circuit, build
from ..model.circuit_stepper import METHOD_CODES, CircuitStepper
from ..model.joint import Load, ServoJoint
from ..model.scenario import Scenario
from ..model.servo import ServoScenario
from ..model.servo_stepper import ServoStepper
from ..model.stepper import OUTPUTS

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
BASE_UNITS: dict[str, dict[str, float] | None] = {
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
    # the units of circuits (fmi_unit of their declarations' pint units) and of the
    # display units of their outputs (bar, degrees, L/min: a factor to SI)
    "bar": {"kg": 1, "m": -1, "s": -2, "factor": 1.0e5},
    "deg": {"rad": 1, "factor": math.pi / 180.0},
    "L/min": {"m": 3, "s": -1, "factor": 1.0 / 6.0e4},
    "W": {"kg": 1, "m": 2, "s": -3},
    "kg": {"kg": 1},
    "Hz": {"s": -1},
    "m/s2": {"m": 1, "s": -2},
    "kg/m3": {"kg": 1, "m": -3},
    "N/m": {"kg": 1, "s": -2},
    "N.m/rad": {"kg": 1, "m": 2, "s": -2, "rad": -1},
    "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
    "m3/rad": {"m": 3, "rad": -1},
    "m3/s/Pa": {"kg": -1, "m": 4, "s": 1},
    "m3/s/Pa0.5": None,
    # the component servo's parameters and outputs
    "1/s": {"s": -1},
    "deg/s": {"rad": 1, "s": -1, "factor": math.pi / 180.0},
    "m2/s": {"m": 2, "s": -1},
    "m.s": {"m": 1, "s": 1},
    "N.m.s": {"kg": 1, "m": 2, "s": -1},
    "m2/s/Pa0.5": None,
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


@dataclass(frozen=True)
class Variable:
    """One FMU variable (module doc); ``integer``: an FMI Integer (the method code)."""

    name: str
    causality: str
    unit: str
    description: str
    start: float | None = None
    integer: bool = False


@dataclass(frozen=True)
class Model:
    """What an FMU's resources describe: ``joint``, ``arm``, ``servo`` or ``circuit``, the
    scenario (or circuit) read from the embedded file, the solver's method and step [s]."""

    kind: str
    scenario: Scenario | ArmScenario | ServoScenario | Circuit
    method: str
    step: float
    outputs: tuple[str, ...] = ()  # a circuit's outputs exported (empty: every one)


def default_value(joint: ServoJoint, name: str) -> float:
    """The joint's value of a parameter of `JOINT_PARAMETERS` as the FMU gives it:
    an unset static friction is the Coulomb friction, no end stop is INF."""
    v = getattr(joint, name)
    if name == "static_friction" and v is None:
        return joint.breakaway_friction
    if name == "end_stop_angle" and v is None:
        return math.inf
    return v


def method_codes(kind: str = "joint") -> dict[str, int]:
    """Fixed-step method name -> its code (the FMU's ``solver.method``): the registry's for
    the joint and the arm, `METHOD_CODES` for a
    circuit."""
    if kind == "circuit":
        return dict(METHOD_CODES)
    return {m.name: m.code for m in registry.METHODS.values() if m.fixed_step}


def method_name(code, kind: str = "joint") -> str:
    """The fixed-step method of a ``solver.method`` code; another code: a HydroarmError."""
    for name, c in method_codes(kind).items():
        if c == int(code):
            return name
    known = ", ".join(str(c) for c in method_codes(kind).values())
    raise HydroarmError("solver.method", f"must be one of {known}, got {code}")


def fmi_unit(unit: str) -> str:
    """The FMI unit name of a unit in pint's syntax (``"N*m*s/rad"`` → ``"N.m.s/rad"``,
    ``"m**3/s"`` → ``"m3/s"``); ``""`` for none or any (``"*"``)."""
    if unit in ("", "*"):
        return ""
    return unit.replace("**", "").replace("*", ".")


def load_model(
    config,
    kind: str,
    method: str | None = None,
    step: float | None = None,
    outputs: list[str] | None = None,
) -> Model:
    """The model of a configuration file: a scenario file (``kind`` ``"joint"``), an arm
    file (``"arm"``), a component servo file (``"servo"``) or a circuit file
    (``"circuit"``), read and validated by hydroarm's readers; ``method`` and ``step`` [s]
    override the file's solver; ``outputs``: a circuit's outputs to export (default: every
    one)."""
    if kind == "circuit":
        return _load_circuit_model(config, method, step, outputs)
    if outputs:
        raise HydroarmError("--outputs", "is for circuit files (the joint and the arm export all)")
    sc: Scenario | ArmScenario | ServoScenario
    if kind == "arm":
        sc = load_arm(config)
    else:
        sc = load_scenario(config)
        if isinstance(sc, ServoScenario) != (kind == "servo"):
            want = "a component servo" if kind == "servo" else "a paper joint scenario"
            raise HydroarmError("--config", f"is not {want} file")
    if method is None and sc.method not in method_codes():
        raise HydroarmError(
            "solver.method",
            f"must be {' or '.join(method_codes())} (an FMU takes fixed steps), got {sc.method!r}",
        )
    model = Model(kind, sc, method or sc.method, float(step or sc.step))
    if isinstance(sc, ServoScenario):  # started as the slave will (the step's stability)
        ServoStepper(sc, method=model.method, step=model.step)
    if isinstance(sc, ArmScenario):  # its circuit built as the slave will (what it refuses)
        ArmStepper(sc, method=model.method, step=model.step)
    return model


def _load_circuit_model(config, method: str | None, step: float | None, outputs) -> Model:
    """A circuit file's model, compiled and started as the slave will (every error first)."""
    circuit = load_circuit(config)
    if method is None and circuit.method not in METHOD_CODES:
        raise HydroarmError(
            "solver.method",
            f"must be {', '.join(METHOD_CODES)} (an FMU takes fixed steps), got "
            f"{circuit.method!r}: give one in the file or with --method",
        )
    h = float(step or circuit.step)
    names = CircuitStepper(build(circuit), method=method or circuit.method, step=h).outputs()
    if outputs is not None and not outputs:
        raise HydroarmError("--outputs", "names no output (give at least one, or leave it out)")
    for name in outputs or ():
        if name not in names:
            close = difflib.get_close_matches(name, list(names), n=3)
            raise HydroarmError(
                "--outputs",
                f"{name!r}: no such output of the circuit"
                + (f" (did you mean {', '.join(close)}?)" if close else "")
                + " (its outputs are the columns of hydroarm simulate --out)",
            )
    chosen = tuple(dict.fromkeys(outputs or ()))
    return Model("circuit", circuit, method or circuit.method, h, chosen)


def read_model(resources) -> Model:
    """The model of an FMU's resources folder (``hydroarm_fmu.json`` and the file it names)."""
    folder = Path(resources)
    meta = json.loads((folder / META_FILE).read_text(encoding="utf-8"))
    return load_model(
        folder / meta["config"],
        meta["kind"],
        meta.get("method"),
        meta.get("step"),
        meta.get("outputs"),
    )


def _method_variable(method: str, kind: str = "joint") -> Variable:
    codes = method_codes(kind)
    text = "fixed-step method: " + ", ".join(f"{c} {n}" for n, c in codes.items())
    return Variable("solver.method", "parameter", "", text, codes[method], integer=True)


def joint_variables(sc: Scenario, method: str, step: float) -> list[Variable]:
    """The variables of the joint FMU (docs/fmu.md) of a scenario."""
    jd, ld = field_descriptions(ServoJoint), field_descriptions(Load)
    out = [
        Variable(
            f"joint.{n}",
            "parameter",
            DIMENSION_UNITS.get(FIELD_DIMENSIONS[n], ""),
            jd.get(n, n),
            default_value(sc.joint, n),
        )
        for n in JOINT_PARAMETERS
    ]
    out += [
        Variable(
            f"load.{n}",
            "parameter",
            DIMENSION_UNITS[FIELD_DIMENSIONS[n]],
            ld.get(n, n),
            getattr(sc.load, n),
        )
        for n in LOAD_PARAMETERS
    ]
    out += [
        Variable("initial.angle", "parameter", "rad", "joint angle at the start", sc.initial_angle),
        Variable("solver.step", "parameter", "s", "internal fixed step", step),
        _method_variable(method),
        Variable(
            "lever",
            "input",
            "m",
            "lever (valve input) position in jack coordinates",
            float(sc.lever(sc.t0)[0]),
        ),
        Variable(
            "supply_pressure",
            "input",
            "Pa",
            "momentary supply pressure the valve sees (until set: joint.supply_pressure)",
            sc.joint.supply_pressure,
        ),
        Variable(
            "external_torque",
            "input",
            "N.m",
            "external load torque at the joint, added to the load's gravity torque",
            0.0,
        ),
    ]
    out += [Variable(n, "output", unit, text) for n, unit, text in OUTPUTS]
    return out


def arm_variables(sc: ArmScenario, method: str, step: float) -> list[Variable]:
    """The variables of the arm FMU (docs/fmu.md) of an arm scenario."""
    names = [j.name for j in sc.joints]
    pk = sc.power_pack
    out = [
        Variable("solver.step", "parameter", "s", "internal fixed step", step),
        _method_variable(method),
        Variable(
            "power_pack.supply_pressure",
            "parameter",
            "Pa",
            "relief (supply) pressure of the power pack",
            pk.supply_pressure,
        ),
        Variable(
            "power_pack.pump_flow", "parameter", "m3/s", "pump flow (INF: unlimited)", pk.pump_flow
        ),
    ]
    out += [
        Variable(
            f"{n}.lever",
            "input",
            "m",
            f"{n}: lever (valve input) position in jack coordinates",
            float(sc.inputs[n](0.0)[0]),
        )
        for n in names
    ]
    out += [
        Variable(f"{n}.{k}", "output", unit, f"{n}: {text}")
        for n in names
        for k, unit, text in JOINT_OUTPUTS
    ]
    out += [Variable(k, "output", unit, text) for k, unit, text in ARM_OUTPUTS]
    return out


def circuit_parameters(circuit: Circuit) -> dict[str, tuple[str, str, float]]:
    """The parameters of a circuit FMU: every parameter a sweep may vary
    (``<component>.<parameter>``, ``system.<parameter>``) but those an input of the same
    name sets; name -> (pint unit, doc, start value [SI])."""
    compiled = build(circuit)
    stepper = CircuitStepper(compiled)
    decls = {c.name: d for c, d in zip(circuit.components, compiled.decls, strict=True)}
    decls["system"] = SYSTEM
    out = {}
    for name in compiled.sweepable:
        if name in stepper.inputs:
            continue
        comp, _, pname = name.partition(".")
        p = decls[comp].parameter(pname)
        out[name] = (p.unit, p.doc, float(compiled.P[compiled.parameter_index[name]]))
    return out


def circuit_variables(
    circuit: Circuit, method: str, step: float, outputs: tuple[str, ...] = ()
) -> list[Variable]:
    """The variables of a circuit FMU (docs/fmu.md): its solver and sweepable parameters,
    the inputs its components declare (`circuit_inputs`), every output ``simulate`` writes (its
    column names and units), or those of ``outputs``."""
    stepper = CircuitStepper(build(circuit), method=method, step=step)
    out = [
        Variable("solver.step", "parameter", "s", "internal fixed step", step),
        _method_variable(method, "circuit"),
    ]
    out += [
        Variable(name, "parameter", fmi_unit(unit), doc, start)
        for name, (unit, doc, start) in circuit_parameters(circuit).items()
    ]
    starts = stepper.start_values()
    out += [
        Variable(name, "input", fmi_unit(i.unit), i.doc, starts[name])
        for name, i in stepper.inputs.items()
    ]
    units = stepper.output_units()
    out += [
        Variable(name, "output", fmi_unit(units[name]), f"{name} (hydroarm simulate's column)")
        for name in stepper.outputs()
        if not outputs or name in outputs
    ]
    return out


def servo_parameters(sc: ServoScenario) -> dict[str, tuple[str, str, float]]:
    """The parameters of a servo FMU: every parameter a servo sweep may vary that the
    servo's components use (`SWEEP_PARAMETERS`, by name) but
    ``external_force``, an input; name -> (FMI unit, doc, start value [SI])."""
    P = sc.vector()
    values = {name: float(P[i]) for name, i in PARAMETER_INDEX.items()}
    docs = {name: doc for name, _, doc in PARAMETERS}
    out = {}
    for name in SWEEP_PARAMETERS:
        if name == "external_force":
            continue
        try:
            check_sweep_name(name, name, values)
        except HydroarmError:
            continue  # a component the servo does not have
        dim = sweep_dimension(name, values)
        if name == "spool_frequency":
            unit = "rad/s"
        elif dim == "frequency":
            unit = "1/s"
        else:
            unit = fmi_unit(SI_UNITS[dim])
        out[name] = (unit, docs[name], values[name])
    return out


def servo_variables(sc: ServoScenario, method: str, step: float) -> list[Variable]:
    """The variables of a component servo FMU (docs/fmu.md): its solver and sweepable
    parameters, the inputs ``reference`` and ``external_force``
    (`ServoStepper`), every column ``simulate`` writes
    (its names and units)."""
    stepper = ServoStepper(sc, method=method, step=step)
    P = stepper.P
    linear = int(P[P_LOAD]) == LOAD_MASS
    lever = P[P_FEEDBACK] == FEEDBACK_MECHANICAL
    out = [
        Variable("solver.step", "parameter", "s", "internal fixed step", step),
        _method_variable(method),
    ]
    out += [
        Variable(name, "parameter", unit, doc, start)
        for name, (unit, doc, start) in servo_parameters(sc).items()
    ]
    ref_doc = (
        "lever position in the actuator's coordinates"
        if lever
        else f"reference {'position' if linear else 'angle'} of the controller"
    )
    out += [
        Variable(
            "reference",
            "input",
            "m" if linear or lever else "rad",
            f"{ref_doc}, held (until set: the file's [input])",
            stepper.reference,
        ),
        Variable(
            "external_force",
            "input",
            "N" if linear else "N.m",
            "external force (torque) on the load, opposing positive motion",
            float(P[P_FORCE]),
        ),
    ]
    units = stepper.output_units()
    out += [
        Variable(name, "output", fmi_unit(units[name]), f"{name} (hydroarm simulate's column)")
        for name in stepper.outputs()
    ]
    return out


def model_variables(model: Model) -> list[Variable]:
    """The variables of an FMU's model, in the order the slave registers them."""
    if model.kind == "circuit":
        assert isinstance(model.scenario, Circuit)
        return circuit_variables(model.scenario, model.method, model.step, model.outputs)
    if model.kind == "arm":
        assert isinstance(model.scenario, ArmScenario)
        return arm_variables(model.scenario, model.method, model.step)
    if model.kind == "servo":
        assert isinstance(model.scenario, ServoScenario)
        return servo_variables(model.scenario, model.method, model.step)
    assert isinstance(model.scenario, Scenario)
    return joint_variables(model.scenario, model.method, model.step)
