"""Energy sources, rotary parts, sensors and the accumulator of the circuit library
(hydroarm/core/circuit/components: flow_source, accumulator, pressure_sensor, flow_sensor,
variable_pump, hydraulic_motor, inertia), each against a closed form.

Tolerances: the circuits below are smooth linear or polynomial problems integrated with
classical RK4 at steps far below their time constants (h/τ ≤ 1e-3 unless said), whose
global error is O((h/τ)⁴) ≈ 1e-12 relative; the bounds leave room for round-off over 1e5
steps (≈ 1e5·1e-16) and say where they are looser (a step input inside a step, a trapezoid
over records).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hydroarm.core.circuit.components import TYPES
from hydroarm.errors import HydroarmError
from hydroarm.io.circuit import circuit_from_doc
from hydroarm.io.sections import parse_toml
from hydroarm.model.circuit import Circuit, build, simulate
from hydroarm.model.circuit import ComponentSpec as C

BETA = 1.5e9  # [Pa] the volume's default bulk modulus
P_ATM = 1.0e5
REV = 2.0 * math.pi


def run(name, comps, *, step=1e-5, duration=0.2, every=100, **kw):
    circuit = Circuit(name, tuple(comps), step=step, duration=duration, record_every=every, **kw)
    r = simulate(circuit)
    assert r.bad_step == -1
    return r, r.to_pandas()


def test_components_registered():
    for name in (
        "flow_source",
        "accumulator",
        "pressure_sensor",
        "flow_sensor",
        "variable_pump",
        "hydraulic_motor",
        "inertia",
    ):
        assert name in TYPES


# ------------------------------------------------------------------- flow source ---
def test_flow_source_parameter_and_signal_fill_a_volume():
    """q into a closed volume V: p = p₀ + q·t·β/V (parameter); a ramp signal q = a·t:
    p = p₀ + a·t²/2·β/V. Both polynomial in t, which RK4 integrates exactly."""
    q, a, vol = 2.0e-5, 1.0e-4, 1.0e-3
    r, df = run(
        "fs",
        [
            C("tank", "tank", {"port": "T"}),
            C("flow_source", "src", {"inlet": "T", "outlet": "n1"}, {"flow": q}),
            C("volume", "v1", {"port": "n1"}, {"volume": vol}),
            C("signal_source", "ramp", {"out": "qs"}, {"waveform": "ramp", "rate": a}),
            C("flow_source", "src2", {"inlet": "T", "outlet": "n2", "flow": "qs"}, {"flow": 1.0}),
            C("volume", "v2", {"port": "n2"}, {"volume": vol}),
        ],
    )
    t = df["t_s"].to_numpy()
    p1 = P_ATM + q * t * BETA / vol
    p2 = P_ATM + 0.5 * a * t**2 * BETA / vol
    np.testing.assert_allclose(df["n1_pressure_bar"] * 1e5, p1, rtol=1e-12)
    np.testing.assert_allclose(df["n2_pressure_bar"] * 1e5, p2, rtol=1e-12, atol=1e-6)
    # the source's flow output (into it at its inlet) is the flow it passes
    np.testing.assert_allclose(df["src_flow_lpm"], q * 6e4, rtol=1e-12)
    np.testing.assert_allclose(df["src2_flow_lpm"], a * t * 6e4, rtol=1e-12, atol=1e-15)
    # the source delivers the volume's stored energy ∫p·C dp = V/β·(p² − p₀²)/2 (and the
    # tank's p_T·∫q): the account closes to round-off (the power sums to zero each record)
    e = r.energy()
    assert abs(e["closure_energy_j"]) < 1e-9 * abs(e["src_energy_j"])
    stored = vol / BETA * (p1[-1] ** 2 - P_ATM**2) / 2
    # trapezoid over 1 ms records of a power linear in t: exact
    assert e["v1_energy_j"] == pytest.approx(stored, rel=1e-9)


# ------------------------------------------------------------------- accumulator ---
def _acc_volume(p, p0, v0, n):
    """Closed form: oil stored in a gas accumulator at p (polytropic gas p·V^n = const)."""
    return v0 * (1.0 - (p0 / p) ** (1.0 / n))


@pytest.mark.parametrize("n", [1.0, 1.4])
def test_accumulator_charged_from_a_flow_source_follows_the_gas_law(n):
    """A flow source q charges an accumulator from p_s (above the precharge p₀): the oil
    delivered, q·t, is the stored oil V₀·(1 − (p₀/p)^(1/n)) − V₀·(1 − (p₀/p_s)^(1/n)) plus the
    connection's compression V_c/β·(p − p_s) (Boyle's law for n = 1, the adiabatic for
    1.4). The absorbed energy is the gas's compression work (p·V_g − p_s·V_gs)/(n − 1)
    (p₀·V₀·ln(p/p_s) at n = 1) plus the oil's V_c/β·(p² − p_s²)/2."""
    q, v0, p0, vc, p_s = 1.0e-4, 1.0e-3, 50.0e5, 2.0e-5, 60.0e5
    r, df = run(
        "acc",
        [
            C("tank", "tank", {"port": "T"}),
            C("flow_source", "src", {"inlet": "T", "outlet": "n"}, {"flow": q}),
            C(
                "accumulator",
                "acc",
                {"port": "n"},
                {
                    "gas_volume": v0,
                    "precharge_pressure": p0,
                    "exponent": n,
                    "connection_volume": vc,
                },
            ),
        ],
        step=1e-4,
        duration=5.0,
        every=10,
        initial={"n": p_s},
    )
    t = df["t_s"].to_numpy()
    p = df["n_pressure_bar"].to_numpy() * 1e5
    delivered = _acc_volume(p, p0, v0, n) - _acc_volume(p_s, p0, v0, n) + vc / BETA * (p - p_s)
    # RK4 with h = 0.1 ms against the charge's time scale (V₀/q = 10 s): error ≪ 1e-12 m³
    np.testing.assert_allclose(delivered, q * t, rtol=0, atol=1e-12)
    assert p[-1] > 2.0 * p_s  # a real charge: the pressure more than doubled
    # the account
    v_g, v_gs = v0 * (p0 / p[-1]) ** (1 / n), v0 * (p0 / p_s) ** (1 / n)
    gas = p0 * v0 * math.log(p[-1] / p_s) if n == 1.0 else (p[-1] * v_g - p_s * v_gs) / (n - 1)
    oil = vc / BETA * (p[-1] ** 2 - p_s**2) / 2
    e = r.energy()
    # the trapezoid over 1 ms records of a smooth power p·q: relative error ~ (Δt/T)²/12
    # with T ≈ 1 s the pressure's time scale, about 1e-7
    assert e["acc_energy_j"] == pytest.approx(gas + oil, rel=1e-6)
    assert abs(e["closure_energy_j"]) < 1e-9 * e["acc_energy_j"]


