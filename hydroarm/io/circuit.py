"""Circuit files (TOML, a unit on every quantity; docs/components.md "Circuits in files").

A file with ``[[component]]`` entries describes a circuit::

    name = "pump into a relief valve"
    [[component]]
    type = "fixed_pump"                      # a registered component type
    name = "pump"                            # unique; outputs are named after it
    ports = { inlet = "tank", outlet = "supply", speed = "motor_speed" }
    displacement = "10 cm**3/rev"            # its parameters, each with a unit
    ...
    [system]      cavitation_pressure (the system's own parameters)
    [initial]     pressure = "1 bar" (every node), <node> = "<pressure>" (one node),
                  <joint> = "30 deg" (a joint of the mechanism: its angle or position),
                  equilibrium = true (start from the static state at the initial pose)
    [mechanism]   links and joints, or a URDF (docs/mechanism.md): every moving joint is
                  a mechanical node named after it, to which components connect
    [solver]      method = "euler" | "rk4" | "heun" | "midpoint", step, duration, record_every

Every parameter's file key, unit and rule come from its component's declaration
(`hydroarm.core.circuit.declare`); values are converted to SI here, once. Errors are
one line naming the field: ``component.cv1.cracking_pressure: …``.
"""

from __future__ import annotations

import difflib
from pathlib import Path

from ..core.circuit.components import TYPES
from ..core.circuit.declare import Param
from ..core.circuit.system import SYSTEM
from ..errors import HydroarmError
from ..integrators.system import STEPPERS
from ..model.circuit import Circuit, ComponentSpec
from .mechanism import mechanism_from_section
from .sections import (
    as_table,
    check_run_size,
    read_csv_columns,
    read_toml_file,
    reject_unknown_keys,
    solver_values,
    text_value,
)
from .units import quantity, value_in

#: ``[explore]`` and a mechanism's ``[block_task]`` are read by ``hydroarm explore`` only
#: (hydroarm/explore/system.py, mechanism_task.py): the other commands accept the sections
#: and leave them alone
SECTIONS = {
    "name", "description", "component", "system", "initial", "solver", "mechanism", "explore",
    "block_task",
}  # fmt: skip
MAX_COMPONENTS = 1000
MAX_ARRAY = 10**6


def is_circuit_file(doc: dict) -> bool:
    """Whether a parsed file describes a circuit (has ``[[component]]`` entries, or is a
    mechanism to run: a ``[mechanism]`` section)."""
    return "component" in doc or "mechanism" in doc


def _param_value(field: str, p: Param, value):
    if p.choices:
        return text_value(field, value, p.choices)
    return value_in(field, value, p.unit)


