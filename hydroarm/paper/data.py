"""The paper's published tables and measurements, read from ``hydroarm/data/paper``.

One home per datum: every value of the paper that hydroarm uses as an input or compares
against is a row of ``measurements.csv`` (``quantity,value,unit,source``) or a cell of the
published Tables I–III (``table1.csv`` … ``table3.csv``), as printed.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from types import MappingProxyType
from typing import Any

from ..errors import HydroarmError
from ..io.catalog import read_data_csv

NO_LOAD_READINGS = 4  # the four no-load transients of the No Load Transient Test


def published_table(name: str) -> list[dict]:
    """A published table (``table1``, ``table2``, ``table3``) as printed."""
    rows = read_data_csv(f"paper/{name}.csv")
    return [{k: (int(v) if k == "load" else float(v)) for k, v in r.items()} for r in rows]


@lru_cache(maxsize=1)
def measurement_rows() -> tuple[Mapping[str, Any], ...]:
    """The rows of ``measurements.csv`` (value as float), in file order."""
    return tuple(
        MappingProxyType({**r, "value": float(r["value"])})
        for r in read_data_csv("paper/measurements.csv")
    )


@lru_cache(maxsize=1)
def _by_name() -> MappingProxyType:
    return MappingProxyType({r["quantity"]: r["value"] for r in measurement_rows()})


def measurements() -> MappingProxyType:
    """{quantity: value} of every measured value (read-only), in the units of its name."""
    return _by_name()


def measurement(name: str) -> float:
    """The paper's value of ``name`` (a ``quantity`` of ``measurements.csv``)."""
    try:
        return _by_name()[name]
    except KeyError:
        raise HydroarmError("measurement", f"no measured quantity {name!r}") from None


def no_load_time_constants_ms() -> tuple[float, ...]:
    """The four no-load 63 % time constants [ms] as read on the arm: 25, 28, 24, 26."""
    return tuple(
        measurement(f"no_load_time_constant_{i}_ms") for i in range(1, NO_LOAD_READINGS + 1)
    )


def table1() -> dict:
    """Measured Table I velocities {(load, direction): mm/s}."""
    return _cells("table1")


def table3() -> dict:
    """Model 2 Table III velocities {(load, direction): mm/s}."""
    return _cells("table3")


def _cells(name: str) -> dict:
    return {
        (r["load"], d): r[f"{d}_mm_s"] for r in published_table(name) for d in ("raise", "lower")
    }