def test_accumulator_is_compliant_below_its_precharge():
    """Below p₀ only the connection's oil is compliant: a node with nothing else is valid
    (no algebraic loop) and its pressure rises as q·β/V_c."""
    q, vc = 1.0e-6, 1.0e-4
    r, df = run(
        "acc_low",
        [
            C("tank", "tank", {"port": "T"}),
            C("flow_source", "src", {"inlet": "T", "outlet": "n"}, {"flow": q}),
            C(
                "accumulator",
                "acc",
                {"port": "n"},
                {"gas_volume": 1e-3, "precharge_pressure": 100e5, "connection_volume": vc},
            ),
        ],
        duration=0.1,
    )
    t = df["t_s"].to_numpy()
    np.testing.assert_allclose(df["n_pressure_bar"] * 1e5, P_ATM + q * t * BETA / vc, rtol=1e-12)


# --------------------------------------------------------------- pressure sensor ---
def test_pressure_sensor_filter_follows_a_pressure_ramp():
    """The node's pressure ramps, p = p₀ + a·t; the sensor reads bar gauge (g = 1e-5 /Pa,
    y₀ = −1 bar). Filtered (τ = 10 ms) from a settled start: y = g·p(t) + y₀ −
    g·a·τ·(1 − e^(−t/τ)); unfiltered: y = g·p + y₀. It draws nothing from the node."""
    q, vol, tau = 1e-5, 1e-3, 0.01
    a = q * BETA / vol
    r, df = run(
        "ps",
        [
            C("tank", "tank", {"port": "T"}),
            C("flow_source", "src", {"inlet": "T", "outlet": "n"}, {"flow": q}),
            C("volume", "v", {"port": "n"}, {"volume": vol}),
            C(
                "pressure_sensor",
                "gauge",
                {"node": "n", "out": "p_f"},
                {"gain": 1e-5, "offset": -1.0, "time_constant": tau},
            ),
            C("pressure_sensor", "raw", {"node": "n", "out": "p_r"}, {"gain": 1e-5}),
        ],
        initial={"n": 20e5},
        duration=0.1,
        every=10,
    )
    t = df["t_s"].to_numpy()
    p = 20e5 + a * t
    np.testing.assert_allclose(df["n_pressure_bar"] * 1e5, p, rtol=1e-12)
    want = 1e-5 * p - 1.0 - 1e-5 * a * tau * (1.0 - np.exp(-t / tau))
    # RK4 at h/τ = 1e-3: error ~ (h/τ)⁴ of the lag's amplitude 1e-5·a·τ = 0.3 bar
    np.testing.assert_allclose(df["p_f_signal"], want, rtol=0, atol=1e-9)
    np.testing.assert_allclose(df["p_r_signal"], 1e-5 * p, rtol=1e-12)
    assert np.all(df["gauge_power_w"] == 0.0) and np.all(df["raw_power_w"] == 0.0)


