"""The paper's built-in data: loads 1–10, published tables, the shoulder-elevation joint."""

from __future__ import annotations

import csv
import io
from functools import lru_cache
from importlib import resources

from ..core.joint import Load, ServoJoint
from ..errors import HydroarmError

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
    """Load ``number`` (1–10) of Appendix I in SI units."""
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
    """No gravity load; inertia of the piston (m = 0.227 kg) referred to the joint, m·(r/n)²."""
    return Load(
        weight=0.0,
        arm=0.0,
        inertia=piston_mass * (joint.crank_radius / joint.gear_ratio) ** 2,
        name="no load",
    )


def shoulder_elevation(parameter_set: str = DEFAULT_SET) -> ServoJoint:
    """The paper's shoulder-elevation joint (a built-in parameter set)."""
    from .loader import parameter_set as _ps

    return _ps(parameter_set)


def published_table(name: str) -> list[dict]:
    """A published table (``table1``, ``table2``, ``table3``) as printed."""
    rows = read_data_csv(f"paper/{name}.csv")
    return [{k: (int(v) if k == "load" else float(v)) for k, v in r.items()} for r in rows]
