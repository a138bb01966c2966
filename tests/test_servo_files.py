"""Component servo files (hydroarm.io.components): the rotary example against statics, areas
from diameters, units of gains, and the mechanical (paper-like) configuration."""

import math
import pathlib

import numpy as np
import pytest

from hydroarm.io.schema import load_scenario, load_scenario_text

EXAMPLES = pathlib.Path(__file__).parents[1] / "examples"


def test_rotary_example_holds_gravity_with_its_pressure_difference():
    """At rest the vane holds the limb: D·(p_A − p_B) = W·X·cos θ (statics; the viscous term
    vanishes at rest). Tolerance 1 % of the holding torque: the run's residual motion (the
    integral still removing the droop) and the last samples' small accelerations."""
    sc = load_scenario(EXAMPLES / "rotary_joint.toml")
    res = sc.run()
    late = res.t > 1.4
    theta = res.state("position")[late].mean()
    assert abs(math.degrees(theta)) < 0.5  # settles at the 0° reference
    dp = (res.state("pressure_a") - res.state("pressure_b"))[late].mean()
    torque = 20.0 * 0.15 * math.cos(theta)
    assert 5e-6 * dp == pytest.approx(torque, rel=0.01)
    assert res.energies()["balance_j"] == pytest.approx(
        0.0, abs=1e-6 * res.energies()["supply_energy_j"]
    )
    cols = res.columns()
    assert "angle_deg" in cols and "reference_deg" in cols


SINGLE_ROD = """
[actuator]
type = "single_rod"
piston_diameter = "20 mm"
rod_diameter = "10 mm"
stroke = "100 mm"
dead_volume = "2 cm**3"
bulk_modulus = "1 GPa"
internal_leakage = "2e-12 m**3/s/Pa"
[valve]
type = "linearised"
flow_gain = "0.05 m**2/s"
max_stroke = "0.2 mm"
[feedback]
type = "mechanical"
[load]
mass = "2 kg"
[supply]
pressure = "50 bar"
[initial]
position = "50 mm"
[input]
type = "ramp"
from = "50 mm"
to = "52 mm"
end = "0.1 s"
[solver]
duration = "0.08 s"
"""


def test_single_rod_areas_from_diameters():
    sc = load_scenario_text(SINGLE_ROD)
    p = sc.parameters
    assert p["area_a"] == pytest.approx(math.pi * 0.02**2 / 4)
    assert p["area_b"] == pytest.approx(math.pi * (0.02**2 - 0.01**2) / 4)
    assert sc.initial["position"] == pytest.approx(0.05)
    assert p["feedback_kind"] == 0 and p["valve_kind"] == 1


def test_mechanical_servo_follows_its_lever_ramp():
    """Mechanical feedback (spool = lever − jack) tracks a slow lever ramp with the velocity
    error of a type-1 loop: lag = v/K_v with K_v = K_q/A_A for extension (the linearised
    valve; the load is light and the chambers stiff, so the lag is the kinematic one).
    Tolerance 2 %: after 12 loop time constants (1/K_v = 6.3 ms) the start's transient
    has died out to e⁻¹², the leakage's flow at the small holding pressure is 0.3 % of the
    jack's."""
    sc = load_scenario_text(SINGLE_ROD)
    res = sc.run()
    v = 0.002 / 0.1  # the ramp: 2 mm in 0.1 s, inside the spool stroke's reach
    k_v = 0.05 / sc.parameters["area_a"]
    lag = res.reference[-1] - res.state("position")[-1]
    assert lag == pytest.approx(v / k_v, rel=0.02)


def test_natural_frequency_in_hz_is_angular():
    text = (EXAMPLES / "position_servo.toml").read_text()
    sc = load_scenario_text(
        text.replace('natural_frequency = "200 rad/s"', 'natural_frequency = "10 Hz"')
    )
    assert sc.parameters["spool_frequency"] == pytest.approx(2 * math.pi * 10)


