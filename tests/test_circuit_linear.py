"""The linear view of circuits and the equilibrium start (issue 29; docs/linear.md "Circuits").

Every check runs the kernel's own right-hand side: the linear model by central differences
about a steady state, the nonlinear model by ``simulate`` from the same state.
"""

import math

import numpy as np
import pytest

from hydroarm.analysis import lti
from hydroarm.analysis.circuit_linear import linearize_circuit
from hydroarm.cli import main
from hydroarm.errors import HydroarmError
from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import ComponentSpec, build, simulate

SERVO = "examples/circuit_position_servo.toml"
POSE = 0.7  # [m] the servo held there, the reference freed to hold it
# Test variants of the example: the example itself (0.1 mm overlap, no leakage, K_p = 0.0264)
# sits in its overlap at rest, and with zero lap it limit-cycles (ζ_h = 0 without leakage:
# K_v > 2ζ_hω_h). Internal leakage C_i = 5e-11 m³/s/Pa gives ζ_h ≈ 0.41 and half the
# example's K_p keeps the underlap variant (twice the flow gain at null) stable.
STABLE = {"jack.internal_leakage": 5e-11, "controller.proportional_gain": 0.0132}
UNDERLAP = -1e-5  # [m] 10 µm on every edge
AMPLITUDE = 1e-4  # [m] reference sine and step: the spool moves ±2.6 µm, inside the underlap


def servo(lap, **extra):
    values = {"valve.overlap": lap, **STABLE, **extra}
    return load_circuit(SERVO).with_values(values)


def with_reference(circuit, arrays=None, **values):
    comps = [
        ComponentSpec("signal_source", c.name, c.ports, values, arrays or {})
        if c.name == "reference"
        else c
        for c in circuit.components
    ]
    return circuit.replace(components=tuple(comps))


def run_from(circuit, s0, **solver):
    compiled = build(circuit.replace(**solver))
    compiled.s0 = s0.copy()
    return simulate(compiled)


@pytest.fixture(scope="module", params=[0.0, UNDERLAP], ids=["zero-lap", "underlap"])
def model(request):
    return request.param, linearize_circuit(servo(request.param), position=POSE)


def test_operating_point_is_physical(model):
    """No NaN, no negative absolute pressure, the pose held, the reference found."""
    _, m = model
    s = m.summary()
    assert m.point.inputs["reference"] == pytest.approx(POSE, abs=1e-9)
    for k, v in s["operating_point"].items():
        assert math.isfinite(v), k
        if k.endswith("_pressure_bar"):
            assert v >= 1.0 - 1e-9, k  # the tank's 1 bar is the lowest source
    assert s["gain_margin_db"] is not None and s["phase_margin_deg"] is not None
    assert s["bandwidth_rad_s"] is not None and s["loop_open"] is None
    assert np.max(m.poles.real) < 0


def test_small_sine_agrees_with_linear_model(model):
    """Gain within 0.5 dB and phase within 3° of the nonlinear model's small sine response
    (issue 29), ω_h/4 … 2·ω_h. Each run starts at the operating point, settles 1.5 s (the
    slowest oscillatory pole decays by e⁻⁶⁰ by then; the slow integral pole is absorbed by
    an offset and a trend in the fit) and fits the fundamental over three periods."""
    lap, m = model
    w_h, _ = m.hydraulic_mode()
    for w in (0.25 * w_h, 0.5 * w_h, w_h, 2 * w_h):
        period = 2 * math.pi / w
        settle = max(3 * period, 1.5)
        c = with_reference(
            servo(lap),
            waveform="sine",
            offset=POSE,
            amplitude=AMPLITUDE,
            frequency=w / (2 * math.pi),
        )
        r = run_from(c, m.point.state, duration=settle + 3 * period, record_every=1)
        y = r.output("load_position_m") - POSE
        keep = r.t >= settle
        t = r.t[keep]
        X = np.column_stack([np.sin(w * t), np.cos(w * t), np.ones_like(t), t])
        a, b, _, _ = np.linalg.lstsq(X, y[keep], rcond=None)[0]
        g_nl = complex(a, b) / AMPLITUDE
        g_lin = m.freqresp(w)[0]
        assert 20 * math.log10(abs(g_nl) / abs(g_lin)) == pytest.approx(0.0, abs=0.5), w
        assert math.degrees(abs(np.angle(g_nl / g_lin))) < 3.0, w


def test_small_step_agrees_with_linear_model(model):
    """A 0.1 mm reference step: the nonlinear position within 2 % of the step of the linear
    model's step over 0.3 s (the oscillatory transient's decay; the tolerance covers the
    kink of a zero-lap spool at null, whose two slopes differ by the load's Δp)."""
    lap, m = model
    c = with_reference(
        servo(lap), {"times": (0.0,), "values": (POSE + AMPLITUDE,)}, waveform="steps"
    )
    r = run_from(c, m.point.state, duration=0.3, record_every=10)
    y = r.output("load_position_m") - POSE
    y_lin = lti.step(m.A, m.B[:, 0], m.C[0], float(m.D[0, 0]), r.t) * AMPLITUDE
    assert np.max(np.abs(y - y_lin)) < 0.02 * AMPLITUDE


