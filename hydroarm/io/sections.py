"""Section and value readers shared by scenario, arm and sweep files.

Every reader takes the dotted path of what it reads (``joint.supply_pressure``,
``inputs.elbow_reach.end``, ``scenario.solver.step``) and reports a bad value as a
[`HydroarmError`][hydroarm.HydroarmError] naming that path, which the CLI prints as one line
``hydroarm: error: <field>: <problem>`` (exit status 2). So the same bad value gives the same
problem text in every kind of file; only the path differs with where the section sits.
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import tomllib
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import HydroarmError, check_number
from ..files import checked_path, shown_path
from ..metrics.step import MetricOptions
from ..model.joint import ServoJoint
from ..model.rules import CROSS_RULES, FIELD_RULES, NONNEGATIVE, POSITIVE
from .catalog import parameter_set_tables
from .units import length_or_angle, quantity

# joint fields -> dimension; the sign rules come from hydroarm.model.rules.FIELD_RULES
JOINT_KEYS = {
    "piston_area": "area",
    "flow_coefficient": "flow_coefficient",
    "valve_saturation": "length",
    "leakage_coefficient": "leakage",
    "trapped_volume": "volume",
    "hydraulic_stiffness": "stiffness",
    "bulk_modulus": "pressure",
    "supply_pressure": "pressure",
    "crank_radius": "length",
    "gear_ratio": "dimensionless",
    "horizontal_angle": "angle",
}
JOINT_TEXT_KEYS = {"torque_arm", "name", "parameter_set", "description", "base", "source"}
# physics options (docs/physics.md): in a [physics] section, a [joint] table or a parameter set
PHYSICS_KEYS = {
    "transition_pressure": "pressure",
    "atmospheric_pressure": "pressure",
    "coulomb_friction": "force",
    "static_friction": "force",
    "viscous_friction": "viscous",
    "gearbox_friction_torque": "torque",
    "gearbox_loss_at_stall": "dimensionless",
    "gearbox_loss_exponent": "dimensionless",
    "end_stop_angle": "angle",
    "backlash": "angle",
    "null_leakage_coefficient": "leakage",
}
PHYSICS_TEXT_KEYS = {"valve_model", "torque_arm"}
LOAD_KEYS = {"weight": "force", "arm": "length", "inertia": "inertia"}
FIELD_DIMENSIONS = {**JOINT_KEYS, **PHYSICS_KEYS, **LOAD_KEYS}
REQUIRED_JOINT_KEYS = (
    "piston_area",
    "flow_coefficient",
    "valve_saturation",
    "leakage_coefficient",
    "trapped_volume",
    "bulk_modulus",
    "supply_pressure",
    "crank_radius",
    "gear_ratio",
)
SOLVER_KEYS = {"method", "step", "duration", "record_every"}
METRIC_KEYS = ("middle", "threshold", "stall_tolerance")


def dotted(section: str, key: str) -> str:
    return f"{section}.{key}" if section else key


# ------------------------------------------------------------------------ files ---
MAX_NESTING = 32  # tables and arrays inside each other in an input file
MAX_FILE_BYTES = 256 * 2**20  # an input file (config or trace)
# data rows of one CSV table (a trace, a lever or reference table, an arm's moves): 10⁷ rows
# of a few columns are under 1 GB as floats, and this reader's per-row loop takes about a
# minute; a 256 MiB file of short rows would hold 6·10⁷
MAX_CSV_ROWS = 10**7


def did_you_mean(name, known) -> str:
    """``did you mean 'x'?`` for a close match of ``name`` among ``known``, or the list."""
    known = [str(k) for k in known]
    close = difflib.get_close_matches(str(name), known, n=1) if isinstance(name, str) else []
    if close:
        return f"did you mean {close[0]!r}? (known: {', '.join(known)})"
    return f"known: {', '.join(known)}"


def unknown_name(field: str, what: str, name, known) -> HydroarmError:
    """``<field>: unknown <what> 'x'; did you mean 'y'? (known: ...)``."""
    return HydroarmError(field, f"unknown {what} {name!r}; {did_you_mean(name, known)}")


def read_text_file(path) -> tuple[str, Path]:
    """(text, path) of a UTF-8 input file (a byte-order mark is allowed), or a one-line
    error naming it: missing, a folder, unreadable, binary or not UTF-8."""
    path = Path(path)
    return read_text(shown_path(path), path), path


def read_text(field: str, path: Path) -> str:
    """The text of the UTF-8 file ``path``; errors name ``field``. The path passes
    `hydroarm.files.checked_path` first (NUL, over-long names, symbolic-link loops)."""
    path = Path(path)
    name = shown_path(path)
    where = f"{name}: " if field != name else ""
    checked_path(field, path)
    if path.is_dir():
        raise HydroarmError(field, f"{where}is a folder, not a file")
    if not path.exists():
        raise HydroarmError(field, f"{where}file not found")
    if not path.is_file():
        raise HydroarmError(field, f"{where}not a regular file")
    try:
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise HydroarmError(
                field,
                f"{where}{size / 2**20:.0f} MiB is too large (at most "
                f"{MAX_FILE_BYTES // 2**20} MiB)",
            )
        data = path.read_bytes()
    except PermissionError:
        raise HydroarmError(field, f"{where}permission denied (cannot read the file)") from None
    except OSError as exc:
        raise HydroarmError(field, f"{where}cannot read ({exc.strerror or exc})") from None
    if b"\0" in data:
        raise HydroarmError(field, f"{where}a binary file, not text")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise HydroarmError(
            field, f"{where}not UTF-8 text (byte {exc.start + 1}); save it as UTF-8"
        ) from None


def _depth(v, level: int = 0) -> int:
    if level > MAX_NESTING:
        return level
    if isinstance(v, dict):
        return max((_depth(x, level + 1) for x in v.values()), default=level + 1)
    if isinstance(v, list):
        return max((_depth(x, level + 1) for x in v), default=level + 1)
    return level


def parse_toml(text: str, source: str) -> dict:
    """A TOML document, or ``<source>: malformed TOML (...)``."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise HydroarmError(source, f"malformed TOML ({exc})") from None
    except RecursionError:
        raise HydroarmError(
            source, f"tables or arrays nested too deeply (at most {MAX_NESTING} levels)"
        ) from None
    if _depth(doc) > MAX_NESTING:
        raise HydroarmError(
            source, f"tables or arrays nested too deeply (at most {MAX_NESTING} levels)"
        )
    return doc


