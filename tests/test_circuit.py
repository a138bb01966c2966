"""The circuit kernel (issue 28): components joined at nodes on one system kernel.

Checks that can fail: the position servo written as a circuit against the component servo
(an independent implementation of the same equations), the energy account closing at every
record, the batch engine equal to the single run bit for bit, the stepper family's orders of
convergence, and one-line errors for bad circuits.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from hydroarm.cli import main
from hydroarm.io.circuit import circuit_from_doc, load_circuit
from hydroarm.io.schema import load_scenario_text
from hydroarm.io.sections import parse_toml
from hydroarm.model.circuit import build, simulate, simulate_many

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SERVO = EXAMPLES / "circuit_position_servo.toml"


def _short(circuit, duration=0.3, record_every=100):
    return circuit.replace(duration=duration, record_every=record_every)


@pytest.fixture(scope="module")
def servo_run():
    return simulate(_short(load_circuit(SERVO), duration=0.6))


def test_servo_circuit_agrees_with_the_component_servo(servo_run):
    """The same servo through the component-servo kernel (hydroarm.core.servo, written
    independently as one function) with the relief valve's flow-force slope set to the
    circuit's (Hopsan's 1e-8 m³/s/Pa). Both are RK4 at 10 µs on the same equations; they
    differ in the order of floating-point operations only, and the overlap's dead band makes
    the closed loop sensitive to round-off (it rings in a ±7 mm limit cycle), so the
    positions are compared to 0.5 mm and the supply pressure to 0.1 bar."""
    text = (EXAMPLES / "position_servo.toml").read_text()
    text = text.replace(
        'relief_nominal_flow = "0.01 m**3/s"',
        'relief_nominal_flow = "0.01 m**3/s"\nrelief_flow_force_slope = "1e-8 m**3/s/Pa"',
    )
    text = re.sub(r'duration = "[^"]+"', 'duration = "0.6 s"', text)
    old = load_scenario_text(text, "position_servo").run().to_pandas()
    new = servo_run.to_pandas()
    n = min(len(old), len(new))
    x_old = old["position_m"].to_numpy()[:n]
    x_new = new["load_position_m"].to_numpy()[:n]
    assert np.max(np.abs(x_old - x_new)) < 5e-4
    p_old = old["supply_bar"].to_numpy()[:n]
    assert np.max(np.abs(p_old - new["supply_pressure_bar"].to_numpy()[:n])) < 0.1


def test_energy_account_closes(servo_run):
    """Σ of the components' absorbed powers is zero at every record up to round-off (each
    node's flows balance its compliance; each mass's forces its inertia), so the energies
    close to the trapezoid rule's error of the records."""
    _, power, _, _ = servo_run._quantities
    scale = np.max(np.abs(power))
    assert np.max(np.abs(power.sum(axis=1))) < 1e-9 * scale
    e = servo_run.energy()
    assert abs(e["closure_energy_j"]) < 1e-9 * max(
        abs(v) for k, v in e.items() if k != "closure_energy_j"
    )
    # the pump delivers, the relief valve and the metering edges dissipate
    assert e["pump_energy_j"] < 0 < e["relief_energy_j"] and e["valve_energy_j"] > 0


def test_batch_equals_single_run_bit_for_bit():
    circuit = _short(load_circuit(SERVO), duration=0.05, record_every=50)
    compiled = build(circuit)
    masses = [90.0, 100.0, 110.0]
    table = np.stack([compiled.parameter_vector({"payload.mass": m}) for m in masses])
    t, S, bad = simulate_many(compiled, table)
    assert (bad == -1).all()
    for i, m in enumerate(masses):
        one = simulate(circuit.with_values({"payload.mass": m}))
        assert one.states.tobytes() == S[i].tobytes()
        assert one.t.tobytes() == t.tobytes()


ORDER_CIRCUIT = """
name = "mass on a spring driven through an orifice"
[[component]]
type = "tank"
name = "supply"
ports = { port = "P" }
pressure = "50 bar"
[[component]]
type = "tank"
name = "tank"
ports = { port = "T" }
pressure = "1 bar"
[[component]]
type = "orifice"
name = "inlet"
ports = { a = "P", b = "A" }
area = "1 mm**2"
[[component]]
type = "orifice"
name = "outlet"
ports = { a = "B", b = "T" }
area = "1 mm**2"
[[component]]
type = "cylinder"
name = "jack"
ports = { a = "A", b = "B", rod = "x" }
area_a = "5 cm**2"
area_b = "5 cm**2"
stroke = "1 m"
position_at_a_end = "-0.5 m"
dead_volume_a = "50 cm**3"
dead_volume_b = "50 cm**3"
[[component]]
type = "mass"
name = "load"
ports = { body = "x" }
mass = "20 kg"
spring_rate = "20 kN/m"
damping = "100 N*s/m"
[solver]
duration = "0.02 s"
"""


