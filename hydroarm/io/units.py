"""Unit parsing at the boundary (files and CLI).

Every quantity a user types carries its unit (``"0.469 in**2"``, ``"31 bar"``, ``"10 us"``).
It is converted here, once, to a plain SI float; the numeric core never sees pint. The text is
checked before pint evaluates it (`check_expression`: length, characters, one number with a
decimal point, small plain exponents), so no input can make pint hang or allocate without bound.
"""

from __future__ import annotations

import hashlib
import math
import pickle
import re
from functools import lru_cache

from ..errors import HydroarmError, check_number  # noqa: F401 (re-exported)

try:  # pint's own dependency (its cache folder): ours for the cache of this environment
    import platformdirs
except ImportError:  # pragma: no cover
    platformdirs = None  # type: ignore[assignment]

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
    "angular_velocity": "rad/s",
    "torque": "N*m",
    "frequency": "Hz",
    "viscous": "N*s/m",
    "stiffness": "N/m",
    "flow": "m**3/s",
    "flow_per_length": "m**2/s",  # a linearised valve's flow gain
    "density": "kg/m**3",
    "torque_s": "N*m*s",  # rotary damping (per radian)
    "length_per_time": "m/s",  # a controller's integral gain per radian
    "length_time": "m*s",  # a controller's derivative gain per radian
    "energy": "J",
    "charge": "C",
    "voltage": "V",
    "dimensionless": "",
}


def si_suffix(dimension: str) -> str:
    """The SI unit of ``dimension`` (`SI_UNITS`) as a column name ends in SI
    (docs/model.md "Units in names"): ``pressure`` → ``pa``, ``velocity`` → ``m_s``,
    ``volume`` → ``m3``, ``torque`` → ``n_m``, ``leakage`` → ``m3_per_s_per_pa``;
    ``""`` for a dimensionless one."""
    return unit_suffix(SI_UNITS[dimension])


def unit_suffix(unit: str) -> str:
    """A unit in pint's syntax as a column name ends: ``Pa`` → ``pa``, ``m/s`` → ``m_s``,
    ``m**3/s/Pa`` → ``m3_per_s_per_pa``, ``N*m`` → ``n_m``; ``""`` for none."""
    if unit in ("m/s", "rad/s"):
        return unit.replace("/", "_")
    if unit == "m*s":  # not m_s, a velocity's
        return "s_m"
    text = unit.replace("**0.5", "_sqrt").replace("**", "").replace("^", "").replace("*", "_")
    return text.replace("/", "_per_").lower()


# Limits on what reaches pint: it evaluates a unit expression, so "10**10**10 N" would hang.
MAX_QUANTITY_LENGTH = 100
MAX_EXPONENT = 10
MAX_POWERS = 4
_ALLOWED = re.compile(r"[A-Za-z0-9_ \t.+\-*/^()°²³Ω]*")
_NUMBER = r"(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_LEADING_NUMBER = re.compile(rf"[-+]?(?:{_NUMBER}|(?:nan|inf|infinity)(?![A-Za-z]))", re.I)
_POWER = re.compile(r"\*\*|\^")
_EXPONENT = re.compile(rf"\s*(?:[-+]?{_NUMBER}|\(\s*[-+]?{_NUMBER}\s*(?:/\s*{_NUMBER}\s*)?\))")
_TWO_NUMBERS = re.compile(r"[\d.]\s+[-+]?[\d.]")


def check_expression(field: str, value: str, text: str) -> None:
    """Refuse a quantity text that pint should not evaluate (too long, odd characters, a
    decimal comma, two numbers, a large or nested exponent), with a hint."""
    shown = value if len(value) <= 40 else value[:37] + "..."
    if len(text) > MAX_QUANTITY_LENGTH:
        raise HydroarmError(
            field, f"{shown!r} is too long (at most {MAX_QUANTITY_LENGTH} characters)"
        )
    if "," in text:
        raise HydroarmError(
            field, f'cannot read {value!r}: use a decimal point, not a comma (e.g. "18.73 N")'
        )
    if not _ALLOWED.fullmatch(text):
        bad = next(c for c in text if not _ALLOWED.fullmatch(c))
        raise HydroarmError(field, f"cannot read {value!r}: character {bad!r} is not allowed")
    if not _LEADING_NUMBER.match(text):
        raise HydroarmError(
            field, f'cannot read {value!r}: expected a number and a unit, e.g. "31 bar"'
        )
    if _TWO_NUMBERS.search(text):
        raise HydroarmError(
            field,
            f"cannot read {value!r}: two numbers; write one number with a decimal point "
            'and its unit, e.g. "18.73 N"',
        )
    if len(_POWER.findall(text)) > MAX_POWERS:
        raise HydroarmError(field, f"cannot read {value!r}: more than {MAX_POWERS} powers")
    for m in _POWER.finditer(text):
        e = _EXPONENT.match(text, m.end())
        if e is None:
            raise HydroarmError(field, f"cannot read {value!r}: an exponent must be a plain number")
        if _POWER.match(text[e.end() :].lstrip()):
            raise HydroarmError(field, f"cannot read {value!r}: nested powers are not allowed")
        try:
            x = float(eval_exponent(e.group()))
        except (ValueError, ZeroDivisionError):
            raise HydroarmError(field, f"cannot read {value!r}: bad exponent") from None
        if not abs(x) <= MAX_EXPONENT:
            raise HydroarmError(
                field, f"cannot read {value!r}: exponent {x:g} is beyond ±{MAX_EXPONENT}"
            )


