"""Figures of the paper's evaluation (Figs. 6–11) and of the validation."""

from __future__ import annotations

import numpy as np

from .joint import _axes, _plt

# a trace is drawn from at most about 4 points per bucket, 2000 buckets: several per pixel
# column of the 7-inch, 110-dpi figures, so that the drawn line does not change visibly
PLOT_BUCKETS = 2000


def thin(x, *ys, buckets: int = PLOT_BUCKETS):
    """(x, *ys) reduced for plotting by a min/max decimation: of each of ``buckets``
    consecutive runs of samples, the first and last and where each y is smallest and
    largest (the extremes and the envelope of every curve are kept, the order too)."""
    x = np.asarray(x)
    ys = tuple(np.asarray(y) for y in ys)
    n = x.shape[0]
    size = -(-n // buckets)  # samples per bucket
    if size <= 2:
        return (x, *ys)
    m = (n // size) * size
    starts = np.arange(0, m, size)
    keep = [starts, starts + size - 1, np.arange(m, n)]
    for y in ys:
        blocks = y[:m].reshape(-1, size)
        keep += [starts + blocks.argmin(axis=1), starts + blocks.argmax(axis=1)]
        if m < n:
            keep += [m + np.array([y[m:].argmin(), y[m:].argmax()])]
    i = np.unique(np.concatenate(keep))
    return (x[i], *(y[i] for y in ys))


def fig_model_runs(runs: dict, title: str, *, ax=None):
    """Angular displacement [deg] against time for each (load, direction) run (Figs. 7, 8)."""
    fig, ax, made = _axes(ax, figsize=(7, 4.2))
    styles = {"raise": "-", "lower": "--"}
    for (load, d), res in sorted(runs.items()):
        ax.plot(
            *thin(res.t, np.degrees(res.theta)),
            styles[d],
            lw=1.5,
            label=f"load {load}, {'rising' if d == 'raise' else 'falling'}",
        )
    ax.set_xlabel("time [s]")
    ax.set_ylabel("angular displacement θ₂ [deg]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if made:
        fig.tight_layout()
    return fig


def fig_transients(
    runs: dict,
    direction: str,
    title: str,
    window: float = 0.15,
    *,
    compare: dict | None = None,
    labels: tuple[str, str] = ("", ""),
):
    """Initial transients: jack velocity and displacement in the first ``window`` [s], with
    the start time constant T' of each run of ``runs`` marked.

    ``compare``: runs of a second model, drawn dashed in the same colour per load;
    ``labels``: the names of the two models in the legend ((``runs``, ``compare``))."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(7, 5.4))
    sets = [(runs, "-", labels[0])]
    if compare is not None:
        sets.append((compare, "--", labels[1]))
    loads = sorted({k for k, d in runs if d == direction})
    colour = {k: f"C{i}" for i, k in enumerate(loads)}
    for data, style, name in sets:
        for (load, d), res in sorted(data.items()):
            if d != direction or load not in colour:
                continue
            m = res.t <= window
            label = f"load {load}" + (f", {name}" if name else "")
            c = colour[load]
            t_ms = res.t[m] * 1e3
            a1.plot(*thin(t_ms, np.abs(res.xdot[m]) * 1e3), style, c=c, lw=1.5, label=label)
            a2.plot(
                *thin(t_ms, np.abs(np.degrees(res.theta[m] - res.theta[0]))),
                style,
                c=c,
                lw=1.5,
                label=label,
            )
    # T' of each run drawn solid: the jack has moved 63 % of the full valve opening
    marked = False
    for (load, d), res in sorted(runs.items()):
        if d != direction or load not in colour:
            continue
        tc = res.metric_values()["time_constant_start"]
        if not np.isfinite(tc) or tc > window:
            continue
        t0 = float(res.scenario.lever.times[0])
        moved = np.degrees(abs(np.interp(t0 + tc, res.t, res.theta) - res.theta[0]))
        a2.plot([(t0 + tc) * 1e3], [moved], "o", c=colour[load], ms=5, mfc="white",
                label=None if marked else "T': jack moved 63 % of e_o")  # fmt: skip
        marked = True
    a1.set_ylabel("jack velocity |ẋ| [mm/s]")
    a2.set_ylabel("angular displacement [deg]")
    a2.set_xlabel("time [ms]")
    a1.set_title(title)
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
        a.legend(fontsize=7, ncol=2 if compare is not None else 1)
    fig.tight_layout()
    return fig


def fig_time_constant_sweep(
    sweep: dict,
    *,
    paper_max_ms: float | None = None,
    tested_pct: float = 100.0,
    requirement_ms: float | None = None,
    ax=None,
):
    """Fig. 11: loaded time constant T' against stall ratio γ, rising (a) and falling (b),
    with the no-load point (``sweep["no_load_tc_raise_ms"]``, ``…_lower_ms``).

    ``sweep["paper_theory_ms"]``: the paper's no-load value; ``paper_max_ms``: the paper's
    largest measured T', up to the stall ratio ``tested_pct`` [%]; ``requirement_ms``: the
    required bound (drawn when given)."""
    fig, ax, made = _axes(ax, figsize=(7, 4.4))
    g = sweep["gamma_pct"]
    (ra,) = ax.plot(g, sweep["tc_raise_ms"], "-o", ms=3, label="(a) arm rising")
    (fa,) = ax.plot(g, sweep["tc_lower_ms"], "-s", ms=3, label="(b) arm falling")
    # the no-load points on the same definition (the piston alone), not joined to the curves:
    # nothing between γ = 0 and the sweep's first load was simulated
    ax.plot(
        [0],
        [sweep["no_load_tc_lower_ms"]],
        "s",
        mfc="none",
        color=fa.get_color(),
        ms=6,
        label=f"no load, falling: simulated {sweep['no_load_tc_lower_ms']:.1f} ms",
    )
    # the no-load points: simulated T', the standard formula A/K_q, the paper's value
    for value, marker, size, what in (
        (sweep["no_load_tc_raise_ms"], "ko", 5, "rising: simulated {:.1f} ms"),
        (sweep["no_load_formula_ms"], "k^", 7, "A/K_q = {:.1f} ms"),
        (sweep["paper_theory_ms"], "kx", 8, "paper {:g} ms"),
    ):
        ax.plot([0], [value], marker, ms=size, label="no load, " + what.format(value))
    if paper_max_ms is not None:
        ax.axhline(
            paper_max_ms,
            color="grey",
            ls=":",
            lw=1,
            label=f"{paper_max_ms:g} ms (paper: not exceeded up to γ = {tested_pct:g} %)",
        )
    if requirement_ms is not None:
        ax.axhline(
            requirement_ms, color="red", ls=":", lw=1, label=f"{requirement_ms:g} ms requirement"
        )
    ax.set_xlabel("stall ratio γ = W·X / (A·p_s·r/n) [%]")
    ax.set_ylabel("time constant T' [ms]")
    ax.set_title("Fig. 11 — time constant against stall ratio")
    ax.set_xlim(-3, 103)
    top = ax.get_ylim()[1]
    ax.set_ylim(0, max(top, 1.15 * (requirement_ms or 0.0)))  # room for the legend
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    if made:
        fig.tight_layout()
    return fig


# fig_validation's x axis: linear within ±this many %, logarithmic beyond (symlog), so that
# a few % stay readable beside a model's +900 % (nothing is clipped away)
VALIDATION_LINEAR_PCT = 10.0


def fig_validation(rows, *, ax=None, name_of=None):
    """Horizontal bars: relative error of each model against the measurement, on an axis
    linear within ±`VALIDATION_LINEAR_PCT` % and logarithmic beyond (no error is
    clipped). A value equal to the measurement by construction, or a calibrated input of
    hydroarm's model (a row whose note says "input"), is a marker at 0, not a 0 % bar: it is
    not a prediction. The legend sits below the axes, clear of the bars. ``name_of``: the
    row's shown name from its code name (default: the code name itself)."""
    rows = [r for r in rows if r["measured"]]
    name_of = name_of or (lambda code: code)
    fig, ax, made = _axes(ax, figsize=(8, 0.42 * len(rows) + 2.0))
    y = np.arange(len(rows))
    models = (
        ("paper_model1", "paper Model 1 (real loads)"),
        ("paper_model2", "paper Model 2 (re-rated loads)"),
        ("hydroarm", "hydroarm physics model"),
    )
    equal_shown = False
    for k, (col, label) in enumerate(models):
        err = np.array(
            [
                100 * (r[col] / r["measured"] - 1)
                if r[col] is not None and np.isfinite(r[col])
                else np.nan
                for r in rows
            ]
        )
        # the measurement itself (equal by construction) or a calibrated input of hydroarm's
        # model (its note says so): not a prediction, so no 0 % bar
        equal = (np.abs(err) < 1e-9) | np.array(
            [col == "hydroarm" and "input" in str(r.get("note", "")) for r in rows]
        )
        bars = ax.barh(y + (k - 1) * 0.27, np.where(equal, np.nan, err), height=0.26, label=label)
        if equal.any():
            ax.plot(
                np.zeros(int(equal.sum())),
                (y + (k - 1) * 0.27)[equal],
                "D",
                mfc="none",
                color=bars.patches[0].get_facecolor() if bars.patches else "k",
                ms=5,
                label=None if equal_shown else "an input, or equal by construction (no prediction)",
            )
            equal_shown = True
    ax.axvspan(-5, 5, color="green", alpha=0.08, label="±5 %")
    ax.set_xscale("symlog", linthresh=VALIDATION_LINEAR_PCT)
    ax.set_yticks(y, [name_of(r["quantity"]) for r in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel(
        "relative error against the measurement [%]\n(linear within "
        f"±{VALIDATION_LINEAR_PCT:g} %, logarithmic beyond)"
    )
    ax.axvline(0, color="k", lw=0.8)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, frameon=False)
    ax.set_title("Validation against the measured UCL arm")
    if made:
        fig.tight_layout()
    return fig


def fig_leave_one_out(rows, *, ax=None):
    """Horizontal bars: relative error of each Table I velocity in-sample (fitted on both
    loads) and predicted (fitted on the other load alone): rows of
    `hydroarm.paper.calibration.leave_one_load_out`."""
    fig, ax, made = _axes(ax, figsize=(8, 0.5 * len(rows) + 1.4))
    y = np.arange(len(rows))
    for k, (col, label) in enumerate(
        (
            ("in_sample_rel_error", "in-sample (fitted on both loads)"),
            ("predicted_rel_error", "predicted (fitted on the other load)"),
        )
    ):
        err = np.array([100 * r[col] for r in rows])
        ax.barh(y + (k - 0.5) * 0.38, err, height=0.36, label=label)
    ax.set_yticks(y, [f"{r['quantity']}\n({r['fitted_on']})" for r in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("saturation velocity: relative error against Table I [%]")
    ax.axvline(0, color="k", lw=0.8)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("Measured arm: fit against prediction (leave one load out)")
    if made:
        fig.tight_layout()
    return fig


def fig_gearbox_efficiency(joint, *, paper_point=None, stall_force: float | None = None, ax=None):
    """Fig. 6: gearbox torque efficiency η against stall ratio γ (the model's law).

    ``paper_point``: (γ [%], η [%]) the paper reports, marked when given; ``stall_force``
    [N]: the force γ is referred to (default: the joint's A·p_s)."""
    g = np.linspace(0.02, 1.0, 200)
    fig, ax, made = _axes(ax, figsize=(6, 4))
    ax.plot(
        100 * g,
        100 * joint.gearbox_efficiency(g, joint.horizontal_angle),
        label=f"model: 1 − {joint.gearbox_loss_at_stall:.3g}·γ^{joint.gearbox_loss_exponent:g}"
        f" − {joint.gearbox_friction_torque:.3g} N m / T_in",
    )
    if paper_point is not None:
        g_p, eta_p = paper_point
        ax.plot(
            [g_p], [eta_p], "o", color="C3", label=f"paper Fig. 6: {eta_p:g} % at γ = {g_p:g} %"
        )
    f_stall = joint.stall_force if stall_force is None else stall_force
    ax.set_xlabel(f"stall ratio γ = W_in / {f_stall:.0f} N [%]")
    ax.set_ylabel("torque efficiency η [%]")
    ax.set_ylim(0, 105)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Shoulder-elevation gearbox torque efficiency")
    if made:
        fig.tight_layout()
    return fig
