"""A component servo file is a shorthand for a circuit (issue 28; hydroarm/io/servo_circuit.py,
docs/components.md "A servo file as a circuit").

The component servo's own kernel (hydroarm.core.servo, one right-hand side written for that
shape) and the circuit the file expands into (the system kernel over the linear_valve or
valve_4_3, cylinder or rotary_actuator, mass, inertia and crank_linkage, pid and
position_sensor, pump, volume, relief valve and accumulator components) are two
independent codings of the same equations. Stepped by the same RK4 at the same step they
differ by the order of floating-point operations only, so the traces are compared to
1e-9 of their range (of their value, for a constant): round-off (1e-16) amplified by the
closed loop stays below 1e-12 of it in every file here (measured), and any difference in a
law (a sign, a missing term, a default) shows at 1e-4 or more.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hydroarm.integrators.system import derivatives_at
from hydroarm.io.circuit import circuit_from_doc
from hydroarm.io.schema import load_scenario_text
from hydroarm.io.sections import parse_toml
from hydroarm.io.servo_circuit import circuit_toml, load_servo_circuit, servo_circuit
from hydroarm.model.circuit import build, simulate
from hydroarm.reference import run_on_servo_kernel

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "servo_circuit"
FILES = {
    "position_servo": (ROOT / "examples" / "position_servo.toml", 0.3),
    "rotary_joint": (ROOT / "examples" / "rotary_joint.toml", 0.5),
    "linear_mechanical": (DATA / "linear_mechanical.toml", 0.5),
    "crank_pump": (DATA / "crank_pump.toml", 0.6),
    "single_rod_pi": (DATA / "single_rod_pid.toml", 0.5),
}
# servo column -> the circuit's (its nodes: rod, joint, A, B, supply; the valve's spool)
PAIRS = {
    "position_m": "rod_position_m",
    "velocity_m_s": "rod_velocity_m_s",
    "angle_deg": "joint_angle_deg",
    "pressure_a_bar": "A_pressure_bar",
    "pressure_b_bar": "B_pressure_bar",
    "supply_bar": "supply_pressure_bar",
}


def both(path: Path, duration: float, edit=lambda text: text):
    text = edit(path.read_text())
    doc = parse_toml(text, path.name)
    servo = load_scenario_text(text, path.parent, path.stem).replace(duration=duration)
    circuit = dataclasses.replace(servo_circuit(doc, path.parent, path.stem), duration=duration)
    return run_on_servo_kernel(servo).to_pandas(), simulate(circuit).to_pandas()


def differences(old, new):
    n = min(len(old), len(new))
    assert abs(len(old) - len(new)) <= 1
    out = {}
    for a, b in PAIRS.items():
        if a in old and b in new:
            x = old[a].to_numpy()[:n]
            out[a] = (np.max(np.abs(x - new[b].to_numpy()[:n])), max(np.ptp(x), np.max(np.abs(x))))
    return out


@pytest.mark.parametrize("name", sorted(FILES))
def test_circuit_of_a_servo_file_gives_the_servo_kernel_numbers(name):
    path, duration = FILES[name]
    old, new = both(path, duration)
    diffs = differences(old, new)
    assert {"pressure_a_bar", "pressure_b_bar"} <= set(diffs)
    assert "position_m" in diffs or "angle_deg" in diffs
    for column, (d, span) in diffs.items():
        assert d <= 1e-9 * span, f"{column}: {d:.3g} over a range of {span:.3g}"


def test_the_printed_torque_arm_gives_the_servo_kernel_numbers():
    """The crank with the torque arm r/n printed in the paper's eq. (3): the circuit's
    crank_linkage carries the rod's force by that lever instead of g' (system.fold_slaves)."""
    path, duration = FILES["crank_pump"]
    old, new = both(
        path, duration, lambda t: t.replace('torque_arm = "kinematic"', 'torque_arm = "paper"')
    )
    base, _ = both(path, duration)
    assert np.max(np.abs(old["angle_deg"] - base["angle_deg"])) > 1e-3  # the option acts
    for column, (d, span) in differences(old, new).items():
        assert d <= 1e-9 * span, f"{column}: {d:.3g} over a range of {span:.3g}"


def test_euler_with_dry_friction_gives_the_servo_kernel_numbers():
    """The semi-implicit Euler moves the position by the whole step's friction impulse, in
    both kernels (hydroarm.core.circuit.laws.POSITION_SHARE_EULER)."""
    path, duration = FILES["linear_mechanical"]
    old, new = both(path, duration, lambda t: t.replace('method = "rk4"', 'method = "euler"'))
    for column, (d, span) in differences(old, new).items():
        assert d <= 1e-9 * span, f"{column}: {d:.3g} over a range of {span:.3g}"


def test_a_pid_without_the_sensors_rate_filters_its_measurement():
    """The servo's PID differentiates the sensor's rate exactly, as the circuit's pid does
    with the position_sensor's ``rate`` on its ``measurement_rate`` (the file's circuit,
    above: 1e-9 of the range). Unconnected, the pid filters its measurement instead, here
    by τ_d = one solver step (10 µs): the demand then lags by about K_d·ÿ·τ_d, measured
    2.1e-6 m in position and 0.33 bar in pressure over a 0.15 m, 150 bar move; bounded
    here at about 3× that, and above 1e3× the exact form's tolerance."""
    path, duration = FILES["single_rod_pi"]
    circuit = servo_circuit(parse_toml(path.read_text(), path.name), path.parent, path.stem)
    parts = []
    for c in circuit.components:
        ports = {k: v for k, v in c.ports.items() if v != "measurement_rate"}
        values = dict(c.values)
        if c.type == "pid":
            assert c.ports["measurement_rate"] == "measurement_rate"
            values["derivative_time_constant"] = circuit.step
        parts.append(dataclasses.replace(c, ports=ports, values=values))
    filtered = dataclasses.replace(circuit, components=tuple(parts), duration=duration)
    old, _ = both(path, duration)
    diffs = differences(old, simulate(filtered).to_pandas())
    assert 1e3 * 1e-9 * diffs["position_m"][1] < diffs["position_m"][0] < 1e-5
    assert diffs["pressure_a_bar"][0] < 1.0 and diffs["pressure_b_bar"][0] < 1.0


