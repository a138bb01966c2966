"""Model 3 (Figs. 9 and 10): its reading of Appendix I, its equations against closed forms, and
its difference to Model 2 as docs/model.md ("Model 3") states it."""

import math

import numpy as np
import pytest
from scipy.linalg import expm

import hydroarm as ha
from hydroarm.core.equations import angular_acceleration, flow_gain, jack_velocity
from hydroarm.io.catalog import PISTON_MASS, model3_values, paper_load, read_data_csv
from hydroarm.io.units import quantity
from hydroarm.paper.data import measurement, published_table
from hydroarm.paper.model3 import (
    jack_mass,
    model3_joint,
    model3_load,
    model3_runs,
    transient_features,
)

LBF_IN_TO_N_M = quantity("c", "1 lbf*in", "torque")  # 0.11298 N m


def printed():
    return {r["symbol"]: r for r in read_data_csv("appendix1_parameters.csv")}


# --------------------------------------------------------------------------- reading ---
def test_f_o_and_lambda_o_si_prints_are_one_conversion_slip():
    # the SI column of f_o (2.31 "N s/m") and of λ_o (7.24 "kN/m") are the imperial values
    # times the lbf·in → N·m factor, to the print's 3 figures: the imperial column is the
    # original, and f_o = 20.4 lbf s/in is adopted
    p = printed()
    for sym, si_scale in (("f_o", 1.0), ("lambda_o", 1e3)):
        slip = float(p[sym]["imperial_value"]) * LBF_IN_TO_N_M
        assert float(p[sym]["si_value"]) * si_scale == pytest.approx(slip, rel=5e-3)
    v = model3_values()
    assert v["f_o"] == pytest.approx(20.4 * 4.4482216152605 / 0.0254)  # 3573 N s/m
    assert v["lambda_o"] == pytest.approx(ha.parameter_set("paper-printed").hydraulic_stiffness)
    assert v["m"] == PISTON_MASS  # one piston mass for the no-load case and Model 3


def test_jack_masses_are_the_printed_imperial_values_and_one_rule():
    # M = I·(n/r)² with r = 0.8 in gives both printed M (8.04, 17.8 lbf s²/in) to the print's
    # precision; the same rule gives the unprinted load 8. The SI print of M_10 (2123 kg) is not
    # the imperial 17.8 lbf s²/in (3117 kg).
    j = ha.parameter_set("paper-calibrated")
    v = model3_values()
    assert v["r"] == pytest.approx(0.8 * 0.0254)
    for k in (6, 10):
        rule = paper_load(k).inertia * (j.gear_ratio / v["r"]) ** 2
        assert jack_mass(j, k) == pytest.approx(rule, rel=5e-3)
    assert jack_mass(j, 10) == pytest.approx(3117, rel=1e-3)
    assert float(printed()["M_10"]["si_value"]) / jack_mass(j, 10) < 0.7
    assert jack_mass(j, 8) == pytest.approx(paper_load(8).inertia * (2 / v["r"]) ** 2)
    # referred back with the model's r = 20 mm, Model 3's inertia is 3-4 % below Model 2's I
    for k in (6, 8, 10):
        ratio = model3_load(j, k).inertia / paper_load(k).inertia
        assert 0.96 < ratio < 0.97


# -------------------------------------------------------------------------- equations ---
def test_joint_and_load_give_the_jack_equation():
    # (m + M)·s̈ = A·p − f_o·ẋ − F_g,  F_g = W·X·cos(θ₂ − θ_h)·n/r,  s = r·θ₂/n  ⇔
    # θ̈₂ = (A·p − f_o·ẋ − F_g)/(m + M)·(n/r), with ẋ = r·cos(θ₂/n)·θ̇₂/n (eq. 4)
    base = ha.parameter_set("paper-calibrated")
    j = model3_joint(base)
    J = j.params()
    r, n, A = j.crank_radius, j.gear_ratio, j.piston_area
    f_o, m = model3_values()["f_o"], model3_values()["m"]
    rng = np.random.default_rng(3)
    for k in (6, 8, 10):
        load = model3_load(base, k)
        L = load.params()
        mass = m + jack_mass(base, k)
        for theta, omega, p in zip(
            rng.uniform(-1.0, 1.0, 20),
            rng.uniform(-4.0, 4.0, 20),
            rng.uniform(-4e6, 6e6, 20),
            strict=True,
        ):
            xdot = r * math.cos(theta / n) * omega / n
            f_g = load.weight * load.arm * math.cos(theta - j.horizontal_angle) * n / r
            expected = (A * p - f_o * xdot - f_g) / mass * (n / r)
            got = angular_acceleration(theta, omega, p, J, L)
            assert got == pytest.approx(expected, rel=1e-12, abs=1e-9)
            assert jack_velocity(theta, omega, J) == pytest.approx(xdot, rel=1e-14)


