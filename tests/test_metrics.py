"""The evaluation methods on traces with known answers (no model needed)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hydroarm.metrics.step import saturation_velocity, step_metrics


def servo_trace(v, tau, e_o, x0, x1, t_end=2.0, n=20001):
    """Ideal saturating first-order servo: ẋ = min(v, (y − x)/τ)·sign, exact piecewise form."""
    t = np.linspace(0, t_end, n)
    d = abs(x1 - x0)
    s = math.copysign(1.0, x1 - x0)
    t_sat = (d - v * tau) / v  # saturated until the error falls to v·τ
    dist = np.where(t < t_sat, v * t, d - v * tau * np.exp(-(t - t_sat) / tau))
    return t, x0 + s * dist


@pytest.mark.parametrize("x0, x1", [(-10.0, 10.0), (10.0, -10.0)])
def test_recovers_velocity_and_end_time_constant(x0, x1):
    v, tau = 30.0, 0.025  # mm/s, s; full valve opening e_o = v·τ for a no-load servo
    t, x = servo_trace(v, tau, v * tau, x0, x1)
    m = step_metrics(t, x, valve_opening=v * tau, target=x1)
    assert m["saturation_velocity"] == pytest.approx(v, rel=1e-4)
    # 63 % of the opening is covered in τ·ln(1/0.37) = 0.994 τ
    assert m["time_constant_end"] == pytest.approx(tau * math.log(1 / 0.37), rel=1e-3)
    assert m["stalled"] is False
    assert m["direction"] == (1 if x1 > x0 else -1)


def test_start_time_constant_velocity_reading_of_exponential_rise():
    # velocity rising as v(1 − exp(−t/T)): the velocity reaches 63 % at T·ln(1/0.37)
    T, v = 0.03, 25.0
    t = np.linspace(0, 1.5, 30001)
    x = v * (t - T * (1 - np.exp(-t / T)))
    m = step_metrics(t, x, t_start=0.0)
    assert m["time_constant_start_velocity"] == pytest.approx(T * math.log(1 / 0.37), rel=2e-3)
    assert math.isnan(m["time_constant_start"])  # the literal reading needs e_o


def test_start_time_constant_is_the_time_to_move_63_percent_of_the_opening():
    # the paper's "time to move 63 % of full valve opening", read literally, on the same
    # exponential rise: x(t) = 0.63·e_o solved by bisection (the trace is interpolated
    # linearly between samples 50 us apart, where x'' ≤ v/T: error ≪ 1e-4 relative)
    from scipy.optimize import brentq

    T, v, e_o = 0.03, 25.0, 0.75
    t = np.linspace(0, 1.5, 30001)
    x = v * (t - T * (1 - np.exp(-t / T)))
    exact = brentq(lambda s: v * (s - T * (1 - math.exp(-s / T))) - 0.63 * e_o, 0, 1)
    m = step_metrics(t, x, t_start=0.0, valve_opening=e_o)
    assert m["time_constant_start"] == pytest.approx(exact, rel=1e-4)
    # an ideal saturating servo moves at v from the step: 0.63·e_o/v = 0.63·τ with e_o = v·τ
    tau = 0.025
    t, x = servo_trace(30.0, tau, 30.0 * tau, -10.0, 10.0)
    m = step_metrics(t, x, t_start=0.0, valve_opening=30.0 * tau, target=10.0)
    assert m["time_constant_start"] == pytest.approx(0.63 * tau, rel=1e-6)


def test_stalled_motion_measured_up_to_stall():
    # moves at 20 mm/s from −10 to 5 mm, then stops; commanded to +10 mm
    t = np.linspace(0, 2, 4001)
    x = np.minimum(-10 + 20 * t, 5.0)
    m = step_metrics(t, x, target=10.0, valve_opening=0.75)
    assert m["stalled"] is True
    assert m["stall_position"] == pytest.approx(5.0)
    assert m["saturation_velocity"] == pytest.approx(20.0, rel=1e-6)
    assert math.isnan(m["time_constant_end"])


def test_without_target_stall_is_unknown():
    t = np.linspace(0, 1, 101)
    assert step_metrics(t, 5 * t)["stalled"] is None


@settings(max_examples=60, deadline=None)
@given(
    slope=st.floats(0.1, 1e3),
    offset=st.floats(-1e3, 1e3),
    sign=st.sampled_from([-1, 1]),
    middle=st.floats(0.2, 0.95),
)
def test_constant_velocity_gives_its_slope(slope, offset, sign, middle):
    t = np.linspace(0.0, 1.0, 501)
    x = offset + sign * slope * t
    assert saturation_velocity(t, x, middle=middle) == pytest.approx(slope, rel=1e-9)


def test_rejects_bad_traces():
    from hydroarm.errors import HydroarmError

    with pytest.raises(HydroarmError):
        step_metrics([0, 1, 1], [0, 1, 2])
    with pytest.raises(HydroarmError):
        step_metrics([0, 1, 2], [0, np.nan, 2])
    with pytest.raises(HydroarmError):
        step_metrics([0, 1, 2], [1, 1, 1])
    with pytest.raises(HydroarmError):
        step_metrics([0, 1, 2], [0, 1, 2], middle=1.5)
