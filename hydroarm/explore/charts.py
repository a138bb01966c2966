"""ECharts options built on the server and sent to the browser as data (no pictures): the
stacked time panels that the single-joint view and the system page both draw."""

from __future__ import annotations

import numpy as np


def rounded(v) -> float:
    """A float with 6 significant digits (what the browser is sent)."""
    return float(f"{float(v):.6g}")


def time_panels(
    t,
    panels: list[tuple[str, list[tuple[str, np.ndarray]]]],
    *,
    top: int,
    height: int,
    step: int,
    time_name: str,
    max_points: int,
) -> dict:
    """The grids, axes and series of curves against time ``t`` [s], one panel per entry of
    ``panels`` (its y axis's name, then its curves as (name, values) pairs), stacked from
    ``top`` [px] every ``step`` px, each ``height`` px high, the time axis named and labelled
    under the last one; at most ``max_points`` points a curve, evenly spaced. Returns the
    keys ``grid``, ``xAxis``, ``yAxis``, ``series``, ``axisPointer`` and ``dataZoom`` of an
    ECharts option (linked cursors, zoom with the wheel)."""
    t = np.asarray(t)
    idx = np.unique(np.linspace(0, len(t) - 1, min(len(t), max_points)).astype(int))
    grids, xs, ys, series = [], [], [], []
    last = len(panels) - 1
    for i, (axis_name, curves) in enumerate(panels):
        grids.append({"left": 64, "right": 16, "top": top + i * step, "height": height})
        xs.append(
            {
                "type": "value",
                "gridIndex": i,
                "min": rounded(t[0]),
                "max": rounded(t[-1]),
                "name": time_name if i == last else "",
                "nameLocation": "middle",
                "nameGap": 24,
                "axisLabel": {"show": i == last},
            }
        )
        ys.append({"type": "value", "gridIndex": i, "name": axis_name, "scale": True})
        for name, v in curves:
            series.append(
                {
                    "name": name,
                    "type": "line",
                    "showSymbol": False,
                    "xAxisIndex": i,
                    "yAxisIndex": i,
                    "data": [[rounded(t[k]), rounded(v[k])] for k in idx],
                }
            )
    return {
        "axisPointer": {"link": [{"xAxisIndex": "all"}]},
        "dataZoom": [{"type": "inside", "xAxisIndex": list(range(len(xs)))}],
        "grid": grids,
        "xAxis": xs,
        "yAxis": ys,
        "series": series,
    }
