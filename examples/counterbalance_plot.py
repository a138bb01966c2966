"""Figure of examples/counterbalance.toml: the spool, the pressures and the load's motion
while it is lowered through the counterbalance valve and held (docs/examples/counterbalance.md).

Usage: python examples/counterbalance_plot.py OUT_DIR     (writes OUT_DIR/counterbalance.png)
"""

import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.model.circuit import simulate  # noqa: E402

EXAMPLE = Path(__file__).resolve().parent / "counterbalance.toml"


def main(out_dir):
    r = simulate(load_circuit(EXAMPLE))
    c = r.columns()
    t = c["t_s"]
    P = {name: float(r.P[i]) for name, i in r.compiled.parameter_index.items()}
    # the runaway bound: the meter-in edge's flow with the rod side at the cavitation floor
    k_v = (
        P["valve.discharge_coefficient"]
        * math.pi
        * P["valve.spool_diameter"]
        * P["valve.circumference_fraction"]
        * math.sqrt(2.0 / P["valve.density"])
    )
    stroke = -min(c["spool_demand_signal"])
    bound = k_v * stroke * math.sqrt(P["supply.pressure"]) / P["jack.area_b"]

    fig, axes = plt.subplots(4, 1, figsize=(7.5, 9), sharex=True)
    ax = axes[0]
    ax.plot(t, c["spool_demand_signal"] * 1e3, label="spool x_v [mm]")
    ax.plot(t, c["cbv_opening"], label="counterbalance opening x [–]")
    ax.plot(t, c["float_opening_signal"], ":", label="float centre open [–]")
    ax.legend(fontsize=8, loc="lower right")
    ax.set_ylabel("command")
    ax = axes[1]
    for node, label in (
        ("cap", "cap side (load port)"),
        ("line_a", "line A (valve port)"),
        ("line_b", "rod side = pilot"),
    ):
        ax.plot(t, c[f"{node}_pressure_bar"], label=label)
    ax.axhline(P["cbv.setting"] / 1e5, color="k", lw=0.8, ls="--", label="setting")
    ax.set_ylabel("pressure [bar]")
    ax.legend(fontsize=8, loc="upper right")
    ax = axes[2]
    ax.plot(t, -c["load_velocity_m_s"] * 1e3, label="lowering speed")
    ax.axhline(bound * 1e3, color="r", lw=0.8, ls="--", label="runaway bound")
    ax.set_ylabel("speed [mm/s]")
    ax.legend(fontsize=8, loc="upper right")
    ax = axes[3]
    ax.plot(t, c["load_position_m"] * 1e3)
    ax.set_ylabel("load position [mm]")
    ax.set_xlabel("time [s]")
    fig.suptitle("Counterbalance valve: an 800 kg load lowered and held")
    fig.tight_layout()
    out = Path(out_dir) / "counterbalance.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"written {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
