"""Validation rules of joint and load fields, in one place.

[`ServoJoint`][hydroarm.ServoJoint] and [`Load`][hydroarm.Load] check
themselves with these rules; the file readers (`hydroarm.io.sections`) use the same
sign rules when they parse a value, and sweeps check their Monte Carlo rows, possibly 10⁶
of them, with `check_rows`, vectorised, reporting the first bad row.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import HydroarmError, check_number

POSITIVE = "positive"
NONNEGATIVE = "nonnegative"
FINITE = "finite"

# field -> (section it is reported under by default, sign rule)
FIELD_RULES: dict[str, tuple[str, str]] = {
    "piston_area": ("joint", POSITIVE),
    "flow_coefficient": ("joint", POSITIVE),
    "valve_saturation": ("joint", POSITIVE),
    "leakage_coefficient": ("joint", NONNEGATIVE),
    "trapped_volume": ("joint", POSITIVE),
    "hydraulic_stiffness": ("joint", POSITIVE),  # files only: gives the trapped volume
    "bulk_modulus": ("joint", POSITIVE),
    "supply_pressure": ("joint", POSITIVE),
    "crank_radius": ("joint", POSITIVE),
    "gear_ratio": ("joint", POSITIVE),
    "horizontal_angle": ("joint", FINITE),
    "transition_pressure": ("physics", POSITIVE),
    "atmospheric_pressure": ("physics", NONNEGATIVE),
    "coulomb_friction": ("physics", NONNEGATIVE),
    "static_friction": ("physics", NONNEGATIVE),
    "viscous_friction": ("physics", NONNEGATIVE),
    "gearbox_friction_torque": ("physics", NONNEGATIVE),
    "gearbox_loss_at_stall": ("physics", NONNEGATIVE),
    "gearbox_loss_exponent": ("physics", NONNEGATIVE),
    "end_stop_angle": ("physics", POSITIVE),
    "backlash": ("physics", NONNEGATIVE),
    "null_leakage_coefficient": ("physics", NONNEGATIVE),
    "weight": ("load", NONNEGATIVE),
    "arm": ("load", NONNEGATIVE),
    "inertia": ("load", POSITIVE),
}
# fields that may be None (off)
OPTIONAL_FIELDS = frozenset({"static_friction", "end_stop_angle"})


def check_field(name: str, value, field: str | None = None, *, shown=None) -> float:
    """Check one value against its rule; errors name ``field`` (default ``section.name``)."""
    section, rule = FIELD_RULES[name]
    return check_number(
        field or f"{section}.{name}",
        value,
        positive=rule == POSITIVE,
        nonnegative=rule == NONNEGATIVE,
        shown=shown,
    )


@dataclass(frozen=True)
class CrossRule:
    """A rule between fields: ``ok(values)`` works on floats and on numpy columns alike."""

    field: str  # the field the error names
    needs: tuple  # the fields it reads
    ok: Callable[[dict], Any]  # bool, or a bool array for columns
    problem: str


CROSS_RULES = (
    CrossRule(
        "static_friction",
        ("static_friction", "coulomb_friction"),
        lambda v: v["static_friction"] >= v["coulomb_friction"],
        "must not be below the Coulomb friction",
    ),
    CrossRule(
        "gearbox_loss_at_stall",
        ("gearbox_loss_at_stall",),
        lambda v: v["gearbox_loss_at_stall"] < 1.0,
        "must be below 1",
    ),
    CrossRule(
        "end_stop_angle",
        ("end_stop_angle", "gear_ratio"),
        lambda v: v["end_stop_angle"] < v["gear_ratio"] * math.pi / 2.0,
        "is beyond the crank's reach (n·90°)",
    ),
)


def check_object(obj, names) -> None:
    """Check the fields ``names`` of a joint or load and the cross rules among them."""
    values = {}
    for name in names:
        v = getattr(obj, name)
        if v is None and name in OPTIONAL_FIELDS:
            continue
        values[name] = check_field(name, v)
    for rule in CROSS_RULES:
        if all(k in values for k in rule.needs) and not rule.ok(values):
            raise HydroarmError(f"{FIELD_RULES[rule.field][0]}.{rule.field}", rule.problem)


def check_rows(columns: dict, varied: dict) -> None:
    """Vectorised check of many scenarios' values.

    ``columns``: field -> float (the same in every row) or 1-D array (one value per row);
    ``varied``: the fields that vary -> the name errors give them (``"monte_carlo.weight"``).
    Raises a [`HydroarmError`][hydroarm.HydroarmError] for the first bad row: ``monte_carlo.weight:
    row 17: must not be negative, got -0.3``.
    """
    for name, field in varied.items():
        if name not in FIELD_RULES:
            continue
        col = np.asarray(columns[name], dtype=float)
        _, rule = FIELD_RULES[name]
        bad = ~np.isfinite(col)
        if rule == POSITIVE:
            bad |= ~(col > 0)
        elif rule == NONNEGATIVE:
            bad |= col < 0
        if np.any(bad):
            row = int(np.argmax(bad))
            try:
                check_field(name, float(col[row]))
            except HydroarmError as exc:
                raise HydroarmError(field, f"row {row}: {exc.problem}") from None
    for cross in CROSS_RULES:
        moved = [k for k in cross.needs if k in varied]
        if not moved or any(columns.get(k) is None for k in cross.needs):
            continue
        ok = np.asarray(cross.ok(columns))
        if not np.all(ok):
            row = int(np.argmax(~np.broadcast_to(ok, np.shape(columns[moved[0]]))))
            if cross.field in varied:
                raise HydroarmError(varied[cross.field], f"row {row}: {cross.problem}")
            problem = f"{cross.field.replace('_', ' ')} {cross.problem}"
            raise HydroarmError(varied[moved[0]], f"row {row}: {problem}")