def test_pressure_sensor_alone_does_not_make_a_node_compliant():
    with pytest.raises(HydroarmError, match="no compliance"):
        run(
            "ps_bad",
            [
                C("tank", "tank", {"port": "T"}),
                C("flow_source", "src", {"inlet": "T", "outlet": "n"}, {"flow": 1e-5}),
                C("pressure_sensor", "ps", {"node": "n", "out": "p"}),
            ],
        )


# ------------------------------------------------------------------- flow sensor ---
def test_flow_sensor_reads_the_flow_into_the_measured_port():
    """A ramp flow q = a·t passes a source from T into a volume. The flow *into* the source
    at its outlet is −q, at its inlet +q; the sensor's output is the lag of g·q + y₀
    (τ = 5 ms, from y₀): for a ramp, g·a·(t − τ·(1 − e^(−t/τ))). The relief valve reading
    shows a tap on another kind of component (nothing flows: the node stays below
    cracking)."""
    a, tau, g = 1e-3, 5e-3, 6e4  # g: m³/s → L/min
    r, df = run(
        "flowmeter",
        [
            C("tank", "tank", {"port": "T"}),
            C("signal_source", "ramp", {"out": "qs"}, {"waveform": "ramp", "rate": a}),
            C("flow_source", "src", {"inlet": "T", "outlet": "n", "flow": "qs"}),
            C("volume", "v", {"port": "n"}, {"volume": 1e-2}),
            C("relief_valve", "relief", {"inlet": "n", "outlet": "T"}, {"cracking_pressure": 1e7}),
            C(
                "flow_sensor",
                "out_meter",
                {"measures": "src.outlet", "out": "q_out"},
                {"gain": g, "time_constant": tau},
            ),
            C(
                "flow_sensor",
                "in_meter",
                {"measures": "src.inlet", "out": "q_in"},
                {"gain": g, "offset": 1.0, "time_constant": tau},
            ),
            C("flow_sensor", "relief_meter", {"measures": "relief.inlet", "out": "q_rv"}),
        ],
        duration=0.05,
        every=10,
    )
    t = df["t_s"].to_numpy()
    lag = g * a * (t - tau * (1.0 - np.exp(-t / tau)))
    # RK4 at h/τ = 2e-3 on a lag of amplitude g·a·τ = 0.3 L/min: error ≪ 1e-9
    np.testing.assert_allclose(df["q_out_signal"], -lag, rtol=0, atol=1e-9)
    np.testing.assert_allclose(df["q_in_signal"], 1.0 + lag, rtol=0, atol=1e-9)
    assert df["n_pressure_bar"].iloc[-1] < 100.0
    assert np.all(df["q_rv_signal"] == 0.0)


