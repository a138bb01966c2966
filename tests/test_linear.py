"""Linear analysis (issue 15; docs/linear.md): closed forms against the linearisation, the
analytic Jacobian against finite differences, the linear step against the nonlinear model,
the step limit against the step check, the component servo against Merritt."""

import json
import math

import control
import numpy as np
import pytest

import hydroarm as ha
from hydroarm.analysis.linear import joint_jacobian, joint_jacobian_fd
from hydroarm.cli import main
from hydroarm.core.equations import holding_pressure, jack_position
from hydroarm.core.servo import (
    P_AREA_A,
    P_AREA_B,
    P_BETA,
    P_DEAD_A,
    P_DEAD_B,
    P_MASS,
    P_STROKE_MAX,
    P_STROKE_MIN,
)
from hydroarm.integrators.stability import (
    PAPER_EULER_ORDER,
    is_stable,
    jacobian,
    largest_stable_step_for,
    stable_step_limit,
)
from hydroarm.model.lever import step

PRINTED = "paper-printed"


def joint_model(load=6, angle=None, name=PRINTED, **changes):
    joint = ha.parameter_set(name)
    if changes:
        joint = joint.replace(**changes)
    sc = ha.saturation_test(joint, ha.paper_load(load), "raise")
    return sc, ha.linearize(sc, at=joint.horizontal_angle if angle is None else angle)


def merritt(sc, theta):
    """ω_h, ζ_h, K_v of hydroarm's lumped joint (eqs. (1)–(4) linearised at rest, valve in its
    band, no load stiffness), in Merritt's form (Hydraulic Control Systems, 1967, §6.2:
    ω_h = √(K_h/M), ζ_h = K_ce/A·√(β·M/V_t), K_v = K_q/A with V_t/4 → V for the lumped load
    pressure): ω_h² = β·A²·a·c/(V·I), ζ_h = (β/V)·K_ce·I/(2·I·ω_h)·..., K_v = K_q/A, with
    a = r/n the paper's torque arm and c = r·cos(θ₂/n)/n the jack's ∂x/∂θ₂."""
    j, load = sc.joint, sc.load
    a = j.crank_radius / j.gear_ratio
    c = j.crank_radius * math.cos(theta / j.gear_ratio) / j.gear_ratio
    k_ce = 2 * j.leakage_coefficient
    w_h = math.sqrt(j.bulk_modulus * j.piston_area**2 * a * c / (j.trapped_volume * load.inertia))
    z_h = (
        k_ce
        / (2 * j.piston_area)
        * math.sqrt(j.bulk_modulus * load.inertia / (j.trapped_volume * a * c))
    )
    return w_h, z_h, j.flow_gain / j.piston_area


@pytest.mark.parametrize("load", [6, 10])
@pytest.mark.parametrize("name", [PRINTED, "paper-calibrated"])
def test_merritt_closed_forms(load, name):
    """At the horizontal (gravity's stiffness W·X·sin(θ₂ − θ_h) is zero there) the loop broken
    at the valve opening is exactly K_v/(s·(s²/ω_h² + 2ζ_h·s/ω_h + 1)): the linearisation's
    hydraulic mode, velocity constant and gain margin (20·log₁₀(2ζ_h·ω_h/K_v), the Routh
    limit of that loop) equal the closed forms to rounding (1e-9 for eigenvalues of a 3×3
    matrix; 1e-6 for the margin, which python-control finds by a root search)."""
    sc, m = joint_model(load, name=name)
    q = m.quantities
    w_h, z_h, k_v = merritt(sc, sc.joint.horizontal_angle)
    assert q["hydraulic_natural_frequency_rad_s"] == pytest.approx(w_h, rel=1e-9)
    assert q["hydraulic_damping_ratio"] == pytest.approx(z_h, rel=1e-9)
    assert q["merritt_natural_frequency_rad_s"] == pytest.approx(w_h, rel=1e-12)
    assert q["velocity_constant_1_s"] == pytest.approx(k_v, rel=1e-12)
    gm = m.margins()["gain_margin_db"]
    assert gm == pytest.approx(20 * math.log10(2 * z_h * w_h / k_v), rel=1e-6)
    # the loop's low-frequency asymptote is K_v/s: |s·L(s)| at ω = 10⁻⁴·ω_h
    s = 1j * 1e-4 * w_h
    assert abs(s * m.loop(s)) == pytest.approx(k_v, rel=1e-6)
    # the hydraulic stiffness at the jack is the one every parameter set prints
    assert q["hydraulic_stiffness_n_m"] == pytest.approx(sc.joint.hydraulic_stiffness, rel=1e-12)


