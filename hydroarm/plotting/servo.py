"""Plot of a component servo run (matplotlib; the backend is the caller's choice)."""

from __future__ import annotations

from .joint import _plt


def servo_figure(result):
    """Position and reference, spool, chamber and supply pressures against time, from a
    [`hydroarm.model.servo.ServoResult`][hydroarm.ServoResult] (its `columns`)."""
    plt = _plt()
    cols = result.columns()
    t = cols["t_s"]
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(7, 7.2))
    if "position_m" in cols:
        axes[0].plot(t, cols["position_m"], label="position")
        axes[0].set_ylabel("position [m]")
    else:
        axes[0].plot(t, cols["angle_deg"], label="angle")
        axes[0].set_ylabel("angle [deg]")
    name = next(k for k in cols if k.startswith(("reference", "lever")))
    axes[0].plot(t, cols[name], "--", color="0.4", label=name.split("_")[0])
    axes[0].legend(loc="best", fontsize="small")
    axes[1].plot(t, cols["spool_m"] * 1e3)
    axes[1].set_ylabel("spool [mm]")
    axes[2].plot(t, cols["pressure_a_bar"], label="chamber A")
    axes[2].plot(t, cols["pressure_b_bar"], label="chamber B")
    axes[2].plot(t, cols["supply_bar"], label="supply", color="k", lw=0.8)
    axes[2].set_ylabel("pressure [bar abs]")
    axes[2].legend(loc="best", fontsize="small")
    axes[-1].set_xlabel("time [s]")
    for a in axes:
        a.grid(True, alpha=0.3)
    fig.suptitle(result.scenario.name)
    fig.tight_layout()
    return fig
