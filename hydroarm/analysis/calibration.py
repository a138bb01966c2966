"""Calibration of a parameter set against the paper's Table III (Model 2 velocities).

The printed Appendix I parameters give Model 2 velocities about 10 % above Table III on
average while reproducing the raise/lower split well (docs/model.md). A least-squares fit
of the valve flow coefficient K and the leakage coefficient L to the four Table III cells
closes the gap to about 1 %; the fitted K gives a no-load time constant A/K_q of 25.8 ms,
the measured no-load value, although no time constant enters the fit.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from ..scenarios.paper import paper_load, published_table
from ..simulation import saturation_test, simulate


def table3_targets() -> dict:
    out = {}
    for r in published_table("table3"):
        out[(r["load"], "raise")] = r["raise_mm_s"] * 1e-3
        out[(r["load"], "lower")] = r["lower_mm_s"] * 1e-3
    return out


def model_velocities(joint, cells, **kw) -> dict:
    """Saturation velocity [m/s] of each (load, direction) cell."""
    return {k: simulate(saturation_test(joint, paper_load(k[0]), k[1], **kw)).metrics()[
        "saturation_velocity"] for k in cells}


def fit_table3(joint, fields=("flow_coefficient", "leakage_coefficient"), **kw):
    """Least-squares fit of ``fields`` of ``joint`` to Table III (relative errors).

    Returns (fitted joint, dict of relative errors per cell).
    """
    target = table3_targets()
    x0 = np.array([getattr(joint, f) for f in fields])

    def make(v):
        return joint.replace(**{f: float(s * x) for f, s, x in zip(fields, v, x0, strict=True)})

    def residuals(v):
        m = model_velocities(make(v), target, **kw)
        return [m[k] / target[k] - 1 for k in target]

    sol = least_squares(residuals, np.ones(len(fields)), x_scale=0.1, xtol=1e-10)
    fitted = make(sol.x)
    errs = dict(zip(target, residuals(sol.x), strict=True))
    return fitted, errs