def test_issue_hand_numbers():
    """The issue's hand-worked numbers (Merritt on the printed parameters, V = 2.8 cm³):
    ω_h ≈ 90 / 60 rad/s at loads 6 / 10, a gain margin near 9 dB for both, phase margins of
    about 50° and 33°, small-step overshoot 20–40 %. hydroarm gets 86.1 / 57.9 rad/s, 8.66 dB,
    48.7° / 31.4°, 22.6 / 40.7 %: the same within the hand's rounding (ω_h to 5 %, margins
    to 0.5 dB and 2°)."""
    _, m6 = joint_model(6)
    _, m10 = joint_model(10)
    s6, s10 = m6.summary(), m10.summary()
    assert s6["hydraulic_natural_frequency_rad_s"] == pytest.approx(90, rel=0.05)
    assert s10["hydraulic_natural_frequency_rad_s"] == pytest.approx(60, rel=0.05)
    assert s6["gain_margin_db"] == pytest.approx(9, abs=0.5)
    assert s10["gain_margin_db"] == pytest.approx(s6["gain_margin_db"], rel=1e-9)  # load-free
    assert s6["phase_margin_deg"] == pytest.approx(50, abs=2)
    assert s10["phase_margin_deg"] == pytest.approx(33, abs=2)
    assert 20 <= s6["step_overshoot_percent"] <= 25
    assert 38 <= s10["step_overshoot_percent"] <= 42


@pytest.mark.parametrize(
    "changes",
    [
        {},
        {"torque_arm": "kinematic"},
        {"viscous_friction": 3573.0, "torque_arm": "kinematic"},
        {"null_leakage_coefficient": 3.9e-13, "viscous_friction": 500.0},
    ],
)
@pytest.mark.parametrize("state", [(0.3, 0.0, 12e5, 0.1e-3), (-0.7, 1.5, -4e5, -0.3e-3)])
def test_analytic_jacobian_matches_finite_differences(changes, state):
    """Analytic (A, B) of the linear valve against central differences of the compiled
    right-hand side, on and off rest, with every smooth option: agreement to 1e-6 of each
    column's scale (central differences with steps of 1e-7 rad, 1e-6 rad/s, 1 Pa, 1 nm: their
    truncation and round-off are below 1e-7 relative here)."""
    joint = ha.parameter_set(PRINTED).replace(**changes)
    load = ha.paper_load(8)
    sc = ha.saturation_test(joint, load, "raise")
    J, L = sc.params
    theta, omega, p, e = state
    y = float(jack_position(theta, J)) + e
    A, B = joint_jacobian(theta, omega, p, y, J, L)
    A_fd, B_fd = joint_jacobian_fd(theta, omega, p, y, J, L)
    for M, M_fd in ((A, A_fd), (B, B_fd)):
        scale = np.maximum(np.abs(M_fd).max(axis=0), 1e-30)
        assert np.all(np.abs(M - M_fd) <= 1e-6 * scale), (M, M_fd)


def test_closing_the_loop_gives_the_closed_loop():
    """The loop broken at the valve opening, closed with unity feedback, has the closed
    loop's poles (1e-9 relative)."""
    for sc_m in (joint_model(6, angle=0.2), joint_model(8, angle=-0.5, torque_arm="kinematic")):
        m = sc_m[1]
        closed = control.feedback(m.loop, 1)
        a = np.sort_complex(np.linalg.eigvals(closed.A))
        b = np.sort_complex(m.poles)
        assert np.allclose(a, b, rtol=1e-9, atol=0)


def test_no_load_time_constant_is_a_over_kq():
    """With no load (the piston's 0.227 kg only) the closed loop's slow real pole is −K_q/A:
    the standard formula τ = A/K_q of the paper (23.4 ms printed). The oil column is then at
    ω_h ≈ 7000 rad/s, and the cubic's slow root differs from −K_v by about K_v·2ζ_h/ω_h +
    (K_v/ω_h)² ≈ 4·10⁻⁵ relative; tolerance 10⁻³."""
    joint = ha.parameter_set(PRINTED)
    sc = ha.saturation_test(joint, ha.no_load(joint), "raise")
    m = ha.linearize(sc, at=0.0)
    real = m.poles[np.abs(m.poles.imag) < 1e-9 * np.abs(m.poles)]
    tau = 1.0 / float(np.min(np.abs(real)))
    assert tau == pytest.approx(joint.piston_area / joint.flow_gain, rel=1e-3)
    assert tau == pytest.approx(0.0234, abs=0.0001)


