"""Verification ladder: convergence orders, adaptive reference, stability limit."""

import math

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.arm.config import ARM_METHODS
from hydroarm.cli import build_parser, main
from hydroarm.errors import HydroarmError, StabilityError
from hydroarm.integrators import fixed, registry


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


def _cli_method_choices():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    simulate = sub.choices["simulate"]
    return next(a for a in simulate._actions if a.dest == "method").choices


def test_registry_names_are_the_cli_choices_and_hydroarm_methods():
    names = tuple(registry.METHODS)
    assert names == ("euler", "rk4", "adaptive")
    assert tuple(_cli_method_choices()) == names
    assert ha.METHODS == names and isinstance(ha.METHODS, tuple)
    assert registry.fixed_step_methods() == ("euler", "rk4") == ARM_METHODS
    assert all(m.name == n for n, m in registry.METHODS.items())


def test_registry_codes_are_unique_and_the_kernel_constants():
    codes = [m.code for m in registry.METHODS.values()]
    assert len(set(codes)) == len(codes)
    assert registry.method("euler").code == fixed.EULER
    assert registry.method("rk4").code == fixed.RK4
    assert not registry.method("adaptive").fixed_step
    assert all(m.description and m.reference for m in registry.METHODS.values())


@pytest.mark.parametrize("bad", ["x", "Euler", "", None])
def test_unknown_method_is_one_line_error(bad):
    with pytest.raises(HydroarmError) as e:
        registry.method(bad)
    msg = str(e.value)
    assert msg == f"solver.method: must be one of euler, rk4, adaptive, got {bad!r}"
    assert "\n" not in msg
    assert e.value.field == "solver.method"


def test_scenario_refuses_an_unknown_method(calibrated):
    with pytest.raises(HydroarmError) as e:
        smooth_case(calibrated, "x", 1e-4)
    assert str(e.value) == "solver.method: must be one of euler, rk4, adaptive, got 'x'"


def test_cli_refuses_an_unknown_method(capsys):
    assert main(["simulate", "--method", "x"]) == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'x' (choose from 'euler', 'rk4', 'adaptive')" in err
    assert err.count("\n") == 1


def test_adaptive_refuses_non_smooth_physics(calibrated):
    sc = smooth_case(calibrated.replace(end_stop_angle=1.0), "adaptive", 1e-3)
    with pytest.raises(HydroarmError) as e:
        ha.simulate(sc)
    assert str(e.value) == (
        "solver.method: 'adaptive' cannot integrate dry friction or end stops "
        "(non-smooth physics); use 'euler' or 'rk4'"
    )
