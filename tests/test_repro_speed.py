"""The shortcuts of ``hydroarm reproduce`` (issue 21) give what the long way gives."""

import numpy as np
import pytest

from hydroarm.io.catalog import paper_load
from hydroarm.io.schema import parameter_set
from hydroarm.model.result import measure_together
from hydroarm.model.scenario import saturation_test, simulate
from hydroarm.paper import validation as V
from hydroarm.plotting.paper import thin


@pytest.fixture(scope="module")
def arm():
    return parameter_set("ucl-arm-measured")


@pytest.mark.parametrize("mass", [0.2, 0.4495, 0.4510, 3.0])
def test_early_stopping_probe_agrees_with_the_full_run(arm, mass):
    """The probe stops once decided; the full run's recorded maximum decides the same."""
    sc = V._horizontal_probe(arm, V.hand_load(mass), 2.5, 10e-6)
    full = bool(np.max(simulate(sc).theta) > arm.horizontal_angle)
    assert V.passes_horizontal(sc) == full


def test_batch_metrics_equal_single_runs(arm):
    """One batch-engine run gives each scenario the metrics of its own run, bit for bit."""
    paper = parameter_set("paper-calibrated")
    scs = [saturation_test(j, paper_load(k), "raise") for j in (arm, paper) for k in (1, 5)]
    batch = V.batch_metrics(scs)
    for sc, m in zip(scs, batch, strict=True):
        single = simulate(sc).metrics()
        assert m["saturation_velocity"] == single["saturation_velocity_m_s"]
        assert m["time_constant_end"] == single["time_constant_end_s"] or (
            np.isnan(m["time_constant_end"]) and np.isnan(single["time_constant_end_s"])
        )
    results = [simulate(sc) for sc in scs]
    measure_together(results)
    for r, m in zip(results, batch, strict=True):
        assert r.metrics()["saturation_velocity_m_s"] == m["saturation_velocity"]


def test_thin_keeps_extremes_and_ends():
    t = np.linspace(0.0, 1.0, 100_001)
    y = np.sin(40 * t) + (t == t[31_337]) * 5.0  # one spike
    tt, yy = thin(t, y, buckets=500)
    assert len(tt) <= 4 * 500 + 2
    assert (tt[0], tt[-1]) == (t[0], t[-1])
    assert yy.max() == y.max() and yy.min() == y.min()
    assert np.all(np.diff(tt) > 0)
    short = np.arange(10.0)
    assert thin(short, short)[0] is not None and len(thin(short, short)[0]) == 10
