"""The system a study runs, named by file (issue 29; docs/design.md "Any system").

A study file names its system ``[system] file = "servo.toml"`` (relative to the study's
file); the fields beside it override the file's: the solver's (``method``, ``step``,
``duration``, ``record_every``) and any parameter by its name. The system file is either a
circuit (``[[component]]`` entries or a ``[mechanism]``, `hydroarm.io.circuit`; its
parameters ``<component>.<parameter>``) or a fixed-shape component servo (``[actuator]``,
``[valve]`` … `hydroarm.io.components`; its parameters by their sweep names,
``proportional_gain``, ``piston_area`` …, optionally behind their section's name,
``feedback.proportional_gain``). A *reference file* — only ``[system] file = …`` with
fields beside it, as ``hydroarm fit`` writes ``fitted.toml`` for a mechanism or a component
servo — is a system file too: it is read through the file it names (one level).
"""

from __future__ import annotations

from pathlib import Path

from ..errors import HydroarmError
from ..model.circuit import Circuit
from ..model.servo import SERVO_METHODS, ServoScenario
from .circuit import (
    SYSTEM_REFERENCE_KEYS,
    circuit_with_overrides,
    is_circuit_file,
    system_reference,
)
from .components import (
    check_sweep_name,
    is_component_file,
    servo_from_doc,
    sweep_names,
    sweep_targets,
    sweep_value,
)
from .sections import (
    as_table,
    check_run_size,
    read_toml_file,
    solver_values,
    unknown_name,
    within,
)
from .servo_circuit import servo_circuit

#: the sections of a component servo file a parameter's name may start with
SERVO_SECTIONS = ("actuator", "valve", "feedback", "load", "supply", "accumulator")
SOLVER_KEYS = SYSTEM_REFERENCE_KEYS - {"file"}
#: the sections of a reference file (`is_reference_file`)
REFERENCE_SECTIONS = {"name", "description", "system", "explore"}  # [explore]: hydroarm explore

System = Circuit | ServoScenario


def servo_parameter_name(field: str, name: str) -> str:
    """A component servo's parameter by its sweep name (``proportional_gain``), or behind
    its section's name (``feedback.proportional_gain``): the sweep name."""
    section, dot, rest = name.partition(".")
    plain = rest if dot and section in SERVO_SECTIONS else name
    known = sweep_names()
    if plain not in known:
        raise unknown_name(field, "servo parameter", name, known)
    return plain


def servo_value(field: str, servo: ServoScenario, name: str, value) -> float:
    """A study's value [SI] of the servo parameter ``name`` (its sweep name), read in the
    dimension the servo's components give it, with its sign rule."""
    check_sweep_name(field, name, servo.parameters)
    return sweep_value(field, name, value, servo.parameters)


def servo_with(servo: ServoScenario, values: dict[str, float]) -> ServoScenario:
    """The servo with parameters set by sweep name (a convenience name sets each of its
    targets)."""
    params = dict(servo.parameters)
    for k, v in values.items():
        for target in sweep_targets(k):
            params[target] = float(v)
    return servo.replace(parameters=params)


def _servo_reference(field: str, table: dict, doc: dict, p: Path) -> ServoScenario:
    with within(f"{field}.file"):
        try:
            servo = servo_from_doc(doc, p.parent, p.stem)
        except HydroarmError as exc:
            raise HydroarmError(exc.field, f"{p.name}: {exc.problem}") from None
    return servo_with_overrides(field, servo, table)


def servo_with_overrides(field: str, servo: ServoScenario, table) -> ServoScenario:
    """``servo`` with the fields of a ``[system]`` table beside ``file`` set: the solver's
    and any parameter by its sweep name."""
    solver = solver_values(
        field, {k: v for k, v in table.items() if k in SOLVER_KEYS}, SERVO_METHODS
    )
    values = {}
    for k, v in table.items():
        if k in SYSTEM_REFERENCE_KEYS:
            continue
        name = servo_parameter_name(f"{field}.{k}", k)
        values[name] = servo_value(f"{field}.{k}", servo, name, v)
    servo = servo_with(servo, values).replace(**solver)
    check_run_size(
        servo.duration,
        servo.step,
        servo.record_every,
        duration_field=f"{field}.duration",
        record_field=f"{field}.record_every",
    )
    return servo