def read_toml_file(path) -> tuple[dict, Path]:
    """(document, path) of a TOML input file."""
    text, path = read_text_file(path)
    return parse_toml(text, path.name), path


@contextmanager
def within(prefix: str):
    """Errors raised inside name their field under ``prefix`` (a nested section)."""
    try:
        yield
    except HydroarmError as exc:
        if exc.field and not exc.field.startswith(prefix + "."):
            exc.field = f"{prefix}.{exc.field}"
            exc.args = (f"{exc.field}: {exc.problem}",)
        raise


# ----------------------------------------------------------------------- tables ---
def as_table(field: str, value) -> dict:
    if not isinstance(value, dict):
        raise HydroarmError(field, "must be a table")
    return value


def require_table(doc: dict, key: str, section: str = "") -> dict:
    field = dotted(section, key)
    if key not in doc:
        raise HydroarmError(field, "section is missing")
    return as_table(field, doc[key])


def optional_table(doc: dict, key: str, section: str = "", default=None) -> dict:
    return as_table(dotted(section, key), doc.get(key, {} if default is None else default))


def reject_unknown_keys(section: str, table: dict, allowed) -> None:
    """An unknown key: ``unknown key; did you mean 'x'? (allowed: ...)``."""
    for k in table:
        if k not in allowed:
            names = sorted(allowed)
            close = difflib.get_close_matches(k, names, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise HydroarmError(
                dotted(section, k), f"unknown key{hint} (allowed: {', '.join(names)})"
            )


def require_keys(section: str, table: dict, keys, hint: str = "") -> None:
    for k in keys:
        if k not in table:
            raise HydroarmError(dotted(section, k), "is missing" + (f" ({hint})" if hint else ""))


def text_value(field: str, value, choices=None) -> str:
    if not isinstance(value, str):
        raise HydroarmError(field, "must be a string")
    if choices is not None and value not in choices:
        close = difflib.get_close_matches(value, list(choices), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise HydroarmError(field, f"must be one of {', '.join(choices)}, got {value!r}{hint}")
    return value


# ----------------------------------------------------------------------- values ---
def number_or_quantity(
    field: str, value, dimension: str, *, positive: bool = False, nonnegative: bool = False
) -> float:
    """A quantity with a unit, or for a dimensionless field also a plain number, in SI."""
    if dimension == "dimensionless" and isinstance(value, (int, float)):
        if not isinstance(value, bool):
            value = float(value)
        return check_number(field, value, positive=positive, nonnegative=nonnegative)
    return quantity(field, value, dimension, positive=positive, nonnegative=nonnegative)


def field_value(field: str, key: str, value) -> float:
    """A joint, physics or load field (``key``) with its dimension and sign rule."""
    rule = FIELD_RULES[key][1]
    return number_or_quantity(
        field,
        value,
        FIELD_DIMENSIONS[key],
        positive=rule == POSITIVE,
        nonnegative=rule == NONNEGATIVE,
    )


def whole_number(
    field: str, value, minimum: int = 1, maximum: int | None = None, why: str = ""
) -> int:
    """A whole number ≥ ``minimum``; ≤ ``maximum`` when given (a size budget: ``why`` says
    what it bounds, in the message)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise HydroarmError(field, f"must be a whole number ≥ {minimum}, got {value!r}")
    if maximum is not None and value > maximum:
        raise HydroarmError(
            field, f"{value} is above the budget of {maximum}" + (f" ({why})" if why else "")
        )
    return value


def angle_value(field: str, value) -> float:
    return quantity(field, value, "angle")


def time_value(field: str, value, *, positive: bool = False) -> float:
    """A time [s]; not negative (positive with ``positive``)."""
    return quantity(field, value, "time", positive=positive, nonnegative=not positive)


def ramp_times(section: str, table: dict) -> tuple[float, float]:
    """``start`` (default 0 s) and ``end`` of a ramp; end after start."""
    require_keys(section, table, ("end",))
    t0 = time_value(f"{section}.start", table.get("start", "0 s"))
    t1 = time_value(f"{section}.end", table["end"], positive=True)
    if not t1 > t0:
        raise HydroarmError(f"{section}.end", "must be after start")
    return t0, t1


def position_value(field: str, value, joint: ServoJoint) -> float:
    """A lever/jack position [m] given as a length or as a joint angle."""
    kind, v = length_or_angle(field, value)
    if kind == "angle":
        if abs(v) >= joint.max_angle:
            raise HydroarmError(field, "is beyond the crank's reach")
        return joint.jack_position(v)
    if abs(v) > joint.crank_radius:
        raise HydroarmError(field, "is beyond the crank radius")
    return v


def solver_values(section: str, table: dict, methods) -> dict:
    """The given entries of a ``[solver]`` table (method, step, duration, record_every)."""
    reject_unknown_keys(section, table, SOLVER_KEYS)
    kw: dict[str, Any] = {}
    if "method" in table:
        kw["method"] = text_value(f"{section}.method", table["method"], methods)
    for k in ("step", "duration"):
        if k in table:
            kw[k] = time_value(f"{section}.{k}", table[k], positive=True)
    if "record_every" in table:
        kw["record_every"] = whole_number(f"{section}.record_every", table["record_every"])
    return kw


MAX_STEPS = 10**8  # integration steps of one run
MAX_RECORDED = 10**7  # rows of one run's time series


def check_run_size(
    duration: float,
    step: float,
    record_every: int | None,
    *,
    duration_field: str = "solver.duration",
    record_field: str = "solver.record_every",
    steps: str = "steps",
) -> None:
    """Refuse a run too long to finish or to hold in memory, or one that keeps fewer than the
    3 points the metrics need, naming the field to change. ``record_every`` None: a run that
    keeps no trace (a sweep's scenario: metrics on the fly), only its steps are checked."""
    n = int(round(duration / step))
    if n > MAX_STEPS:
        raise HydroarmError(
            duration_field,
            f"{duration:.4g} s at a step of {step:.4g} s is {n:.3g} {steps} (at most "
            f"{MAX_STEPS:.0e}); shorten the duration or lengthen the step",
        )
    if n < 2:
        raise HydroarmError(
            duration_field,
            f"{duration:.4g} s at a step of {step:.4g} s is {n} of the "
            f"at least 2 {steps} a run needs",
        )
    if record_every is None:
        return
    if n // record_every > MAX_RECORDED:
        raise HydroarmError(
            record_field,
            f"keeps {n // record_every:.3g} of {n:.3g} {steps} (at most {MAX_RECORDED:.0e}); "
            f"keep every {-(-n // MAX_RECORDED)}-th step or fewer",
        )
    if n // record_every + 1 < 3:
        raise HydroarmError(
            record_field,
            f"{record_every} keeps fewer than 3 points of the run's {n} {steps}; "
            f"give at most {n // 2}",
        )


def metric_options(section: str, table: dict) -> MetricOptions:
    """A ``[metrics]`` table: middle, threshold, stall_tolerance (fractions)."""
    reject_unknown_keys(section, table, METRIC_KEYS)
    kw = {
        k: number_or_quantity(f"{section}.{k}", table[k], "dimensionless", positive=True)
        for k in METRIC_KEYS
        if k in table
    }
    try:
        return MetricOptions(**kw)
    except HydroarmError as exc:  # "metrics.middle" -> the section's own path
        raise HydroarmError(dotted(section, exc.field.split(".")[-1]), exc.problem) from None


# -------------------------------------------------------------------- CSV files ---
def read_csv_columns(field: str, path: Path, columns=None) -> dict:
    """Columns (name -> float array) of a CSV file with a header line; ``#`` lines skipped.

    ``columns``: the columns needed (default: all, every one numeric).
    """
    path = Path(path)
    text = read_text(field, path)
    try:
        rows = [(n, r) for n, r in enumerate(csv.reader(io.StringIO(text, newline="")), start=1)]
    except csv.Error as exc:
        raise HydroarmError(field, f"{path.name}: not a readable CSV file ({exc})") from None
    rows = [(n, r) for n, r in rows if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise HydroarmError(field, f"{path.name} is empty")
    header = [h.strip() for h in rows[0][1]]
    if len(rows) < 2:
        raise HydroarmError(field, f"{path.name} has no data rows")
    if len(rows) - 1 > MAX_CSV_ROWS:
        raise HydroarmError(
            field,
            f"{path.name}: {len(rows) - 1} data rows are above the budget of {MAX_CSV_ROWS} "
            "(keep every k-th row)",
        )
    wanted = header if columns is None else list(columns)
    for c in wanted:
        if c not in header:
            raise HydroarmError(
                field, f"{path.name} has no column {c!r} (columns: {', '.join(header)})"
            )
    idx = [header.index(c) for c in wanted]
    data = np.empty((len(rows) - 1, len(idx)))
    for k, (n, r) in enumerate(rows[1:]):
        if len(r) != len(header):
            raise HydroarmError(
                field, f"{path.name} line {n}: {len(r)} values for {len(header)} columns"
            )
        try:
            data[k] = [float(r[i]) for i in idx]
        except ValueError:
            raise HydroarmError(field, f"{path.name} line {n}: not a number") from None
    return {c: data[:, i] for i, c in enumerate(wanted)}


def check_times(field: str, name: str, times: np.ndarray) -> np.ndarray:
    """Times of a trace: finite and not decreasing."""
    if not np.all(np.isfinite(times)) or np.any(np.diff(times) < 0):
        raise HydroarmError(field, f"{name}: times must be finite and not decrease")
    return times


# ----------------------------------------------------------------------- joints ---
def joint_values(section: str, table: dict, *, physics_only: bool = False) -> dict:
    """Parse joint (and physics) fields with units into SI floats (no defaults applied)."""
    allowed = set(PHYSICS_KEYS) | PHYSICS_TEXT_KEYS
    if not physics_only:
        allowed |= set(JOINT_KEYS) | JOINT_TEXT_KEYS
    reject_unknown_keys(section, table, allowed)
    out: dict = {}
    for key, val in table.items():
        field = f"{section}.{key}"
        if key in JOINT_TEXT_KEYS or key in PHYSICS_TEXT_KEYS:
            out[key] = text_value(field, val)
        else:
            out[key] = field_value(field, key, val)
    return out


def parameter_set_values(name: str, field: str = "joint.parameter_set") -> dict:
    """SI values of a built-in parameter set (``paper-printed``, ``paper-calibrated``…)."""
    sets = parameter_set_tables()
    if not isinstance(name, str) or name not in sets:
        raise unknown_name(field, "parameter set", name, sets)
    raw = dict(sets[name])
    values: dict = {}
    base = raw.get("base")
    if base:
        values.update(parameter_set_values(base, field))
    mine = joint_values(f"parameter_set.{name}", raw)
    if "trapped_volume" in mine or "hydraulic_stiffness" in mine:
        values.pop("trapped_volume", None)
    values.update(mine)
    values["name"] = name
    # resolve V = β·A²/λ_o once, so that a later override of β or A keeps the set's volume
    lam = values.pop("hydraulic_stiffness", None)
    if lam is not None and "trapped_volume" not in values:
        values["trapped_volume"] = values["bulk_modulus"] * values["piston_area"] ** 2 / lam
    return values


def build_joint(values: dict, section: str = "joint", origin: dict | None = None) -> ServoJoint:
    """ServoJoint from parsed SI values; V may be given as hydraulic stiffness β·A²/V.

    ``origin``: field -> the section it was read from, so that ServoJoint's own errors
    (``physics.static_friction``) name the path in the file; default ``section``.
    """
    origin = origin or {}
    v = dict(values)
    for k in ("parameter_set", "description", "base", "source"):
        v.pop(k, None)
    lam = v.pop("hydraulic_stiffness", None)
    if lam is not None and "trapped_volume" not in v:  # an explicit volume wins
        try:
            v["trapped_volume"] = v["bulk_modulus"] * v["piston_area"] ** 2 / lam
        except KeyError as exc:
            where = origin.get("hydraulic_stiffness", section)
            raise HydroarmError(
                f"{where}.hydraulic_stiffness", f"needs {exc.args[0]} to give the trapped volume"
            ) from None
    for k in REQUIRED_JOINT_KEYS:
        if k not in v:
            raise HydroarmError(f"{section}.{k}", "is missing")
    try:
        return ServoJoint(**v)
    except HydroarmError as exc:
        key = exc.field.rsplit(".", 1)[-1]
        if key not in origin:  # a rule between fields: name the one this file gave
            for rule in CROSS_RULES:
                given = [k for k in rule.needs if k in origin]
                if rule.field == key and given:
                    problem = f"{key.replace('_', ' ')} {exc.problem}"
                    raise HydroarmError(f"{origin[given[0]]}.{given[0]}", problem) from None
        raise HydroarmError(f"{origin.get(key, section)}.{key}", exc.problem) from None


def joint_from_table(
    section: str,
    table: dict,
    *,
    default_set: str,
    physics: dict | None = None,
    physics_section: str = "physics",
    name: str | None = None,
    base_dir: Path | None = None,
) -> ServoJoint:
    """The joint of a ``[joint]`` table (scenario and sweep files) or ``[joints.<name>]``
    table (arm files): a ``parameter_set`` (default ``default_set``) or the ``[joint]`` table
    of a ``file`` (e.g. the ``fitted.toml`` of ``hydroarm fit``, relative to ``base_dir``),
    with any joint or physics field overridden, plus an optional separate physics table."""
    table = dict(table)
    source = table.pop("file", None)
    if source is not None and "parameter_set" in table:
        raise HydroarmError(f"{section}.file", "give a file or a parameter_set, not both")
    vals = joint_values(section, table)
    origin = dict.fromkeys(vals, section)
    if physics is not None:
        phys = joint_values(physics_section, physics, physics_only=True)
        vals.update(phys)
        origin.update(dict.fromkeys(phys, physics_section))
    if source is not None:
        values = joint_file_values(f"{section}.file", source, base_dir, default_set)
    else:
        base = vals.pop("parameter_set", default_set)
        values = parameter_set_values(base, f"{section}.parameter_set")
    if "hydraulic_stiffness" in vals and "trapped_volume" not in vals:
        values.pop("trapped_volume", None)  # the file gives V through the stiffness
    values.update(vals)
    if name is not None:
        values["name"] = name
    return build_joint(values, section, origin)


def joint_file_values(field: str, source, base_dir: Path | None, default_set: str) -> dict:
    """SI values of the ``[joint]`` table of the TOML file ``source`` (its own
    ``parameter_set``, default ``default_set``, with its fields over it)."""
    path = checked_path(field, text_value(field, source), base_dir or ".")
    if not path.is_file():
        raise HydroarmError(field, f"{path.name}: no such file")
    doc = parse_toml(read_text(field, path), f"{field}: {path.name}")
    if not isinstance(doc.get("joint"), dict):
        raise HydroarmError(field, f"{path.name} has no [joint] table")
    sub = f"{path.name}: joint"
    vals = joint_values(sub, doc["joint"])
    values = parameter_set_values(vals.pop("parameter_set", default_set), f"{sub}.parameter_set")
    if "hydraulic_stiffness" in vals and "trapped_volume" not in vals:
        values.pop("trapped_volume", None)
    values.update(vals)
    values["name"] = path.stem
    return values


# ----------------------------------------------------------------------- misc ---
def finite_or_unlimited(field: str, value, dimension: str) -> float:
    """A positive quantity, or ``"unlimited"`` (infinity)."""
    if value == "unlimited":
        return math.inf
    return quantity(field, value, dimension, positive=True)
