"""Bode plots of a linearised servo (docs/linear.md); frequency responses as plain arrays."""

from __future__ import annotations

import numpy as np

from .joint import _axes, _plt


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


def pole_figure(
    poles, *, omega_h=None, zeta_h=None, damping=(0.2, 0.4, 0.6, 0.8), title=None, ax=None
):
    """Pole map: the closed-loop poles (×) in the s-plane [1/s], the circle |s| = ω_h of the
    hydraulic natural frequency, and lines of constant damping ratio ζ (the rays at angle
    arccos ζ from the negative real axis), ζ_h's drawn solid.

    ``poles``: complex array; ``omega_h``, ``zeta_h``: the hydraulic mode (optional)."""
    p = np.asarray(poles, complex)
    fig, ax, made = _axes(ax, figsize=(6.4, 5.6))
    finite = p[np.isfinite(p)]
    reach = max([float(np.max(np.abs(finite))) if finite.size else 1.0, omega_h or 0.0]) * 1.15
    zetas = [z for z in damping if zeta_h is None or abs(z - zeta_h) > 0.02]
    for z in zetas:
        ang = np.arccos(min(max(z, 0.0), 1.0))
        x, y = -reach * np.cos(ang), reach * np.sin(ang)
        ax.plot([0.0, x], [0.0, y], color="0.8", lw=0.8, ls=":", label="_nolegend_")
        ax.plot([0.0, x], [0.0, -y], color="0.8", lw=0.8, ls=":", label="_nolegend_")
        ax.annotate(f"ζ = {z:g}", (0.92 * x, 0.92 * y), color="0.5", fontsize=8)
    if zeta_h is not None and np.isfinite(zeta_h):
        ang = np.arccos(min(max(zeta_h, 0.0), 1.0))
        x, y = -reach * np.cos(ang), reach * np.sin(ang)
        ax.plot(
            [0.0, x, np.nan, 0.0, x],
            [0.0, y, np.nan, 0.0, -y],
            color="C2",
            lw=1.0,
            label=f"ζ_h = {zeta_h:.3g}",
        )
    if omega_h is not None and np.isfinite(omega_h):
        phi = np.linspace(0.5 * np.pi, 1.5 * np.pi, 200)
        ax.plot(
            omega_h * np.cos(phi),
            omega_h * np.sin(phi),
            color="C1",
            lw=1.0,
            ls="--",
            label=f"|s| = ω_h = {omega_h:.4g} rad/s",
        )
    ax.plot(finite.real, finite.imag, "x", color="C0", ms=9, mew=2, label="closed-loop poles")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.axvline(0.0, color="0.6", lw=0.8)
    right = max(0.05 * reach, float(np.max(finite.real)) * 1.2 if finite.size else 0.0)
    ax.set_xlim(-reach, right)
    ax.set_ylim(-reach, reach)
    ax.set_xlabel("real part [1/s]")
    ax.set_ylabel("imaginary part [rad/s]")
    ax.legend(loc="upper left", fontsize=8)
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)
    if made:
        fig.tight_layout()
    return fig


def step_figure(t, y, info, *, title=None, label="small-signal step (linear)", ax=None):
    """Small-signal step response, normalised to its final value, with the rise time (10 to
    90 %), the overshoot (the peak) and the settling time (2 % band) marked.

    ``t`` [s], ``y``: the response divided by its final value; ``info``: a dict with
    ``RiseTime``, ``SettlingTime``, ``Overshoot`` [%], ``PeakTime`` [s] (``step_info``)."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    fig, ax, made = _axes(ax, figsize=(7, 4.4))
    ax.plot(t * 1e3, y, color="C0", label=label)
    ax.axhline(1.0, color="0.5", lw=0.8)
    ax.axhspan(0.98, 1.02, color="C2", alpha=0.12, label="±2 % band")
    rise = info.get("RiseTime", np.nan)
    if np.isfinite(rise):
        t10 = float(np.interp(0.1, np.maximum.accumulate(y), t))
        ax.axvspan(
            t10 * 1e3,
            (t10 + rise) * 1e3,
            color="C1",
            alpha=0.15,
            label=f"rise 10–90 %: {rise * 1e3:.3g} ms",
        )
    peak_t = info.get("PeakTime", np.nan)
    over = info.get("Overshoot", np.nan)
    if np.isfinite(peak_t) and np.isfinite(over):
        peak = 1.0 + over / 100.0
        ax.plot([peak_t * 1e3], [peak], "v", color="C3", label=f"overshoot {over:.3g} %")
        ax.annotate(
            f"{over:.3g} %",
            (peak_t * 1e3, peak),
            textcoords="offset points",
            xytext=(6, 4),
            color="C3",
        )
    settle = info.get("SettlingTime", np.nan)
    if np.isfinite(settle):
        ax.axvline(
            settle * 1e3,
            color="C2",
            ls="--",
            lw=1.0,
            label=f"settling (2 %): {settle * 1e3:.3g} ms",
        )
    ax.set_xlabel("time after the step [ms]")
    ax.set_ylabel("response / final value")
    ax.set_xlim(t[0] * 1e3, t[-1] * 1e3)
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)
    if made:
        fig.tight_layout()
    return fig


VARIATION_PANELS = (
    ("hydraulic_natural_frequency_rad_s", "ω_h [rad/s]"),
    ("hydraulic_damping_ratio", "ζ_h"),
    ("gain_margin_db", "gain margin [dB]"),
    ("phase_margin_deg", "phase margin [deg]"),
)


def variation_figure(frame, *, title=None):
    """ω_h, ζ_h and the gain and phase margins against the joint angle, one line per load.

    ``frame``: a table (pandas DataFrame or a mapping of columns) with ``load``,
    ``angle_deg`` and the columns of `VARIATION_PANELS`
    ([`hydroarm.analysis.linear.linear_variation`][hydroarm.linear_variation])."""
    plt = _plt()
    cols = {
        k: np.asarray(frame[k])
        for k in ("load", "angle_deg") + tuple(c for c, _ in VARIATION_PANELS)
    }
    fig, axes = plt.subplots(2, 2, sharex=True, figsize=(9, 6.4))
    loads = list(dict.fromkeys(cols["load"].tolist()))
    for ax, (col, ylabel) in zip(axes.ravel(), VARIATION_PANELS, strict=True):
        for k, load in enumerate(loads):
            sel = cols["load"] == load
            ax.plot(
                cols["angle_deg"][sel],
                cols[col][sel],
                "-",
                color=f"C{k % 10}",
                label=f"load {load}",
            )
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.ticklabel_format(axis="y", useOffset=False)
        v = cols[col][np.isfinite(cols[col].astype(float))].astype(float)
        if v.size and np.ptp(v) < 1e-3 * max(abs(float(np.mean(v))), 1e-12):
            mid = float(np.mean(v))  # a constant (the gain margin): show it, not round-off
            ax.set_ylim(mid - 0.1 * abs(mid) - 1e-12, mid + 0.1 * abs(mid) + 1e-12)
    for ax in axes[1]:
        ax.set_xlabel("joint angle θ₂ [deg]")
    axes[0, 0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
