"""A component servo file as the circuit it stands for (issue 28: the fixed-shape servo
``[actuator] [valve] [feedback] [load] [supply]`` is a shorthand for a circuit): the file
boundary of `hydroarm.model.servo_circuit`, which maps a servo's parameters onto the
circuit's components (nodes ``T``, ``supply``, ``A``, ``B``, ``rod``, ``joint``; signals
``reference``, ``measurement``, ``demand``).

`servo_circuit` reads a servo file's sections as `servo_from_doc` does (every check and default is
that reader's) and expands the scenario, with the file's valve geometry and pump speed (in the
file's units) so that the circuit is written in the file's own terms. `circuit_toml` writes any
`Circuit` of ``[[component]]`` tables as a circuit file
(``hydroarm expand``), each value in its component's declared unit.
``tests/test_servo_circuit.py`` runs every servo example both ways and compares the traces.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..core.circuit.components import TYPES
from ..core.circuit.system import SYSTEM
from ..errors import HydroarmError
from ..model.circuit import Circuit
from ..model.mechanism import DEFAULT_GRAVITY, ZERO3, Mechanism
from ..model.servo import ServoScenario
from ..model.servo_circuit import (  # noqa: F401  (the expansion's parts, re-exported)
    NAMES,
    actuator_spec,
    crank_friction,
    crank_has_friction,
    crank_spec,
    feedback_specs,
    reference_source,
    valve_spec,
)
from ..model.servo_circuit import scenario_circuit as model_scenario_circuit
from .components import is_component_file, servo_from_doc
from .sections import as_table, read_toml_file
from .units import value_in


def load_servo_circuit(path) -> Circuit:
    """Read a component servo file as its circuit (``hydroarm expand``)."""
    doc, p = read_toml_file(path)
    if not is_component_file(doc):
        raise HydroarmError(p.name, "not a component servo file (no [actuator] section)")
    return servo_circuit(doc, p.parent, p.stem)


def servo_circuit(doc: dict, base_dir: Path, source: str = "servo") -> Circuit:
    """The circuit a parsed component servo file stands for (module doc)."""
    scenario = servo_from_doc(doc, base_dir, source)
    return scenario_circuit(
        scenario,
        as_table("valve", doc.get("valve", {})),
        as_table("supply", doc.get("supply", {})),
    )


def scenario_circuit(
    scenario: ServoScenario, valve: Mapping[str, Any], supply: Mapping[str, Any]
) -> Circuit:
    """The circuit of a checked [`ServoScenario`][hydroarm.ServoScenario]
    (`hydroarm.model.servo_circuit.scenario_circuit`); ``valve`` and ``supply`` are
    the file's tables, read for what the parameter vector folds away (the valve's geometry,
    the pump's speed), so that the circuit file is written in the file's own terms."""
    geometry = {}
    if "discharge_coefficient" in valve:
        geometry["discharge_coefficient"] = float(valve["discharge_coefficient"])
    if "density" in valve:
        geometry["density"] = value_in("valve.density", valve["density"], "kg/m**3")
    if "circumference_fraction" in valve:
        geometry["circumference_fraction"] = float(valve["circumference_fraction"])
    speed = None
    if "speed" in supply and "pump_flow" not in supply:
        speed = value_in("supply.speed", supply["speed"], "rad/s")
    return model_scenario_circuit(scenario, geometry, speed)


# ------------------------------------------------------------------ writing ---
def _toml_value(value: float | str, unit: str) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    if math.isinf(value):
        return '"inf"' if value > 0 else '"-inf"'
    if unit in ("", "*"):
        return repr(float(value))
    return f'"{float(value)!r} {unit}"'


def circuit_toml(circuit: Circuit, header: str = "") -> str:
    """A circuit file of ``circuit``'s components (values that differ from the declared
    defaults, each in its declared SI unit, written to round-trip exactly), its initial
    pressures and its solver; a ``[mechanism]`` as links, joints, payloads and couplings
    (`mechanism_lines`) and the joints' initial positions."""
    lines = [f"# {line}" if line else "#" for line in header.splitlines()]
    lines.append(f"name = {_toml_value(circuit.name, '')}")
    if circuit.mechanism is not None:
        lines += ["", *mechanism_lines(circuit.mechanism)]
    for spec in circuit.components:
        decl = TYPES[spec.type].DECLARATION
        ports = ", ".join(f"{k} = {_toml_value(v, '')}" for k, v in spec.ports.items())
        lines += ["", "[[component]]", f'type = "{spec.type}"', f'name = "{spec.name}"']
        lines.append(f"ports = {{ {ports} }}")
        for p in decl.parameters:
            if p.name in spec.values and spec.values[p.name] != p.default:
                lines.append(f"{p.name} = {_toml_value(spec.values[p.name], p.unit)}")
        for a in decl.arrays:
            if a.name in spec.arrays:
                items = ", ".join(_toml_value(v, a.unit) for v in spec.arrays[a.name])
                lines.append(f"{a.name} = [{items}]")
    if circuit.system:
        lines += ["", "[system]"]
        for k, v in circuit.system.items():
            lines.append(f"{k} = {_toml_value(v, SYSTEM.parameter(k).unit)}")
    lines += ["", "[initial]", f"pressure = {_toml_value(circuit.initial_pressure, 'Pa')}"]
    lines += [f"{k} = {_toml_value(v, 'Pa')}" for k, v in circuit.initial.items()]
    kinds = {j.name: j.type for j in circuit.mechanism.joints} if circuit.mechanism else {}
    for k, v in circuit.initial_joints.items():
        lines.append(f"{k} = {_toml_value(v, 'm' if kinds[k] == 'prismatic' else 'rad')}")
    if circuit.equilibrium:
        lines.append("equilibrium = true")
    lines += [
        "",
        "[solver]",
        f'method = "{circuit.method}"',
        f"step = {_toml_value(circuit.step, 's')}",
        f"duration = {_toml_value(circuit.duration, 's')}",
        f"record_every = {circuit.record_every}",
    ]
    return "\n".join(lines) + "\n"


