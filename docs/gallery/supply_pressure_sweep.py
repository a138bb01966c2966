"""A sweep: saturation velocity against supply pressure
=====================================================

The paper's shoulder joint raises and lowers load 6 at full valve opening while the supply
pressure is swept from 20 to 40 bar: a list of scenarios made with `Scenario.replace`, run
one by one with `hydroarm.simulate` (`hydroarm sweep` runs such grids on the batch engine,
docs/batch.md). The saturation velocity grows with the square root of the pressure drop
across the valve.
"""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import hydroarm as ha

joint = ha.shoulder_elevation()
pressures_bar = np.linspace(20.0, 40.0, 6)

fig, ax = plt.subplots(figsize=(7, 4))
for direction in ("raise", "lower"):
    velocities = []
    for p in pressures_bar:
        scenario = ha.saturation_test(
            joint.replace(supply_pressure=p * 1e5), ha.paper_load(6), direction
        ).replace(duration=1.2)
        velocities.append(ha.simulate(scenario).summary()["saturation_velocity_mm_s"])
    ax.plot(pressures_bar, velocities, "o-", label=f"load 6, {direction}")
    print(direction, np.round(velocities, 2))
ax.axvline(joint.supply_pressure / 1e5, color="0.6", ls=":", label="the paper's supply")
ax.set_xlabel("supply pressure [bar]")
ax.set_ylabel("saturation velocity [mm/s]")
ax.grid(True, alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig("supply_pressure_sweep.png", dpi=100)
