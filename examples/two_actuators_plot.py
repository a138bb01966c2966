"""Figure of examples/two_actuators.toml (docs/examples/two_actuators.md): the two loads'
positions and the pump, branch and load pressures, with the flow control sharing the pump's
flow and, for comparison, with its setting above the pump's flow (no compensation).

Usage: python examples/two_actuators_plot.py <folder>     (writes <folder>/two_actuators.png)
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.model.circuit import simulate  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent


def main(folder: str) -> pathlib.Path:
    circuit = load_circuit(HERE / "two_actuators.toml")
    shared = simulate(circuit).to_pandas()
    plain = simulate(circuit.with_values({"priority.flow_setting": 1e-3})).to_pandas()
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for df, style, label in ((shared, "-", "flow control 8 L/min"), (plain, ":", "uncompensated")):
        ax1.plot(df["t_s"], df["light_position_m"] * 1e3, "C0" + style, label=f"light, {label}")
        ax1.plot(df["t_s"], df["heavy_position_m"] * 1e3, "C3" + style, label=f"heavy, {label}")
    ax1.set_ylabel("position [mm]")
    ax1.legend(fontsize="small")
    ax1.grid(alpha=0.3)
    for col, label in (
        ("supply_pressure_bar", "pump"),
        ("a1_pressure_bar", "light cylinder, cap side"),
        ("a2_pressure_bar", "heavy cylinder, cap side"),
    ):
        ax2.plot(shared["t_s"], shared[col], label=label)
    ax2.set_ylabel("pressure [bar]")
    ax2.set_xlabel("time [s]")
    ax2.legend(fontsize="small")
    ax2.grid(alpha=0.3)
    ax1.set_title("two cylinders on one 15 L/min pump")
    fig.tight_layout()
    out = pathlib.Path(folder) / "two_actuators.png"
    fig.savefig(out, dpi=110)
    return out


if __name__ == "__main__":
    print(main(sys.argv[1] if len(sys.argv) > 1 else "."))
