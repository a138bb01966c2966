"""How results show themselves (issue 33): a one-line ``repr`` (no arrays) and, in a
notebook, an HTML summary table (``_repr_html_``). A result class derives from
`Summarised` and says what to show in ``_summary()``: (label, value) rows, values
already formatted with their units."""

from __future__ import annotations

import html
import math

import numpy as np

REPR_ROWS = 4  # rows of the summary in the one-line repr
TRACE_ROWS = 12  # trace columns in the HTML table (the rest counted)


def fmt(v, unit: str = "", digits: int = 4) -> str:
    """A number with its unit, ``digits`` significant digits."""
    try:
        f = float(v)
    except (TypeError, ValueError):
        return str(v)
    s = "nan" if math.isnan(f) else f"{f:.{digits}g}"
    return f"{s} {unit}".strip()


def span(t) -> str:
    """``n samples, t0 … t1 s`` of a time vector."""
    t = np.asarray(t)
    if t.size == 0:
        return "no samples"
    return f"{t.size} samples, {fmt(t[0])} … {fmt(t[-1])} s"


def trace_rows(columns: dict, units: dict | None = None) -> list[tuple[str, str, str, str]]:
    """(name, final, min, max) of each 1-D column, formatted."""
    units = units or {}
    rows = []
    for name, v in columns.items():
        a = np.asarray(v, dtype=float)
        if a.ndim != 1 or a.size == 0:
            continue
        u = units.get(name, "")
        finite = a[np.isfinite(a)]
        lo, hi = (finite.min(), finite.max()) if finite.size else (math.nan, math.nan)
        rows.append((name, fmt(a[-1], u), fmt(lo, u), fmt(hi, u)))
    return rows


class Summarised:
    """A short ``__repr__`` and a ``_repr_html_`` summary table from ``_summary()`` (and the
    traces' first, last, min and max from ``_trace_columns()``, when the result has traces)."""

    def _summary(self) -> list[tuple[str, str]]:  # pragma: no cover - each result says
        raise NotImplementedError

    def _trace_columns(self) -> tuple[dict, dict] | None:
        """(columns, units) of the result's traces, or None."""
        return None

    def __repr__(self) -> str:
        rows = self._summary()[:REPR_ROWS]
        return f"{type(self).__name__}(" + ", ".join(f"{k}: {v}" for k, v in rows) + ")"

    def _repr_html_(self) -> str:
        e = html.escape
        out = [
            f"<div><strong>{e(type(self).__name__)}</strong>",
            '<table style="text-align:left">',
        ]
        out += [
            f"<tr><th style='text-align:left'>{e(k)}</th><td style='text-align:left'>{e(v)}"
            "</td></tr>"
            for k, v in self._summary()
        ]
        out.append("</table>")
        traces = self._trace_columns()
        if traces is not None:
            rows = trace_rows(*traces)
            out.append('<table style="text-align:right">')
            out.append("<tr><th>column</th><th>final</th><th>min</th><th>max</th></tr>")
            for r in rows[:TRACE_ROWS]:
                out.append(
                    f"<tr><td style='text-align:left'>{e(r[0])}</td>"
                    + "".join(f"<td>{e(x)}</td>" for x in r[1:])
                    + "</tr>"
                )
            out.append("</table>")
            if len(rows) > TRACE_ROWS:
                out.append(f"<p>… and {len(rows) - TRACE_ROWS} more columns</p>")
        out.append("</div>")
        return "\n".join(out)
