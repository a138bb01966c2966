"""Figures of a design study (hydroarm.analysis.design): the Pareto front of pairs of
objectives and the feasible region by pairs of design variables."""

from __future__ import annotations

import itertools
import textwrap

import numpy as np

from .joint import _plt

STYLE = {  # class -> (label, marker, colour, size)
    "infeasible": ("infeasible", "x", "0.65", 14),
    "feasible": ("feasible", "o", "tab:blue", 14),
    "pareto": ("Pareto front", "*", "tab:red", 60),
}


def _classes(feasible, pareto) -> dict:
    feasible = np.asarray(feasible, bool)
    pareto = np.asarray(pareto, bool)
    return {"infeasible": ~feasible, "feasible": feasible & ~pareto, "pareto": pareto}


# SI unit -> (the unit shown, factor): the axes in the units a designer reads
DISPLAY_UNITS = {
    "Pa": ("bar", 1e-5),
    "m**2": ("mm²", 1e6),
    "m^3/s": ("L/min", 6e4),
    "m**3/s": ("L/min", 6e4),
    "s": ("ms", 1e3),
    "m": ("mm", 1e3),
}


def display(unit: str) -> tuple[str, float]:
    """(unit shown, factor from SI) of an SI unit."""
    return DISPLAY_UNITS.get(unit, (unit, 1.0))


def _label(name: str, unit: str) -> str:
    shown = display(unit)[0]
    return f"{name} [{shown}]" if shown else name


def _shown(values, unit: str) -> np.ndarray:
    return np.asarray(values, float) * display(unit)[1]


def _plain_log_ticks(axis) -> None:
    from matplotlib.ticker import NullFormatter

    axis.set_minor_formatter(NullFormatter())


def pareto_figure(values: dict, labels: dict, feasible, pareto, *, title=None):
    """One panel per pair of objectives: each design's worst value over the load cases
    (``values[name]`` [SI unit of ``labels[name] = (quantity, unit)``], shown in bar, mm²,
    L/min, ms where the unit is Pa, m², m³/s, s), infeasible,
    feasible and Pareto designs apart. One objective: its values against the design index."""
    plt = _plt()
    names = list(values)
    pairs = list(itertools.combinations(names, 2)) or [(None, names[0])]
    n = len(pairs)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 4.0 * rows), squeeze=False)
    cls = _classes(feasible, pareto)
    for ax, (a, b) in zip(axes.flat, pairs, strict=False):
        yb = _shown(values[b], labels[b][1])
        xa = np.arange(len(yb)) if a is None else _shown(values[a], labels[a][1])
        for c, mask in cls.items():
            lab, mk, col, s = STYLE[c]
            ax.scatter(xa[mask], yb[mask], marker=mk, c=col, s=s, label=lab, linewidths=0.8)
        ax.set_xlabel("design" if a is None else _label(*labels[a]))
        ax.set_ylabel(_label(*labels[b]))
        ax.grid(True, alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=8)
    if title:  # wrapped to the figure's width (about 11 characters an inch at this size)
        fig.suptitle(textwrap.fill(title, width=max(30, int(11 * fig.get_figwidth()))))
    fig.tight_layout()
    return fig


def feasibility_figure(variables: dict, labels: dict, feasible, pareto, *, log=(), title=None):
    """Scatter matrix of the design variables (``variables[name]`` [SI unit of
    ``labels[name] = (quantity, unit)``], shown as `pareto_figure` shows them), each
    design marked infeasible, feasible or Pareto;
    the diagonal: histograms of all and of the feasible designs."""
    plt = _plt()
    names = list(variables)
    k = len(names)
    fig, axes = plt.subplots(k, k, figsize=(2.6 * k + 1, 2.6 * k + 0.5), squeeze=False)
    cls = _classes(feasible, pareto)
    feas = np.asarray(feasible, bool)
    for i, yi in enumerate(names):
        for j, xj in enumerate(names):
            ax = axes[i][j]
            x = _shown(variables[xj], labels[xj][1])
            if i == j:
                bins = np.geomspace(x.min(), x.max(), 12) if xj in log and x.min() > 0 else 12
                ax.hist(x, bins=bins, color="0.75", label="all")
                if feas.any():
                    ax.hist(x[feas], bins=bins, color="tab:blue", label="feasible")
            else:
                y = _shown(variables[yi], labels[yi][1])
                for c, mask in cls.items():
                    lab, mk, col, s = STYLE[c]
                    ax.scatter(x[mask], y[mask], marker=mk, c=col, s=s * 0.6, label=lab, lw=0.6)
                if yi in log:
                    ax.set_yscale("log")
                    _plain_log_ticks(ax.yaxis)
            if xj in log:
                ax.set_xscale("log")
                _plain_log_ticks(ax.xaxis)
            if i == k - 1:
                ax.set_xlabel(_label(*labels[xj]), fontsize=8)
            if i == j == 0:
                ax.set_ylabel("designs", fontsize=8)
            elif j == (1 if i == 0 else 0):
                ax.set_ylabel(_label(*labels[yi]), fontsize=8)
            ax.tick_params(labelsize=7)
    if k > 1:
        axes[0][1].legend(fontsize=7)
    else:
        axes[0][0].legend(fontsize=7)
    if title:  # wrapped to the figure's width (about 11 characters an inch at this size)
        fig.suptitle(textwrap.fill(title, width=max(30, int(11 * fig.get_figwidth()))))
    fig.tight_layout()
    return fig