def test_overlap_reported_open_with_nearest_point():
    """The example's 0.1 mm overlap (no leakage, so no flow at rest: with the variants'
    leakage the spool would leave the overlap to feed it): at rest the spool sits inside it,
    the loop is open (no margins), and the nearest operating point with flow is the spool
    displaced by its overlap, linearised as a zero-lap valve."""
    m = linearize_circuit(load_circuit(SERVO), position=POSE)
    assert m.open_loop_reason is not None and "overlap" in m.open_loop_reason
    assert m.margins() is None
    s = m.summary()
    assert s["gain_margin_db"] is None and s["loop_open"]
    near = m.nearest
    assert near is not None and near.margins() is not None
    assert near.point_values["valve_spool_m"] == pytest.approx(1e-4, abs=1e-6)
    zero = linearize_circuit(load_circuit(SERVO).with_values({"valve.overlap": 0.0}), position=POSE)
    assert np.sort_complex(near.poles) == pytest.approx(np.sort_complex(zero.poles), rel=1e-6)
    assert "loop open" in m.report()


def test_floating_level_removed_not_a_pole():
    """Zero lap, no leakage: the chambers' common level floats (no leakage path). It is
    reported and removed: no pole at 0 (the example's own PI servo, which limit-cycles,
    reported as unstable, not with a spurious zero pole)."""
    m = linearize_circuit(load_circuit(SERVO).with_values({"valve.overlap": 0.0}), position=POSE)
    assert m.floating == ["A.pressure + B.pressure"]
    assert np.min(np.abs(m.poles)) > 1e-3
    p = m.point_values
    # the level placed at mid-pressure: p_A + p_B = p_s + p_T
    assert p["A_pressure_bar"] + p["B_pressure_bar"] == pytest.approx(
        p["supply_pressure_bar"] + p["T_pressure_bar"], rel=1e-9
    )
    assert "structural zero removed" in m.report()


def test_hydraulic_natural_frequency_is_merritts():
    """Merritt 1967 §6.2, a symmetric cylinder at mid-stroke: ω_h = √(4βA²/(V_t·m)) and, with
    internal leakage only (K_ce = C_i), ζ_h = (C_i/A)·√(β·m/V_t). V_t = 2·(3e-4 + 1e-3·0.5)
    = 1.6e-3 m³ includes the dead volumes (the same in both). The model adds the mass's
    spring k = 100 N/m: ω² = ω_h² + k/m shifts ω by 2e-5 (tolerance 1e-4). ζ_h comes out
    1.1e-3 above Merritt's (0.39572 against 0.39528), more than the spring's 4e-5 share: not
    yet accounted for, so its tolerance is 2e-3."""
    beta, area, mass, c_i = 1e9, 1e-3, 100.0, 5e-11
    v_t = 2 * (3e-4 + area * 0.5)
    m = linearize_circuit(servo(0.0), position=0.5)
    w_h, z_h = m.hydraulic_mode()
    assert w_h == pytest.approx(math.sqrt(4 * beta * area**2 / (v_t * mass)), rel=1e-4)
    assert z_h == pytest.approx(c_i / area * math.sqrt(beta * mass / v_t), rel=2e-3)


def test_pose_outside_stroke_is_refused():
    with pytest.raises(HydroarmError, match=r"--position: 1\.3 is outside the stroke of jack"):
        linearize_circuit(servo(0.0), position=1.3)


# ------------------------------------------------------------- equilibrium start ---
def test_equilibrium_start_holds_a_gravity_load():
    """The counterbalance example's vertical cylinder (800 kg, stroke 0.5 m) with every node
    at 1 bar: started as is it drops; started at equilibrium (the static state at its initial
    pose 0.4 m and the inputs at t = 0) its first 0.1 s moves less than 1e-6 of the stroke."""
    c = load_circuit("examples/counterbalance.toml").replace(initial={}, duration=0.1)
    x = simulate(c).output("load_position_m")
    assert np.max(np.abs(x - 0.4)) > 1e-3 * 0.5
    r = simulate(c.replace(equilibrium=True))
    x = r.output("load_position_m")
    assert np.max(np.abs(x - 0.4)) < 1e-6 * 0.5
    assert r.output("cap_pressure_bar")[0] == pytest.approx(
        (800 * 9.81 + 1e5 * 12.566e-4) / 19.635e-4 / 1e5, rel=1e-3
    )


def test_equilibrium_start_from_a_file(tmp_path):
    text = open("examples/counterbalance.toml").read()
    text = text.replace('cap = "40.610 bar"', "equilibrium = true")
    path = tmp_path / "held.toml"
    path.write_text(text)
    c = load_circuit(path)
    assert c.equilibrium and "cap" not in c.initial


def test_reference_outside_stroke_is_one_line(tmp_path, capsys):
    text = open(SERVO).read().replace('values = ["0.2 m", "0.7 m"]', 'values = ["0.2 m", "1.2 m"]')
    path = tmp_path / "far.toml"
    path.write_text(text)
    assert main(["simulate", "--config", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        "hydroarm: error: component.reference.values[1]: the reference 1.2 asks for position "
        "1.2 at node 'load', outside the stroke of jack (0 … 1)"
    )


# ---------------------------------------------------------------------------- CLI ---
def test_cli_linearize_circuit(tmp_path, capsys):
    bode = tmp_path / "bode.png"
    code = main(
        [
            "linearize",
            "--config",
            SERVO,
            "--position",
            "0.7 m",
            "--output",
            "load_position_m",
            "--input",
            "reference",
            "--bode",
            str(bode),
        ]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert "supply_pressure_bar = 218.49" in out
    assert "loop open" in out and "nearest operating point with flow" in out
    assert "nan" not in out.lower()
    assert bode.exists()
