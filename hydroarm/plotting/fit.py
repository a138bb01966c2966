"""Figures of a fit (hydroarm.analysis.fit): measured against fitted, with residuals."""

from __future__ import annotations

from .joint import _plt

# a trace's column -> (quantity, unit) for the axes
COLUMN_LABELS = {
    "x_mm": ("jack position x", "mm"),
    "theta_deg": ("angle θ₂", "deg"),
    "p_bar": ("load pressure p", "bar"),
    "position_m": ("position", "m"),
    "angle_deg": ("angle", "deg"),
}


def fit_trace_figure(t, measured, fitted, column: str, *, title=None):
    """One trace: the measured samples and the fitted model [in the column's unit] against
    time [s], and their difference below."""
    plt = _plt()
    name, unit = COLUMN_LABELS.get(column, (column, ""))
    suffix = f" [{unit}]" if unit else ""
    fig, (ax, axr) = plt.subplots(2, 1, sharex=True, figsize=(7, 5), height_ratios=(3, 1))
    ax.plot(t, measured, ".", ms=3, label="measured")
    ax.plot(t, fitted, "-", label="fitted")
    ax.set_ylabel(name + suffix)
    if title:
        ax.set_title(title)
    ax.legend()
    axr.plot(t, measured - fitted, ".", ms=2)
    axr.axhline(0.0, color="0.6", lw=0.8)
    axr.set_ylabel("residual" + suffix)
    axr.set_xlabel("time [s]")
    for a in (ax, axr):
        a.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig
