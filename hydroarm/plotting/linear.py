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


def frequency_response_figure(
    w, linear, linear_phase_deg, w_meas, gain_db, phase_deg, labels, *, title=None, marks=None
):
    """A frequency response by simulation on the linear Bode of the same transfer.

    ``w``, ``linear``, ``linear_phase_deg``: a dense grid [rad/s], the linear response there
    (complex) and its unwrapped phase [deg]; ``w_meas``: the simulated frequencies;
    ``gain_db``, ``phase_deg``: (amplitudes × frequencies) measured gain and phase, one curve
    per amplitude labelled by ``labels``; ``marks``: {label: frequency} drawn as vertical
    lines (ω_h, 2·ω_h)."""
    plt = _plt()
    fig, (ax_m, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(7, 5.8))
    ax_m.semilogx(
        w, 20 * np.log10(np.maximum(np.abs(linear), 1e-300)), "k-", lw=1.2, label="linear"
    )
    ax_p.semilogx(w, linear_phase_deg, "k-", lw=1.2)
    markers = "os^vDp*h"
    for k, (g, ph, label) in enumerate(
        zip(np.atleast_2d(gain_db), np.atleast_2d(phase_deg), labels, strict=True)
    ):
        mk = markers[k % len(markers)]
        ax_m.semilogx(w_meas, g, mk + "--", ms=5, lw=0.8, label=label)
        ax_p.semilogx(w_meas, ph, mk + "--", ms=5, lw=0.8)
    for name, f in (marks or {}).items():
        for ax in (ax_m, ax_p):
            ax.axvline(f, color="0.7", lw=0.8, ls=":")
        ax_m.annotate(name, (f, 1), xycoords=("data", "axes fraction"), va="top", fontsize=8)
    ax_m.set_ylabel("gain [dB]")
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [rad/s]")
    ax_m.legend(loc="lower left", fontsize=8)
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, which="both", alpha=0.3)
    if title:
        ax_m.set_title(title, fontsize=10)
    fig.tight_layout()
    return fig
