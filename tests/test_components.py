"""Component servo kernel (issue 14): each component against a case with a known answer.

Every test works on the kernel functions and parameter vectors (hydroarm.core.components,
hydroarm.core.servo, hydroarm.reference.servo_kernel); every tolerance says where it comes from:
round-off, the regularisation of the orifice law, or the integrator's discretisation.
Pressures are absolute [Pa].
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import hydroarm as ha
from hydroarm.core import components as C
from hydroarm.core import servo as S
from hydroarm.core.equations import flow_gain, holding_pressure, valve_flow
from hydroarm.core.params import VALVE_ORIFICE, joint_params
from hydroarm.integrators import fixed
from hydroarm.reference import servo_kernel as K

EULER, RK4 = fixed.EULER, fixed.RK4
NO_SINE = np.zeros(3)
C_Q, RHO = 0.67, 890.0


def edge_coefficient(diameter, c_q=C_Q, rho=RHO):
    """k = C_q·w·√(2/ρ) of an edge with the full circumference w = π·d as area gradient."""
    return c_q * math.pi * diameter * math.sqrt(2.0 / rho)


def cylinder(area_a=1e-3, area_b=None, stroke=(0.0, 1.0), dead=3e-4, beta=1e9, mass=100.0):
    """A parameter vector: a cylinder (symmetric unless area_b), a mass load, a fixed supply."""
    P = S.default_parameters()
    P[S.P_AREA_A] = area_a
    P[S.P_AREA_B] = area_a if area_b is None else area_b
    P[S.P_STROKE_MIN], P[S.P_STROKE_MAX] = stroke
    P[S.P_DEAD_A] = P[S.P_DEAD_B] = dead
    P[S.P_BETA] = beta
    P[S.P_LOAD] = S.LOAD_MASS
    P[S.P_MASS] = mass
    P[S.P_SUPPLY] = S.SUPPLY_FIXED
    return P


def spool(P, k, lap=0.0, x_max=0.01, order=0):
    """A 4/3 spool valve with four equal edges of coefficient k and overlap ``lap``."""
    P[S.P_VALVE] = S.VALVE_SPOOL
    for i in (S.P_K_PA, S.P_K_AT, S.P_K_PB, S.P_K_BT):
        P[i] = k
    for i in (S.P_LAP_PA, S.P_LAP_AT, S.P_LAP_PB, S.P_LAP_BT):
        P[i] = lap
    P[S.P_SPOOL_MAX] = x_max
    P[S.P_SPOOL_ORDER] = order
    return P


def closed_valve(P):
    """Electronic feedback with no gain: the spool demand is 0, inside the overlap."""
    P[S.P_FEEDBACK] = S.FEEDBACK_ELECTRONIC
    P[S.P_KP] = P[S.P_KI] = P[S.P_KD] = 0.0
    return P


def pump(P, q=25e-5 * 200 / (2 * math.pi), leak=1e-12, volume=1e-3, beta=1e9):
    P[S.P_SUPPLY] = S.SUPPLY_PUMP
    P[S.P_PUMP_Q] = q
    P[S.P_PUMP_LEAK] = leak
    P[S.P_SUPPLY_VOL] = volume
    P[S.P_SUPPLY_BETA] = beta
    return P


P_NOM = 7e6  # Hopsan's nominal pressure drop of the relief valve


def relief(P, p_crack=2e7, tau=1e-3, slope=1e-8, q_nom=0.01, flow_slope=1e-8):
    """The issue's relief valve: C_s = √p_nom/k_cs, C_f = 1/(k_cf·√p_nom) with Hopsan's
    default k_cf = 1e-8 (the file reader's default), x_max = q_nom/√p_nom."""
    P[S.P_RELIEF_P] = p_crack
    P[S.P_RELIEF_TAU] = tau
    P[S.P_RELIEF_CS] = math.sqrt(P_NOM) / slope
    P[S.P_RELIEF_CF] = 1.0 / (flow_slope * math.sqrt(P_NOM))
    P[S.P_RELIEF_XMAX] = q_nom / math.sqrt(P_NOM)
    return P


def state(q=0.0, v=0.0, p_a=1e5, p_b=1e5, p_s=1e5, x_v=0.0):
    s = np.zeros(S.N_STATES)
    s[S.S_Q], s[S.S_V], s[S.S_PA], s[S.S_PB], s[S.S_PS], s[S.S_XV] = q, v, p_a, p_b, p_s, x_v
    return s


def run(P, s0, h, duration, method=RK4, record_every=1, ref=0.0, tab=None):
    tab_t, tab_y = tab if tab is not None else (np.array([0.0]), np.array([float(ref)]))
    n = int(round(duration / h))
    T, X, _, bad = K.integrate(method, s0, 0.0, h, n, record_every, tab_t, tab_y, NO_SINE, P)
    assert bad == -1
    return T, X


def reg(dp, dp_t):
    """Relative error bound of the regularised √Δp, (1 + (p_t/Δp)²)^(−¼) ≥ 1 − ¼(p_t/Δp)², plus
    round-off."""
    return 0.25 * (dp_t / dp) ** 2 + 1e-13


def simpson(y, h):
    """Composite Simpson rule over an even number of intervals (O(h⁴))."""
    assert (len(y) - 1) % 2 == 0
    return h / 3.0 * (y[0] + y[-1] + 4.0 * y[1:-1:2].sum() + 2.0 * y[2:-1:2].sum())


# ---------------------------------------------------------------------------------------
# orifice edge


def test_edge_flow_turbulent_law():
    d, o, dp_t = 10e-3, 0.5e-3, 1e4
    k = edge_coefficient(d)
    for dp in (1e6, 1e7, 2e7):
        exact = C_Q * (math.pi * d) * o * math.sqrt(2.0 * dp / RHO)
        # regularisation: √Δp·(1 + (p_t/Δp)²)^(−¼) ≈ √Δp·(1 − ¼(p_t/Δp)²), at most 2.5e-5 here
        # at Δp = 1 MPa; the bound ¼(p_t/Δp)² (plus round-off) is the tolerance
        assert C.edge_flow(k, o, dp, dp_t) == pytest.approx(exact, rel=reg(dp, dp_t))
    # a closed edge (overlap not yet crossed) passes nothing
    assert C.edge_flow(k, 0.0, 1e7, dp_t) == 0.0
    assert C.edge_flow(k, -1e-4, 1e7, dp_t) == 0.0


def test_edge_flow_regularisation():
    k, o, dp_t = edge_coefficient(10e-3), 1e-3, 1e4
    # finite slope at Δp = 0: k·o/√p_t (the laminar limit of u/(u² + u_t²)^¼); a central
    # difference at δ = 1e-3·p_t has the cubic term's error (δ/p_t)²/4 = 2.5e-7
    delta = 1e-3 * dp_t
    slope = (C.edge_flow(k, o, delta, dp_t) - C.edge_flow(k, o, -delta, dp_t)) / (2 * delta)
    assert slope == pytest.approx(k * o / math.sqrt(dp_t), rel=1e-6)
    assert C.edge_flow(k, o, 0.0, dp_t) == 0.0
    # odd symmetry, exactly (the formula is odd in Δp; no rounding differs between ±Δp)
    for dp in (1.0, 3e3, 1e4, 7e4, 1e7):
        assert C.edge_flow(k, o, -dp, dp_t) == -C.edge_flow(k, o, dp, dp_t)
    # monotone through zero
    dps = np.linspace(-5 * dp_t, 5 * dp_t, 201)
    assert np.all(np.diff([C.edge_flow(k, o, x, dp_t) for x in dps]) > 0)


def test_effective_bulk_modulus():
    beta, kappa, p_atm = 1.5e9, 1.4, 101325.0
    assert C.effective_bulk_modulus(1e7, beta, 0.0, kappa, p_atm, 1.0) == beta
    alpha = 0.01
    # at atmospheric pressure the air fraction is α: 1/β_e = (1 − α)/β + α/(κ·p_atm); exact
    # up to round-off
    expected = 1.0 / ((1 - alpha) / beta + alpha / (kappa * p_atm))
    got = C.effective_bulk_modulus(p_atm, beta, alpha, kappa, p_atm, 1.0)
    assert got == pytest.approx(expected, rel=1e-13)
    # against −V/(dV/dp) of a mixture whose oil compresses with β and whose air is polytropic:
    # V(p) = (1 − α)·(1 − (p − p_atm)/β) + α·(p_atm/p)^(1/κ). The component keeps the oil's
    # volume 1 − α in the air fraction a(p), an error of order (p − p_atm)/β: the tolerance
    for p in (2e5, 1e6, 1e7):

        def vol(x):
            return (1 - alpha) * (1 - (x - p_atm) / beta) + alpha * (p_atm / x) ** (1 / kappa)

        dv = (vol(p * (1 + 1e-6)) - vol(p * (1 - 1e-6))) / (2e-6 * p)
        got = C.effective_bulk_modulus(p, beta, alpha, kappa, p_atm, 1.0)
        assert got == pytest.approx(-vol(p) / dv, rel=2 * (p - p_atm) / beta + 1e-6)
    # far above the air's collapse β_e tends to β
    assert C.effective_bulk_modulus(1e9, beta, 1e-4, kappa, p_atm, 1.0) > 0.999 * beta


# ---------------------------------------------------------------------------------------
# 4/3 spool valve


def test_zero_lap_spool_is_the_orifice_option():
    """A critically-centred spool valve with four equal edges of coefficient K and tank at 0
    gives today's orifice option K·e·√((p_s − sgn(e)·p)/2) (equations.valve_flow, O1)."""
    K, ps, dp_t = 1e-5, 3.1e6, 1e4
    J = joint_params(
        3e-4, K, 0.75e-3, 0.0, 3e-6, 3.4e8, ps, 0.02, 2.0,
        valve_model=VALVE_ORIFICE, transition_pressure=2 * dp_t,
    )  # fmt: skip
    # valve_flow regularises ½(p_s ∓ p) at ½·p_t: the edges must use ½·p_t to be the same law
    for e in (0.75e-3, 0.2e-3, -0.2e-3, -0.75e-3):
        for p in (-0.5 * ps, 0.0, 0.3 * ps, 0.9 * ps):
            p_a, p_b = 0.5 * (ps + p), 0.5 * (ps - p)
            q_a, q_b, q_p, _ = C.spool_valve_flows(
                e, ps, 0.0, p_a, p_b, K, K, K, K, 0.0, 0.0, 0.0, 0.0, dp_t
            )
            ref = valve_flow(e, p, J)
            # round-off only: p_s − p_A versus ½(p_s − p) differ in the last bits
            assert q_a == pytest.approx(ref, rel=1e-12)
            assert -q_b == pytest.approx(ref, rel=1e-12)
            assert 0.5 * (q_a - q_b) == pytest.approx(ref, rel=1e-12)


def test_spool_overlap_has_no_flow_inside_the_lap():
    k, lap, ps, pt, dp_t = edge_coefficient(10e-3), 1e-4, 2e7, 1e5, 1e4
    p_a, p_b = 8e6, 5e6
    for x_v in np.linspace(-lap, lap, 41):
        assert C.spool_valve_flows(x_v, ps, pt, p_a, p_b, k, k, k, k, lap, lap, lap, lap, dp_t) == (
            0.0,
            0.0,
            0.0,
            0.0,
        )
    # beyond the lap the edge opens by x_v − lap (regularisation as the edge test: ¼(p_t/Δp)²)
    x_v = lap + 2e-4
    q_a, q_b, q_p, _ = C.spool_valve_flows(
        x_v, ps, pt, p_a, p_b, k, k, k, k, lap, lap, lap, lap, dp_t
    )
    assert q_a == pytest.approx(k * 2e-4 * math.sqrt(ps - p_a), rel=reg(ps - p_a, dp_t))
    assert q_b == pytest.approx(-k * 2e-4 * math.sqrt(p_b - pt), rel=reg(p_b - pt, dp_t))
    assert q_p == pytest.approx(q_a, rel=1e-15)


def test_spool_underlap_flows_at_null():
    k, u, ps, pt, dp_t = edge_coefficient(10e-3), 5e-5, 2e7, 1e5, 1e4
    mid = 0.5 * (ps + pt)
    q_a, q_b, q_p, loss = C.spool_valve_flows(
        0.0, ps, pt, mid, mid, k, k, k, k, -u, -u, -u, -u, dp_t
    )
    # blocked ports at null hold the mid pressure: no load flow (round-off of two equal edges)
    assert abs(q_a) < 1e-15 and abs(q_b) < 1e-15
    # but the supply leaks through all four edges: 2·k·u·√((p_s − p_T)/2) (regularisation)
    leak = 2 * k * u * math.sqrt(0.5 * (ps - pt))
    assert q_p == pytest.approx(leak, rel=reg(0.5 * (ps - pt), dp_t))
    assert loss == pytest.approx(leak * (ps - pt), rel=reg(0.5 * (ps - pt), dp_t))
    # the flow gain at null is twice the critically-centred valve's: the load flow is linear in
    # x_v while |x_v| < u, so a central difference is exact up to round-off
    dx = 1e-6
    ga = (
        C.spool_valve_flows(dx, ps, pt, mid, mid, k, k, k, k, -u, -u, -u, -u, dp_t)[0]
        - C.spool_valve_flows(-dx, ps, pt, mid, mid, k, k, k, k, -u, -u, -u, -u, dp_t)[0]
    ) / (2 * dx)
    assert ga == pytest.approx(2 * k * math.sqrt(0.5 * (ps - pt)), rel=1e-6)


# ---------------------------------------------------------------------------------------
# chambers: hydraulic stiffness and Merritt's ω_h


def hydraulic_case(air):
    P = cylinder(area_a=1e-3, stroke=(0.0, 0.5), dead=2e-4, beta=1e9, mass=50.0)
    spool(P, edge_coefficient(10e-3), lap=1e-4, order=1)
    P[S.P_SPOOL_TAU] = 1e-3
    closed_valve(P)
    P[S.P_P_SUPPLY] = 2.1e7
    P[S.P_AIR] = air
    P[S.P_AIR_EXP] = 1.4
    return P


def jacobian(P, s, idx, steps):
    n = len(idx)
    Jm = np.zeros((n, n))
    dp, dm = np.zeros(S.N_STATES), np.zeros(S.N_STATES)
    for j, (i, h) in enumerate(zip(idx, steps, strict=True)):
        sp, sm = s.copy(), s.copy()
        sp[i] += h
        sm[i] -= h
        K.servo_rhs(0.0, sp, P, dp)
        K.servo_rhs(0.0, sm, P, dm)
        Jm[:, j] = (dp[idx] - dm[idx]) / (2 * h)
    return Jm


@pytest.mark.parametrize("air", [0.0, 0.005])
def test_hydraulic_natural_frequency(air):
    P = hydraulic_case(air)
    x0, p0 = 0.15, 1e7
    s0 = state(q=x0, p_a=p0, p_b=p0, p_s=P[S.P_P_SUPPLY])
    v_a, v_b = K.chamber_volumes(x0, P)
    b_e = C.effective_bulk_modulus(p0, P[S.P_BETA], air, 1.4, P[S.P_P_ATM], 1.0)
    A, m = P[S.P_AREA_A], P[S.P_MASS]
    # Merritt 1967, ch. 3 (valve-controlled piston): ω_h² = 4·β_e·A²/(V_t·m) at mid-stroke;
    # off centre the two trapped oil columns in parallel, ω_h² = β_e·A²·(1/V_A + 1/V_B)/m
    omega_h = math.sqrt(b_e * A * A * (1 / v_a + 1 / v_b) / m)
    idx = [S.S_Q, S.S_V, S.S_PA, S.S_PB]
    Jm = jacobian(P, s0, idx, [1e-6, 1e-4, 1e2, 1e2])
    lam = np.linalg.eigvals(Jm)
    # the closed valve leaves q and the mean pressure neutral (two zero eigenvalues) and one
    # undamped pair ±iω_h. The right-hand side is linear in (v, p_A, p_B) at v = 0, so the
    # central differences are exact up to round-off (eps·p/δp ≈ 1e-11): rel 1e-8
    assert np.max(np.abs(lam.real)) < 1e-8 * omega_h
    assert np.max(lam.imag) == pytest.approx(omega_h, rel=1e-8)
    # a free oscillation from a small pressure difference has the period 2π/ω_h: rk4 at
    # 2000 steps a period (phase error ~ (ωh)⁴ ≈ 1e-13), zero crossings of v by linear
    # interpolation (O(h³) where v'' = 0), amplitude ~1e-5 of the chamber volume: rel 1e-4
    period = 2 * math.pi / omega_h
    h = period / 2000
    s0[S.S_PA] += 1e4
    s0[S.S_PB] -= 1e4
    T, X = run(P, s0, h, 5.2 * period)
    v = X[:, S.S_V]
    i = np.nonzero((v[1:-1] > 0) & (v[2:] <= 0) | (v[1:-1] < 0) & (v[2:] >= 0))[0] + 1
    tz = T[i] - v[i] * (T[i + 1] - T[i]) / (v[i + 1] - v[i])
    assert len(tz) >= 8
    measured = 2 * (tz[-1] - tz[0]) / (len(tz) - 1)
    assert measured == pytest.approx(period, rel=1e-4)


# ---------------------------------------------------------------------------------------
# single-rod actuator: the area-ratio velocity split


def steady_velocity(extend, ko, a_a, a_b, ps, pt, force, damping):
    """Steady piston speed [m/s] of a valve with four equal edges of conductance k·o fully
    open, from the flows k·o·√Δp = A·v of the metering-in and -out edges and the force
    balance A_A·p_A − A_B·p_B = F + c·v, solved with brentq."""
    if extend:  # P→A and B→T: p_A = p_s − (A_A·v/ko)², p_B = p_T + (A_B·v/ko)²

        def g(v):
            return (
                a_a * (ps - (a_a * v / ko) ** 2)
                - a_b * (pt + (a_b * v / ko) ** 2)
                - force
                - damping * v
            )

    else:  # P→B and A→T, speed u = −v: p_A = p_T + (A_A·u/ko)², p_B = p_s − (A_B·u/ko)²

        def g(v):
            return (
                a_a * (pt + (a_a * v / ko) ** 2)
                - a_b * (ps - (a_b * v / ko) ** 2)
                - force
                + damping * v
            )

    return brentq(g, 0.0, 100.0, xtol=1e-15, rtol=1e-15)


def test_single_rod_velocity_split_closed_form():
    # no load, tank at 0: v_ext/v_ret = 1/√α with α = A_B/A_A (both speeds ∝ 1/√(1 + α³))
    for alpha in (0.3, 0.5, 0.8, 1.0):
        ve = steady_velocity(True, 2e-7, 2e-3, alpha * 2e-3, 1e7, 0.0, 0.0, 0.0)
        vr = steady_velocity(False, 2e-7, 2e-3, alpha * 2e-3, 1e7, 0.0, 0.0, 0.0)
        assert ve / vr == pytest.approx(1 / math.sqrt(alpha), rel=1e-12)
        assert ve == pytest.approx(2e-7 / 2e-3 * math.sqrt(1e7 / (1 + alpha**3)), rel=1e-12)


@pytest.mark.parametrize("extend", [True, False])
def test_single_rod_velocity_split(extend):
    a_a, alpha = 2e-3, 0.5
    P = cylinder(area_a=a_a, area_b=alpha * a_a, stroke=(-0.5, 0.5), dead=1e-4, mass=20.0)
    k, x_max = edge_coefficient(2e-3), 1e-3
    spool(P, k, lap=0.0, x_max=x_max, order=0)
    P[S.P_FEEDBACK] = S.FEEDBACK_MECHANICAL
    P[S.P_FB_GAIN] = 1.0  # demand = reference − x, saturated at the spool stroke
    P[S.P_P_TRANS] = 1e3  # regularisation error ¼(p_t/Δp)² < 1e-7 at the Δp ≥ 1 MPa here
    ps, pt, force, damping = 1e7 + 1e5, 1e5, 3e3, 2e4
    P[S.P_P_SUPPLY], P[S.P_P_TANK] = ps, pt
    P[S.P_FORCE], P[S.P_DAMPING] = force, damping
    s0 = state(q=0.0, p_a=5e6, p_b=5e6, p_s=ps)
    T, X = run(P, s0, 2e-5, 0.15, record_every=50, ref=1e3 if extend else -1e3)
    assert np.all(np.abs(X[:, S.S_XV]) == x_max)  # fully open all the run
    v = steady_velocity(extend, k * x_max, a_a, alpha * a_a, ps, pt, force, damping)
    v_sim = X[-1, S.S_V]
    # the transient (c/m = 1000 s⁻¹, hydraulic mode damped by the orifices) has died out to
    # < 1e-7 by 0.15 s, and the regularisation adds < 1e-7: rel 1e-6
    assert abs(v_sim) == pytest.approx(v, rel=1e-6)
    assert np.sign(v_sim) == (1 if extend else -1)


# ---------------------------------------------------------------------------------------
# supply: relief valve, accumulator


def dead_ended_supply(tau=1e-3):
    """The issue's power pack into a closed valve (no actuator flow)."""
    P = cylinder()
    spool(P, edge_coefficient(10e-3), lap=1e-4)
    closed_valve(P)
    pump(P)
    relief(P, tau=tau)
    return P


@pytest.mark.parametrize("tau", [1e-3, 0.0])
def test_relief_pressure(tau):
    P = dead_ended_supply(tau)
    pt, q, cl = P[S.P_P_TANK], P[S.P_PUMP_Q], P[S.P_PUMP_LEAK]

    def balance(p):
        x = C.relief_static_opening(
            p, pt, P[S.P_RELIEF_P], P[S.P_RELIEF_CS], P[S.P_RELIEF_CF], P[S.P_RELIEF_XMAX]
        )
        return q - cl * (p - pt) - x * math.sqrt(p - pt)

    p_ss = brentq(balance, P[S.P_RELIEF_P], 2 * P[S.P_RELIEF_P], xtol=1e-6, rtol=1e-15)
    T, X = run(P, state(p_a=1e6, p_b=1e6, p_s=1e5), 1e-5, 0.2, record_every=1000)
    # regularisation of √(p − p_T) at p_t = 1e4 Pa: ¼(p_t/2e7)² ≈ 6e-8 of the relief flow,
    # which moves p by 6e-8·q/(dq/dp) < 1 Pa; the transient (τ = 1 ms, supply 1e-12 m³/Pa
    # against a slope of ~4e-9 m³/(s Pa)) is gone by 0.2 s: rel 1e-7 (measured 4.6e-9).
    # τ = 0 is the static valve, x_r = x*(p_s) at every step
    assert X[-1, S.S_PS] == pytest.approx(p_ss, rel=1e-7)
    x_star = C.relief_static_opening(
        p_ss, pt, P[S.P_RELIEF_P], P[S.P_RELIEF_CS], P[S.P_RELIEF_CF], P[S.P_RELIEF_XMAX]
    )
    assert X[-1, S.S_XR] == pytest.approx(x_star, rel=1e-6)
    # the numbers: 20 MPa cracking, 1e-8 (m³/s)/Pa slopes (spring and flow forces,
    # Hopsan's defaults) → about 218.49 bar (204.65 bar without the flow-force term)
    assert p_ss / 1e5 == pytest.approx(218.49, abs=0.01)


def test_accumulator_pressure_rise():
    P = cylinder()
    spool(P, edge_coefficient(10e-3), lap=1e-4)
    closed_valve(P)
    q = 1e-4
    pump(P, q=q, leak=0.0, volume=1e-4, beta=1e9)
    p0, v0, n = 5e6, 1e-3, 1.4
    P[S.P_ACC_P0], P[S.P_ACC_V0], P[S.P_ACC_N] = p0, v0, n
    p_start = 6e6  # above the precharge: the capacitance is smooth on the run
    h, duration = 1e-4, 2.0
    T, X = run(P, state(p_a=1e6, p_b=1e6, p_s=p_start), h, duration, record_every=1000)

    def oil(p):  # oil taken in since the start: accumulator (polytropic) + supply volume
        return v0 * ((p0 / p_start) ** (1 / n) - (p0 / p) ** (1 / n)) + 1e-4 / 1e9 * (p - p_start)

    for t, p in zip(T[1:], X[1:, S.S_PS], strict=True):
        expected = brentq(lambda x, t=t: oil(x) - q * t, p_start, 1e9, xtol=1e-6, rtol=1e-15)
        # rk4 on ṗ = q/C(p) with h = 1e-4 s, smooth in p: error ~ (h/t_char)⁴ ≪ 1e-10
        assert p == pytest.approx(expected, rel=1e-10)
    # the oil-volume law and the capacitance are one law: dV/dp by central difference
    # (relative step 1e-5, truncation ~1e-10)
    for p in (5.5e6, 1e7, 2e7):
        dv = (
            C.accumulator_oil_volume(p * (1 + 1e-5), p0, v0, n)
            - C.accumulator_oil_volume(p * (1 - 1e-5), p0, v0, n)
        ) / (2e-5 * p)
        assert C.accumulator_capacitance(p, p0, v0, n) == pytest.approx(dv, rel=1e-8)
    assert C.accumulator_capacitance(0.9 * p0, p0, v0, n) == 0.0
    assert C.accumulator_oil_volume(0.9 * p0, p0, v0, n) == 0.0


# ---------------------------------------------------------------------------------------
# spool dynamics


def spool_step_case(order):
    """Mechanical feedback through a valve passing nothing (linearised, K_q = 0): the jack
    stays at 0 and the spool demand is the reference step."""
    P = cylinder()
    P[S.P_VALVE] = S.VALVE_LINEARISED
    P[S.P_FLOW_GAIN] = 0.0
    P[S.P_SPOOL_MAX] = 0.01
    P[S.P_SPOOL_ORDER] = order
    P[S.P_SPOOL_TAU] = 2e-3
    P[S.P_SPOOL_OMEGA] = 200.0
    P[S.P_SPOOL_ZETA] = 1.0
    return P


def test_spool_first_order_step():
    P = spool_step_case(1)
    y0, tau = 1e-3, P[S.P_SPOOL_TAU]
    h = tau / 1000
    T, X = run(P, state(p_a=1e6, p_b=1e6), h, 5 * tau, record_every=10, ref=y0)
    i = int(np.argmin(np.abs(T - tau)))
    assert T[i] == pytest.approx(tau, rel=1e-12)
    assert X[i, S.S_XV] / y0 == pytest.approx(1 - math.exp(-1), rel=1e-12)  # 63.2 % at τ
    # rk4's error (h/τ)⁵/120 a step: ~1e-17; round-off dominates: abs 1e-12·y0
    np.testing.assert_allclose(X[:, S.S_XV], y0 * (1 - np.exp(-T / tau)), rtol=0, atol=1e-12 * y0)
    # order 0: the spool is the (stroke-limited) demand at once
    P0 = spool_step_case(0)
    T, X = run(P0, state(p_a=1e6, p_b=1e6), h, tau, record_every=100, ref=0.02)
    assert np.all(X[:, S.S_XV] == P0[S.P_SPOOL_MAX])


def test_spool_second_order_critically_damped_step():
    P = spool_step_case(2)
    y0, w = 1e-3, P[S.P_SPOOL_OMEGA]
    h = 1e-3 / w
    T, X = run(P, state(p_a=1e6, p_b=1e6), h, 10 / w, record_every=20, ref=y0)
    exact = y0 * (1 - (1 + w * T) * np.exp(-w * T))
    # rk4 with ωh = 1e-3: global error ~ (ωh)⁴ ≈ 1e-12 of the amplitude
    np.testing.assert_allclose(X[:, S.S_XV], exact, rtol=0, atol=1e-11 * y0)
    assert np.all(np.diff(X[:, S.S_XV]) >= 0)  # ζ = 1: no overshoot
    # a larger demand is limited to the spool's stroke x_max, which the spool approaches
    T, X = run(P, state(p_a=1e6, p_b=1e6), h, 10 / w, record_every=20, ref=0.05)
    assert P[S.P_SPOOL_MAX] * (1 - 1e-3) < X[-1, S.S_XV] <= P[S.P_SPOOL_MAX]
    assert X[:, S.S_XV].max() <= P[S.P_SPOOL_MAX]


# ---------------------------------------------------------------------------------------
# electronic feedback: PI steady state, anti-windup


def pi_case(kp, ki):
    """Symmetric jack, 10 kg on a 1e5 N/m spring, damper 1e4 N s/m, internal leakage 1e-11,
    critically-centred spool valve, fixed supply 200 bar, position sensor."""
    P = cylinder(area_a=1e-3, stroke=(0.0, 0.5), dead=1e-4, mass=10.0)
    spool(P, edge_coefficient(10e-3), lap=0.0, x_max=5e-3, order=0)
    P[S.P_FEEDBACK] = S.FEEDBACK_ELECTRONIC
    P[S.P_KP], P[S.P_KI] = kp, ki
    P[S.P_SPRING], P[S.P_DAMPING] = 1e5, 1e4
    P[S.P_LEAK_INT] = 1e-11
    P[S.P_P_SUPPLY] = 2e7 + 1e5
    return P


def p_steady_position(P, r):
    """Steady position under P control: the spring's load pressure p_L = k·x/A must be held
    against the internal leakage C_i·p_L by the valve, which at the spool opening x_v meters
    k_e·x_v·√((p_s − p_T − p_L)/2) through each edge (p_A + p_B = p_s + p_T); with
    x_v = K_p·(r − x):  K_p·(r − x)·k_e·√((p_s − p_T − p_L)/2) = C_i·p_L."""
    a, ke, ci = P[S.P_AREA_A], P[S.P_K_PA], P[S.P_LEAK_INT]
    ps, pt = P[S.P_P_SUPPLY], P[S.P_P_TANK]

    def g(x):
        pl = P[S.P_SPRING] * x / a
        return P[S.P_KP] * (r - x) * ke * math.sqrt(0.5 * (ps - pt - pl)) - ci * pl

    return brentq(g, 0.0, r, xtol=1e-15, rtol=1e-15)


def test_p_control_steady_error():
    r = 0.1
    errors = []
    for kp in (2e-3, 8e-3):
        P = pi_case(kp, 0.0)
        x_ss = p_steady_position(P, r)
        T, X = run(P, state(q=0.0, p_a=1.05e7, p_b=1.05e7, p_s=P[S.P_P_SUPPLY]), 1e-5, 4.0,
                   record_every=1000, ref=r)  # fmt: skip
        # the slowest mode (τ ≈ 0.5 s at the lower gain) has decayed to ~1e-6 of the error by
        # 4 s; the regularisation at Δp ≈ 6 MPa adds ¼(1e4/6e6)² ≈ 7e-7 to the edge flow:
        # rel 1e-5 of the steady error (measured 6e-7)
        assert r - X[-1, S.S_Q] == pytest.approx(r - x_ss, rel=1e-5)
        errors.append(r - x_ss)
    assert errors[0] > errors[1] > 0  # nonzero, decreasing with the gain


def test_pi_control_zero_steady_error():
    r = 0.1
    P = pi_case(8e-3, 8e-2)
    T, X = run(P, state(q=0.0, p_a=1.05e7, p_b=1.05e7, p_s=P[S.P_P_SUPPLY]), 1e-5, 4.0,
               record_every=1000, ref=r)  # fmt: skip
    # the integral's mode decays at ~K_i/K_p = 10 s⁻¹: e^(−40) of the 1.2 cm P-only error
    assert abs(X[-1, S.S_Q] - r) < 1e-9
    # the integral holds the spool opening that feeds the leakage: K_i·∫e = x_v
    x_v = P[S.P_KI] * X[-1, S.S_INT]
    p_l = X[-1, S.S_PA] - X[-1, S.S_PB]
    assert p_l == pytest.approx(P[S.P_SPRING] * r / P[S.P_AREA_A], rel=1e-6)
    ke = P[S.P_K_PA]
    q_edge = ke * x_v * math.sqrt(X[-1, S.S_PS] - X[-1, S.S_PA])
    assert q_edge == pytest.approx(P[S.P_LEAK_INT] * p_l, rel=1e-5)


def test_pid_anti_windup_law():
    # saturated high with the error pushing further: hold; pushing back: integrate
    assert C.pid_output(1.0, 0.0, 0.0, 2.0, 1.0, 0.0, -1.0, 1.0) == (1.0, 0.0)
    assert C.pid_output(-0.1, 5.0, 0.0, 2.0, 1.0, 0.0, -1.0, 1.0) == (1.0, 1.0)
    assert C.pid_output(-1.0, 0.0, 0.0, 2.0, 1.0, 0.0, -1.0, 1.0) == (-1.0, 0.0)
    assert C.pid_output(0.1, -5.0, 0.0, 2.0, 1.0, 0.0, -1.0, 1.0) == (-1.0, 1.0)
    assert C.pid_output(0.2, 0.1, 0.0, 2.0, 1.0, 0.0, -1.0, 1.0) == (0.5, 1.0)


def test_anti_windup_in_a_run():
    r = 0.1
    P = pi_case(8e-3, 8e-2)
    P[S.P_U_MIN], P[S.P_U_MAX] = -1e-4, 1e-4  # well below K_p·r = 8e-4: saturated at first
    T, X = run(P, state(q=0.0, p_a=1.05e7, p_b=1.05e7, p_s=P[S.P_P_SUPPLY]), 1e-5, 2.0,
               record_every=10, ref=r)  # fmt: skip
    e = r - X[:, S.S_Q]
    raw = P[S.P_KP] * e + P[S.P_KI] * X[:, S.S_INT]
    sat = raw > P[S.P_U_MAX]
    assert sat[:10].all() and not sat[-10:].any()
    first = int(np.argmin(sat))  # the first record out of saturation
    # while saturated with e > 0 the integral's rate is 0 in every rk4 stage: it does not move
    assert np.all(X[:first, S.S_INT] == 0.0)
    assert np.all(X[:first, S.S_XV] == P[S.P_U_MAX])
    # afterwards it integrates, and the loop still settles at the reference
    assert X[-1, S.S_INT] > 0.0
    assert abs(X[-1, S.S_Q] - r) < 1e-6


# ---------------------------------------------------------------------------------------
# energy


def position_servo():
    """The issue's industrial position servo (examples/position_servo.toml)."""
    P = cylinder(area_a=1e-3, stroke=(0.0, 1.0), dead=3e-4, beta=1e9, mass=100.0)
    spool(P, edge_coefficient(10e-3), lap=1e-4, x_max=0.01, order=2)
    P[S.P_SPOOL_OMEGA], P[S.P_SPOOL_ZETA] = 200.0, 1.0
    P[S.P_FEEDBACK] = S.FEEDBACK_ELECTRONIC
    P[S.P_KP], P[S.P_KI] = 0.0264249, 0.000672426
    P[S.P_SPRING] = 100.0
    P[S.P_Q_MIN], P[S.P_Q_MAX] = 0.0, 1.0
    pump(P)
    relief(P)
    P[S.P_P_SUPPLY] = 1e5
    return P


PS_TAB = (np.array([0.0, 1.0, 1.0]), np.array([0.2, 0.2, 0.7]))


def energy_residual(E):
    return (
        E[S.S_E_SUPPLY]
        - E[S.S_E_RELIEF]
        - E[S.S_E_THROTTLE]
        - E[S.S_E_ACT]
        - E[S.S_E_LEAK]
        - E[S.S_E_COMP]
    )


@pytest.mark.parametrize("method", [EULER, RK4])
def test_energy_balance_closes(method):
    """Supply = relief + throttling + actuator work + leakage + compression, to round-off.

    The power balance holds at every state (each energy rate is one term of the same flows),
    and the method integrates all rates with the same weights, so the residual is round-off
    accumulated over the steps: below n·eps·E_supply. Case: the issue's servo with leakage
    switched on and air in the oil, 0.3 s (no stop, no cavitation floor reached)."""
    P = position_servo()
    P[S.P_LEAK_INT] = 1e-12
    P[S.P_LEAK_EXT_A] = P[S.P_LEAK_EXT_B] = 1e-13
    P[S.P_AIR], P[S.P_AIR_EXP] = 1e-3, 1.4
    P[S.P_ACC_P0], P[S.P_ACC_V0], P[S.P_ACC_N] = 1e7, 1e-4, 1.4
    h = 1e-5
    n = 30000
    s0 = state(q=0.01, p_a=1e6, p_b=1e6, p_s=1e5)
    T, X = run(P, s0, h, n * h, method=method, record_every=100, tab=PS_TAB)
    # projections not active: inside the stops, above the floors, relief opening in range
    assert np.all((X[:, S.S_Q] > 0.0) & (X[:, S.S_Q] < 1.0))
    assert np.all(X[:, [S.S_PA, S.S_PB]] > 0.0)
    assert np.all(np.abs(X[:, S.S_XV]) < P[S.P_SPOOL_MAX])
    E = X[-1]
    assert E[S.S_E_RELIEF] > 0 and E[S.S_E_THROTTLE] > 0 and E[S.S_E_LEAK] > 0
    assert abs(energy_residual(E)) < n * np.finfo(float).eps * E[S.S_E_SUPPLY]


def test_actuator_work_is_load_energy():
    """Actuator work = kinetic + spring energy + damper dissipation (symmetric jack: the tank
    pressure's force cancels). ∫c·v² dt by Simpson on the per-step record (O(h⁴)); the rk4 run
    itself converges at second order here, the overlapped edges opening with a kink in the
    flow: measured 7e-8 of the work at h = 2e-5 and 1.8e-8 at h = 1e-5; tolerance 1e-7."""
    P = position_servo()
    P[S.P_DAMPING] = 500.0
    P[S.P_SPRING] = 2e4
    P[S.P_SPRING_FREE] = 0.05
    h, duration = 1e-5, 0.3
    s0 = state(q=0.01, p_a=1e6, p_b=1e6, p_s=1e5)
    T, X = run(P, s0, h, duration, tab=PS_TAB)
    q, v = X[:, S.S_Q], X[:, S.S_V]
    assert np.all((q > 0.0) & (q < 1.0))
    kin = 0.5 * P[S.P_MASS] * (v[-1] ** 2 - v[0] ** 2)
    k, q0 = P[S.P_SPRING], P[S.P_SPRING_FREE]
    spring = 0.5 * k * ((q[-1] - q0) ** 2 - (q[0] - q0) ** 2)
    damper = simpson(P[S.P_DAMPING] * v**2, h)
    work = X[-1, S.S_E_ACT]
    assert damper > 0.1 * abs(work)  # every term matters
    assert work == pytest.approx(kin + spring + damper, rel=1e-7)


def test_pump_energy_is_pressure_times_flow():
    """The supply energy of a pump is its shaft's hydraulic energy ∫(p_s − p_T)·Q_pump dt
    (Simpson on the per-step record; the run converges at second order through the edges'
    kinks at the overlap: measured 2e-8 at h = 2e-5, 5e-9 at h = 1e-5; tolerance 5e-8)."""
    P = position_servo()
    h, duration = 1e-5, 0.2
    T, X = run(P, state(q=0.01, p_a=1e6, p_b=1e6, p_s=1e5), h, duration, tab=PS_TAB)
    shaft = simpson((X[:, S.S_PS] - P[S.P_P_TANK]) * P[S.P_PUMP_Q], h)
    assert X[-1, S.S_E_SUPPLY] == pytest.approx(shaft, rel=5e-8)
    # and it is spent: relief, pump leakage, valve, compression of the supply
    assert X[-1, S.S_E_RELIEF] > 0.5 * X[-1, S.S_E_SUPPLY]


# ---------------------------------------------------------------------------------------
# batch engine and convergence


def test_batch_equals_single():
    base = position_servo()
    rows = np.array([base.copy() for _ in range(3)])
    rows[1, S.P_MASS] = 60.0
    rows[2, S.P_KP] = 0.02
    rows[2, S.P_ACC_P0], rows[2, S.P_ACC_V0], rows[2, S.P_ACC_N] = 1e7, 2e-4, 1.4
    S0 = np.array([state(q=0.01, p_a=1e6, p_b=1e6, p_s=1e5) for _ in range(3)])
    S0[1, S.S_Q] = 0.05
    h, n, rec = 1e-5, 20000, 100
    tab_t, tab_y = PS_TAB
    for method in (EULER, RK4):
        Tb, Xb, bad = K.run_many(method, S0, 0.0, h, n, rec, tab_t, tab_y, NO_SINE, rows)
        assert np.all(bad == -1)
        for i in range(3):
            T, X, _, b = K.integrate(method, S0[i], 0.0, h, n, rec, tab_t, tab_y, NO_SINE, rows[i])
            assert b == -1
            np.testing.assert_array_equal(Xb[i], X)  # bit for bit
            np.testing.assert_array_equal(Tb, T)


def test_rk4_fourth_order():
    """A smooth case: underlapped spool (every edge open on the whole run, so no edge's
    opening kink), second-order spool, mechanical feedback, mass-spring load, fixed supply.
    Differences between h, h/2 and h/4 fall by 2⁴ (observed order within ±0.3 of 4; measured
    4.08, differences 3.7e-9 and 2.2e-10 of the scales, well above round-off)."""
    P = cylinder(area_a=1e-3, stroke=(0.0, 1.0), dead=3e-4, mass=50.0)
    spool(P, edge_coefficient(10e-3), lap=-2e-3, x_max=1e-3, order=2)
    P[S.P_SPOOL_OMEGA], P[S.P_SPOOL_ZETA] = 300.0, 0.7
    P[S.P_FEEDBACK] = S.FEEDBACK_MECHANICAL
    P[S.P_FB_GAIN] = 0.01
    P[S.P_SPRING], P[S.P_DAMPING] = 1e4, 2e3
    P[S.P_P_SUPPLY] = 1e7
    s0 = state(q=0.3, p_a=5e6, p_b=5e6, p_s=1e7)
    ref = 0.35
    finals = []
    for h in (8e-5, 4e-5, 2e-5):
        T, X = run(P, s0, h, 0.1, record_every=int(round(2e-3 / h)), ref=ref)
        finals.append(X[:, [S.S_Q, S.S_V, S.S_PA, S.S_PB]] / [1.0, 1.0, 1e7, 1e7])
    assert np.ptp(finals[-1][:, 0]) > 0.01  # it moves
    d1 = np.max(np.abs(finals[0] - finals[1]))
    d2 = np.max(np.abs(finals[1] - finals[2]))
    assert math.log2(d1 / d2) == pytest.approx(4.0, abs=0.3)


# ---------------------------------------------------------------------------------------
# the paper's lumped joint as a special case


@pytest.mark.parametrize("method", [EULER, RK4])
def test_lumped_paper_joint_is_a_special_case(method):
    """A symmetric two-chamber jack with the linearised valve, chamber volumes 2V and internal
    leakage C_i = 2L gives (V/β)·ṗ_L = K_q·e − A·ẋ − 2·L·p_L, the paper's eq. (1).

    With V_A = 2V(1 + ε), V_B = 2V(1 − ε), ε = A·Δx/(2V) the stroke's share, the load pressure
    obeys β·(1/V_A + 1/V_B) = (β/V)/(1 − ε²): the two models differ in ε² only (the mean
    pressure, which also moves, acts on neither the linearised valve nor the force). Here V
    is 1000× the paper's (ε ≤ 1.2e-4 on the run, ε² ≤ 1.5e-8); tolerance 1e-7 of the
    pressure, angle and velocity scales (≈ 10·ε²; measured 2.4e-10 for both methods)."""
    base = ha.parameter_set("paper-calibrated")
    V = 1000 * base.trapped_volume
    joint = base.replace(trapped_volume=V)
    J = joint.params()
    load = ha.paper_load(6)
    L = load.params()
    h, n, rec = 1e-5, 50000, 100
    tab_t, tab_y = np.array([0.0, 0.05, 0.05]), np.array([0.0, 0.0, 4e-3])
    p0 = holding_pressure(0.0, J, L)
    T1, TH, OM, PL, Y, bad = fixed.integrate(
        method, 0.0, 0.0, p0, 0.0, h, n, rec, tab_t, tab_y, NO_SINE, J, L
    )
    assert bad == -1

    P = S.default_parameters()
    A = J.piston_area
    P[S.P_AREA_A] = P[S.P_AREA_B] = A
    P[S.P_STROKE_MIN], P[S.P_STROKE_MAX] = -J.crank_radius, J.crank_radius
    # 2V at x = 0 in each chamber
    P[S.P_DEAD_A] = P[S.P_DEAD_B] = 2 * V - A * J.crank_radius
    P[S.P_BETA] = J.bulk_modulus
    P[S.P_LEAK_INT] = 2 * J.leakage_coefficient
    P[S.P_VALVE] = S.VALVE_LINEARISED
    P[S.P_FLOW_GAIN] = flow_gain(J)
    P[S.P_SPOOL_MAX] = J.valve_saturation
    P[S.P_SPOOL_ORDER] = 0
    P[S.P_FEEDBACK] = S.FEEDBACK_MECHANICAL
    P[S.P_FB_GAIN] = 1.0
    P[S.P_LOAD] = S.LOAD_CRANK
    P[S.P_MASS] = L.inertia
    P[S.P_GRAV_MOMENT] = L.weight * L.arm
    P[S.P_GRAV_ANGLE] = J.horizontal_angle
    P[S.P_CRANK_R], P[S.P_CRANK_N] = J.crank_radius, J.gear_ratio
    P[S.P_KIN_ARM] = 0.0  # eq. (3) as printed, as the paper set
    P[S.P_P_SUPPLY] = J.supply_pressure
    mean = 1e7  # chamber pressures far from the cavitation floor (the paper's p is a difference)
    s0 = state(p_a=mean + 0.5 * p0, p_b=mean - 0.5 * p0, p_s=J.supply_pressure)
    T2, X = run(P, s0, h, n * h, method=method, record_every=rec, tab=(tab_t, tab_y))
    np.testing.assert_array_equal(T1, T2)
    x = J.crank_radius * np.sin(X[:, S.S_Q] / J.gear_ratio)
    eps = np.max(np.abs(A * x / (2 * V)))
    assert eps < 1.5e-4
    assert np.ptp(TH) > 0.1  # the joint moves
    p_scale = np.max(np.abs(PL))
    np.testing.assert_allclose(X[:, S.S_PA] - X[:, S.S_PB], PL, rtol=0, atol=1e-7 * p_scale)
    np.testing.assert_allclose(X[:, S.S_Q], TH, rtol=0, atol=1e-7 * np.ptp(TH))
    np.testing.assert_allclose(X[:, S.S_V], OM, rtol=0, atol=1e-7 * np.max(np.abs(OM)))