def test_flow_sensor_refuses_no_filter_and_a_wrong_tap():
    doc = parse_toml(
        """
        [[component]]
        type = "tank"
        name = "tank"
        ports = { port = "T" }
        [[component]]
        type = "flow_source"
        name = "src"
        ports = { inlet = "T", outlet = "T" }
        [[component]]
        type = "flow_sensor"
        name = "fm"
        ports = { measures = "src.outlet", out = "q" }
        time_constant = "0 s"
        """,
        "fm.toml",
    )
    with pytest.raises(HydroarmError, match=r"component\.fm\.time_constant: must be > 0"):
        build(circuit_from_doc(doc, "x"))
    with pytest.raises(HydroarmError, match="not a hydraulic port"):
        run(
            "fm_bad",
            [
                C("tank", "tank", {"port": "T"}),
                C("signal_source", "s", {"out": "qs"}),
                C("flow_source", "src", {"inlet": "T", "outlet": "T", "flow": "qs"}),
                C("flow_sensor", "fm", {"measures": "src.flow", "out": "q"}),
            ],
        )


# ----------------------------------------------------------------- variable pump ---
D_P = 10e-6 / REV  # 10 cm³/rev
W_P = 1500.0 * REV / 60.0  # 1500 rpm


def test_variable_pump_deadhead_pressure():
    """A compensated pump (static compensator) into a blocked line settles where its flow
    ε*(p)·D·ω equals its leakage C_l·(p − p_T), with ε* = (p_c + Δp_r − p)/Δp_r:
    p = (D·ω·(p_c + Δp_r)/Δp_r + C_l·p_T)/(D·ω/Δp_r + C_l). The transient's time
    constant is C/(D·ω/Δp_r + C_l) ≈ 1.7 ms, so after 0.3 s the node is at its fixed point
    (which RK4 preserves exactly)."""
    p_c, band, c_l = 150e5, 10e5, 1e-12
    r, df = run(
        "deadhead",
        [
            C("tank", "tank", {"port": "T"}),
            C(
                "variable_pump",
                "pump",
                {"inlet": "T", "outlet": "S"},
                {
                    "displacement": D_P,
                    "speed": W_P,
                    "leakage": c_l,
                    "cracking_pressure": p_c,
                    "regulation_band": band,
                    "time_constant": 0.0,
                },
            ),
            C("volume", "v", {"port": "S"}, {"volume": 0.5e-3}),
        ],
        duration=0.3,
    )
    k = D_P * W_P / band
    p_dead = (k * (p_c + band) + c_l * P_ATM) / (k + c_l)
    assert df["S_pressure_bar"].iloc[-1] * 1e5 == pytest.approx(p_dead, abs=1.0)  # [Pa]
    eps = df["pump_fraction"].iloc[-1]
    assert eps == pytest.approx(c_l * (p_dead - P_ATM) / (D_P * W_P), rel=1e-6)
    assert df["pump_flow_lpm"].iloc[-1] == pytest.approx(0.0, abs=1e-9)
    # full stroke while below cracking
    below = df["S_pressure_bar"] * 1e5 < p_c
    assert np.all(df["pump_fraction"][below] == 1.0)


