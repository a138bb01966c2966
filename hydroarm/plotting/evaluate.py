"""Figures of the evaluation card (``hydroarm evaluate``, ``hydroarm arm``): each number
against its requirement or its reference band."""

from __future__ import annotations

import math

from .joint import _plt

PASS_COLOUR = "#d8f0d8"
FAIL_COLOUR = "#f6d8d8"
BAND_COLOUR = "#d8e4f6"


def fig_card(panels, *, title=None):
    """One panel per quantity, one horizontal bar per case (value in the panel's unit).

    ``panels``: dicts with ``quantity``, ``unit``, ``labels`` (one per bar), ``values``,
    optional ``limit`` and ``sense`` ("max": the value must be ≤ limit, "min": ≥; the side
    that meets it is shaded green, the other red), optional ``band`` (low, high, label: a
    reference range shaded blue) and optional ``paper`` (one value or None per bar: the
    paper's measurement, a black mark)."""
    plt = _plt()
    n = max(len(panels), 1)
    rows = [len(p["labels"]) for p in panels] or [1]
    fig, axes = plt.subplots(
        n, 1, figsize=(10.0, 0.9 + sum(0.32 * r + 0.75 for r in rows)), height_ratios=rows
    )
    axes = [axes] if n == 1 else list(axes)
    for ax, p in zip(axes, panels, strict=False):
        values = [v if v is not None and math.isfinite(v) else math.nan for v in p["values"]]
        y = list(range(len(values)))
        finite = [v for v in values if v == v]
        marks = [v for v in (p.get("paper") or []) if v is not None]
        limit = p.get("limit")
        band = p.get("band")
        top = max([*finite, *marks, limit or 0.0, band[1] if band else 0.0]) * 1.15
        top = top if top > 0 else 1.0  # all zero (no backlash): a unit axis
        ax.set_xlim(0.0, top)
        if limit is not None:
            good = (0.0, limit) if p.get("sense") == "max" else (limit, top)
            bad = (limit, top) if p.get("sense") == "max" else (0.0, limit)
            ax.axvspan(*good, color=PASS_COLOUR, zorder=0)
            ax.axvspan(*bad, color=FAIL_COLOUR, zorder=0)
            ax.axvline(limit, color="0.3", lw=1.0, ls="--", label=f"requirement {limit:.3g}")
        if band is not None:
            ax.axvspan(band[0], band[1], color=BAND_COLOUR, alpha=0.8, zorder=0, label=band[2])
        ax.barh(y, values, height=0.55, color="#4c72b0", zorder=2, label="hydroarm")
        for yi, v in zip(y, values, strict=True):
            if v == v:
                ax.text(v, yi, f" {v:.3g}", va="center", fontsize=8, zorder=3)
        paper = p.get("paper") or []
        py = [yi for yi, v in zip(y, paper, strict=False) if v is not None]
        pv = [v for v in paper if v is not None]
        if pv:
            ax.plot(pv, py, "k|", ms=14, mew=2, zorder=4, label="paper (measured)")
        ax.set_yticks(y)
        ax.set_yticklabels(p["labels"], fontsize=8)
        ax.invert_yaxis()
        ax.set_xlabel(f"{p['quantity']} [{p['unit']}]")
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
        ax.grid(True, axis="x", alpha=0.3)
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    return fig


def fig_block_score(score, references, *, title=None):
    """The arm's block-transfer score [blocks/min] against published Box and Block Test
    ranges (``references``: (label, low, high)), and its time per block split into moves,
    grasp and release [s]."""
    plt = _plt()
    fig, (ax, ax2) = plt.subplots(
        2, 1, figsize=(8.5, 5.4), height_ratios=(len(references) + 1, 1.4)
    )
    labels = ["hydroarm (simulated joints, stated hand)"] + [r[0] for r in references]
    y = list(range(len(labels)))
    bpm = float(score["blocks_per_minute"])
    ax.barh(y[0], bpm, height=0.55, color="#4c72b0")
    ax.text(bpm, y[0], f" {bpm:.3g}", va="center", fontsize=8)
    for yi, (_, lo, hi) in zip(y[1:], references, strict=True):
        ax.barh(yi, hi - lo, left=lo, height=0.55, color=BAND_COLOUR, edgecolor="0.5")
        ax.text(hi, yi, f" {lo:g}–{hi:g}", va="center", fontsize=8)
    ax.set_yticks(y)
    ax.set_yticklabels(labels, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0.0, max(bpm, *(r[2] for r in references)) * 1.25)
    ax.set_xlabel("blocks moved per minute [1/min]")
    ax.grid(True, axis="x", alpha=0.3)
    ax.set_title(title or "Box-and-Blocks-style score")
    parts = [
        ("move to place", float(score["move_out_s"])),
        ("release", float(score["release_s"])),
        ("move back", float(score["move_back_s"])),
        ("grasp", float(score["grasp_s"])),
    ]
    left = 0.0
    for (name, t), c in zip(parts, ("#4c72b0", "#c0c0c0", "#55a868", "#a0a0a0"), strict=True):
        ax2.barh(0, t, left=left, color=c, edgecolor="white", label=f"{name} {t:.3g} s")
        left += t
    ax2.set_yticks([])
    ax2.set_xlabel("time per block [s]")
    ax2.legend(fontsize=7, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.45))
    fig.tight_layout()
    return fig