def with_overrides(field: str, system: System, table) -> System:
    """``system`` with the fields of a ``[system]`` table beside ``file`` set."""
    if isinstance(system, Circuit):
        return circuit_with_overrides(field, system, table)
    return servo_with_overrides(field, system, table)


def is_reference_file(doc: dict) -> bool:
    """Whether a parsed file only names a system with values beside it (``[system] file``
    and fields, as ``hydroarm fit`` writes ``fitted.toml`` for a mechanism or a component
    servo): a system file too, read through the one it names."""
    s = doc.get("system")
    return isinstance(s, dict) and "file" in s and set(doc) <= REFERENCE_SECTIONS


def system_of(field: str, table, base_dir: Path, *, _followed: bool = False) -> System:
    """The system ``[system] file = …`` names, with the fields beside it overriding the
    file's (module doc): a `Circuit` or a
    [`ServoScenario`][hydroarm.ServoScenario]. The file may itself be a reference file
    (`is_reference_file`; one level: it names a circuit or a servo file)."""
    table = as_table(field, table)
    if "file" not in table:
        raise HydroarmError(f"{field}.file", "is missing (the system file this study runs)")
    path = table["file"]
    if not isinstance(path, str) or not path.strip():
        raise HydroarmError(f"{field}.file", "must be a path to a system file")
    try:
        doc, p = read_toml_file((base_dir / path).expanduser())
    except HydroarmError as exc:
        raise HydroarmError(f"{field}.file", exc.problem) from None
    if is_component_file(doc):
        return _servo_reference(field, table, doc, p)
    if is_reference_file(doc) and not _followed:
        try:
            inner = system_of("system", doc["system"], p.parent, _followed=True)
        except HydroarmError as exc:
            raise HydroarmError(f"{field}.file", f"{path}: {exc}") from None
        return with_overrides(field, inner, table)
    if not is_circuit_file(doc):
        raise HydroarmError(
            f"{field}.file",
            f"{path}: not a system file: neither a circuit ([[component]] entries, a "
            "[mechanism]) nor a component servo ([actuator], [valve], …)"
            + (
                " (a reference file names a system file, not another reference)"
                if is_reference_file(doc)
                else ""
            ),
        )
    return system_reference(field, table, base_dir)


def is_system_file(doc: dict) -> bool:
    """Whether a parsed file is itself a system (a circuit or a component servo), not a
    study of one."""
    return is_component_file(doc) or is_circuit_file(doc) or is_reference_file(doc)


def reference_target(path) -> System | None:
    """The system a reference file names, its fields set (`is_reference_file`: the
    ``fitted.toml`` that ``hydroarm fit`` writes for a mechanism or a component servo), so
    that ``hydroarm simulate`` and ``linearize`` run it as they run a system file; None for
    any other file (or one that cannot be read: the caller's own reader says what is wrong)."""
    try:
        doc, p = read_toml_file(path)
    except HydroarmError:
        return None
    if not (isinstance(doc, dict) and is_reference_file(doc)):
        return None
    return system_of("system", doc["system"], p.parent)


def study_circuit(field: str, table, base_dir: Path) -> Circuit:
    """The circuit a sweep or a sensitivity study runs, named by its ``[system]`` table: a
    circuit or mechanism file, a reference file naming one (``fitted.toml``), or a component
    servo file as the circuit ``hydroarm expand`` writes for it
    (`servo_circuit`: equal to the servo's own kernel to
    1e-9 of the range, tests/test_servo_circuit.py), so that one servo file serves every
    study. The fields beside ``file`` override the circuit's: the solver's, and any
    parameter by its circuit name (``"load.mass" = "120 kg"``; ``hydroarm expand`` lists
    them)."""
    table = as_table(field, table)
    path = table.get("file")
    if isinstance(path, str) and path.strip():
        try:
            doc, p = read_toml_file((base_dir / path).expanduser())
        except HydroarmError:
            doc = None  # system_of names what is wrong with it
        if doc is not None and is_component_file(doc):
            with within(f"{field}.file"):
                try:
                    circuit = servo_circuit(doc, p.parent, p.stem)
                except HydroarmError as exc:
                    raise HydroarmError(exc.field, f"{p.name}: {exc.problem}") from None
            return circuit_with_overrides(field, circuit, table)
    system = system_of(field, table, base_dir)
    if not isinstance(system, Circuit):
        raise HydroarmError(
            f"{field}.file",
            f"{path}: a reference to a component servo: name the servo file itself, with the "
            "fitted values beside it",
        )
    return system
