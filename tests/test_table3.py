"""Table III of the paper (Model 2 saturation velocities) and the no-load time constant."""

import pytest

import hydroarm as ha
from hydroarm.paper.data import published_table

TABLE3 = {
    (r["load"], d): r[f"{d}_mm_s"] for r in published_table("table3") for d in ("raise", "lower")
}


def velocity(joint, load, direction, **kw):
    res = ha.simulate(ha.saturation_test(joint, ha.paper_load(load), direction, **kw))
    return res.metrics()["saturation_velocity_m_s"] * 1e3


@pytest.mark.parametrize("cell", sorted(TABLE3))
def test_table3_within_3_percent(calibrated, cell):
    # The acceptance limit is 3 %; the fit leaves about 1 % (docs/model.md).
    v = velocity(calibrated, *cell)
    assert v == pytest.approx(TABLE3[cell], rel=0.03)


@pytest.mark.parametrize("cell", [(6, "raise"), (10, "lower")])
def test_table3_step_converged(calibrated, cell):
    # Halving the 10 us step changes the velocity by far less than the paper's 3 s.f. (0.2 %).
    v1 = velocity(calibrated, *cell, step=10e-6)
    v2 = velocity(calibrated, *cell, step=5e-6)
    assert v1 == pytest.approx(v2, rel=2e-4)


def test_printed_parameters_miss_the_mean_but_keep_the_split(printed):
    # Documented discrepancy (docs/model.md): as printed, the mean velocity is ~10 % above
    # Table III, while the raise/lower half-difference (the leakage term) is within 5 %.
    for load in (6, 10):
        up, down = velocity(printed, load, "raise"), velocity(printed, load, "lower")
        mean_paper = (TABLE3[(load, "raise")] + TABLE3[(load, "lower")]) / 2
        half_paper = (TABLE3[(load, "lower")] - TABLE3[(load, "raise")]) / 2
        assert 1.07 < (up + down) / 2 / mean_paper < 1.13
        assert (down - up) / 2 == pytest.approx(half_paper, rel=0.05)


def test_no_load_time_constant_standard_formula(printed, calibrated):
    # "calculated from the standard formula as 23 ms": A/K_q of the printed set, 2 s.f. print.
    assert printed.no_load_time_constant * 1e3 == pytest.approx(23.0, rel=0.03)
    # the calibrated K gives the measured no-load mean, 25.8 ms (3 s.f.)
    assert calibrated.no_load_time_constant * 1e3 == pytest.approx(25.8, rel=0.01)


@pytest.mark.parametrize("set_name", ["paper-printed", "paper-calibrated"])
@pytest.mark.parametrize("direction", ["raise", "lower"])
def test_simulated_no_load_time_constant_matches_formula(set_name, direction):
    # The end-of-travel 63 % time constant of a no-load run is the valve-loop lag A/K_q;
    # the piston mass adds a little inertia: 3 % is the acceptance limit.
    j = ha.parameter_set(set_name)
    res = ha.simulate(ha.saturation_test(j, ha.no_load(j), direction))
    tc = res.metrics()["time_constant_end_s"]
    assert tc == pytest.approx(j.no_load_time_constant, rel=0.03)


@pytest.mark.slow
def test_calibration_refit_reproduces_stored_set(printed, calibrated):
    # The stored calibrated values come from fit_table3 as the first release's model ran it;
    # re-run today it gives K +0.05 % and L -0.25 % away from them. Both are far inside what
    # the four Table III cells can tell: the same fit as a fit file (docs/fit.md, 1 % per
    # cell) has standard errors of 0.5 % on K and 2.3 % on L. The test allows a fifth of K's
    # and under half of L's (abs=0: L is ~5e-13 in SI, below pytest.approx's default abs).
    from hydroarm.paper.calibration import fit_table3

    fitted, errs = fit_table3(printed)
    assert fitted.flow_coefficient == pytest.approx(calibrated.flow_coefficient, rel=1e-3, abs=0)
    assert fitted.leakage_coefficient == pytest.approx(
        calibrated.leakage_coefficient, rel=1e-2, abs=0
    )
    assert max(abs(e) for e in errs.values()) < 0.011  # ≈1 %, what docs/model.md states
