"""Unit parsing at the boundary (files and CLI).

Every quantity a user types carries its unit (``"0.469 in**2"``, ``"31 bar"``, ``"10 us"``).
It is converted here, once, to a plain SI float; the numeric core never sees pint.
"""

from __future__ import annotations

from functools import lru_cache

from ..errors import HydroarmError, check_number  # noqa: F401 (re-exported)

# Dimension name -> SI unit the core works in.
SI_UNITS: dict[str, str] = {
    "length": "m",
    "area": "m**2",
    "volume": "m**3",
    "pressure": "Pa",
    "force": "N",
    "mass": "kg",
    "time": "s",
    "inertia": "kg*m**2",
    "angle": "rad",
    "flow_coefficient": "m**2/s/Pa**0.5",
    "leakage": "m**3/s/Pa",
    "velocity": "m/s",
    "torque": "N*m",
    "frequency": "Hz",
    "viscous": "N*s/m",
    "stiffness": "N/m",
    "flow": "m**3/s",
    "dimensionless": "",
}


@lru_cache(maxsize=1)
def registry():
    import pint

    try:  # parsed definitions cached on disk (~/.cache/pint): 0.05 s instead of 0.35 s
        ureg: pint.UnitRegistry = pint.UnitRegistry(cache_folder=":auto:")
    except OSError:  # no writable cache folder
        ureg = pint.UnitRegistry()
    # the paper's abbreviations
    ureg.define("ltr = liter")
    return ureg


def _parse(field: str, value):
    ureg = registry()
    if isinstance(value, bool):
        raise HydroarmError(field, f"expected a quantity with a unit, got {value!r}")
    if isinstance(value, (int, float)):
        raise HydroarmError(
            field, f'{value!r} has no unit; write it with one, e.g. "{value} <unit>"'
        )
    if not isinstance(value, str) or not value.strip():
        raise HydroarmError(field, f"expected a quantity with a unit, got {value!r}")
    text = value.strip().replace("µ", "u").replace("μ", "u")
    try:
        q = ureg.Quantity(text)
    except Exception as exc:  # pint raises many types
        raise HydroarmError(field, f"cannot read {value!r} as a quantity ({exc})") from None
    if not hasattr(q, "units") or str(q.units) == "dimensionless":
        raise HydroarmError(field, f"{value!r} has no unit; write it with one")
    return q


def quantity(
    field: str, value, dimension: str, *, positive: bool = False, nonnegative: bool = False
) -> float:  # noqa: C901
    """Parse ``value`` (``"31 bar"``) as ``dimension`` and return it in SI units.

    Parameters
    ----------
    field : name reported in errors (``"joint.supply_pressure"``)
    value : string with a number and a unit
    dimension : a key of :data:`SI_UNITS`
    positive, nonnegative : sign checks

    Raises
    ------
    HydroarmError
        With a one-line message naming ``field`` and the problem.
    """
    q = _parse(field, value)
    target = SI_UNITS[dimension]
    ureg = registry()
    try:
        si = q.to(target).magnitude if target else q.to("dimensionless").magnitude
    except Exception:
        want = ureg.Quantity(1, target).dimensionality if target else "dimensionless"
        raise HydroarmError(
            field,
            f"{value!r} is not a {dimension.replace('_', ' ')} (has dimension "
            f"{q.dimensionality}, expected {want})",
        ) from None
    si = float(si)
    check_number(field, si, positive=positive, nonnegative=nonnegative, shown=value)
    return si


def length_or_angle(field: str, value) -> tuple[str, float]:
    """Parse a lever/jack position given either as a length or as an arm angle.

    Returns ``("length", metres)`` or ``("angle", radians)``.
    """
    q = _parse(field, value)
    if q.dimensionality == registry().Quantity(1, "m").dimensionality:
        v = float(q.to("m").magnitude)
        check_number(field, v, shown=value)
        return "length", v
    if q.dimensionless and str(q.units) in {
        "degree",
        "radian",
        "arcminute",
        "arcsecond",
        "turn",
        "revolution",
        "grade",
        "gradian",
    }:
        v = float(q.to("rad").magnitude)
        check_number(field, v, shown=value)
        return "angle", v
    raise HydroarmError(field, f"{value!r} is neither a length (jack position) nor an angle")