@pytest.mark.parametrize("name", ["position_servo", "crank_pump"])
def test_written_circuit_file_reads_back_to_the_same_run(name, tmp_path):
    """``circuit_toml`` writes each value with repr() in its declared SI unit: the file read
    back gives the same parameters, so the same run bit for bit."""
    path, _ = FILES[name]
    circuit = dataclasses.replace(load_servo_circuit(path), duration=0.05)
    text = circuit_toml(circuit, "test")
    back = circuit_from_doc(parse_toml(text, "back"), "back", tmp_path)
    assert np.array_equal(build(back).parameter_vector({}), build(circuit).parameter_vector({}))
    a = simulate(circuit).to_pandas()
    b = simulate(back).to_pandas()
    assert a.equals(b)


def _cli(*args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "hydroarm", *args], cwd=cwd, capture_output=True, text=True
    )


def test_expand_command_writes_a_circuit_that_simulates(tmp_path):
    out = tmp_path / "rotary.toml"
    r = _cli("expand", "--config", str(FILES["rotary_joint"][0]), "--out", str(out), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    text = out.read_text()
    assert 'type = "rotary_actuator"' in text and 'type = "pid"' in text
    circuit = circuit_from_doc(parse_toml(text, "x"), "x", tmp_path)
    assert {c.type for c in circuit.components} >= {"rotary_actuator", "inertia", "valve_4_3"}


def test_edges_that_differ_give_the_servo_kernel_numbers(tmp_path):
    """Per-edge overlaps (``overlap_pa`` …) and flow coefficients: the valve_4_3's
    ``extra_overlap_<edge>`` and ``width_ratio_<edge>`` relative to edge P→A's (before,
    refused as having no circuit form). Traces to 1e-9 of their range, as above; the edges'
    difference does act (the position moves by more than 1e-4 of its range)."""
    path, duration = FILES["crank_pump"]

    def edit(text):
        return text.replace(
            'overlap = "0.01 mm"',
            'overlap = "0.01 mm"\noverlap_pa = "0 mm"\noverlap_bt = "0.03 mm"',
        )

    assert edit(path.read_text()) != path.read_text()
    old, new = both(path, duration, edit)
    base, _ = both(path, duration)
    assert np.max(np.abs(old["angle_deg"] - base["angle_deg"])) > 1e-4 * np.ptp(base["angle_deg"])
    for column, (d, span) in differences(old, new).items():
        assert d <= 1e-9 * span, f"{column}: {d:.3g} over a range of {span:.3g}"
    (tmp_path / "s.toml").write_text(edit(path.read_text()))
    r = _cli("expand", "--config", "s.toml", "--out", "c.toml", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    text = (tmp_path / "c.toml").read_text()
    assert "extra_overlap_at" in text and "extra_overlap_bt" in text


def test_unequal_flow_coefficients_are_width_ratios():
    sc = load_scenario_text((ROOT / "examples" / "position_servo.toml").read_text())
    sc = sc.replace(edge_bt=0.5 * sc.parameters["edge_pa"])
    (valve,) = [c for c in sc.circuit.components if c.name == "valve"]
    assert valve.values["width_ratio_bt"] == 0.5 and "width_ratio_at" not in valve.values


def test_linear_valve_into_rotary_actuator_turns_at_the_flow_over_the_displacement():
    """Closed form: a linearised valve held open at x_v passes q = K_q·x_v whatever the
    pressures; into a rotary actuator of displacement D the shaft settles at ω = q/D (the
    chamber's continuity with no leakage), the inertia's damping c taking the torque
    D·Δp = c·ω. The B side passes α·q into a chamber of displacement α·D."""
    k_q, x_v, disp, alpha = 0.02, 2.0e-4, 4.0e-6, 0.5
    comps = [
        {"type": "tank", "name": "tank", "ports": {"port": "T"}, "pressure": "1 bar"},
        {"type": "tank", "name": "source", "ports": {"port": "S"}, "pressure": "100 bar"},
        {
            "type": "linear_valve",
            "name": "valve",
            "ports": {"P": "S", "T": "T", "A": "A", "B": "B"},
            "flow_gain": f"{k_q} m**2/s",
            "area_ratio": alpha,
            "max_stroke": "1 mm",
            "demand": f"{x_v} m",
        },
        {
            "type": "rotary_actuator",
            "name": "vane",
            "ports": {"a": "A", "b": "B", "shaft": "shaft"},
            "displacement_a": f"{disp} m**3/rad",
            "displacement_b": f"{alpha * disp} m**3/rad",
            "travel": "10 rad",
            "angle_at_a_end": "-5 rad",
            "dead_volume_a": "5 cm**3",
            "dead_volume_b": "5 cm**3",
        },
        {
            "type": "inertia",
            "name": "load",
            "ports": {"body": "shaft"},
            "inertia": "0.001 kg*m**2",
            "damping": "0.5 N*m*s",
        },
    ]
    doc = {
        "component": comps,
        "initial": {"pressure": "20 bar"},
        "solver": {"method": "rk4", "step": "20 us", "duration": "0.5 s", "record_every": 500},
    }
    res = simulate(circuit_from_doc(doc, "t")).to_pandas()
    omega = res["shaft_angular_velocity_rad_s"].to_numpy()
    expected = k_q * x_v / disp
    # the oil column's ring (ω_n ≈ 1200 rad/s) decays as exp(−c·t/2J): by e⁻¹²⁵ at 0.5 s
    assert omega[-1] == pytest.approx(expected, rel=1e-6)
    q = k_q * x_v * 6e4  # [L/min]; a port's flow is into the component: out at A, in at B
    assert res["valve_A_flow_lpm"].to_numpy()[-1] == pytest.approx(-q, rel=1e-9)
    assert res["valve_B_flow_lpm"].to_numpy()[-1] == pytest.approx(alpha * q, rel=1e-9)


def _crank_with_friction(step_us: float):
    """crank_pump with piston friction (5 N sliding, 8 N breakaway) and a gearbox (0.05 N m
    no-load, a loss of 0.3 at a 40 bar rated load) at the step ``step_us``."""

    def edit(text: str) -> str:
        text = text.replace(
            'damping = "0.05 N*m*s"',
            'damping = "0.05 N*m*s"\ngearbox_friction_torque = "0.05 N*m"\n'
            'gearbox_loss_at_stall = 0.3\nrated_pressure = "40 bar"',
        )
        text = text.replace(
            "air_fraction = 0.002",
            'air_fraction = 0.002\ncoulomb_friction = "5 N"\nbreakaway_friction = "8 N"',
        )
        every = round(1000 / step_us)
        text = text.replace('step = "10 us"', f'step = "{step_us} us"')
        return text.replace("record_every = 100", f"record_every = {every}")

    return edit


def test_crank_with_dry_friction_gives_the_servo_kernel_numbers():
    """A crank load's piston and gearbox friction on the circuit's crank_linkage, driven by
    the cylinder's pressure force (io.servo_circuit.crank_friction): the same friction law
    and stick-or-slide rule as the servo kernel, with the torque arm a = (r/n)·cos(θ/n) at
    the step's start and the drive force at its end in both (the paper joint's rule), so
    the numbers agree to 1e-9 of the range. (When the servo kernel took the arm at the
    smooth update's end, the two differed by (r/n²)·sin(θ/n)·θ̇·h per step: over 0.6 s,
    1.8e-4° of a 47.5° range at 10 µs, 9.1e-5° at 5 µs.) The friction itself moves the
    angle by degrees, far above the tolerance."""
    path, duration = FILES["crank_pump"][0], 0.6
    coarse = differences(*both(path, duration, _crank_with_friction(10)))
    for column in ("angle_deg", "pressure_a_bar", "pressure_b_bar"):
        d, span = coarse[column]
        assert d <= 1e-9 * span, f"{column}: {d:.3g} over a range of {span:.3g}"

    def frictionless(text: str) -> str:
        text = _crank_with_friction(10)(text).replace("gearbox_loss_at_stall = 0.3", "")
        text = text.replace('coulomb_friction = "5 N"', "")
        return text.replace('breakaway_friction = "8 N"', "")

    without, _ = both(path, duration, frictionless)
    with_friction, _ = both(path, duration, _crank_with_friction(10))
    moved = np.max(np.abs(with_friction["angle_deg"] - without["angle_deg"]))
    assert moved > 1e3 * 1e-9 * coarse["angle_deg"][1]


@pytest.mark.parametrize("name", ["position_servo", "crank_pump"])
def test_scenario_builds_its_circuit_once_and_it_gives_the_servo_kernel_numbers(name):
    """``ServoScenario.circuit`` (hydroarm.model.servo_circuit: the expansion without the
    file, the valve's geometry at the component's defaults) is built once per scenario, left
    out of a pickle, and runs the servo kernel's numbers to the same 1e-9 of the range as the
    file's circuit (module doc: the valve's k = C_d·π·d·f·√(2/ρ) differs from the file's by
    round-off only)."""
    import pickle

    path, duration = FILES[name]
    servo = load_scenario_text(path.read_text(), path.parent, path.stem).replace(duration=duration)
    circuit = servo.circuit
    assert servo.circuit is circuit and servo.compiled_circuit is servo.compiled_circuit
    assert "circuit" not in pickle.loads(pickle.dumps(servo)).__dict__
    assert "circuit" not in servo.replace(mass=1.0).__dict__
    diffs = differences(servo.run().to_pandas(), simulate(servo.compiled_circuit).to_pandas())
    assert {"pressure_a_bar", "pressure_b_bar"} <= set(diffs)
    for column, (d, span) in diffs.items():
        assert d <= 1e-9 * span, f"{column}: {d:.3g} over a range of {span:.3g}"


@pytest.mark.parametrize("name", sorted(FILES))
def test_circuit_step_limit_is_the_servo_kernels(name):
    """The step check on the circuit's Jacobians (model.servo_circuit.circuit_step_limit:
    central differences of the system kernel's right-hand side at the servo check's states)
    finds the servo kernel's largest stable step: the same linearisation, so equal up to the
    differences' round-off (measured: equal to 4 digits in every file); bounded at 1e-6,
    while a missing term in a law moves it by percents. (The single-rod PI file's
    derivative takes the sensor's rate in both.) Each file's own step is accepted by both."""
    from hydroarm.model.servo_circuit import circuit_step_limit
    from hydroarm.reference.servo_kernel import servo_step_limit

    path, _ = FILES[name]
    base = load_scenario_text(path.read_text(), path.parent, path.stem)
    for method in ("rk4", "euler"):
        sc = base.replace(method=method, step=0.05, duration=1.0)  # above every limit
        old = servo_step_limit(
            method, sc.step, sc.initial_state(), float(sc.reference(0.0)[0]), sc.vector()
        )
        new = circuit_step_limit(sc)
        assert old is not None and new is not None
        assert new == pytest.approx(old, rel=1e-6)
    assert circuit_step_limit(base) is None


@pytest.mark.parametrize("time_constant", [0.0, 2.0e-3])
def test_the_sensors_rate_is_its_measurements_derivative(time_constant):
    """The position_sensor's ``rate`` is dy/dt of its output, from the node's velocity:
    g·ẋ unfiltered, the filter's (g·x + y_0 − y_f)/τ filtered; the pid's filter state,
    its ``measurement_rate`` connected, follows it (ẏ_f = ẏ): equal to the last bit at a
    state in motion, the rod's velocity and the filter's state set off their start."""
    path, _ = FILES["single_rod_pi"]
    circuit = servo_circuit(parse_toml(path.read_text(), path.name), path.parent, path.stem)
    parts = []
    for c in circuit.components:
        if c.type == "position_sensor":
            c = dataclasses.replace(c, values={**c.values, "time_constant": time_constant})
        parts.append(c)
    compiled = build(dataclasses.replace(circuit, components=tuple(parts)))
    index = {name: i for i, (name, _) in enumerate(compiled.state_names)}
    s = compiled.s0.copy()
    s[index["rod.velocity"]] = 0.3
    s[index["rod.position"]] += 0.01
    if time_constant > 0.0:
        s[index["sensor.filtered"]] += 0.002
    d = derivatives_at(0.0, s, compiled.P, compiled.net)
    gain = next(c for c in parts if c.type == "position_sensor").values["gain"]
    want = d[index["sensor.filtered"]] if time_constant > 0.0 else gain * 0.3
    assert want != 0.0
    assert d[index["controller.measurement_filtered"]] == want
