"""The paper's Table III and Fig. 7
================================

The shoulder joint with the paper's calibrated parameters raises and lowers loads 6 and 10
at full valve opening (the saturation test). The saturation velocities are set beside
Table III of the paper, and the runs are drawn as in Figs. 7 and 8
(`hydroarm.plotting.paper.fig_model_runs`). The full reproduction, with every table and
figure and a report, is `hydroarm reproduce`.
"""

import matplotlib

matplotlib.use("Agg")

import hydroarm as ha
from hydroarm.paper.data import table3
from hydroarm.plotting.paper import fig_model_runs

joint = ha.shoulder_elevation()
cells = [(k, d) for k in (6, 10) for d in ("raise", "lower")]
runs = {(k, d): ha.simulate(ha.saturation_test(joint, ha.paper_load(k), d)) for k, d in cells}

paper = table3()
print(f"{'load':>4} {'direction':<9} {'hydroarm':>9} {'Table III':>9}  [mm/s]")
for (k, d), res in runs.items():
    v = res.summary()["saturation_velocity_mm_s"]
    print(f"{k:>4} {d:<9} {v:9.2f} {paper[(k, d)]:9.2f}  ({100 * (v / paper[(k, d)] - 1):+.1f} %)")

fig = fig_model_runs(runs, "shoulder elevation, loads 6 and 10 (Figs. 7, 8)")
fig.savefig("paper_table3.png", dpi=100)
