"""The pressure and flow control valves of the circuit library against closed forms:
pilot_check_valve, counterbalance_valve, flow_control, reducing_valve, variable_orifice
(docs/components/<type>.md).

Two kinds of check. *Sweeps*: the valve between tanks whose pressures follow ramps (a tank's
``setpoint`` signal), so that every record is the valve's static law at known pressures;
the flow is compared with the law written out here (√Δp regularised as
u/(u² + p_t²)^¼, the library's ``signed_sqrt``), to round-off. *Circuits*: the valve feeding
a compliant node drained by an orifice, run to its steady state, compared with the root of
the steady flow balance (scipy's brentq on the closed-form flows), and the energy account
(closure, and the valve's absorbed power q·Δp ≥ 0).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from hydroarm.io.circuit import circuit_from_doc
from hydroarm.model.circuit import simulate

BAR = 1.0e5
P_T = 1.0e4  # [Pa] the transition pressure every valve here takes by default
LPM = 6.0e4  # (L/min)/(m³/s)
RHO = 870.0


def ssqrt(u):
    """The regularised signed square root of the library (:func:`signed_sqrt`)."""
    u = np.asarray(u, float)
    return u / (u * u + P_T * P_T) ** 0.25


def run(components, duration="1 s", step="1 ms", record_every=1, initial=None):
    doc = {
        "component": components,
        "solver": {
            "method": "rk4",
            "step": step,
            "duration": duration,
            "record_every": record_every,
        },
    }
    if initial:
        doc["initial"] = initial
    return simulate(circuit_from_doc(doc, "test"))


def tank(name, node, pressure=None, signal=None):
    c = {"type": "tank", "name": name, "ports": {"port": node}}
    if signal:
        c["ports"]["setpoint"] = signal
    if pressure:
        c["pressure"] = pressure
    return c


def ramp(name, signal, start, rate):
    """A signal source ``start + rate·t`` (pressures: any unit)."""
    return {
        "type": "signal_source",
        "name": name,
        "ports": {"out": signal},
        "waveform": "ramp",
        "offset": start,
        "rate": rate,
    }


def band(e, width):
    return np.clip(np.asarray(e, float) / width, 0.0, 1.0)


# ------------------------------------------------------------------- pilot check ---
def test_pilot_check_free_flow_above_its_cracking_pressure():
    """Inlet swept 1 → 21 bar, outlet and pilot at 1 bar: closed below the cracking drop
    p_c = 1 bar, then q = k·x·√Δp with x rising linearly to 1 over Δp_o = 1 bar
    (k = 0.5 L/s/√(10 bar): Hopsan's K_s = 5e-7 m³/s/√Pa)."""
    r = run(
        [
            tank("hi", "in", signal="p_in"),
            ramp("sweep", "p_in", "1 bar", "20 bar/s"),
            tank("lo", "out", "1 bar"),
            tank("pilot_src", "x", "1 bar"),
            {
                "type": "pilot_check_valve",
                "name": "pc",
                "ports": {"inlet": "in", "outlet": "out", "pilot": "x"},
            },
        ]
    )
    dp = r.output("in_pressure_bar") * BAR - BAR
    q = r.output("pc_flow_lpm") / LPM
    expected = 5e-7 * band(dp - 1.0 * BAR, 1.0 * BAR) * ssqrt(dp)
    assert np.all(q[dp <= 1.0 * BAR] == 0.0)
    # fully open at 20 bar; the plain √ within the regularisation's ¼(p_t/Δp)² = 6e-6
    assert q.max() == pytest.approx(5e-7 * math.sqrt(20 * BAR), rel=1e-5)
    np.testing.assert_allclose(q, expected, rtol=1e-9, atol=1e-15)  # round-off only
    assert np.all(r.output("pc_power_w") >= 0.0)  # a valve only dissipates


def test_pilot_check_opens_backwards_only_with_pilot_pressure():
    """A load of 100 bar at the outlet, the inlet at 1 bar, the pilot swept 1 → 41 bar. With
    φ = 3.5 and p_c = 1 bar the poppet holds until p_pilot = p_in + (p_out − p_in + p_c)/φ
    = 1 + 100/3.5 = 29.57 bar (force balance, module doc), then passes the reverse flow."""
    r = run(
        [
            tank("drain", "in", "1 bar"),
            tank("load", "out", "100 bar"),
            tank("pilot_src", "x", signal="p_x"),
            ramp("sweep", "p_x", "1 bar", "40 bar/s"),
            {
                "type": "pilot_check_valve",
                "name": "pc",
                "ports": {"inlet": "in", "outlet": "out", "pilot": "x"},
            },
        ]
    )
    p_x = r.output("x_pressure_bar")
    q = r.output("pc_flow_lpm") / LPM
    threshold = 1.0 + 100.0 / 3.5
    assert np.all(q[p_x <= threshold] == 0.0)  # held: not a drop passes
    assert np.all(q[p_x > threshold + 1e-6] < 0.0)  # piloted open: outlet → inlet
    excess = (1.0 - 100.0) * BAR + 3.5 * (p_x - 1.0) * BAR - 1.0 * BAR
    np.testing.assert_allclose(
        q, 5e-7 * band(excess, BAR) * ssqrt(-99.0 * BAR), rtol=1e-9, atol=1e-15
    )
    assert q.min() == pytest.approx(-5e-7 * math.sqrt(99 * BAR), rel=1e-6)  # fully open


def test_pilot_check_poppet_lag_is_first_order():
    """τ = 20 ms: the opening follows x* = 1 (a 5 bar free-flow drop) as 1 − e^(−t/τ); RK4
    at h = 0.1 ms = τ/200 is exact to ~(h/τ)⁴/120 ≈ 1e-11, so 1e-9."""
    r = run(
        [
            tank("hi", "in", "6 bar"),
            tank("lo", "out", "1 bar"),
            {
                "type": "pilot_check_valve",
                "name": "pc",
                "ports": {"inlet": "in", "outlet": "out", "pilot": "out"},
                "time_constant": "20 ms",
            },
        ],
        duration="0.1 s",
        step="0.1 ms",
        record_every=10,
    )
    t = r.output("t_s")
    np.testing.assert_allclose(r.output("pc_opening"), 1.0 - np.exp(-t / 0.02), atol=1e-9)
    q = r.output("pc_flow_lpm") / LPM
    np.testing.assert_allclose(q, 5e-7 * r.output("pc_opening") * ssqrt(5 * BAR), rtol=1e-9)


# -------------------------------------------------------------- counterbalance ---
def counterbalance(**values):
    return {
        "type": "counterbalance_valve",
        "name": "cbv",
        "ports": {"load": "load", "valve": "valve", "pilot": "x"},
        "setting": "130 bar",
        **values,
    }


def test_counterbalance_check_gives_free_flow_to_the_load():
    """Valve port swept 1 → 21 bar, load and pilot at 1 bar: the integral check cracks at
    1.7 bar (Sun's standard check) and opens fully 1 bar later; q = k_c·x_c·√Δp with
    k_c = 1 L/s/√(70 bar) (Hopsan's over-centre valve's q_nom, p_nom)."""
    r = run(
        [
            tank("src", "valve", signal="p_v"),
            ramp("sweep", "p_v", "1 bar", "20 bar/s"),
            tank("cyl", "load", "1 bar"),
            tank("pilot_src", "x", "1 bar"),
            counterbalance(),
        ]
    )
    dp = (r.output("valve_pressure_bar") - 1.0) * BAR
    q_in = -r.output("cbv_flow_lpm") / LPM  # into the load
    k_c = 1e-3 / math.sqrt(70 * BAR)
    assert np.all(q_in[dp <= 1.7 * BAR] == 0.0)
    np.testing.assert_allclose(
        q_in, k_c * band(dp - 1.7 * BAR, BAR) * ssqrt(dp), rtol=1e-9, atol=1e-15
    )
    assert np.all(r.output("cbv_opening") == 0.0)  # the relief stage stays shut


def test_counterbalance_pilot_lowers_the_setting_by_the_pilot_ratio():
    """Load at 101 bar (100 bar gauge: set at 1.3× it, 130 bar), valve port at 1 bar, pilot
    swept 1 → 21 bar: the relief stage cracks at p_pilot = p_valve + (p_set − (p_load −
    p_valve))/φ = 1 + 30/3 = 11 bar (Sun: the pilot lowers the setting at the pilot ratio)
    and meters load → valve at k·x·√(p_load − p_valve)."""
    r = run(
        [
            tank("src", "valve", "1 bar"),
            tank("cyl", "load", "101 bar"),
            tank("pilot_src", "x", signal="p_x"),
            ramp("sweep", "p_x", "1 bar", "20 bar/s"),
            counterbalance(),
        ]
    )
    p_x = r.output("x_pressure_bar")
    q = r.output("cbv_flow_lpm") / LPM  # load → valve
    assert np.all(q[p_x <= 11.0] == 0.0)  # held with less pilot than that
    assert np.all(q[p_x > 11.0 + 1e-6] > 0.0)
    x = band((100.0 + 3.0 * (p_x - 1.0) - 130.0) * BAR, BAR)
    np.testing.assert_allclose(r.output("cbv_opening"), x, rtol=1e-9, atol=1e-12)
    k = 1e-3 / math.sqrt(70 * BAR)
    np.testing.assert_allclose(q, k * x * ssqrt(100 * BAR), rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("back", [0.0, 10.0])
def test_counterbalance_back_pressure_adds_one_plus_pilot_ratio(back):
    """Pilot vented to 1 bar, valve port at 1 bar + a back pressure b, load swept up: the load
    pressure at which the relief stage cracks is p_set + (1 + φ)·b above the vented one (Sun
    Hydraulics: back pressure at port 2 adds to the setting at 1 + the pilot ratio). The
    crack point is read off each record inside the band, p_load − x·Δp_o, to round-off."""
    r = run(
        [
            tank("src", "valve", f"{1.0 + back} bar"),
            tank("cyl", "load", signal="p_l"),
            ramp("sweep", "p_l", "100 bar", "100 bar/s"),
            tank("pilot_src", "x", "1 bar"),
            counterbalance(),
        ]
    )
    x = r.output("cbv_opening")
    inside = (x > 0.0) & (x < 1.0)
    assert inside.sum() > 3
    crack = r.output("load_pressure_bar")[inside] - x[inside] * 1.0  # Δp_o = 1 bar
    # gauge: p_set + p_valve + φ·(p_valve − p_pilot) = 130 + b + 3·b
    np.testing.assert_allclose(crack - 1.0, 130.0 + (1.0 + 3.0) * back, rtol=1e-9)


# ---------------------------------------------------------------- flow control ---
FC = {
    "type": "flow_control",
    "name": "fc",
    "ports": {"inlet": "in", "outlet": "out"},
    "flow_setting": "10 l/min",
    "compensator_pressure": "7 bar",
}


def test_flow_control_holds_its_setting_over_the_drop():
    """Drop swept 0 → 200 bar: q within 1 % of q_set = 10 L/min from 2·Δp_c = 14 bar up
    (the smooth minimum of exponent 8 is 0.76 % below q_set there and closer above: a
    compensator's regulation within ±1–2 % is what a datasheet promises); the metering orifice
    k_m·√Δp (k_m = q_set/√Δp_c) within 0.05 % below Δp_c/4 (smooth minimum
    (1 + 0.5⁸)^(−1/8)); and the law itself to round-off."""
    r = run(
        [
            tank("hi", "in", signal="p_in"),
            ramp("s", "p_in", "1 bar", "200 bar/s"),
            tank("lo", "out", "1 bar"),
            FC,
        ]
    )
    dp = (r.output("in_pressure_bar") - 1.0) * BAR
    q = r.output("fc_flow_lpm") / LPM
    q_set = 10.0 / LPM
    regulating = dp >= 14 * BAR
    assert regulating.sum() > 900
    assert np.max(np.abs(q[regulating] / q_set - 1.0)) < 0.01
    low = (dp > 0.1 * BAR) & (dp <= 1.75 * BAR)
    q_o = q_set / math.sqrt(7 * BAR) * ssqrt(dp)
    np.testing.assert_allclose(q[low], q_o[low], rtol=5e-4)
    np.testing.assert_allclose(q, q_o / (1.0 + (q_o / q_set) ** 8) ** (1 / 8), rtol=1e-9)
    assert np.all(np.diff(q) >= 0.0)  # monotone in the drop


@pytest.mark.parametrize("reverse", ["orifice", "blocked"])
def test_flow_control_reverse_flow(reverse):
    """Outlet above the inlet (reverse): no compensation; through the metering orifice
    q = −k_m·√|Δp| (20 bar: 16.9 L/min, above q_set), or none with ``reverse = "blocked"``."""
    r = run(
        [tank("hi", "in", "1 bar"), tank("lo", "out", "21 bar"), {**FC, "reverse": reverse}],
        duration="10 ms",
    )
    q = r.output("fc_flow_lpm")[-1] / LPM
    expected = -10.0 / LPM * math.sqrt(20.0 / 7.0) if reverse == "orifice" else 0.0
    assert q == pytest.approx(expected, rel=1e-5, abs=1e-15)  # ¼(p_t/Δp)² = 6e-6


@pytest.mark.parametrize("load_area", ["10 mm**2", "2.2 mm**2"])
def test_flow_control_meters_in_independently_of_the_load(load_area):
    """100 bar supply → flow control → a node (0.1 L) → a load orifice → tank: at steady
    state the flow is the root of q_fc(p_s − p) = q_orifice(p − p_t), and within 1 % of
    q_set whatever the load (node at 4 or 68 bar: both leave the valve ≥ 2·Δp_c); energy
    closes."""
    r = run(
        [
            tank("supply", "in", "100 bar"),
            tank("tank", "T", "1 bar"),
            {**FC, "ports": {"inlet": "in", "outlet": "m"}},
            {"type": "volume", "name": "line", "ports": {"port": "m"}, "volume": "0.1 l"},
            {"type": "orifice", "name": "load", "ports": {"a": "m", "b": "T"}, "area": load_area},
        ],
        duration="0.5 s",
        step="20 us",
        record_every=250,
    )
    area = float(load_area.split()[0]) * 1e-6
    k_o = 0.61 * area * math.sqrt(2.0 / RHO)
    q_set, k_m = 10.0 / LPM, 10.0 / LPM / math.sqrt(7 * BAR)

    def balance(p):
        q_o = k_m * ssqrt(100 * BAR - p)
        return q_o / (1.0 + (q_o / q_set) ** 8) ** (1 / 8) - k_o * ssqrt(p - BAR)

    p = brentq(balance, 1.0 * BAR, 100 * BAR, xtol=1e-6)
    assert r.output("m_pressure_bar")[-1] * BAR == pytest.approx(p, rel=1e-6)
    q = r.output("fc_flow_lpm")[-1] / LPM
    assert abs(q / q_set - 1.0) < 0.01
    assert 100 * BAR - p >= 14 * BAR
    e = r.energy()
    assert abs(e["closure_energy_j"]) < 1e-6 * e["fc_energy_j"]
    assert np.all(r.output("fc_power_w") >= 0.0)


# ------------------------------------------------------------- reducing valve ---
PRV = {
    "type": "reducing_valve",
    "name": "prv",
    "ports": {"inlet": "in", "outlet": "out"},
    "set_pressure": "30 bar",
}


def test_reducing_valve_static_law():
    """Outlet swept 1 → 41 bar under a 100 bar inlet: fully open below p_set − Δp_r = 29 bar,
    shut above p_set = 30 bar (whatever the inlet), q = k·x·√(p_in − p_out) with
    k = 1 L/s/√(70 bar) (Hopsan's defaults), to round-off."""
    r = run(
        [
            tank("hi", "in", "100 bar"),
            tank("lo", "out", signal="p_out"),
            ramp("s", "p_out", "1 bar", "40 bar/s"),
            PRV,
        ]
    )
    p_out = r.output("out_pressure_bar")
    x = band((30.0 - p_out) * BAR, 1.0 * BAR)
    np.testing.assert_allclose(r.output("prv_opening"), x, rtol=1e-9, atol=1e-12)
    q = r.output("prv_flow_lpm") / LPM
    k = 1e-3 / math.sqrt(70 * BAR)
    np.testing.assert_allclose(q, k * x * ssqrt((100.0 - p_out) * BAR), rtol=1e-9, atol=1e-15)
    assert np.all(q[p_out >= 30.0] == 0.0)


@pytest.mark.parametrize(
    ("supply", "load_area"),
    [("100 bar", "1 mm**2"), ("200 bar", "1 mm**2"), ("100 bar", "3 mm**2")],
)
def test_reducing_valve_holds_its_outlet_within_the_band(supply, load_area):
    """Supply → reducing valve (p_set = 30 bar, Δp_r = 1 bar, τ = 5 ms) → a node (0.1 L) → a
    load orifice → tank: the outlet settles inside [p_set − Δp_r, p_set] = [29, 30] bar for
    either supply and load, at the root of k·x(p)·√(p_s − p) = q_orifice(p − p_t) (1e-6
    relative: the run is long enough to settle); energy closes; the valve only dissipates."""
    r = run(
        [
            tank("supply", "in", supply),
            tank("tank", "T", "1 bar"),
            {**PRV, "time_constant": "5 ms"},
            {"type": "volume", "name": "line", "ports": {"port": "out"}, "volume": "0.1 l"},
            {"type": "orifice", "name": "load", "ports": {"a": "out", "b": "T"}, "area": load_area},
        ],
        duration="0.5 s",
        step="20 us",
        record_every=250,
    )
    p_s = float(supply.split()[0]) * BAR
    k_o = 0.61 * float(load_area.split()[0]) * 1e-6 * math.sqrt(2.0 / RHO)
    k = 1e-3 / math.sqrt(70 * BAR)

    def balance(p):
        return k * band(30 * BAR - p, BAR) * ssqrt(p_s - p) - k_o * ssqrt(p - BAR)

    p = brentq(balance, 1.0 * BAR, 30 * BAR, xtol=1e-6)
    p_out = r.output("out_pressure_bar")[-1] * BAR
    assert 29 * BAR <= p_out <= 30 * BAR
    assert p_out == pytest.approx(p, rel=1e-6)
    e = r.energy()
    assert abs(e["closure_energy_j"]) < 1e-6 * e["prv_energy_j"]
    assert np.all(r.output("prv_power_w") >= 0.0)


# ----------------------------------------------------------- variable orifice ---
def test_variable_orifice_area_follows_its_signal():
    """50 bar across, the opening signal swept −0.5 → 2.5 with g = 1 mm² per unit and
    A_max = 1.5 mm²: q = C_d·A·√(2Δp/ρ) with A = clip(g·u, 0, A_max), the orifice law
    (regularisation error ¼(p_t/Δp)² = 1e-6 relative against the plain √)."""
    r = run(
        [
            tank("hi", "a", "51 bar"),
            tank("lo", "b", "1 bar"),
            ramp("lever", "u", -0.5, 3.0),
            {
                "type": "variable_orifice",
                "name": "vo",
                "ports": {"a": "a", "b": "b", "opening": "u"},
                "area_gain": "1 mm**2",
                "max_area": "1.5 mm**2",
            },
        ]
    )
    area = np.clip(r.output("u_signal") * 1e-6, 0.0, 1.5e-6)
    q = r.output("vo_flow_lpm") / LPM
    np.testing.assert_allclose(q, 0.61 * area * math.sqrt(2 * 50 * BAR / RHO), rtol=2e-6)
    assert np.all(q[r.output("u_signal") <= 0.0] == 0.0)


def test_variable_orifice_is_the_orifice_at_a_fixed_signal():
    """At a constant signal the variable orifice and an orifice of the same area pass the
    same flow (one law, :mod:`orifice`'s), at any drop including the laminar region."""
    r = run(
        [
            tank("hi", "a", signal="p_a"),
            ramp("s", "p_a", "0.9 bar", "10 bar/s"),
            tank("lo", "b", "1 bar"),
            {
                "type": "signal_source",
                "name": "lever",
                "ports": {"out": "u"},
                "offset": 0.8,
            },
            {
                "type": "variable_orifice",
                "name": "vo",
                "ports": {"a": "a", "b": "b", "opening": "u"},
                "area_gain": "2 mm**2",
            },
            {
                "type": "orifice",
                "name": "fixed",
                "ports": {"a": "a", "b": "b"},
                "area": "1.6 mm**2",
            },
        ]
    )
    np.testing.assert_allclose(
        r.output("vo_flow_lpm"), r.output("fixed_flow_lpm"), rtol=1e-12, atol=1e-18
    )