@pytest.mark.parametrize("method, order", [("euler", 1), ("heun", 2), ("rk4", 4)])
def test_stepper_orders(method, order):
    """Error against a run at a step 8× smaller falls by 2^order per halving of the step
    (a smooth circuit: no stops, no latches). The observed order is accepted within ±0.5:
    the asymptotic range is reached only approximately at these steps."""
    base = circuit_from_doc(parse_toml(ORDER_CIRCUIT, "t"), "t")

    def end(h):
        c = base.replace(method=method, step=h, record_every=int(round(base.duration / h)))
        return simulate(c).states[-1]

    h = 2e-6 if method != "euler" else 5e-7
    if method == "rk4":
        h = 8e-6
    ref = end(h / 8)
    e1 = np.max(np.abs(end(h) - ref) / np.maximum(np.abs(ref), 1.0))
    e2 = np.max(np.abs(end(h / 2) - ref) / np.maximum(np.abs(ref), 1.0))
    observed = np.log2(e1 / e2)
    assert abs(observed - order) < 0.5, (e1, e2, observed)


BAD = [
    ("unknown type", ('type = "orifice"\nname = "inlet"', 'type = "orifce"\nname = "inlet"'),
     "component.inlet.type", ["unknown component type", "did you mean 'orifice'"]),
    ("unknown port", ('ports = { a = "P", b = "A" }', 'ports = { a = "P", c = "A" }'),
     "component.inlet.ports.c", ["unknown port"]),
    ("port left unconnected", ('ports = { a = "P", b = "A" }', 'ports = { a = "P" }'),
     "component.inlet.ports.b", ["not connected"]),
    ("out of range", ('area = "1 mm**2"\n[[component]]\ntype = "orifice"\nname = "outlet"',
                      'area = "-1 mm**2"\n[[component]]\ntype = "orifice"\nname = "outlet"'),
     "component.inlet.area", ["must be > 0"]),
    ("wrong unit", ('mass = "20 kg"', 'mass = "20 m"'), "component.load.mass", ["kg"]),
    ("no compliance", ('ports = { a = "B", b = "T" }', 'ports = { a = "Q", b = "T" }'),
     "node.", ["no compliance", "volume"]),
    ("no mass", ('ports = { body = "x" }', 'ports = { body = "y" }'), "node.x",
     ["no mass or inertia"]),
    ("unknown parameter", ('mass = "20 kg"', 'mass = "20 kg"\nmas = "1 kg"'),
     "component.load.mas", ["unknown key", "mass"]),
    ("two drivers", ('[solver]', '[[component]]\ntype = "cylinder"\nname = "jack2"\n'
                     'ports = { a = "A", b = "B", rod = "x" }\narea_a = "5 cm**2"\n'
                     'area_b = "5 cm**2"\nstroke = "1 m"\n[solver]'),
     "node.x", ["two components drive one mechanical degree of freedom"]),
    ("mixed domains", ('ports = { body = "x" }', 'ports = { body = "A" }'),
     "component.load.ports.body", ["hydraulic node"]),
]  # fmt: skip


@pytest.mark.parametrize("old_new, field, words", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_circuit_is_one_line(old_new, field, words, tmp_path, monkeypatch, capsys):
    old, new = old_new
    assert old in ORDER_CIRCUIT
    (tmp_path / "c.toml").write_text(ORDER_CIRCUIT.replace(old, new, 1))
    monkeypatch.chdir(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    code = main(["simulate", "--config", "c.toml", "--out", "run.csv"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and err.startswith("hydroarm: error: " + field), err
    for w in words:
        assert w in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_signal_errors():
    doc = parse_toml(SERVO.read_text(), "s")
    pid = next(c for c in doc["component"] if c["name"] == "controller")
    pid["ports"]["measurement"] = "nowhere"
    with pytest.raises(Exception, match="nowhere.*no component writes it"):
        build(circuit_from_doc(doc, "s"))
    doc = parse_toml(SERVO.read_text(), "s")
    src = next(c for c in doc["component"] if c["name"] == "reference")
    src["ports"]["out"] = "position"  # the sensor writes it too
    with pytest.raises(Exception, match="already written by"):
        build(circuit_from_doc(doc, "s"))


def test_cli_writes_named_outputs(tmp_path):
    out = tmp_path / "run.csv"
    code = main(["simulate", "--config", str(SERVO), "--duration", "0.05 s", "--out", str(out)])
    assert code == 0
    header = out.read_text().splitlines()[0].split(",")
    for col in ("supply_pressure_bar", "relief_flow_lpm", "pump_power_w", "load_position_m"):
        assert col in header


def test_rk4_agrees_with_the_adaptive_reference():
    """The smooth circuit of the order test through Radau (rtol 1e-8, the projections idle:
    no stop or latch acts) and through rk4 at 2 µs: rk4's error at that step is ~1e-9 of the
    pressures (the order test's figures), so they agree to 1e-6 relative."""
    base = circuit_from_doc(parse_toml(ORDER_CIRCUIT, "t"), "t").replace(
        step=2e-6, record_every=1000
    )
    ref = simulate(base.replace(method="adaptive")).states
    rk4 = simulate(base.replace(method="rk4")).states
    assert ref.shape == rk4.shape
    np.testing.assert_allclose(rk4, ref, rtol=1e-6, atol=1e-9)