def _vector_value(values, unit: str) -> str:
    return "[" + ", ".join(_toml_value(float(v), unit) for v in values) + "]"


def mechanism_lines(mech: Mechanism) -> list[str]:
    """The ``[mechanism]`` section of ``mech`` (docs/mechanism.md): every value that differs
    from its default, in SI units with all its digits (it reads back to the same
    mechanism)."""
    lines = ["[mechanism]", f"name = {_toml_value(mech.name, '')}"]
    if mech.gravity != DEFAULT_GRAVITY:
        lines.append(f"gravity = {_vector_value(mech.gravity, 'm/s**2')}")
    inertia_keys = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")

    def inertia(values) -> list[str]:
        return [
            f"{k} = {_toml_value(float(v), 'kg*m**2')}"
            for k, v in zip(inertia_keys, values, strict=True)
            if v != 0.0
        ]

    for link in mech.links:
        lines += ["", "[[mechanism.link]]", f"name = {_toml_value(link.name, '')}"]
        if link.mass != 0.0:
            lines.append(f"mass = {_toml_value(link.mass, 'kg')}")
        if link.com != ZERO3:
            lines.append(f"com = {_vector_value(link.com, 'm')}")
        lines += inertia(link.inertia)
    for j in mech.joints:
        lines += ["", "[[mechanism.joint]]", f"name = {_toml_value(j.name, '')}"]
        lines += [f'type = "{j.type}"', f'parent = "{j.parent}"', f'child = "{j.child}"']
        lines.append("axis = [" + ", ".join(repr(float(a)) for a in j.axis) + "]")
        if j.origin != ZERO3:
            lines.append(f"origin = {_vector_value(j.origin, 'm')}")
        if j.rpy != ZERO3:
            lines.append(f"rpy = {_vector_value(j.rpy, 'rad')}")
        linear = j.type == "prismatic"
        for key, unit in (
            ("lower", "m" if linear else "rad"),
            ("upper", "m" if linear else "rad"),
            ("damping", "N*s/m" if linear else "N*m*s"),
            ("friction", "N" if linear else "N*m"),
        ):
            v = getattr(j, key)
            given = math.isfinite(v) if key in ("lower", "upper") else v != 0.0
            if given:
                lines.append(f"{key} = {_toml_value(v, unit)}")
    for pl in mech.payloads:
        lines += ["", "[[mechanism.payload]]", f"name = {_toml_value(pl.name, '')}"]
        lines += [f'link = "{pl.link}"', f"mass = {_toml_value(pl.mass, 'kg')}"]
        if pl.point != ZERO3:
            lines.append(f"point = {_vector_value(pl.point, 'm')}")
        lines += inertia(pl.inertia)
    kinds = {j.name: j.type for j in mech.joints}
    for c in mech.couplings:
        lines += ["", "[[mechanism.coupling]]", f'joint = "{c.joint}"', f'follows = "{c.follows}"']
        slave, master = kinds[c.joint] == "prismatic", kinds[c.follows] == "prismatic"
        unit = {(True, False): "m/rad", (False, True): "rad/m"}.get((slave, master), "")
        lines.append(f"ratio = {_toml_value(c.ratio, unit)}")
        if c.offset != 0.0:
            lines.append(f"offset = {_toml_value(c.offset, 'm' if slave else 'rad')}")
    return lines