def test_variable_pump_compensator_lag():
    """The pump delivers into a node held by a pressure source that steps at t_s from
    below cracking to mid-band: ε follows τ·ε̇ = ε* − ε, ε = ε*₂ + (1 − ε*₂)·e^(−(t − t_s)/τ),
    and the flow is ε·D·ω. The step falls somewhere inside one step of h = 10 µs: the bound
    is (h/τ)·(1 − ε*₂)."""
    p_c, band, tau, t_s = 100e5, 10e5, 0.04, 0.05
    p2 = p_c + 0.25 * band  # ε*₂ = 0.75
    r, df = run(
        "lag",
        [
            C("tank", "tank", {"port": "T"}),
            C(
                "signal_source",
                "p_set",
                {"out": "ps"},
                {"waveform": "steps", "offset": 50e5},
                {"times": (t_s,), "values": (p2,)},
            ),
            C("tank", "supply", {"port": "S", "setpoint": "ps"}),
            C(
                "variable_pump",
                "pump",
                {"inlet": "T", "outlet": "S"},
                {
                    "displacement": D_P,
                    "speed": W_P,
                    "cracking_pressure": p_c,
                    "regulation_band": band,
                    "time_constant": tau,
                },
            ),
        ],
        duration=0.25,
    )
    t = df["t_s"].to_numpy()
    eps = df["pump_fraction"].to_numpy()
    want = np.where(t < t_s, 1.0, 0.75 + 0.25 * np.exp(-np.maximum(t - t_s, 0.0) / tau))
    np.testing.assert_allclose(eps, want, rtol=0, atol=1e-5 / tau * 0.25 + 1e-12)
    np.testing.assert_allclose(df["pump_flow_lpm"], eps * D_P * W_P * 6e4, rtol=1e-12)


# ------------------------------------------------- motor spun up by a compensated pump ---
def test_motor_spun_up_by_a_compensated_pump():
    """A compensated pump (static compensator) drives a hydraulic motor (D_m = 20 cm³/rev,
    cross-port leakage C_i, torque efficiency η) turning an inertia with viscous load c.
    At rest the inertia stalls the motor: the compensator destrokes and holds the pressure
    within its band (never above p_c + Δp_r: with ε = 0 the pump only leaks); as the speed
    grows the pressure falls below cracking, the pump returns to full stroke, and the steady
    state solves
        pump:  D_p·ω_p − C_l·Δp = D_m·ω + C_i·Δp,    torque:  η·D_m·Δp = c·ω
    ω = D_p·ω_p/(D_m + (C_l + C_i)·c/(η·D_m)), Δp = c·ω/(η·D_m): the speed q/D_m less the
    leaks. The line's compliance and the load make one oscillating mode (ω_n ≈ 55 rad/s)
    decaying at σ = (C_l + C_i)/(2C) + c/(2J) ≈ 14 /s: after 2 s the transient is e^-28 of
    its start."""
    d_m = 20e-6 / REV
    c_l, c_i, eta = 1e-12, 2e-12, 0.95
    p_c, band = 100e5, 12.5e5
    w_nominal = D_P * W_P / d_m  # 78.5 rad/s = 750 rpm
    c = eta * d_m * 50e5 / w_nominal  # about 50 bar at speed
    J = 0.01
    r, df = run(
        "motor",
        [
            C("tank", "tank", {"port": "T"}),
            C(
                "variable_pump",
                "pump",
                {"inlet": "T", "outlet": "S"},
                {
                    "displacement": D_P,
                    "speed": W_P,
                    "leakage": c_l,
                    "cracking_pressure": p_c,
                    "regulation_band": band,
                    "time_constant": 0.0,
                },
            ),
            C("volume", "line", {"port": "S"}, {"volume": 0.5e-3}),
            C(
                "hydraulic_motor",
                "motor",
                {"a": "S", "b": "T", "shaft": "w"},
                {"displacement": d_m, "internal_leakage": c_i, "mechanical_efficiency": eta},
            ),
            C("inertia", "load", {"body": "w"}, {"inertia": J, "damping": c}),
        ],
        duration=2.0,
        every=100,
    )
    dp = df["S_pressure_bar"].to_numpy() * 1e5 - P_ATM
    w = df["w_angular_velocity_rad_s"].to_numpy()
    eps = df["pump_fraction"].to_numpy()
    # spin-up: the compensator destrokes the pump (to ε ≈ 0.56 at 20 ms) and bounds the
    # pressure within its band
    assert eps.min() < 0.7
    assert p_c < dp.max() + P_ATM <= p_c + band
    w_ss = D_P * W_P / (d_m + (c_l + c_i) * c / (eta * d_m))
    dp_ss = c * w_ss / (eta * d_m)
    assert w[-1] == pytest.approx(w_ss, rel=1e-9)
    assert dp[-1] == pytest.approx(dp_ss, rel=1e-9)
    # q/D_m less the leaks' (C_l + C_i)·Δp = 1.4e-5 m³/s of the pump's 2.5e-4: 5.7 % slower
    assert w_ss == pytest.approx(w_nominal * (1 - (c_l + c_i) * dp_ss / (D_P * W_P)), rel=1e-9)
    assert eps[-1] == 1.0
    # the motor's torque output and its loss at speed: (1 − η)·D_m·Δp·ω + C_i·Δp²
    assert df["motor_torque_n_m"].iloc[-1] == pytest.approx(c * w_ss, rel=1e-9)
    loss = (1 - eta) * d_m * dp_ss * w_ss + c_i * dp_ss**2
    assert df["motor_power_w"].iloc[-1] == pytest.approx(loss, rel=1e-6)
    e = r.energy()
    assert abs(e["closure_energy_j"]) < 1e-9 * abs(e["pump_energy_j"])
    # the load absorbs what the motor delivers: viscous heat ∫c·ω² + kinetic J·ω²/2 > 0
    assert e["load_energy_j"] > 0.5 * J * w_ss**2


