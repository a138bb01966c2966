"""Global sensitivity: Sobol indices of the saturation velocity
=============================================================

Which uncertain parameter of the shoulder joint matters for its saturation velocity? A Sobol
study (docs/sensitivity.md) varies the flow coefficient, the leakage coefficient and the
trapped volume and splits the variance of the velocity into first-order (S1) and total (ST)
shares, drawn with `hydroarm.plotting.sensitivity.sobol_figure`. A small sample keeps the
example quick; the confidence bars say how rough it is.
"""

import matplotlib

matplotlib.use("Agg")

import hydroarm as ha
from hydroarm.analysis.sensitivity import study_from_doc
from hydroarm.plotting.sensitivity import sobol_figure

study = study_from_doc(
    {
        "joint": {"parameter_set": "paper-calibrated"},
        "load": 6,
        "direction": "raise",
        "sensitivity": {
            "method": "sobol",
            "samples": 32,
            "seed": 3,
            "solver": {"duration": "1.2 s"},
            "parameters": {
                "flow_coefficient": {"distribution": "uniform", "relative": 0.1},
                "leakage_coefficient": {"distribution": "uniform", "relative": 0.2},
                "trapped_volume": {"distribution": "uniform", "relative": 0.1},
            },
        },
    }
)
result = ha.sensitivity(study)
rows = result.rows
for row in rows:
    print(f"{row['parameter']:<22} S1 {row['S1']:6.3f}  ST {row['ST']:6.3f}")

fig = sobol_figure(
    [r["parameter"] for r in rows],
    [r["S1"] for r in rows],
    [r["S1_conf"] for r in rows],
    [r["ST"] for r in rows],
    [r["ST_conf"] for r in rows],
    metric=rows[0]["metric"],
)
fig.savefig("sensitivity_sobol.png", dpi=100)
