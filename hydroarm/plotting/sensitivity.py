"""Figures of a global sensitivity study (hydroarm.analysis.sensitivity): one bar chart per
metric, the indices of each parameter with their confidence intervals."""

from __future__ import annotations

import numpy as np

from .joint import _axes


def sobol_figure(
    parameters, s1, s1_conf, st, st_conf, *, metric: str, runs: int | None = None, ax=None
):
    """First-order (S1) and total (ST) Sobol indices [1] of one metric against the parameters,
    with their confidence half-widths as error bars. NaN (an output that does not vary) is
    drawn as no bar."""
    names = list(parameters)
    x = np.arange(len(names))
    w = 0.38
    fig, ax, made = _axes(ax, figsize=(max(5.0, 0.9 * len(names) + 2.5), 4.0))
    ax.bar(x - w / 2, s1, w, yerr=s1_conf, capsize=3, label="first order S1")
    ax.bar(x + w / 2, st, w, yerr=st_conf, capsize=3, label="total ST")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xticks(x, names, rotation=30, ha="right", fontsize=8)
    ax.set_xlabel("parameter")
    ax.set_ylabel("Sobol index (share of the variance) [1]")
    ax.set_title(metric + (f" — {runs} runs" if runs else ""), fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    if made:
        fig.tight_layout()
    return fig


def morris_figure(
    parameters,
    mu_star,
    mu_star_conf,
    sigma,
    *,
    metric: str,
    unit: str,
    runs: int | None = None,
    ax=None,
):
    """Morris screening of one metric: the mean absolute elementary effect μ* (with its
    confidence half-width) and the spread σ of the effects [the metric's unit] against the
    parameters."""
    names = list(parameters)
    x = np.arange(len(names))
    w = 0.38
    suffix = f" [{unit}]" if unit else " [1]"
    fig, ax, made = _axes(ax, figsize=(max(5.0, 0.9 * len(names) + 2.5), 4.0))
    ax.bar(x - w / 2, mu_star, w, yerr=mu_star_conf, capsize=3, label="μ* (mean |effect|)")
    ax.bar(x + w / 2, sigma, w, label="σ (spread of the effects)")
    ax.set_xticks(x, names, rotation=30, ha="right", fontsize=8)
    ax.set_xlabel("parameter")
    ax.set_ylabel("elementary effect" + suffix)
    ax.set_title(metric + (f" — {runs} runs" if runs else ""), fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    if made:
        fig.tight_layout()
    return fig