def test_no_gravity_saturated_run_is_the_linear_closed_form():
    # With W = 0 and the valve saturated (e = e_o), Model 3 is linear in (u, p), u = r·θ̇₂/n:
    #   (V/β)·ṗ = K_q·e_o − A·u − 2·L·p,    (m + M)·u̇ = A·p − f_o·u
    # z' = F·z + b, z(0) = 0: z(t) from the exponential of the augmented matrix [[F, b], [0, 0]].
    base = ha.parameter_set("paper-calibrated")
    j = model3_joint(base)
    load = ha.Load(weight=0.0, arm=0.0, inertia=model3_load(base, 8).inertia, name="no gravity")
    mass = model3_values()["m"] + jack_mass(base, 8)
    A, L2, c = j.piston_area, 2 * j.leakage_coefficient, j.bulk_modulus / j.trapped_volume
    q = float(flow_gain(j.params())) * j.valve_saturation
    F = np.array([[-model3_values()["f_o"] / mass, A / mass], [-c * A, -c * L2]])
    b = np.array([0.0, c * q])
    aug = np.zeros((3, 3))
    aug[:2, :2], aug[:2, 2] = F, b
    y1 = 5e-3  # the valve stays saturated while x < y1 − e_o = 4.25 mm
    sc = ha.Scenario(
        joint=j,
        load=load,
        lever=ha.step(0.0, y1, 0.0),
        initial_angle=0.0,
        initial_pressure=0.0,
        duration=0.06,
        method="rk4",
        step=1e-6,
    )
    res = ha.simulate(sc)
    assert np.all(res.e == pytest.approx(j.valve_saturation))
    z = np.array([(expm(aug * t) @ np.r_[0.0, 0.0, 1.0])[:2] for t in res.t[::200]])
    u_lin, p_lin = z[:, 0], z[:, 1]
    # Neglected nonlinearity: the kernel's flow uses ẋ = u·cos(θ₂/n) (eq. 4), the linear form
    # u; the relative size of the dropped term is ε = 1 − cos(φ_max), φ_max = asin(x_max/r)
    # (1.4e-3 here). Through the loop it moves u and p by at most ε times their peak times the
    # peak of the step response over its final value (< 2, one overshoot); rk4 at 1 µs
    # against the fastest mode (|λ| ≈ 90 s⁻¹): error O((h|λ|)⁴) ≈ 1e-16, negligible.
    eps = 1 - math.cos(math.asin(np.max(np.abs(res.x)) / j.crank_radius))
    assert 1e-3 < eps < 3e-3
    u_sim = res.omega[::200] * j.crank_radius / j.gear_ratio
    assert np.max(np.abs(u_sim - u_lin)) <= 2 * eps * np.max(np.abs(u_lin))
    assert np.max(np.abs(res.p[::200] - p_lin)) <= 2 * eps * np.max(np.abs(p_lin))
    # and the kernel's ẋ is u·cos(θ₂/n), not u: the comparison is not trivially exact
    assert np.max(np.abs(res.xdot[::200] - u_lin)) > 0


# ---------------------------------------------------------------- Figs. 9/10 numbers ---
def test_model3_against_model2_as_the_docs_state(repro):
    out, data = repro
    rows = data["model3"]
    j = ha.parameter_set("paper-calibrated")
    f_o = model3_values()["f_o"]
    # steady saturated motion: p = (F_g + f_o·ẋ)/A in A·ẋ + 2L·p = K_q·e_o, so f_o divides
    # every saturation velocity by 1 + 2·L·f_o/A² (1.038 here), independently of load and M
    factor = 1 / (1 + 2 * j.leakage_coefficient * f_o / j.piston_area**2)
    assert factor == pytest.approx(0.963, abs=1e-3)
    assert {(r["load"], r["direction"]) for r in rows} == {
        (k, d) for k in (6, 8, 10) for d in ("raise", "lower")
    }
    for r in rows:
        assert r["v_sat_ratio"] == pytest.approx(factor, abs=2e-3)
        # T' (the jack has moved 0.63·e_o) is 0.1-0.4 ms shorter: 3.1-3.5 % less inertia
        # (the printed M use r = 0.8 in), the friction hardly acting in the first 0.5 mm
        assert -0.5 < r["rise_diff_ms"] < 0
        # the end-of-travel constant is longer by about the same factor (damping in series)
        assert r["model3_tc_end_ms"] / r["model2_tc_end_ms"] == pytest.approx(1 / factor, abs=0.02)
        # at 50 ms the velocities differ by less than 1.1 mm/s
        assert abs(r["v_probe_diff_mm_s"]) < 1.1
    # Model 3 keeps Table III within 5 % (Model 2: 1 %), and the paper's bound on T'
    t3 = {
        (r["load"], d): r[f"{d}_mm_s"]
        for r in published_table("table3")
        for d in ("raise", "lower")
    }
    for r in rows:
        if (r["load"], r["direction"]) in t3:
            assert abs(r["model3_v_sat_mm_s"] / t3[(r["load"], r["direction"])] - 1) < 0.05
        # ... and the requirement the paper says is met at the worst loading
        assert r["model3_rise_ms"] < measurement("time_constant_requirement_ms")
    md = (out / "report.md").read_text()
    assert "Model 3 beside Model 2" in md
    assert f"f_o = {f_o:.0f} N s/m" in md


def test_the_final_leakage_reading_is_not_tenable():
    # L = 1188 ("finally") in Model 3: load 10 raising falls to half of Table I's load 5,
    # lowering runs 18 % above it, and raising takes longer than the 50 ms requirement
    j = ha.parameter_set("paper-calibrated").replace(
        leakage_coefficient=ha.parameter_set("paper-printed-final-leakage").leakage_coefficient
    )
    runs = model3_runs(j, (10,))
    raise_, lower = (transient_features(runs[(10, d)]) for d in ("raise", "lower"))
    t1 = {r["load"]: r for r in published_table("table1")}
    assert raise_["v_sat_mm_s"] < 0.6 * t1[5]["raise_mm_s"]
    assert lower["v_sat_mm_s"] > 1.15 * t1[5]["lower_mm_s"]
    assert raise_["rise_ms"] > measurement("time_constant_requirement_ms")


def test_the_si_f_o_reading_changes_nothing():
    # f_o = 2.31 N s/m would move every saturation velocity by 2·L·f_o/A² ≈ 2.5e-5: a term with no
    # visible effect, which the paper would not list
    j = ha.parameter_set("paper-calibrated")
    assert 2 * j.leakage_coefficient * 2.31 / j.piston_area**2 < 1e-4