def test_matched_linearised_valve_on_a_single_rod_jack():
    """The linearised valve's flow gains are matched to the area ratio (Q_B = −α·Q_A): at
    full opening the jack extends at K_q·x_max/A_A and retracts at α·K_q·x_max/A_B, the
    same speed (the flow into the small chamber is α times that into the large one)."""
    base = load_scenario_text(SINGLE_ROD).replace(duration=0.02, record_every=1)
    up = base.replace(
        reference=type(base.reference)(np.array([0.0, 0.0]), np.array([0.05, 0.09]))
    ).run()
    down = base.replace(
        reference=type(base.reference)(np.array([0.0, 0.0]), np.array([0.05, 0.01]))
    ).run()
    mid = (up.t > 0.01) & (up.t <= 0.02)  # past the start's transient
    v_up = np.mean(up.state("velocity")[mid])
    v_down = -np.mean(down.state("velocity")[mid])
    v = 0.05 * 0.2e-3 / base.parameters["area_a"]
    # tolerance 2 %: the leakage's share of the flow at the running pressures (0.3 %) and
    # what is left of the start's transient (the oil column rings at a few hundred Hz)
    assert v_up == pytest.approx(v, rel=0.02)
    assert v_down == pytest.approx(v, rel=0.02)


def test_initial_spool_is_the_start_of_first_order_spool_dynamics():
    """``[initial] spool`` is the spool's start (it was accepted and ignored): recorded at
    t = 0, then τ·ẋ_v = u − x_v carries it to the demand. Against the same run from the
    spool at 0, the difference of the two spools decays as 1 mm·e^(−t/τ) (the demand is the
    same function of the state in both; the extra opening moves the load a little and the PI
    demand feeds that back: measured 0.11 % of 1 mm over the first τ, tolerance 0.3 %)."""
    text = (EXAMPLES / "position_servo.toml").read_text()
    second = 'dynamics = "second_order"\nnatural_frequency = "200 rad/s"\ndamping_ratio = 1.0'
    assert second in text
    text = text.replace(second, 'dynamics = "first_order"\ntime_constant = "5 ms"')
    text = text.replace('duration = "3 s"', 'duration = "5 ms"').replace(
        "record_every = 100", "record_every = 10"
    )
    sc = load_scenario_text(text.replace("[solver]", '[initial]\nspool = "1 mm"\n[solver]', 1))
    assert sc.initial == {"spool": 1e-3}
    assert sc.initial_state()[4] == 1e-3  # STATES[4]: the spool
    res = sc.run()
    assert res.state("spool")[0] == 1e-3
    assert res.columns()["spool_m"][0] == 1e-3  # the record's first row
    ref = load_scenario_text(text).run()
    assert ref.state("spool")[0] == 0.0
    d = (res.state("spool") - ref.state("spool")) / 1e-3
    np.testing.assert_allclose(d, np.exp(-res.t / 5e-3), rtol=0, atol=3e-3)


def test_relief_flow_force_slope_defaults_to_hopsans():
    """The relief valve's k_cf defaults to Hopsan's 1e-8 m³/(s Pa) (HydraulicPressureReliefValve;
    it was absent: no flow-force term); a given value overrides it."""
    text = (EXAMPLES / "position_servo.toml").read_text()
    assert "relief_flow_force_slope" not in text
    c_f = load_scenario_text(text).parameters["relief_flow_term"]
    assert c_f == pytest.approx(1.0 / (1e-8 * math.sqrt(7e6)), rel=1e-15)
    given = text.replace(
        'relief_nominal_flow = "0.01 m**3/s"',
        'relief_nominal_flow = "0.01 m**3/s"\nrelief_flow_force_slope = "4e-8 m**3/s/Pa"',
    )
    assert load_scenario_text(given).parameters["relief_flow_term"] == pytest.approx(c_f / 4)
