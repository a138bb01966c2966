"""Pint quantities where the model takes numbers (issue 33): ``joint.replace(supply_pressure=
30 * ureg.bar)``. The model does not import pint (only hydroarm.io parses units): a value that
behaves as a pint quantity (``magnitude`` and ``to``) is converted by its own methods to the
field's SI unit, and one of another dimension is refused with the field's name."""

from __future__ import annotations

from ..errors import HydroarmError

# the unit texts of the model's tables (hydroarm.core.servo.PARAMETERS, the joint's fields)
# written as pint reads them; "unit" (a position's or an angle's unit, per servo) goes to SI
# base units unchecked
PINT_UNITS = {
    "-": "dimensionless",
    "m/m": "dimensionless",
    "N m": "N*m",
    "N s/m": "N*s/m",
    "Pa¹ᐟ² s/m³": "Pa**0.5*s/m**3",
    "Pa⁻¹ᐟ² s/m³": "Pa**-0.5*s/m**3",
    "m²": "m**2",
    "m² s⁻¹ Pa⁻¹ᐟ²": "m**2/s/Pa**0.5",
    "m³": "m**3",
    "m³ s⁻¹ Pa⁻¹ᐟ²": "m**3/s/Pa**0.5",
    "m³/(s Pa)": "m**3/s/Pa",
    "m³/s": "m**3/s",
    "kg m²": "kg*m**2",
}


def is_quantity(value) -> bool:
    return hasattr(value, "magnitude") and hasattr(value, "to") and hasattr(value, "units")


def plain(field: str, value, unit: str):
    """``value`` as a number in the SI ``unit`` (a text of the model's tables) when it is a
    pint quantity; anything else unchanged (the model's own checks follow)."""
    if not is_quantity(value):
        return value
    try:
        if "unit" in unit.replace("units", ""):
            q = value.to_base_units()
        else:
            q = value.to(PINT_UNITS.get(unit, unit))
        return float(q.magnitude)
    except Exception as exc:  # pint's DimensionalityError, an unknown unit
        raise HydroarmError(
            field, f"{value} is not a quantity in {unit} ({type(exc).__name__})"
        ) from None
