"""Figures of a fit (hydroarm.analysis.fit): measured against fitted, with residuals; the
targets' residuals in standard deviations."""

from __future__ import annotations

import numpy as np

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


def fit_targets_figure(names, residuals, predicted=None, *, title=None):
    """Targets: (model − value)/uncertainty [standard deviations] of each target, the fit's
    and, when given (leave one out; NaN where not left out), the prediction's."""
    plt = _plt()
    n = len(names)
    fig, ax = plt.subplots(figsize=(7, 0.45 * n + 1.6))
    y = np.arange(n)
    shift = 0.2 if predicted is not None else 0.0
    ax.barh(y - shift, residuals, height=0.38 if shift else 0.6, label="fit")
    if predicted is not None:
        ax.barh(y + shift, predicted, height=0.38, label="predicted (group left out)")
        ax.legend(fontsize=8, loc="best")
    for k in (1, 2):
        ax.axvspan(-k, k, color="green", alpha=0.06)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_yticks(y, names, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("(model − value) / uncertainty [standard deviations]")
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig
