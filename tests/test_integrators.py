"""Verification ladder: convergence orders, adaptive reference, stability limit."""

import math

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.errors import StabilityError


def smooth_case(joint, method, step, duration=0.2):
    # lever oscillating ±0.3 mm around mid-stroke: the valve never saturates (e_o = 0.75 mm),
    # so the right-hand side is smooth and the formal orders apply
    lev = ha.sine(0.0, 0.3e-3, 4.0)
    return ha.Scenario(
        joint=joint,
        load=ha.paper_load(6),
        lever=lev,
        initial_angle=0.0,
        duration=duration,
        method=method,
        step=step,
        record_every=1,
    )


def trajectory(joint, method, h):
    # θ₂ sampled every 4 ms (common to every step tried)
    sc = smooth_case(joint, method, h).replace(record_every=int(round(4e-3 / h)))
    return ha.simulate(sc).theta


@pytest.mark.parametrize(
    "method, order, steps",
    [
        ("euler", 1, [1e-4, 5e-5, 2.5e-5]),
        ("rk4", 4, [4e-3, 2e-3, 1e-3, 5e-4]),
    ],
)
def test_convergence_order(calibrated, method, order, steps):
    ref = trajectory(calibrated, "rk4", 1e-5)
    errs = [np.max(np.abs(trajectory(calibrated, method, h) - ref)) for h in steps]
    orders = [math.log2(errs[i] / errs[i + 1]) for i in range(len(errs) - 1)]
    # observed order (max error over the trajectory) within ±0.3 of the formal order
    for o in orders:
        assert o == pytest.approx(order, abs=0.3)


def test_adaptive_matches_fine_rk4(calibrated):
    sc = ha.saturation_test(calibrated, ha.paper_load(6), "raise", duration=1.0)
    rk = ha.simulate(sc.replace(method="rk4", step=2e-6, record_every=5000))
    ad = ha.simulate(sc.replace(method="adaptive", step=1e-2, record_every=1))
    assert ad.t[-1] == pytest.approx(rk.t[-1])
    assert ad.theta[-1] == pytest.approx(rk.theta[-1], rel=1e-6)


def test_step_above_stability_limit_is_refused(calibrated):
    sc = ha.saturation_test(calibrated, ha.no_load(calibrated), "raise")
    h = sc.largest_stable_step("euler")
    assert 1e-5 < h < 1e-3
    with pytest.raises(StabilityError) as exc:
        ha.simulate(sc.replace(step=1.5 * h))
    assert "largest stable step" in str(exc.value)
    ha.simulate(sc.replace(step=0.9 * h))  # just below: runs, stays finite


def test_stability_limit_is_real(calibrated):
    # Without the check, a step 1.5x the limit blows up (non-finite or huge); 0.5x does not.
    sc = ha.saturation_test(calibrated, ha.no_load(calibrated), "raise", duration=0.3)
    h = sc.largest_stable_step("euler")
    with pytest.raises(StabilityError):
        ha.simulate(sc.replace(step=1.5 * h), check_stability=False)
    ok = ha.simulate(sc.replace(step=0.5 * h), check_stability=False)
    assert np.all(np.isfinite(ok.p))
