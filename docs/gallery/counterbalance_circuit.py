"""A circuit: a load lowered through a counterbalance valve
=========================================================

`examples/counterbalance.toml` is a circuit of components (docs/examples/counterbalance.md):
an 800 kg load hangs on a cylinder whose cap side is held by a counterbalance valve piloted
from the rod side. The spool opens to lower the load, then closes to hold it. The node
pressures of the run are drawn with `hydroarm.plotting.circuit.plot_outputs` on an axes of
our own, beside the load's position.
"""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from hydroarm.io.circuit import load_circuit
from hydroarm.io.examples import examples_folder
from hydroarm.model.circuit import simulate
from hydroarm.plotting.circuit import plot_outputs

EXAMPLES = examples_folder()  # the example files: examples/ in a checkout, or in the wheel

result = simulate(load_circuit(EXAMPLES / "counterbalance.toml"))
columns = result.columns()
t = columns["t_s"]
pressures = {k: v for k, v in columns.items() if k.endswith("_pressure_bar")}
print("peak pressures [bar]:", {k: round(float(v.max()), 1) for k, v in pressures.items()})

fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
plot_outputs(t, pressures, ax=top)
top.set_xlabel("")
top.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
top.set_title("Counterbalance valve: an 800 kg load lowered and held")
bottom.plot(t, columns["load_position_m"] * 1e3)
bottom.set_ylabel("load position [mm]")
bottom.set_xlabel("time [s]")
bottom.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig("counterbalance_circuit.png", dpi=100)