def eval_exponent(text: str) -> float:
    """The value of an exponent matched by ``_EXPONENT`` (a number or ``(a/b)``)."""
    t = text.strip().strip("()").replace(" ", "")
    if "/" in t:
        a, b = t.split("/")
        return float(a) / float(b)
    return float(t)


def _pint_cache_folder(pint) -> object:
    """A disk cache of pint's parsed definitions for this pint installation only: pint's own
    ``":auto:"`` folder is shared by every environment, and its entries (keyed by the
    definition file's content) name the file of the environment that wrote them, so another
    environment's entry, once that one is gone, fails to load and the registry is parsed
    twice (0.6 s instead of 0.05 s)."""
    if platformdirs is None:  # pragma: no cover - pint ≥ 0.24 depends on it
        return ":auto:"
    key = hashlib.sha1(f"{pint.__file__}|{pint.__version__}".encode()).hexdigest()[:16]
    return platformdirs.user_cache_path(appname="pint", appauthor=False) / f"hydroarm-{key}"


@lru_cache(maxsize=1)
def registry():
    import pint

    try:  # parsed definitions cached on disk: 0.05 s instead of 0.35 s
        ureg: pint.UnitRegistry = pint.UnitRegistry(cache_folder=_pint_cache_folder(pint))
    except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ValueError):
        # no writable cache folder, or an entry unreadable: half-written by another process
        # building the same cache at the same moment (pint's cache writes are not atomic;
        # two test workers on a fresh install do this), or stale
        ureg = pint.UnitRegistry()
    # the paper's abbreviations
    ureg.define("ltr = liter")
    ureg.define("rev = revolution")  # pump displacements per revolution
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
    check_expression(field, value, text)
    try:
        q = ureg.Quantity(text)
    except Exception as exc:  # pint raises many types
        raise HydroarmError(field, f"cannot read {value!r} as a quantity ({exc})") from None
    number = _LEADING_NUMBER.match(text)
    unit_text = text[number.end() :].strip() if number else text
    if not hasattr(q, "units") or not unit_text:
        # a unit that cancels ("0.02 m/m", a gain) is a unit the user wrote
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
    dimension : a key of `SI_UNITS`
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


ANGLE_UNIT_WORDS = re.compile(
    r"\b(?:radian|degree|turn|revolution|arcminute|arcsecond|grade|gradian)\b"
)


def velocity_or_angular_velocity(field: str, value) -> tuple[str, float]:
    """Parse a velocity given either as a jack velocity (``"26.5 mm/s"``) or as an angular
    velocity (``"2.37 rad/s"``, ``"136 deg/s"``). Returns ``("velocity", m/s)`` or
    ``("angular_velocity", rad/s)``."""
    q = _parse(field, value)
    ureg = registry()
    if q.dimensionality == ureg.Quantity(1, "m/s").dimensionality:
        v = float(q.to("m/s").magnitude)
        check_number(field, v, shown=value)
        return "velocity", v
    if q.dimensionality == ureg.Quantity(1, "1/s").dimensionality and ANGLE_UNIT_WORDS.search(
        str(q.units)
    ):
        v = float(q.to("rad/s").magnitude)
        check_number(field, v, shown=value)
        return "angular_velocity", v
    raise HydroarmError(
        field,
        f'{value!r} is neither a velocity (e.g. "26.5 mm/s") nor an angular velocity '
        '(e.g. "2.37 rad/s")',
    )


def energy_or_charge(field: str, value) -> tuple[str, float]:
    """Parse a battery capacity given either as an energy (``"14.4 W*h"``) or as a charge
    (``"1200 mA*h"``). Returns ``("energy", joules)`` or ``("charge", coulombs)``, positive."""
    q = _parse(field, value)
    ureg = registry()
    for kind in ("energy", "charge"):
        if q.dimensionality == ureg.Quantity(1, SI_UNITS[kind]).dimensionality:
            v = float(q.to(SI_UNITS[kind]).magnitude)
            check_number(field, v, positive=True, shown=value)
            return kind, v
    raise HydroarmError(
        field,
        f'{value!r} is neither an energy (e.g. "14.4 W*h") nor a charge (e.g. "1200 mA*h")',
    )


def value_in(field: str, value, unit: str) -> float:
    """A quantity in the SI ``unit`` of a declaration (``""``: a plain number; ``"*"``: any
    unit, taken in SI base units; plain numbers accepted for both)."""
    if unit in ("", "*") and isinstance(value, int | float) and not isinstance(value, bool):
        return check_number(field, float(value), shown=value)
    if unit == "":
        return quantity(field, value, "dimensionless")
    if isinstance(value, str) and value.strip().lower() in ("inf", "+inf", "-inf"):
        return math.inf if not value.strip().startswith("-") else -math.inf
    q = _parse(field, value)
    try:
        si = q.to_base_units().magnitude if unit == "*" else q.to(unit).magnitude
    except Exception:
        want = registry().Quantity(1, unit).dimensionality
        raise HydroarmError(
            field,
            f"{value!r} is not in units of {unit} (has dimension {q.dimensionality}, "
            f"expected {want})",
        ) from None
    si = float(si)
    if math.isnan(si):
        raise HydroarmError(field, f"{value!r} is not a number")
    return si