def _component(field: str, table: dict, base_dir: Path | None) -> ComponentSpec:
    table = as_table(field, table)
    for key in ("type", "name", "ports"):
        if key not in table:
            raise HydroarmError(f"{field}.{key}", "is missing")
    ctype = table["type"]
    name = table["name"]
    if not isinstance(name, str) or not name.isidentifier():
        raise HydroarmError(f"{field}.name", f"{name!r}: letters, digits and _ (not first)")
    field = f"component.{name}"
    if not isinstance(ctype, str) or ctype not in TYPES:
        close = difflib.get_close_matches(str(ctype), list(TYPES), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise HydroarmError(
            f"{field}.type", f"unknown component type {ctype!r}{hint} (known: {', '.join(TYPES)})"
        )
    decl = TYPES[ctype].DECLARATION
    ports = as_table(f"{field}.ports", table["ports"])
    for k, v in ports.items():
        if not isinstance(v, str) or not v.strip():
            raise HydroarmError(f"{field}.ports.{k}", "must name a node")
    allowed = {"type", "name", "ports", "description", "csv"} | set(decl.parameter_names)
    allowed |= {a.name for a in decl.arrays}
    reject_unknown_keys(field, table, allowed)
    values: dict[str, float | str] = {}
    for p in decl.parameters:
        if p.name in table:
            values[p.name] = _param_value(f"{field}.{p.name}", p, table[p.name])
    arrays: dict[str, tuple[float, ...]] = {}
    for a in decl.arrays:
        if a.name in table:
            raw = table[a.name]
            if not isinstance(raw, list) or not raw:
                raise HydroarmError(f"{field}.{a.name}", "must be a non-empty list")
            if len(raw) > MAX_ARRAY:
                raise HydroarmError(f"{field}.{a.name}", f"longer than {MAX_ARRAY} entries")
            arrays[a.name] = tuple(
                value_in(f"{field}.{a.name}[{i}]", v, a.unit) for i, v in enumerate(raw)
            )
    if "csv" in table:
        if not decl.arrays:
            raise HydroarmError(f"{field}.csv", f"a {ctype} reads no table")
        arrays.update(_csv_arrays(f"{field}.csv", table["csv"], decl, base_dir))
    if decl.arrays:
        lengths = {len(v) for v in arrays.values()}
        if len(lengths) > 1:
            raise HydroarmError(
                f"{field}.{decl.arrays[-1].name}",
                f"has {len(arrays[decl.arrays[-1].name])} entries, "
                f"{decl.arrays[0].name} {len(arrays[decl.arrays[0].name])}",
            )
        if "times" in arrays:
            ts = arrays["times"]
            if any(b <= a for a, b in zip(ts, ts[1:], strict=False)):
                raise HydroarmError(f"{field}.times", "must increase")
    return ComponentSpec(ctype, name, dict(ports), values, arrays)


def _csv_arrays(field: str, spec, decl, base_dir: Path | None) -> dict[str, tuple[float, ...]]:
    """A table's times and values from a CSV file: ``csv = {file = "speed.csv", time =
    ["t", "s"], value = ["rpm", "rpm"]}`` (column and unit of each)."""
    spec = as_table(field, spec)
    reject_unknown_keys(field, spec, {"file", "time", "value"})
    for k in ("file", "time", "value"):
        if k not in spec:
            raise HydroarmError(f"{field}.{k}", "is missing")
    path = Path(text_value(f"{field}.file", spec["file"]))
    if base_dir is not None and not path.is_absolute():
        path = base_dir / path
    out = {}
    for key, arr in (("time", "times"), ("value", "values")):
        col = spec[key]
        if not (isinstance(col, list) and len(col) == 2 and all(isinstance(x, str) for x in col)):
            raise HydroarmError(f"{field}.{key}", 'must be ["column", "unit"]')
        data = read_csv_columns(field, path, [col[0]])[col[0]]
        unit = decl.parameter(arr).unit
        factor = value_in(f"{field}.{key}", f"1 {col[1]}", unit)
        out[arr] = tuple(float(x) * factor for x in data)
    return out


def circuit_from_doc(doc: dict, source: str, base_dir: Path | None = None) -> Circuit:
    """A `Circuit` from a parsed circuit file."""
    reject_unknown_keys("", doc, SECTIONS)
    mechanism = mechanism_from_section(doc["mechanism"], base_dir) if "mechanism" in doc else None
    entries = doc.get("component", [])
    if not isinstance(entries, list) or (not entries and mechanism is None):
        raise HydroarmError("component", "must be a list of [[component]] tables")
    if len(entries) > MAX_COMPONENTS:
        raise HydroarmError("component", f"more than {MAX_COMPONENTS} components")
    comps = tuple(_component(f"component[{i}]", e, base_dir) for i, e in enumerate(entries))
    system_t = as_table("system", doc.get("system", {}))
    reject_unknown_keys("system", system_t, set(SYSTEM.parameter_names))
    system = {
        p.name: value_in(f"system.{p.name}", system_t[p.name], p.unit)
        for p in SYSTEM.parameters
        if p.name in system_t
    }
    initial_t = as_table("initial", doc.get("initial", {}))
    initial_pressure = 1.0e5
    initial: dict[str, float] = {}
    joints: dict[str, float] = {}
    kinds = {j.name: j.type for j in mechanism.joints} if mechanism is not None else {}
    equilibrium = False
    for k, v in initial_t.items():
        if k == "equilibrium":
            if not isinstance(v, bool):
                raise HydroarmError("initial.equilibrium", f"must be true or false, got {v!r}")
            equilibrium = v
            continue
        if k in kinds and kinds[k] != "fixed":
            dim = "length" if kinds[k] == "prismatic" else "angle"
            joints[k] = quantity(f"initial.{k}", v, dim)
            continue
        p = quantity(f"initial.{k}", v, "pressure", positive=True)
        if k == "pressure":
            initial_pressure = p
        else:
            initial[k] = p
    solver = solver_values(
        "solver", as_table("solver", doc.get("solver", {})), (*STEPPERS, "adaptive")
    )
    name = doc.get("name", source)
    if not isinstance(name, str):
        raise HydroarmError("name", "must be a string")
    circuit = Circuit(
        name=name,
        components=comps,
        system=system,
        initial_pressure=initial_pressure,
        initial=initial,
        equilibrium=equilibrium,
        mechanism=mechanism,
        initial_joints=joints,
        **solver,
    )
    check_run_size(circuit.duration, circuit.step, circuit.record_every)
    return circuit


def is_circuit_path(path) -> bool:
    """Whether a readable TOML file is a circuit file (False for anything else: the
    caller's own reader then reports what is wrong with it)."""
    try:
        doc, _ = read_toml_file(path)
    except HydroarmError:
        return False
    return isinstance(doc, dict) and is_circuit_file(doc)


def is_mechanism_path(path) -> bool:
    """Whether a readable TOML file has a ``[mechanism]`` section (a mechanism to run)."""
    try:
        doc, _ = read_toml_file(path)
    except HydroarmError:
        return False
    return isinstance(doc, dict) and "mechanism" in doc


def load_circuit(path) -> Circuit:
    """Read and check a circuit file."""
    doc, p = read_toml_file(path)
    if not is_circuit_file(doc):
        raise HydroarmError(p.name, "not a circuit file (no [[component]] entries)")
    return circuit_from_doc(doc, p.stem, p.parent)


# ------------------------------------------------------- studies of a circuit ---
def parameter_of(field: str, circuit: Circuit, name: str) -> Param:
    """The declaration of a circuit's parameter by its name ``<component>.<parameter>``
    (``system.<parameter>`` for the system's own), for a study's keys."""
    comp, _, pname = name.partition(".")
    if comp == "system":
        decl = SYSTEM
    else:
        types = {c.name: c.type for c in circuit.components}
        if comp not in types or not pname:
            close = difflib.get_close_matches(comp, list(types), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise HydroarmError(
                field,
                f"{name!r}: a parameter is named <component>.<parameter>, and the circuit has "
                f"no component {comp!r}{hint} (components: {', '.join(types)})",
            )
        decl = TYPES[types[comp]].DECLARATION
    if pname not in decl.parameter_names:
        close = difflib.get_close_matches(pname, list(decl.parameter_names), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise HydroarmError(
            field,
            f"{name!r}: a {decl.type} has no parameter {pname!r}{hint} "
            f"(parameters: {', '.join(decl.parameter_names)})",
        )
    return decl.parameter(pname)


def parameter_value(field: str, circuit: Circuit, name: str, value) -> float:
    """A study's value of the parameter ``name`` (``<component>.<parameter>``) in SI, read
    with the unit its component declares (a kind parameter: its choice's index)."""
    p = parameter_of(field, circuit, name)
    v = _param_value(field, p, value)
    if isinstance(v, str):
        return float(p.choices.index(v))
    problem = p.check(v)
    if problem:
        raise HydroarmError(field, problem)
    return v


SYSTEM_REFERENCE_KEYS = {"file"} | {"method", "step", "duration", "record_every"}


def system_reference(field: str, table, base_dir: Path) -> Circuit:
    """The system a study runs: ``[system] file = "circuit.toml"`` (relative to the study's
    file), with the fields beside it overriding the file's: the solver's (``method``,
    ``step``, ``duration``, ``record_every``) and any parameter by its name
    (``"load.mass" = "200 kg"``)."""
    table = as_table(field, table)
    if "file" not in table:
        raise HydroarmError(f"{field}.file", "is missing (the system file this study runs)")
    path = table["file"]
    if not isinstance(path, str) or not path.strip():
        raise HydroarmError(f"{field}.file", "must be a path to a system file")
    full = (base_dir / path).expanduser()
    try:
        doc, p = read_toml_file(full)
    except HydroarmError as exc:
        raise HydroarmError(f"{field}.file", exc.problem) from None
    if not is_circuit_file(doc):
        raise HydroarmError(
            f"{field}.file",
            f"{path}: not a circuit file (no [[component]] entries); a study's [system] file "
            "is a circuit (docs/components.md)",
        )
    try:
        circuit = circuit_from_doc(doc, p.stem, p.parent)
    except HydroarmError as exc:
        raise HydroarmError(f"{field}.file", f"{path}: {exc}") from None
    return circuit_with_overrides(field, circuit, table)


def circuit_with_overrides(field: str, circuit: Circuit, table) -> Circuit:
    """``circuit`` with the fields of a ``[system]`` table beside ``file`` set: the solver's
    and any parameter by its name (`system_reference`)."""
    solver = solver_values(
        field,
        {k: v for k, v in table.items() if k in SOLVER_KEYS_OF_STUDY},
        (*STEPPERS, "adaptive"),
    )
    values = {
        k: parameter_value(f"{field}.{k}", circuit, k, v)
        for k, v in table.items()
        if k not in SYSTEM_REFERENCE_KEYS
    }
    circuit = circuit.with_values(values).replace(**solver)
    check_run_size(
        circuit.duration,
        circuit.step,
        circuit.record_every,
        duration_field=f"{field}.duration",
        record_field=f"{field}.record_every",
    )
    return circuit


SOLVER_KEYS_OF_STUDY = SYSTEM_REFERENCE_KEYS - {"file"}