def test_motor_driven_by_its_load_pumps_with_its_efficiency():
    """Driven backwards by a load torque with both ports on tanks at different pressures,
    the motor absorbs D·Δp/η·ω at the shaft and returns D·Δp·ω to the oil: its loss is
    still positive, (1/η − 1)·D·Δp·ω, and the shaft settles where T_load = D·Δp/η + B·ω
    (time constant J/B = 20 ms: settled to e^-50 after 1 s)."""
    d_m, eta, b = 20e-6 / REV, 0.9, 0.05
    dp = 50e5
    t_load = 20.0
    r, df = run(
        "motor_pumping",
        [
            C("tank", "low", {"port": "L"}),
            C("tank", "high", {"port": "H"}, {"pressure": P_ATM + dp}),
            C(
                "hydraulic_motor",
                "motor",
                {"a": "H", "b": "L", "shaft": "w"},
                {"displacement": d_m, "mechanical_efficiency": eta, "viscous_friction": b},
            ),
            C("inertia", "load", {"body": "w"}, {"inertia": 0.001, "torque": -t_load}),
        ],
        duration=1.0,
    )
    w = df["w_angular_velocity_rad_s"].iloc[-1]
    # T_load = D·Δp/η − B·ω with ω < 0 (the load turns it backwards, pumping L → H)
    assert w == pytest.approx(-(t_load - d_m * dp / eta) / b, rel=1e-9)
    assert w < 0
    loss = (1 / eta - 1) * d_m * dp * abs(w) + b * w**2
    assert df["motor_power_w"].iloc[-1] == pytest.approx(loss, rel=1e-9)


# ----------------------------------------------------------------------- inertia ---
def test_inertia_damped_torsion_oscillator():
    """J·θ̈ = T − k·(θ − θ_k) − c·θ̇ from θ(0) = θ₀, θ̇(0) = ω₀: the underdamped closed
    form about θ_e = θ_k + T/k."""
    J, k, c, T, th_k = 0.02, 50.0, 0.1, 3.0, 0.2
    th0, w0 = 1.0, -2.0
    r, df = run(
        "torsion",
        [
            C(
                "inertia",
                "rotor",
                {"body": "r"},
                {
                    "inertia": J,
                    "spring_rate": k,
                    "spring_free_angle": th_k,
                    "damping": c,
                    "torque": T,
                    "initial_angle": th0,
                    "initial_velocity": w0,
                },
            )
        ],
        duration=1.0,
    )
    t = df["t_s"].to_numpy()
    th_e = th_k + T / k
    sigma = c / (2 * J)
    wd = math.sqrt(k / J - sigma**2)
    x0 = th0 - th_e
    decay = np.exp(-sigma * t)
    want = th_e + decay * (x0 * np.cos(wd * t) + (w0 + sigma * x0) / wd * np.sin(wd * t))
    # RK4 at h·ω_n = 5e-4: error ~ 1e-13 rad over 8 periods
    np.testing.assert_allclose(np.radians(df["r_angle_deg"]), want, rtol=0, atol=1e-9)


