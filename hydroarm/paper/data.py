"""The paper's published tables and measurements, read from ``hydroarm/data/paper``."""

from __future__ import annotations

from ..io.catalog import read_data_csv


def published_table(name: str) -> list[dict]:
    """A published table (``table1``, ``table2``, ``table3``) as printed."""
    rows = read_data_csv(f"paper/{name}.csv")
    return [{k: (int(v) if k == "load" else float(v)) for k, v in r.items()} for r in rows]
