"""Mechanism files: a ``[mechanism]`` section in hydroarm TOML, or a URDF (docs/mechanism.md).

In TOML, every quantity with its unit::

    [mechanism]
    name = "two-link arm"
    gravity = ["0 m/s**2", "0 m/s**2", "-9.80665 m/s**2"]   # optional; this is the default

    [[mechanism.link]]
    name = "base"                                 # the base: no joint's child

    [[mechanism.link]]
    name = "upper_arm"
    mass = "1.2 kg"
    com = ["0 m", "0 m", "-0.15 m"]               # centre of mass in the link frame
    ixx = "0.01 kg*m**2"                          # inertia about the centre of mass, link axes
    iyy = "0.01 kg*m**2"                          # (ixy, ixz, iyz: 0 unless given)
    izz = "0.001 kg*m**2"

    [[mechanism.joint]]
    name = "shoulder"
    type = "revolute"                             # revolute, continuous, prismatic, fixed
    parent = "base"
    child = "upper_arm"
    origin = ["0 m", "0 m", "0.3 m"]              # joint frame in the parent link's frame
    rpy = ["0 deg", "0 deg", "0 deg"]             # roll, pitch, yaw (URDF's convention)
    axis = [0, 1, 0]                              # a direction in the joint frame
    lower = "-30 deg"                             # limits (none unless given)
    upper = "120 deg"
    damping = "0.1 N*m*s/rad"                     # N*s/m for a prismatic joint
    friction = "0.2 N*m"                          # dry friction; N for a prismatic joint

    [[mechanism.payload]]                         # a body fixed to a link (optional)
    name = "tool"
    link = "upper_arm"
    mass = "0.5 kg"
    point = ["0 m", "0 m", "-0.3 m"]

    [[mechanism.coupling]]                        # a joint following another (optional)
    joint = "shoulder_extension"                  # q = ratio·q_follows + offset
    follows = "elbow"
    ratio = -0.5                                  # a plain number between joints of one kind;
    offset = "0 deg"                              # "m/rad" or "rad/m" across kinds

or, instead of links and joints, ``urdf = "leg.urdf"`` (relative to the file): the URDF's links
and joints (``<inertial>``, ``<origin>``, ``<axis>``, ``<limit>``, ``<dynamics damping
friction>``, ``<mimic joint multiplier offset>``: a coupling), read by urdf_parser_py (the
ROS URDF parser); gravity, payloads and further couplings still come from the TOML. This is
the only layer that parses units; the model (`hydroarm.model.mechanism.Mechanism`) is
SI.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from pathlib import Path

from urdf_parser_py import urdf as urdf_model
from urdf_parser_py import xml_reflection

from ..errors import HydroarmError
from ..model.mechanism import (
    DEFAULT_GRAVITY,
    JOINT_TYPES,
    ZERO3,
    Coupling,
    Joint,
    Link,
    Mechanism,
    Payload,
    rpy_matrix,
)
from .sections import as_table, read_text, read_toml_file, reject_unknown_keys, text_value
from .units import value_in

PREFIX = "mechanism"
INERTIA_KEYS = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
LINK_KEYS = {"name", "mass", "com", "description", *INERTIA_KEYS}
JOINT_KEYS = {
    "name",
    "type",
    "parent",
    "child",
    "axis",
    "origin",
    "rpy",
    "lower",
    "upper",
    "damping",
    "friction",
    "description",
}
PAYLOAD_KEYS = {"name", "link", "mass", "point", "description", *INERTIA_KEYS}
COUPLING_KEYS = {"joint", "follows", "ratio", "offset", "description"}
SECTION_KEYS = {"name", "description", "gravity", "link", "joint", "payload", "coupling", "urdf"}
MAX_ENTRIES = 1000
MAX_URDF_BYTES = 10 * 2**20
URDF_TYPES = {"revolute", "continuous", "prismatic", "fixed"}


def _vector(field: str, value, unit: str) -> tuple[float, float, float]:
    if not isinstance(value, list) or len(value) != 3:
        raise HydroarmError(field, f"must be a list of 3 quantities, got {value!r}")
    x, y, z = (value_in(f"{field}[{i}]", v, unit) for i, v in enumerate(value))
    for i, v in enumerate((x, y, z)):
        if not math.isfinite(v):
            raise HydroarmError(f"{field}[{i}]", f"{value[i]!r} is not finite")
    return (x, y, z)


def _direction(field: str, value) -> tuple[float, float, float]:
    """An axis: three plain numbers (a direction, no unit)."""
    if not isinstance(value, list) or len(value) != 3:
        raise HydroarmError(field, f"must be a list of 3 numbers, got {value!r}")
    x, y, z = (value_in(f"{field}[{i}]", v, "") for i, v in enumerate(value))
    return (x, y, z)


def _name(field: str, table: dict) -> str:
    if "name" not in table:
        raise HydroarmError(f"{field}.name", "is missing")
    name = table["name"]
    if not isinstance(name, str) or not name.strip():
        raise HydroarmError(f"{field}.name", f"must be a non-empty name, got {name!r}")
    return name


def _inertia(field: str, table: dict) -> tuple[float, float, float, float, float, float]:
    i6 = tuple(
        value_in(f"{field}.{k}", table[k], "kg*m**2") if k in table else 0.0 for k in INERTIA_KEYS
    )
    return i6  # type: ignore[return-value]


def _entries(field: str, value) -> list:
    if not isinstance(value, list) or not all(isinstance(e, dict) for e in value):
        raise HydroarmError(field, f"must be a list of [[{field}]] tables")
    if len(value) > MAX_ENTRIES:
        raise HydroarmError(field, f"more than {MAX_ENTRIES} entries")
    return value


def _link(table: dict, i: int) -> Link:
    name = _name(f"{PREFIX}.link[{i}]", table)
    f = f"{PREFIX}.link.{name}"
    reject_unknown_keys(f, table, LINK_KEYS)
    mass = value_in(f"{f}.mass", table["mass"], "kg") if "mass" in table else 0.0
    com = _vector(f"{f}.com", table["com"], "m") if "com" in table else ZERO3
    return Link(name=name, mass=mass, com=com, inertia=_inertia(f, table))


def _joint(table: dict, i: int) -> Joint:
    name = _name(f"{PREFIX}.joint[{i}]", table)
    f = f"{PREFIX}.joint.{name}"
    reject_unknown_keys(f, table, JOINT_KEYS)
    for key in ("type", "parent", "child"):
        if key not in table:
            raise HydroarmError(f"{f}.{key}", "is missing")
    jtype = text_value(f"{f}.type", table["type"])
    if jtype not in JOINT_TYPES:
        # the model names the problem (one message for files and code)
        return Joint(name=name, type=jtype, parent="", child="")
    linear = jtype == "prismatic"
    position = "m" if linear else "rad"
    values: dict = {}
    for key, unit in (
        ("lower", position),
        ("upper", position),
        ("damping", "N*s/m" if linear else "N*m*s"),
        ("friction", "N" if linear else "N*m"),
    ):
        if key in table:
            values[key] = value_in(f"{f}.{key}", table[key], unit)
    if "axis" in table:
        values["axis"] = _direction(f"{f}.axis", table["axis"])
    if "origin" in table:
        values["origin"] = _vector(f"{f}.origin", table["origin"], "m")
    if "rpy" in table:
        values["rpy"] = _vector(f"{f}.rpy", table["rpy"], "rad")
    return Joint(
        name=name,
        type=jtype,
        parent=text_value(f"{f}.parent", table["parent"]),
        child=text_value(f"{f}.child", table["child"]),
        **values,
    )


def _payload(table: dict, i: int) -> Payload:
    name = _name(f"{PREFIX}.payload[{i}]", table)
    f = f"{PREFIX}.payload.{name}"
    reject_unknown_keys(f, table, PAYLOAD_KEYS)
    for key in ("link", "mass"):
        if key not in table:
            raise HydroarmError(f"{f}.{key}", "is missing")
    return Payload(
        name=name,
        link=text_value(f"{f}.link", table["link"]),
        mass=value_in(f"{f}.mass", table["mass"], "kg"),
        point=_vector(f"{f}.point", table["point"], "m") if "point" in table else ZERO3,
        inertia=_inertia(f, table),
    )


def _coupling(table: dict, i: int, kinds: dict[str, str]) -> Coupling:
    """A coupling; its ratio's and offset's units follow the two joints' kinds (``kinds``:
    joint name → type; a joint not there is left for the model to name)."""
    for key in ("joint", "follows"):
        if key not in table:
            raise HydroarmError(f"{PREFIX}.coupling[{i}].{key}", "is missing")
    joint = text_value(f"{PREFIX}.coupling[{i}].joint", table["joint"])
    f = f"{PREFIX}.coupling.{joint}"
    reject_unknown_keys(f, table, COUPLING_KEYS)
    follows = text_value(f"{f}.follows", table["follows"])
    linear = kinds.get(joint) == "prismatic"
    unit = {(False, True): "rad/m", (True, False): "m/rad"}.get(
        (linear, kinds.get(follows) == "prismatic"), ""
    )
    values = {}
    if "ratio" in table:
        values["ratio"] = value_in(f"{f}.ratio", table["ratio"], unit)
    if "offset" in table:
        values["offset"] = value_in(f"{f}.offset", table["offset"], "m" if linear else "rad")
    return Coupling(joint=joint, follows=follows, **values)


def _couplings(section, joints) -> tuple[Coupling, ...]:
    kinds = {j.name: j.type for j in joints}
    entries = _entries(f"{PREFIX}.coupling", section.get("coupling", []))
    return tuple(_coupling(t, i, kinds) for i, t in enumerate(entries))


def mechanism_from_section(section, base_dir: Path | None = None) -> Mechanism:
    """A `Mechanism` from a parsed ``[mechanism]`` table
    (``base_dir``: where a ``urdf`` file's relative path starts)."""
    section = as_table(PREFIX, section)
    reject_unknown_keys(PREFIX, section, SECTION_KEYS)
    name = section.get("name", "mechanism")
    if not isinstance(name, str):
        raise HydroarmError(f"{PREFIX}.name", "must be a string")
    gravity = (
        _vector(f"{PREFIX}.gravity", section["gravity"], "m/s**2")
        if "gravity" in section
        else DEFAULT_GRAVITY
    )
    payloads = tuple(
        _payload(t, i)
        for i, t in enumerate(_entries(f"{PREFIX}.payload", section.get("payload", [])))
    )
    if "urdf" in section:
        for key in ("link", "joint"):
            if key in section:
                raise HydroarmError(
                    f"{PREFIX}.{key}", "give links and joints in the URDF or here, not both"
                )
        path = Path(text_value(f"{PREFIX}.urdf", section["urdf"]))
        if base_dir is not None and not path.is_absolute():
            path = base_dir / path
        links, joints, urdf_name, mimics = read_urdf(path)
        with _urdf_errors(path):
            mech = Mechanism(
                links=links,
                joints=joints,
                gravity=gravity,
                payloads=payloads,
                name=section.get("name", urdf_name),
                couplings=mimics,
            )
        if "coupling" not in section:
            return mech
        # the file's own couplings, beside the URDF's mimics: their errors name the file's keys
        return dataclasses.replace(mech, couplings=mimics + _couplings(section, joints))
    for key in ("link", "joint"):
        if key not in section:
            raise HydroarmError(
                f"{PREFIX}.{key}", f"is missing: give [[{PREFIX}.{key}]] tables or a urdf file"
            )
    links = tuple(_link(t, i) for i, t in enumerate(_entries(f"{PREFIX}.link", section["link"])))
    joints = tuple(
        _joint(t, i) for i, t in enumerate(_entries(f"{PREFIX}.joint", section["joint"]))
    )
    return Mechanism(
        links=links,
        joints=joints,
        gravity=gravity,
        payloads=payloads,
        name=name,
        couplings=_couplings(section, joints),
    )


def load_mechanism(path) -> Mechanism:
    """The mechanism of a TOML file's ``[mechanism]`` section, or of a ``.urdf`` file."""
    path = Path(path)
    if path.suffix.lower() == ".urdf":
        links, joints, name, mimics = read_urdf(path, field=str(path))
        with _urdf_errors(path):
            return Mechanism(links=links, joints=joints, name=name, couplings=mimics)
    doc, path = read_toml_file(path)
    if PREFIX not in doc:
        raise HydroarmError(PREFIX, f"{path.name}: section is missing")
    return mechanism_from_section(doc[PREFIX], path.parent)


@contextlib.contextmanager
def _urdf_errors(path: Path):
    """A model error in a URDF's content, as one line naming the file:
    ``mechanism.urdf: leg.urdf: joint.knee.axis: is zero``."""
    try:
        yield
    except HydroarmError as exc:
        where = exc.field.removeprefix(f"{PREFIX}.")
        raise HydroarmError(f"{PREFIX}.urdf", f"{path.name}: {where}: {exc.problem}") from None


@contextlib.contextmanager
def _quiet_parser():
    """urdf_parser_py prints what it does not know (``<gazebo>``, ``<transmission>``) to
    stderr; those elements do not matter here."""
    saved = xml_reflection.core.on_error
    xml_reflection.core.on_error = lambda message: None
    try:
        yield
    finally:
        xml_reflection.core.on_error = saved


def read_urdf(path: Path, field: str = f"{PREFIX}.urdf") -> tuple[tuple, tuple, str, tuple]:
    """(links, joints, robot name, couplings: the ``<mimic>`` s) of a URDF file, in SI; a
    file that cannot be read or parsed is one error naming ``field``."""
    text = read_text(field, path)
    if len(text) > MAX_URDF_BYTES:
        raise HydroarmError(field, f"{path.name}: larger than {MAX_URDF_BYTES} bytes")
    return urdf_from_text(text, path.name, field)


def urdf_from_text(
    text: str, source: str, field: str = f"{PREFIX}.urdf"
) -> tuple[tuple, tuple, str, tuple]:
    """(links, joints, robot name, couplings) of a URDF document (see `read_urdf`); a
    joint's ``<mimic joint multiplier offset>`` is a `Coupling` (multiplier 1 and
    offset 0 when absent, as URDF's)."""
    try:
        with _quiet_parser():
            robot = urdf_model.URDF.from_xml_string(text.encode())
    except Exception as exc:  # lxml and urdf_parser_py raise many kinds
        problem = " ".join(str(exc).split()) or type(exc).__name__
        raise HydroarmError(field, f"{source}: not a readable URDF ({problem[:200]})") from None
    links = []
    for link in robot.links:
        inertial = link.inertial
        if inertial is None or inertial.mass is None:
            links.append(Link(name=link.name))
            continue
        R, xyz = _origin(inertial.origin)
        i3 = inertial.inertia.to_matrix() if inertial.inertia is not None else [[0.0] * 3] * 3
        i3 = R @ i3 @ R.T  # the <inertial><origin rpy> frame into the link's axes
        links.append(
            Link(
                name=link.name,
                mass=float(inertial.mass),
                com=xyz,
                inertia=(i3[0, 0], i3[1, 1], i3[2, 2], i3[0, 1], i3[0, 2], i3[1, 2]),
            )
        )
    joints = []
    mimics = []
    for j in robot.joints:
        if j.type not in URDF_TYPES:
            raise HydroarmError(
                field,
                f"{source}: joint {j.name!r}: type {j.type!r} is not supported "
                f"({', '.join(sorted(URDF_TYPES))})",
            )
        R, xyz = _origin(j.origin)
        rpy = tuple(j.origin.rpy) if j.origin is not None and j.origin.rpy else ZERO3
        lower, upper = -math.inf, math.inf
        if j.type != "continuous" and j.limit is not None:
            if j.limit.lower is not None:
                lower = float(j.limit.lower)
            if j.limit.upper is not None:
                upper = float(j.limit.upper)
        damping = friction = 0.0
        if j.dynamics is not None:
            damping = float(j.dynamics.damping or 0.0)
            friction = float(j.dynamics.friction or 0.0)
        joints.append(
            Joint(
                name=j.name,
                type=j.type,
                parent=j.parent,
                child=j.child,
                axis=tuple(j.axis) if j.axis is not None else (1.0, 0.0, 0.0),
                origin=xyz,
                rpy=rpy,
                lower=lower,
                upper=upper,
                damping=damping,
                friction=friction,
            )
        )
        if j.mimic is not None:
            mimics.append(
                Coupling(
                    joint=j.name,
                    follows=j.mimic.joint,
                    ratio=1.0 if j.mimic.multiplier is None else float(j.mimic.multiplier),
                    offset=0.0 if j.mimic.offset is None else float(j.mimic.offset),
                )
            )
    return tuple(links), tuple(joints), robot.name or source, tuple(mimics)


def _origin(origin):
    """(rotation, xyz) of a URDF ``<origin>`` (identity when absent)."""
    if origin is None:
        return rpy_matrix(ZERO3), ZERO3
    xyz = tuple(float(x) for x in (origin.xyz or ZERO3))
    rpy = tuple(float(x) for x in (origin.rpy or ZERO3))
    return rpy_matrix(rpy), xyz
