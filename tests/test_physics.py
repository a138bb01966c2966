"""Physics options (issue 4): each isolated against a known answer, the measured-arm
parameter set against the measurements, and invariants over random scenarios."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hydroarm as ha
from hydroarm.core.equations import flow_gain, holding_pressure, pressure_limit, valve_flow
from hydroarm.core.lever import play_operator
from hydroarm.errors import HydroarmError
from hydroarm.io.catalog import paper_load
from hydroarm.io.schema import load_scenario_text
from hydroarm.model.joint import Load
from hydroarm.model.scenario import Scenario, saturation_test, simulate
from hydroarm.paper import validation as V
from hydroarm.paper.calibration import measured_arm_base
from hydroarm.paper.data import measurement


@pytest.fixture(scope="module")
def arm():
    return ha.parameter_set("ucl-arm-measured")


@pytest.fixture(scope="module")
def velocities(arm, calibrated):
    return V.velocities(arm), V.velocities(calibrated)


# ----------------------------------------------------------- against the arm ---
def test_table1_from_real_loads_within_5_percent(velocities):
    # issue 4: the physics model with the real loads 1 and 5 predicts Table I within 5 %
    # (the paper's own agreement is ~3 %; Table I prints 3 significant figures)
    hy, _ = velocities
    t1 = V.table1()
    errs = {k: hy[k] / t1[k] - 1 for k in V.CELLS}
    assert max(abs(e) for e in errs.values()) < 0.05, errs


def test_paper_model1_misses_by_more(velocities):
    hy, m1 = velocities
    t1 = V.table1()
    worst_hy = max(abs(hy[k] / t1[k] - 1) for k in V.CELLS)
    worst_m1 = max(abs(m1[k] / t1[k] - 1) for k in V.CELLS)
    assert worst_m1 > 0.05 > worst_hy
    assert worst_m1 > 3 * worst_hy


def test_lowering_faster_than_raising_as_measured(velocities):
    # the paper: lowering is 53.5 % faster than raising on average (±8 % scatter)
    hy, _ = velocities
    ratio = (hy[(1, "lower")] + hy[(5, "lower")]) / (hy[(1, "raise")] + hy[(5, "raise")])
    assert ratio == pytest.approx(1.535, rel=0.08)


def test_stall_mass_within_10_percent(arm):
    # measured: 0.45 kg in the hand stalls the arm at the horizontal (±10 %, issue 4)
    assert V.stall_mass(arm, tol=2e-3) == pytest.approx(0.45, rel=0.10)


def test_paper_model_stalls_far_too_late(calibrated):
    # the linearised valve does not bound the pressure by the supply: many kg to stall
    assert V.stall_mass(calibrated, tol=0.05) > 2.0


def test_no_load_time_constant_within_10_percent(arm):
    # measured 25, 28, 24, 26 ms (mean 25.8 ms): ±10 % (issue 4)
    assert V.no_load_time_constant(arm) == pytest.approx(
        measurement("no_load_time_constant_ms"), rel=0.10
    )


def test_measured_set_is_consistent_with_its_derivation(arm):
    base = measured_arm_base(ha.parameter_set("paper-printed"))
    # gearbox friction from the spring-balance test, printed to 5 figures in the set
    assert arm.gearbox_friction_torque == pytest.approx(base.gearbox_friction_torque, rel=1e-4)
    assert V.friction_torque_unpressurised(arm) == pytest.approx(0.7, rel=1e-4)
    # the stored loss at stall reproduces the stall mass (bisection tolerance 1e-3)
    c = V.gearbox_loss_for_stall(arm, tol=1e-3)
    assert c == pytest.approx(arm.gearbox_loss_at_stall, abs=2e-3)


def test_rk4_agrees_with_euler_under_friction(arm):
    # dry friction is applied as a projection in both; at 10 µs they agree to 0.5 %
    sc = saturation_test(arm, paper_load(5), "raise")
    ve = simulate(sc).metrics()["saturation_velocity_m_s"]
    vr = simulate(sc.replace(method="rk4")).metrics()["saturation_velocity_m_s"]
    assert vr == pytest.approx(ve, rel=5e-3)


# --------------------------------------------------- options, isolated ---
def _held(joint, load, theta0, p0, duration=0.05):
    """Valve closed (lever at the jack position), no leakage: does the joint stay put?"""
    y = joint.jack_position(theta0)
    sc = Scenario(
        joint=joint,
        load=load,
        lever=ha.step(y, y, 0.0),
        initial_angle=theta0,
        initial_pressure=p0,
        duration=duration,
    )
    r = simulate(sc)
    return bool(np.all(r.theta == theta0)), r


def _torque_pressure(joint, theta, torque):
    """Load pressure that gives the net drive torque ``torque`` against gravity at θ."""
    lever = (
        joint.crank_radius
        / joint.gear_ratio
        * (math.cos(theta / joint.gear_ratio) if joint.torque_arm == "kinematic" else 1.0)
    )
    grav = LOAD.weight * LOAD.arm * math.cos(theta - joint.horizontal_angle)
    return (grav + torque) / (joint.piston_area * lever), lever


LOAD = Load(weight=15.0, arm=0.2, inertia=0.05)


@pytest.mark.parametrize("kind", ["piston", "gearbox_constant"])
def test_breakaway_hold_and_move(calibrated, kind):
    # a drive just below the breakaway torque holds still; just above it moves
    j = calibrated.replace(leakage_coefficient=0.0)
    if kind == "piston":
        j = j.replace(coulomb_friction=18.0, static_friction=30.0)
    else:
        j = j.replace(gearbox_friction_torque=0.5)
    th = 0.2
    _, lever = _torque_pressure(j, th, 0.0)
    breakaway = 30.0 * lever if kind == "piston" else 0.5
    for sign in (1, -1):
        p_lo, _ = _torque_pressure(j, th, sign * 0.99 * breakaway)
        p_hi, _ = _torque_pressure(j, th, sign * 1.01 * breakaway)
        assert _held(j, LOAD, th, p_lo)[0]
        held, r = _held(j, LOAD, th, p_hi)
        assert not held and np.sign(r.theta[-1] - th) == sign


def test_gearbox_load_loss_hold_and_move(calibrated):
    # the load-dependent loss c·γᵏ·|T_act| adds to the breakaway torque
    j = calibrated.replace(
        leakage_coefficient=0.0, gearbox_loss_at_stall=0.5, gearbox_loss_exponent=2.0
    )
    th = 0.2
    for frac, held in ((0.99, True), (1.01, False)):
        # solve T_act − T_grav = frac·c·γ²·T_act for p by fixed point
        p, lever = _torque_pressure(j, th, 0.0)
        for _ in range(200):
            t_act = j.piston_area * p * lever
            loss = 0.5 * (p / j.supply_pressure) ** 2 * t_act
            p, _ = _torque_pressure(j, th, frac * loss)
        assert _held(j, LOAD, th, p)[0] is held


def test_coulomb_sliding_deceleration():
    # known answer: a joint coasting against Coulomb friction alone stops after
    # Δθ = I·ω₀²/(2·T_f); the hydraulics are made inert (no flow, huge oil volume)
    j = ha.parameter_set("paper-calibrated").replace(
        leakage_coefficient=0.0, trapped_volume=1e3, coulomb_friction=18.0
    )
    load = Load(weight=0.0, arm=0.0, inertia=0.01)
    th0, w0 = 0.0, 2.0
    sc = Scenario(
        joint=j,
        load=load,
        lever=ha.step(0.0, 0.0, 0.0),
        initial_angle=th0,
        initial_pressure=0.0,
        duration=0.2,
        step=1e-6,
    )
    from hydroarm.integrators import fixed

    lev = sc.lever
    t, th, om, p, y, bad = fixed.integrate(
        fixed.EULER,
        th0,
        w0,
        0.0,
        0.0,
        1e-6,
        200000,
        1,
        lev.times,
        lev.positions,
        lev.sine,
        *sc.params,
    )
    tf = 18.0 * j.crank_radius / j.gear_ratio
    # expected travel I·ω₀²/(2·T_f) (first order in h; the oil column is nearly inert)
    assert th[-1] == pytest.approx(load.inertia * w0**2 / (2 * tf), rel=2e-3)
    assert om[-1] == 0.0


def test_orifice_steady_velocity_closed_form(calibrated):
    # known answer: quasi-steady raising at the horizontal with the valve wide open,
    # no leakage: A·ẋ = K·e_o·√((p_s − p_L)/2), p_L = W·X/(A·r/n)
    j = calibrated.replace(valve_model="orifice", leakage_coefficient=0.0)
    load = Load(weight=15.0, arm=0.2, inertia=0.01)
    r = simulate(saturation_test(j, load, "raise"))
    k = np.argmin(np.abs(r.theta - j.horizontal_angle))
    p_l = load.weight * load.arm / (j.piston_area * j.crank_radius / j.gear_ratio)
    v = j.flow_coefficient * j.valve_saturation * math.sqrt((j.supply_pressure - p_l) / 2)
    assert r.xdot[k] == pytest.approx(v / j.piston_area, rel=5e-3)  # quasi-steady: ½ %
    assert r.p[k] == pytest.approx(p_l, rel=0.02)


def test_orifice_stalled_pressure_is_supply(calibrated):
    # a load whose peak torque (18 N m) exceeds the stall torque A·p_s·r/n (9.4 N m):
    # without leakage the arm stalls where W·X·cos(θ−θ_h) = A·p_s·r/n, at p = p_s exactly
    # (a lightly damped oscillation about it: the last second's mean is compared)
    j = calibrated.replace(valve_model="orifice", leakage_coefficient=0.0)
    load = Load(weight=60.0, arm=0.3, inertia=0.1)
    r = simulate(saturation_test(j, load, "raise", duration=3.0))
    last = r.t > 2.0
    assert np.mean(r.p[last]) == pytest.approx(j.supply_pressure, rel=1e-3)
    theta_stall = j.horizontal_angle - math.acos(j.stall_torque / (load.weight * load.arm))
    assert np.mean(r.theta[last]) == pytest.approx(theta_stall, abs=math.radians(0.5))
    assert np.max(np.abs(r.p)) <= pressure_limit(r.scenario.params[0])


def test_orifice_flow_law(calibrated):
    j = calibrated.replace(valve_model="orifice")
    P = j.params()
    e, ps = j.valve_saturation, j.supply_pressure
    for p in (0.0, 0.3 * ps, 0.9 * ps):
        assert valve_flow(e, p, P) == pytest.approx(
            j.flow_coefficient * e * math.sqrt((ps - p) / 2), rel=1e-3
        )
        assert valve_flow(-e, p, P) == pytest.approx(
            -j.flow_coefficient * e * math.sqrt((ps + p) / 2), rel=1e-3
        )
    # at zero pressure drop the flow is zero and it reverses beyond (regularised)
    assert valve_flow(e, ps, P) == 0.0
    assert valve_flow(e, 1.1 * ps, P) < 0.0
    # the linear option is the paper's K_q·e whatever the pressure
    P0 = calibrated.params()
    assert valve_flow(e, 0.9 * ps, P0) == pytest.approx(calibrated.flow_gain * e, rel=1e-15)


def test_viscous_friction_closed_form(calibrated):
    # no gravity, linear valve: K_q·e_o = A·ẋ + 2L·p with A·p = b·ẋ ⇒ ẋ = K_q·e_o/(A + 2Lb/A)
    b = 2.0e4
    j = calibrated.replace(viscous_friction=b, torque_arm="kinematic")
    load = Load(weight=0.0, arm=0.0, inertia=0.002)
    r = simulate(saturation_test(j, load, "raise"))
    k = np.argmin(np.abs(r.theta))
    A, L = j.piston_area, j.leakage_coefficient
    assert r.xdot[k] == pytest.approx(
        j.flow_gain * j.valve_saturation / (A + 2 * L * b / A), rel=2e-3
    )


def test_kinematic_torque_arm_holds_with_cos_phi(calibrated):
    # the holding pressure with the kinematic arm is W·X·cos(θ−θ_h)/(A·r·cos(θ/n)/n)
    j = calibrated.replace(torque_arm="kinematic", leakage_coefficient=0.0)
    th = 1.0
    p = (
        LOAD.weight
        * LOAD.arm
        * math.cos(th - j.horizontal_angle)
        / (j.piston_area * j.crank_radius * math.cos(th / 2) / 2)
    )
    y = j.jack_position(th)
    sc = Scenario(
        joint=j,
        load=LOAD,
        lever=ha.step(y, y, 0.0),
        initial_angle=th,
        initial_pressure=p,
        duration=0.05,
    )
    r = simulate(sc)
    assert np.max(np.abs(r.theta - th)) < 1e-9
    assert sc.start_pressure() == pytest.approx(p, rel=1e-12)  # default start pressure


def test_end_stop(calibrated):
    stop = math.radians(45)
    j = calibrated.replace(end_stop_angle=stop)
    r = simulate(saturation_test(j, paper_load(1), "raise"))
    assert r.theta.max() <= stop
    assert r.theta[-1] == stop
    r = simulate(saturation_test(j, paper_load(1), "lower"))
    assert r.theta.min() >= -stop and r.theta[-1] == -stop


def test_backlash_play_operator():
    # known answer: a sine through a play of width b comes out with amplitude a − b/2,
    # lagging at each reversal
    t = np.linspace(0, 2, 2001)
    a, b = 0.3, 0.1
    out = play_operator(a * np.sin(2 * np.pi * t), b, initial=0.0)
    assert out.max() == pytest.approx(a - b / 2, abs=1e-12)
    assert out.min() == pytest.approx(-(a - b / 2), abs=1e-12)
    assert np.all(np.abs(out - a * np.sin(2 * np.pi * t)) <= b / 2 + 1e-15)


def test_backlash_in_result(calibrated):
    j = calibrated.replace(backlash=math.radians(4))
    r = simulate(saturation_test(j, paper_load(1), "raise"))
    lag = r.theta - r.arm_angle
    assert np.max(np.abs(lag)) == pytest.approx(math.radians(2), rel=1e-9)
    assert np.array_equal(
        simulate(saturation_test(calibrated, paper_load(1), "raise")).arm_angle,
        simulate(saturation_test(calibrated, paper_load(1), "raise")).theta,
    )


def test_paper_model_unchanged_by_defaults(calibrated):
    # with every option off the kernel is the paper's (Table III number from issue 2)
    assert calibrated.is_paper_model
    v = simulate(saturation_test(calibrated, paper_load(6), "raise")).metrics()
    # (24.84 before issue 13 measured up to the final position, 0.12 mm short of the target)
    assert v["saturation_velocity_m_s"] * 1e3 == pytest.approx(24.83, abs=0.01)


def test_adaptive_refuses_dry_friction(arm):
    with pytest.raises(HydroarmError, match="solver.method"):
        simulate(saturation_test(arm, paper_load(1), "raise", method="adaptive"))


def test_adaptive_reference_for_orifice(calibrated):
    # the smooth orifice option: fixed step against the adaptive Radau reference
    j = calibrated.replace(valve_model="orifice")
    sc = saturation_test(j, paper_load(5), "raise")
    a = simulate(sc.replace(method="adaptive", step=1e-4))
    r = simulate(sc.replace(method="rk4", step=1e-5, record_every=10))
    assert np.max(np.abs(a.theta - r.theta)) < 1e-5


# ------------------------------------------------------------ scenario file ---
SCEN = """
[joint]
parameter_set = "paper-calibrated"
[physics]
valve_model = "orifice"
torque_arm = "kinematic"
coulomb_friction = "4 lbf"
static_friction = "30 N"
gearbox_friction_torque = "0.5 N*m"
gearbox_loss_at_stall = 0.5
gearbox_loss_exponent = 4
end_stop_angle = "85 deg"
backlash = "2 deg"
[load]
builtin = 1
[input]
direction = "raise"
"""


def test_physics_section_parsed():
    sc = load_scenario_text(SCEN)
    j = sc.joint
    assert j.valve_model == "orifice" and j.torque_arm == "kinematic"
    assert j.coulomb_friction == pytest.approx(4 * 4.4482216152605)
    assert j.end_stop_angle == pytest.approx(math.radians(85))
    assert j.backlash == pytest.approx(math.radians(2))
    assert simulate(sc).metrics()["saturation_velocity_m_s"] > 0


@pytest.mark.parametrize(
    "line, field",
    [
        ('valve_model = "spool"', "physics.valve_model"),
        ('coulomb_friction = "18 bar"', "physics.coulomb_friction"),
        ('static_friction = "-3 N"', "physics.static_friction"),
        ("gearbox_loss_at_stall = 1.5", "physics.gearbox_loss_at_stall"),
        ('end_stop_angle = "200 deg"', "physics.end_stop_angle"),
        ('stiction = "30 N"', "physics.stiction"),
    ],
)
def test_physics_section_errors(line, field):
    key = line.split(" =")[0]
    kept = [ln for ln in SCEN.splitlines() if not ln.startswith(key + " =")]
    text = "\n".join(kept).replace("[physics]", f"[physics]\n{line}")
    with pytest.raises(HydroarmError, match=field.replace(".", r"\.")):
        load_scenario_text(text)


# ------------------------------------------------------------- invariants ---
scenario_params = st.fixed_dictionaries(
    {
        "weight": st.floats(0.0, 25.0),
        "arm": st.floats(0.05, 0.35),
        "inertia": st.floats(0.01, 0.3),
        "k_factor": st.floats(0.7, 1.3),
        "leak": st.floats(0.0, 1000e-15),
        "coulomb": st.floats(0.0, 40.0),
        "loss": st.floats(0.0, 0.9),
        "direction": st.sampled_from(["raise", "lower"]),
    }
)


@pytest.mark.slow
@settings(
    max_examples=25, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(scenario_params)
def test_invariants_orifice(q):
    base = ha.parameter_set("ucl-arm-measured")
    j = base.replace(
        flow_coefficient=base.flow_coefficient * q["k_factor"],
        leakage_coefficient=q["leak"],
        coulomb_friction=q["coulomb"],
        static_friction=1.5 * q["coulomb"],
        gearbox_loss_at_stall=q["loss"],
    )
    load = Load(weight=q["weight"], arm=q["arm"], inertia=q["inertia"])
    r = simulate(saturation_test(j, load, q["direction"], duration=1.2))
    # no NaN or inf
    assert np.all(np.isfinite(r.theta)) and np.all(np.isfinite(r.p))
    # pressures within physical bounds: no chamber below zero absolute pressure ...
    assert np.max(np.abs(r.p)) <= j.supply_pressure + 2 * j.atmospheric_pressure
    # ... and not above supply in steady motion (the middle 80 % of the travel; these loads
    # are below the stall torque, so no load overruns the valve)
    ta, tb = r.metrics()["t_middle_s"]
    if np.isfinite(ta) and np.isfinite(tb):
        mid = (r.t >= ta) & (r.t <= tb)
        assert np.max(np.abs(r.p[mid]), initial=0.0) <= j.supply_pressure * (1 + 1e-6)
    # energy in = work on the load + losses, closed to 0.1 % of the throughput
    # (semi-implicit Euler at 10 µs with trapezoidal quadrature of the trace)
    eb = r.energy_balance()
    assert abs(eb["relative_residual"]) < 1e-3, eb


def test_energy_closes_only_with_kinematic_arm(calibrated):
    # the paper's eq. (3) torque arm r/n drops cos φ: its energy does not balance
    sc = saturation_test(calibrated, paper_load(5), "raise")
    assert abs(simulate(sc).energy_balance()["relative_residual"]) > 1e-2
    kin = sc.replace(joint=calibrated.replace(torque_arm="kinematic"))
    assert abs(simulate(kin).energy_balance()["relative_residual"]) < 1e-4


# ------------------------------------------------------- end of travel (issue 13) ---
# docs/model.md "Known limits": raised loads stop short [mm], lowered loads overshoot [deg,
# mm], paper-calibrated, loads 1-10; the documented values, rounded as printed there
DOC_SHORT_MM = {1: 0.066, 2: 0.078, 3: 0.090, 4: 0.103, 5: 0.121,
                6: 0.124, 7: 0.146, 8: 0.169, 9: 0.192, 10: 0.226}  # fmt: skip
DOC_SHORT_DEG = {1: 0.44, 2: 0.52, 3: 0.60, 4: 0.68, 5: 0.80,
                 6: 0.82, 7: 0.97, 8: 1.12, 9: 1.27, 10: 1.49}  # fmt: skip
DOC_OVERSHOOT_DEG = {1: 0.00, 2: 0.01, 3: 0.05, 4: 0.36, 5: 0.84,
                     6: 1.05, 7: 1.56, 8: 2.05, 9: 2.51, 10: 3.16}  # fmt: skip
DOC_OVERSHOOT_MM = {1: 0.000, 2: 0.001, 3: 0.007, 4: 0.054, 5: 0.127,
                    6: 0.158, 7: 0.235, 8: 0.308, 9: 0.377, 10: 0.474}  # fmt: skip
SETTLED = 4.0  # [s]: the slowest mode (load 10, -9.1/s) has decayed by e^-29 after the motion


@pytest.mark.parametrize("load", range(1, 11))
def test_end_of_travel_offset(load):
    """Raised, the jack stops short by e_ss = 2·L·p_hold/K_q (the valve stays open to supply
    the leakage at the holding pressure)."""
    j = ha.parameter_set("paper-calibrated")
    sc = saturation_test(j, paper_load(load), "raise", duration=SETTLED, record_every=100)
    r = simulate(sc)
    J, L = sc.params
    short = sc.target - r.x[-1]  # [m]
    kq = float(flow_gain(J))
    # p_hold where the arm stops: equal to round-off and the last of the transient (< 1e-5)
    at_stop = 2 * J.leakage_coefficient * float(holding_pressure(r.theta[-1], J, L)) / kq
    assert short == pytest.approx(at_stop, rel=1e-4)
    # p_hold at the target angle: smaller by the stop's cos(θ₂ − θ_h) ≈ 1 + tan 30°·δθ₂
    at_target = 2 * J.leakage_coefficient * float(holding_pressure(sc.target_angle(), J, L)) / kq
    d_theta = sc.target_angle() - r.theta[-1]
    assert short / at_target - 1 == pytest.approx(math.tan(math.radians(30)) * d_theta, rel=0.05)
    assert 0 < short / at_target - 1 < 0.016
    # the documented sizes, to their printed rounding
    assert short * 1e3 == pytest.approx(DOC_SHORT_MM[load], abs=0.0005)
    assert math.degrees(d_theta) == pytest.approx(DOC_SHORT_DEG[load], abs=0.005)


@pytest.mark.parametrize("load", range(1, 11))
def test_lowering_overshoot(load):
    """Lowered, no offset (hanging, p_hold = 0) but an overshoot past θ₂ = −60° of the size
    the docs give (rounded as printed)."""
    j = ha.parameter_set("paper-calibrated")
    sc = saturation_test(j, paper_load(load), "lower", duration=SETTLED, record_every=10)
    r = simulate(sc)
    assert abs(r.x[-1] - sc.target) < 1e-9  # [m]: settled on the target
    over_deg = math.degrees(sc.target_angle() - r.theta.min())
    over_mm = (sc.target - r.x.min()) * 1e3
    assert over_deg == pytest.approx(DOC_OVERSHOOT_DEG[load], abs=0.005)
    assert over_mm == pytest.approx(DOC_OVERSHOOT_MM[load], abs=0.0005)
