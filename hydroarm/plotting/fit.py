"""Figures of a fit (hydroarm.analysis.fit): measured against fitted, with residuals; the
targets' residuals in standard deviations."""

from __future__ import annotations

import numpy as np

from .joint import _axes, _plt

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


def fit_targets_figure(names, residuals, predicted=None, *, title=None, ax=None):
    """Targets: (model − value)/uncertainty [standard deviations] of each target, the fit's
    and, when given (leave one out; NaN where not left out), the prediction's."""
    n = len(names)
    fig, ax, made = _axes(ax, figsize=(7, 0.45 * n + 1.6))
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
    if made:
        fig.tight_layout()
    return fig


def fit_profile_figure(
    profiles, cost_min: float, delta: float, jacobian=None, *, title=None, units=None
):
    """Profile-likelihood curves (hydroarm.analysis.fit_intervals): per parameter, the
    cost Σr² with the others re-optimised against the value held [SI], the threshold
    C_min + Δ (the 95 % interval's ends where the curve crosses it), the profile's ends and,
    when given (``jacobian``: (low, high) arrays [SI]), the Jacobian's interval;
    ``units``: each parameter's SI unit, shown on its axis."""
    from matplotlib.lines import Line2D

    plt = _plt()
    n = len(profiles)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    for k, pf in enumerate(profiles):
        ax = axes[k // cols][k % cols]
        q = np.where(np.isfinite(pf.q), pf.q, np.nan)
        ax.plot(pf.values, cost_min + q * delta, "o-", ms=3, label="profile")
        ax.axhline(cost_min + delta, color="C3", lw=1, label="threshold C_min + Δ")
        ax.axvline(pf.estimate, color="0.4", lw=0.8)
        for v, why in ((pf.low, pf.low_open), (pf.high, pf.high_open)):
            ax.axvline(v, color="C2", ls="--" if not why else ":", lw=1)
        if jacobian is not None:
            for v in (jacobian[0][k], jacobian[1][k]):
                if np.isfinite(v):
                    ax.axvline(v, color="C1", ls="-.", lw=1)
        unit = (units or {}).get(pf.parameter, "")
        ax.set_xlabel(f"{pf.parameter} [{unit}]" if unit not in ("", "1") else pf.parameter)
        ax.set_ylabel("cost Σr²")
        ax.grid(True, alpha=0.3)
        if k == 0:
            handles = ax.get_legend_handles_labels()[0]
            handles += [
                Line2D([], [], color="C2", ls="--", label="profile 95 % (dotted: open)"),
                Line2D([], [], color="C1", ls="-.", label="Jacobian 95 %"),
            ]
            ax.legend(handles=handles, fontsize=7)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].set_visible(False)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
