"""Bode plots of a linearised servo (docs/linear.md); frequency responses as plain arrays."""

from __future__ import annotations

import numpy as np

from .joint import _plt


def bode_figure(w, loop, closed, *, title=None, loop_label="open loop", closed_label=None):
    """Open-loop and closed-loop Bode plots (magnitude [dB], phase [deg]) on one figure.

    ``w``: frequencies [rad/s]; ``loop``, ``closed``: complex frequency responses at ``w``
    (the loop broken at the valve opening or spool demand; the closed loop from the lever or
    reference to the fed-back signal)."""
    plt = _plt()
    w = np.asarray(w, float)
    fig, (ax_m, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(7, 5.6))
    for h, label, style in (
        (np.asarray(loop), loop_label, "-"),
        (np.asarray(closed), closed_label or "closed loop", "--"),
    ):
        ax_m.semilogx(w, 20 * np.log10(np.maximum(np.abs(h), 1e-300)), style, label=label)
        ax_p.semilogx(w, np.degrees(np.unwrap(np.angle(h))), style, label=label)
    ax_m.axhline(0.0, color="0.6", lw=0.8)
    ax_m.axhline(-3.0, color="0.8", lw=0.8, ls=":")
    ax_p.axhline(-180.0, color="0.6", lw=0.8)
    ax_m.set_ylabel("magnitude [dB]")
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [rad/s]")
    ax_m.legend(loc="lower left")
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, which="both", alpha=0.3)
    if title:
        ax_m.set_title(title)
    fig.tight_layout()
    return fig
