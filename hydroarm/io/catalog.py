"""Built-in data shipped with hydroarm: the paper's loads 1–10 and the parameter sets.

The parameter sets are read raw here; `hydroarm.io.schema` turns them into joints."""

from __future__ import annotations

import csv
import io
import tomllib
from functools import lru_cache
from importlib import resources

from ..errors import HydroarmError
from ..model.joint import Load, ServoJoint
from .units import quantity

N_MM_S2 = 1e-3  # 1 N·mm·s² = 1e-3 kg·m²
PISTON_MASS = 0.227  # m, "0.227 kg (0.5 lb) (nominal)" of Appendix I [kg]
DEFAULT_SET = "paper-calibrated"


def read_data_csv(name: str) -> list[dict]:
    """Rows of a packaged CSV file (``#`` lines are its header notes)."""
    text = resources.files("hydroarm.data").joinpath(name).read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
    return list(csv.DictReader(io.StringIO("\n".join(lines))))


@lru_cache(maxsize=1)
def loads_table() -> list[dict]:
    """Appendix I loads 1–10 as printed (SI and imperial columns, strings → floats)."""
    rows = read_data_csv("loads.csv")
    return [{k: (int(v) if k == "load" else float(v)) for k, v in r.items()} for r in rows]


def paper_load(number, field: str = "load") -> Load:
    """Load ``number`` (1–10) of Appendix I in SI units.

    Parameters
    ----------
    number : int or str
        The load's number, 1–10.
    field : str
        The field an error names (a file's key, a CLI option).

    Returns
    -------
    Load
        Weight [N], arm [m] and inertia [kg m²] of the load.
    """
    if isinstance(number, bool) or not isinstance(number, (int, str)):
        raise HydroarmError(field, f"must be a load number 1-10, got {number!r}")
    try:
        k = int(number)
    except ValueError:
        raise HydroarmError(field, f"must be a load number 1-10, got {number!r}") from None
    for r in loads_table():
        if r["load"] == k:
            return Load(
                weight=r["W_N"],
                arm=r["X_mm"] * 1e-3,
                inertia=r["I_N_mm_s2"] * N_MM_S2,
                name=f"load {k}",
            )
    raise HydroarmError(field, f"must be a load number 1-10, got {number!r}")


def no_load(joint: ServoJoint, piston_mass: float = PISTON_MASS) -> Load:
    """No gravity load: the inertia of the piston referred to the joint, m·(r/n)².

    Parameters
    ----------
    joint : ServoJoint
        The joint (its crank radius r and gear ratio n).
    piston_mass : float
        Piston mass m [kg] (0.227 kg, the paper's).

    Returns
    -------
    Load
        Weight 0 [N], arm 0 [m], inertia m·(r/n)² [kg m²].
    """
    return Load(
        weight=0.0,
        arm=0.0,
        inertia=piston_mass * (joint.crank_radius / joint.gear_ratio) ** 2,
        name="no load",
    )


@lru_cache(maxsize=1)
def model3_values() -> dict:
    """The Appendix I values of Model 3 in SI, read as ``model3.csv`` says.

    The values come from ``appendix1_parameters.csv`` (the one copy of the print), in the
    column ``model3.csv`` adopts. Returns ``{"m": [kg], "f_o": [N s/m], "lambda_o": [N/m],
    "r": [m], "M": {load: [kg]}}`` (``M``: the printed jack masses only).
    """
    printed = {r["symbol"]: r for r in read_data_csv("appendix1_parameters.csv")}
    out: dict = {"M": {}}
    for row in read_data_csv("model3.csv"):
        sym, col = row["symbol"], row["column"]
        if col not in ("si", "imperial"):
            raise HydroarmError(f"model3.csv.{sym}.column", f"must be si or imperial, got {col!r}")
        p = printed[sym]
        v = quantity(f"model3.{sym}", f"{p[col + '_value']} {p[col + '_unit']}", row["dimension"])
        if row["load"]:
            out["M"][int(row["load"])] = v
        else:
            out[sym] = v
    return out


def _read_package_toml(name: str) -> dict:
    text = resources.files("hydroarm.data").joinpath(name).read_text(encoding="utf-8")
    return tomllib.loads(text)


def parameter_set_tables() -> dict:
    """The raw tables of ``parameter_sets.toml`` (quantities as written, with units)."""
    return _read_package_toml("parameter_sets.toml")


def parameter_set_names() -> list[str]:
    """The names of the built-in joints (``parameter_sets.toml``).

    Returns
    -------
    list of str
        The names [`parameter_set`][hydroarm.parameter_set] takes.
    """
    return list(parameter_set_tables())


def parameter_set_info(name: str) -> dict:
    return dict(parameter_set_tables()[name])