@pytest.mark.parametrize("load, angle", [(6, 0.0), (10, math.radians(-20))])
def test_small_lever_step_matches_the_nonlinear_model(load, angle):
    """A 20 µm lever step (2.7 % of the valve's full opening, so the valve stays linear and the
    crank's angle moves 0.1°) through the nonlinear model (rk4, 10 µs) against the linear step
    response: the angle's deviation agrees within 1 % of the step's size in angle over
    0.4 s. The neglected terms are second order in the step (cos and sin of a 0.1° swing)."""
    sc, m = joint_model(load, angle=angle)
    op = m.operating_point
    delta = 20e-6
    t_step = 0.01
    run = sc.replace(
        lever=step(op["lever"], op["lever"] + delta, t_step),
        initial_angle=op["angle"],
        initial_pressure=op["pressure"],
        duration=0.4,
        method="rk4",
        step=1e-5,
        record_every=10,
    )
    res = ha.simulate(run)
    t = res.t
    lin = np.zeros_like(t)
    after = t >= t_step
    resp = m.step_response(t[after] - t_step, delta)
    lin[after] = resp[:, 0]
    c = sc.joint.crank_radius * math.cos(op["angle"] / sc.joint.gear_ratio) / sc.joint.gear_ratio
    size = delta / c  # the step's size in angle
    err = np.abs(res.theta - op["angle"] - lin)
    assert np.max(err) <= 0.01 * size
    # the hold before the step is steady (the operating point is an equilibrium)
    assert np.max(np.abs(res.theta[~after] - op["angle"])) <= 1e-6 * size


@pytest.mark.parametrize("method", ["euler", "rk4"])
@pytest.mark.parametrize("name", [PRINTED, "ucl-arm-measured"])
def test_step_limit_is_the_step_checks(method, name):
    """The largest stable step from the eigenvalues at the operating point is
    ``largest_stable_step_for`` on the step check's own Jacobian there (bit for bit), the
    check's threshold at that state: accepted at h, refused 0.1 % above. ``stable_step_limit``
    (the CLI's refusal) takes the smallest over more states of a motion, so it refuses
    1.001·h too and suggests at most h."""
    sc, m = joint_model(6, angle=0.1, name=name)
    op = m.operating_point
    J, L = sc.params
    Jac = jacobian(op["angle"], 0.0, op["pressure"], op["lever"], J, L)
    h = m.largest_stable_step(method)
    assert h == largest_stable_step_for(method, [Jac], order=PAPER_EULER_ORDER)
    assert is_stable(method, Jac, h)
    assert not is_stable(method, Jac, 1.001 * h)
    refused = stable_step_limit(method, 1.001 * h, op["angle"], op["angle"], J, L)
    assert refused is not None and refused <= h * (1 + 1e-9)


def test_orifice_valve_uses_finite_differences():
    """ucl-arm-measured (orifice valve, null leakage, kinematic arm): K_c > 0 off null, the
    holding opening balances leakage against the orifice flow, and the closed loop is stable."""
    sc, m = joint_model(5, angle=0.0, name="ucl-arm-measured")
    J, L = sc.params
    op = m.operating_point
    assert op["pressure"] == pytest.approx(float(holding_pressure(0.0, J, L)))
    assert np.max(m.poles.real) < 0
    assert m.quantities["flow_gain_m2_s"] > 0


def test_position_servo_merritt():
    """examples/position_servo.toml at rest at 0.7 m: the hydraulic mode (actuator and mass
    with the spool held) is Merritt's √(β·A²·(1/V_A + 1/V_B)/m) within 1 % (the 100 N/m spring
    adds 100/2.7·10⁶ of stiffness, 2·10⁻⁵; the closed overlapped spool gives no flow gain, so
    the loop is open there and has no margins)."""
    sc = ha.load_scenario("examples/position_servo.toml")
    m = ha.linearize(sc, at=0.7)
    P = sc.vector()
    v_a = P[P_DEAD_A] + P[P_AREA_A] * (0.7 - P[P_STROKE_MIN])
    v_b = P[P_DEAD_B] + P[P_AREA_B] * (P[P_STROKE_MAX] - 0.7)
    w = math.sqrt(P[P_BETA] * P[P_AREA_A] ** 2 * (1 / v_a + 1 / v_b) / P[P_MASS])
    q = m.quantities
    assert q["hydraulic_natural_frequency_rad_s"] == pytest.approx(w, rel=0.01)
    assert q["merritt_natural_frequency_rad_s"] == pytest.approx(w, rel=1e-12)
    assert m.operating_point["position"] == 0.7
    assert m.margins()["gain_margin_db"] == math.inf
    # the state found is steady: the right-hand side vanishes there
    assert m.steady