def test_inertia_gravity_moment_settles_where_the_torque_balances_it():
    """A damped arm with gravity moment W·X (largest at θ_h = 0, the horizontal) held by a
    torque T < W·X settles below the horizontal at cos(θ − θ_h) = T/(W·X), θ = θ_h −
    acos(T/(W·X)) (the stable root). Damping c = 1 N m s/rad on J = 0.05 kg m² decays as
    e^(−c·t/(2J)) = e^-20 over the 2 s."""
    WX, T = 10.0, 5.0
    r, df = run(
        "gravity",
        [
            C(
                "inertia",
                "arm",
                {"body": "r"},
                {"inertia": 0.05, "damping": 1.0, "torque": T, "gravity_moment": WX},
            )
        ],
        duration=2.0,
    )
    assert math.radians(df["r_angle_deg"].iloc[-1]) == pytest.approx(-math.acos(T / WX), abs=1e-8)


def test_inertia_dry_friction_and_end_stop():
    """Coulomb friction T_c stops a rotor spun at ω₀ after the angle J·ω₀²/(2·T_c) (the
    time-stepping rule removes h·T_c/J a step, exact for a constant deceleration); a
    breakaway torque above the drive holds another at rest; an end stop holds a third
    driven into it."""
    J, w0, tc = 0.5, 4.0, 2.0
    r, df = run(
        "friction",
        [
            C(
                "inertia",
                "spun",
                {"body": "a"},
                {"inertia": J, "coulomb_friction": tc, "initial_velocity": w0},
            ),
            C(
                "inertia",
                "stuck",
                {"body": "b"},
                {"inertia": J, "torque": 1.5, "coulomb_friction": 1.0, "breakaway_friction": 2.0},
            ),
            C(
                "inertia",
                "stopped",
                {"body": "c"},
                {"inertia": J, "torque": 1.0, "angle_max": 0.3},
            ),
        ],
        duration=1.5,
    )
    assert math.radians(df["a_angle_deg"].iloc[-1]) == pytest.approx(J * w0**2 / (2 * tc), rel=1e-6)
    assert df["a_angular_velocity_rad_s"].iloc[-1] == 0.0
    assert np.all(df["b_angle_deg"] == 0.0)
    assert math.radians(df["c_angle_deg"].iloc[-1]) == pytest.approx(0.3, abs=1e-15)
    assert df["c_angular_velocity_rad_s"].iloc[-1] == 0.0


def test_inertia_from_a_file_with_units():
    """Rotary units in files: rpm, N m s/rad, kg m², degrees."""
    doc = parse_toml(
        """
        [[component]]
        type = "inertia"
        name = "rotor"
        ports = { body = "r" }
        inertia = "0.1 kg*m**2"
        damping = "0.5 N*m*s/rad"
        initial_angle = "90 deg"
        initial_velocity = "60 rpm"
        [solver]
        step = "100 us"
        duration = "0.5 s"
        record_every = 100
        """,
        "rotor.toml",
    )
    df = simulate(circuit_from_doc(doc, "rotor")).to_pandas()
    assert df["r_angle_deg"].iloc[0] == pytest.approx(90.0)
    w = df["r_angular_velocity_rad_s"].to_numpy()
    t = df["t_s"].to_numpy()
    np.testing.assert_allclose(w, REV * np.exp(-5.0 * t), rtol=1e-9)
