"""Plots of single-joint results (matplotlib; the backend is the caller's choice)."""

from __future__ import annotations

import io

import numpy as np

from ..files import atomic_write_bytes


def _plt():
    """matplotlib.pyplot, imported on first use (keeps the start of the CLI fast). No
    backend is selected here: the CLI sets ``MPLBACKEND=Agg`` unless the user chose one."""
    import matplotlib.pyplot as plt

    return plt


def _axes(ax, **subplots):
    """(figure, axes, made): the given ``ax`` and its figure (a notebook's own layout, left
    alone), or a new figure with one axes (``made``: the caller lays it out)."""
    if ax is not None:
        return ax.figure, ax, False
    fig, ax = _plt().subplots(**subplots)
    return fig, ax, True


def plot_result(result, ax=None, *, quantities=("theta", "x", "p"), title=None):
    """Angular displacement [deg], jack position [mm] and load pressure [bar] against time."""
    plt = _plt()
    if ax is None:
        fig, axes = plt.subplots(
            len(quantities), 1, sharex=True, figsize=(7, 2.2 * len(quantities) + 0.6)
        )
        axes = np.atleast_1d(axes)
    else:
        axes = np.atleast_1d(ax)
        fig = axes[0].figure
    t = result.t
    series = {
        "theta": (np.degrees(result.theta), "angular displacement θ₂ [deg]"),
        "x": (result.x * 1e3, "jack position x [mm]"),
        "p": (result.p * 1e-5, "load pressure p [bar]"),
        "xdot": (result.xdot * 1e3, "jack velocity ẋ [mm/s]"),
        "e": (result.e * 1e3, "valve opening e [mm]"),
    }
    for a, q in zip(axes, quantities, strict=False):
        v, label = series[q]
        a.plot(t, v, lw=1.4)
        if q == "x":
            a.plot(t, result.y * 1e3, "--", lw=0.9, color="grey", label="lever y")
            a.legend(loc="best", fontsize=8)
        a.set_ylabel(label, fontsize=9)
        a.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    sc = result.scenario
    axes[0].set_title(title or f"{sc.name} — {sc.method}, T = {sc.step * 1e6:g} µs")
    fig.tight_layout()
    return fig


def save_figure(fig, path) -> None:
    """Save atomically as PNG and close the figure."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    _plt().close(fig)
    atomic_write_bytes(path, buf.getvalue())


def figure_svg(fig) -> str:
    """The figure as SVG text (its text kept as text, not paths, so that a page can be
    searched and tested) and close it; the markup starts at ``<svg``."""
    plt = _plt()
    buf = io.StringIO()
    with plt.rc_context({"svg.fonttype": "none"}):
        fig.savefig(buf, format="svg")
    plt.close(fig)
    text = buf.getvalue()
    return text[text.find("<svg") :]