def test_servo_linear_valve_loop(tmp_path):
    """A component servo with the paper's linearised valve and mechanical feedback: its
    velocity constant is gain·K_q/A and closing its loop gives the closed loop's poles."""
    sc = ha.load_scenario("examples/position_servo.toml")
    sc = sc.replace(
        valve_kind=1.0,
        flow_gain=0.05,
        feedback_kind=0.0,
        feedback_gain=0.01,
        internal_leakage=1e-11,
    )
    m = ha.linearize(sc, at=0.5)
    assert m.quantities["velocity_constant_1_s"] == pytest.approx(0.01 * 0.05 / 1e-3, rel=1e-9)
    closed = control.feedback(m.loop, 1)
    a = np.sort_complex(np.linalg.eigvals(closed.A))
    b = np.sort_complex(m.poles)
    assert np.allclose(a, b, rtol=1e-5, atol=1e-6 * np.max(np.abs(b)))


def test_cli_json(capsys, tmp_path):
    bode = tmp_path / "b.png"
    code = main(
        ["linearize", "--load", "6", "--parameter-set", PRINTED, "--json", "--bode", str(bode)]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    d = json.loads(out)
    for k in (
        "hydraulic_natural_frequency_rad_s",
        "hydraulic_damping_ratio",
        "velocity_constant_1_s",
        "gain_margin_db",
        "phase_margin_deg",
        "bandwidth_rad_s",
        "poles",
    ):
        assert k in d
    assert all(len(p) == 2 for p in d["poles"])
    assert d["hydraulic_natural_frequency_rad_s"] == pytest.approx(86.11, abs=0.01)
    assert bode.stat().st_size > 10_000


def test_cli_report(capsys):
    assert (
        main(["linearize", "--config", "examples/position_servo.toml", "--position", "0.7 m"]) == 0
    )
    out = capsys.readouterr().out
    assert "ω_h" in out and "163.3" in out


# ---------------------------------------------- numpy quantities, plots, variation ---
@pytest.mark.parametrize("load", [6, 10])
def test_numpy_quantities_equal_python_controls(load):
    """Margins, bandwidth and step metrics in numpy alone (hydroarm.analysis.lti) against
    python-control's stability_margins, bandwidth and step_info: margins and bandwidth to
    1e-9; the overshoot within 0.05 points and the rise and settling times within 3 %
    (python-control reads them off its default time grid, hydroarm interpolates a finer one)."""
    _, m = joint_model(load)
    gm, pm, _, wpc, wgc, _ = control.stability_margins(m.loop)
    mg = m.margins()
    assert mg["gain_margin_db"] == pytest.approx(20 * math.log10(gm), rel=1e-9)
    assert mg["phase_margin_deg"] == pytest.approx(pm, rel=1e-9)
    assert mg["phase_crossover_rad_s"] == pytest.approx(wpc, rel=1e-9)
    assert mg["gain_crossover_rad_s"] == pytest.approx(wgc, rel=1e-9)
    assert m.bandwidth() == pytest.approx(control.bandwidth(m.tracking), rel=1e-9)
    ours, theirs = m.step_info(), control.step_info(m.tracking)
    assert ours["Overshoot"] == pytest.approx(theirs["Overshoot"], abs=0.05)
    assert ours["RiseTime"] == pytest.approx(theirs["RiseTime"], rel=0.03)
    assert ours["SettlingTime"] == pytest.approx(theirs["SettlingTime"], rel=0.03)
    t = np.linspace(0, 0.3, 301)
    _, y = m.small_step(t)
    ref = control.step_response(m.tracking, T=t).outputs
    assert np.allclose(y, np.ravel(ref) / control.dcgain(m.tracking), atol=1e-9)


def test_pole_and_step_figures():
    """The pole map has the poles, the ω_h circle (radius ω_h) and the ζ_h lines; the step
    figure has the normalised response ending at 1, the overshoot marker at 1 + overshoot and
    the rise span and settling line."""
    _, m = joint_model(6)
    q = m.quantities
    fig = m.pole_figure()
    ax = fig.axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    poles = lines["closed-loop poles"]
    assert np.allclose(
        np.sort_complex(poles.get_xdata() + 1j * poles.get_ydata()), np.sort_complex(m.poles)
    )
    circle = next(v for k, v in lines.items() if k.startswith("|s| = ω_h"))
    r = np.hypot(circle.get_xdata(), circle.get_ydata())
    assert np.allclose(r, q["hydraulic_natural_frequency_rad_s"])
    assert any(k.startswith("ζ_h") for k in lines)
    fig = m.step_figure()
    ax = fig.axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    resp = lines["small-signal step (linear)"]
    assert resp.get_ydata()[-1] == pytest.approx(1.0, abs=0.02)
    info = m.step_info()
    over = next(v for k, v in lines.items() if k.startswith("overshoot"))
    assert over.get_ydata()[0] == pytest.approx(1 + info["Overshoot"] / 100)
    assert max(resp.get_ydata()) == pytest.approx(1 + info["Overshoot"] / 100, abs=1e-4)
    labels = [p.get_label() for p in ax.patches]
    assert any(s.startswith("rise 10–90 %") for s in labels)
    assert any(k.startswith("settling (2 %)") for k in lines)


def test_variation_trends():
    """ω_h falls as the load's inertia rises at every angle; the gain margin does not depend
    on the load (the issue: 2ζ_h·ω_h = 2Lβ/V and K_v = K_q/A); the phase margin falls with the
    inertia; the figure has one line per load in each of its four panels."""
    angles = np.radians([-60.0, -20.0, 30.0, 60.0])
    frame = ha.linear_variation(PRINTED, [1, 4, 6, 8, 10], angles)
    assert len(frame) == 20 and frame["held"].all()
    for theta in angles:
        at = frame[frame["angle_rad"] == theta].sort_values("inertia_kg_m2")
        assert np.all(np.diff(at["hydraulic_natural_frequency_rad_s"]) < 0)
        assert np.all(np.diff(at["phase_margin_deg"]) < 0)
        gm = at["gain_margin_db"].to_numpy()
        assert np.allclose(gm, gm[0], rtol=1e-9)
    # at the horizontal, the row equals linearize's summary
    _, m10 = joint_model(10)
    row = frame[(frame["load"] == 10) & np.isclose(frame["angle_deg"], 30.0)].iloc[0]
    s = m10.summary()
    for k in ("hydraulic_natural_frequency_rad_s", "gain_margin_db", "step_overshoot_percent"):
        assert row[k] == pytest.approx(s[k], rel=1e-12)
    fig = ha.analysis.linear.linear_variation_figure(frame)
    assert len(fig.axes) == 4
    for ax in fig.axes:
        assert [ln.get_label() for ln in ax.get_lines()] == [f"load {k}" for k in (1, 4, 6, 8, 10)]


def test_cli_plots_and_variation(capsys, tmp_path):
    files = {k: tmp_path / f"{k}.png" for k in ("poles", "step", "vary")}
    code = main(
        [
            "linearize",
            "--load",
            "6",
            "--poles",
            str(files["poles"]),
            "--step-response",
            str(files["step"]),
        ]
    )
    assert code == 0, capsys.readouterr().err
    code = main(
        [
            "linearize",
            "--vary",
            str(files["vary"]),
            "--loads",
            "1,10",
            "--angles",
            "-30 deg,30 deg,3",
            "--json",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    rows = json.loads(out.splitlines()[-1])["variation"]
    assert [(r["load"], round(r["angle_deg"])) for r in rows] == [
        (1, -30),
        (1, 0),
        (1, 30),
        (10, -30),
        (10, 0),
        (10, 30),
    ]
    for f in files.values():
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "args, field",
    [
        (["--load", "6", "--poles", "/no/such/folder/p.png"], "--poles"),
        (["--load", "6", "--step-response", "."], "--step-response"),
        (["--vary", "/no/such/folder/v.png"], "--vary"),
        (["--vary", "v.png", "--loads", "1,11"], "--loads"),
        (["--vary", "v.png", "--angles", "1,2"], "--angles"),
        (["--vary", "v.png", "--angles", "-200 deg,0 deg,5"], "--angles"),
        (["--load", "6", "--loads", "1,6"], "--loads"),
        (["--step-response", "s.png"], "linearize"),
        (["--config", "examples/position_servo.toml", "--vary", "v.png"], "--vary"),
    ],
)
def test_cli_plot_options_bad_input(capsys, tmp_path, monkeypatch, args, field):
    """Bad plot paths and variation options: one line on stderr naming the option, exit 2,
    nothing written."""
    monkeypatch.chdir(tmp_path) if "examples" not in " ".join(args) else None
    assert main(["linearize", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"hydroarm: error: {field}:"), err
    assert not list(tmp_path.glob("*.png"))
