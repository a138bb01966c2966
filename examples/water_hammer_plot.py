"""Figure of examples/water_hammer.toml (docs/examples/water_hammer.md): the pressure at the
valve and the flow at the supply end of the pipe, with the pipe as a transmission line and
as a lumped hose of 40 segments, against Joukowsky's rise and the period 4·L/c.

Usage: python examples/water_hammer_plot.py <folder>     (writes <folder>/water_hammer.png)
"""

import math
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.model.circuit import ComponentSpec, simulate  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent


def with_hose(circuit, segments):
    """The circuit with its line replaced by a lumped hose of the same pipe."""
    comps = []
    for c in circuit.components:
        if c.type == "line":
            values = {k: v for k, v in c.values.items() if k != "buffer_length"}
            c = ComponentSpec("hose", c.name, c.ports, {**values, "segments": segments})
        comps.append(c)
    return circuit.replace(components=tuple(comps))


def main(folder):
    circuit = load_circuit(HERE / "water_hammer.toml")
    runs = {
        "line (transmission-line model)": simulate(circuit),
        "hose, 40 lumped segments": simulate(with_hose(circuit, 40)),
    }
    pipe = next(c for c in circuit.components if c.type == "line").values
    beta = 1.0 / (1.0 / pipe["bulk_modulus"] + 1.0 / pipe["wall_bulk_modulus"])
    rho = pipe["density"]
    speed = math.sqrt(beta / rho)
    velocity = pipe["initial_flow"] / (math.pi * pipe["diameter"] ** 2 / 4)
    joukowsky = rho * speed * velocity / 1e5  # bar
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for (label, r), style in zip(runs.items(), ("-", "--"), strict=True):
        t = r.t * 1e3
        top.plot(t, r.output("valve_in_pressure_bar"), style, lw=1, label=label)
        bottom.plot(t, r.output("pipe_flow_lpm"), style, lw=1, label=label)
    before = circuit.initial["valve_in"] / 1e5
    top.axhline(before + joukowsky, color="k", lw=0.6, ls=":")
    top.text(1, before + joukowsky + 1, f"Joukowsky ρ·c·Δv = {joukowsky:.1f} bar", fontsize=8)
    shut = 10.5  # ms, the middle of the valve's closing
    period = 4 * pipe["length"] / speed * 1e3
    for k in range(1, 4):
        top.axvline(shut + k * period, color="0.6", lw=0.6, ls=":")
    top.text(shut + period + 1, top.get_ylim()[0] + 2, f"4L/c = {period:.1f} ms", fontsize=8)
    top.set_ylabel("pressure at the valve [bar]")
    bottom.set_ylabel("flow at the supply end [L/min]")
    bottom.set_xlabel("time [ms]")
    top.legend(fontsize=8, loc="upper right")
    top.set_title("Water hammer: a valve shutting in 1 ms at the end of 30 m of steel pipe")
    fig.tight_layout()
    out = pathlib.Path(folder) / "water_hammer.png"
    fig.savefig(out, dpi=120)
    print(f"written {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
