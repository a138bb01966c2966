"""One unit convention for results (issue 29; docs/model.md "Units in names"): every number a
result hands a user carries its unit in its name, `<quantity>_<unit>`, whatever the system
(the paper's joint, a component servo, a circuit, a mechanism, the arm) and whatever the
output (a metrics or summary dictionary, an energy account, a table's columns, a sweep file,
the JSON of `simulate --metrics`)."""

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.arm import load_arm, simulate_arm
from hydroarm.batch.sweep import parse_sweep, run_sweep, summary
from hydroarm.cli import main
from hydroarm.io.circuit import load_circuit
from hydroarm.io.schema import load_scenario
from hydroarm.io.sections import parse_toml
from hydroarm.model.circuit import build, simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

# The endings that spell a unit, as the project spells them: a name ends in `_<one of these>`.
UNIT_SUFFIXES = {
    "s": "time",
    "ms": "time (the paper's time constants)",
    "m": "length",
    "mm": "length (the paper's jack positions)",
    "m_s": "velocity",
    "mm_s": "velocity (the paper's saturation velocity)",
    "rad": "angle (SI)",
    "deg": "angle (tables)",
    "rad_s": "angular velocity",
    "deg_s": "angular velocity (tables)",
    "pa": "pressure (SI)",
    "bar": "pressure (tables; absolute)",
    "n": "force",
    "n_m": "torque",
    "j": "energy",
    "w": "power",
    "lpm": "flow (a circuit's L/min)",
    "l_min": "flow (a servo's relief flow in L/min)",
    "kg": "mass",
    "m2": "area",
    "m3": "volume",
    "m3_per_s_per_pa": "leakage coefficient",
    "m2_per_s_per_pa_sqrt": "flow coefficient",
    "m3_per_s_per_pa_sqrt": "a relief valve's opening as a flow coefficient",
    "m3_per_s": "flow (SI)",
}
# Numbers that have no unit, each named for what it counts or is a fraction of (a name, or
# how a name ends), with the reason.
DIMENSIONLESS = {
    "direction": "the sign of the motion, +1 or -1",
    "overshoot": "a fraction of the step's size",
    "cycles": "task cycles the run counts as",
    "cycles_per_charge": "task cycles per battery charge",
    "relative_residual": "a fraction of the energy throughput",
    "relief_opening": "the relief valve's opening, a fraction of its stroke",
    "scenario": "a sweep row's number",
    "scenarios": "sweep rows (a count)",
    "measured": "sweep rows with a finite velocity (a count)",
    "failed": "sweep rows that failed (a count; a bool in a row)",
    "stalled": "sweep rows that stalled (a count; a bool in a row)",
    "_signal": "a controller's signal, in whatever unit its law gives it",
    "_ratio": "a slave node's ratio to its master",
    "_rows": "rows measured (a count)",
    "_open": "a valve's latch, 1 once open and 0 once reseated (a flag)",
    "_opening": "a valve's opening, a fraction of its stroke in [0, 1]",
    "_fraction": "a variable pump's displacement fraction",
    # a component state in its signal's own unit, which the circuit does not know (a sensor's
    # output unit is its gain's): named like a signal would need the declaration to tell it
    # from a fraction (left, issue 29's report)
    "_filtered": "a sensor's (or a PID's measurement) filtered output, in its signal's unit",
    "_integral": "a PID's integral of the error, in the signal's unit times s",
}
# a statistic of a column, `<column>_mean`, `<column>_sd` (sweep summaries): the column's unit
STATISTICS = ("_mean", "_sd")


def _numeric(v) -> bool:
    if isinstance(v, (bool, np.bool_, str)) or v is None:
        return False
    if isinstance(v, tuple):
        return all(_numeric(x) for x in v)
    if isinstance(v, np.ndarray):
        return v.dtype.kind in "fiu"
    return isinstance(v, (int, float, np.number))


def _has_unit(name: str) -> bool:
    for stat in STATISTICS:
        name = name.removesuffix(stat)
    return any(name.endswith(f"_{u}") for u in UNIT_SUFFIXES) or any(
        name == k or (k.startswith("_") and name.endswith(k)) for k in DIMENSIONLESS
    )


def assert_units_in_names(where: str, d: dict) -> None:
    missing = [k for k, v in d.items() if _numeric(v) and not _has_unit(k)]
    assert not missing, f"{where}: numbers without a unit in their name: {missing}"


def test_the_check_can_fail():
    with pytest.raises(AssertionError, match="saturation_velocity"):
        assert_units_in_names("x", {"saturation_velocity": 0.02, "stalled": False})
    assert_units_in_names("x", {"saturation_velocity_m_s": 0.02, "stall_reason": "text"})


def test_paper_joint(capsys):
    sc = ha.saturation_test(ha.parameter_set("paper-calibrated"), ha.paper_load(6), "raise")
    res = ha.simulate(sc)
    m = res.metrics()
    assert_units_in_names("SimulationResult.metrics()", m)
    # SI under SI names; the identifier-keyed values are the same numbers
    values = res.metric_values()
    assert m["saturation_velocity_m_s"] == values["saturation_velocity"]
    assert m["peak_pressure_pa"] == values["peak_pressure"]
    assert m["time_constant_start_s"] == values["time_constant_start"]
    assert m["final_x_m"] == values["final_x"] and m["t_middle_s"] == values["t_middle"]
    assert res.summary()["saturation_velocity_mm_s"] == round(1e3 * m["saturation_velocity_m_s"], 6)
    assert_units_in_names("SimulationResult.summary()", res.summary())
    assert_units_in_names("SimulationResult.energy_balance()", res.energy_balance())
    assert_units_in_names("SimulationResult.to_pandas()", dict(res.to_pandas().items()))
    assert main(["simulate", "--load", "6", "--direction", "raise", "--metrics"]) == 0
    assert_units_in_names("simulate --metrics", json.loads(capsys.readouterr().out))


def test_component_servo(capsys):
    sc = load_scenario(EXAMPLES / "position_servo.toml")
    res = sc.replace(duration=0.2).run()
    assert_units_in_names("ServoResult.metrics()", res.metrics())
    s = res.summary()
    assert_units_in_names("ServoResult.summary()", s)
    assert s["final_reference_m"] == res.reference[-1]
    assert_units_in_names("ServoResult.energies()", res.energies())
    assert_units_in_names("ServoResult.columns()", res.columns())
    cmd = ["simulate", "--config", str(EXAMPLES / "position_servo.toml"), "--metrics"]
    assert main([*cmd, "--duration", "0.2 s"]) == 0
    assert_units_in_names("simulate --metrics (servo)", json.loads(capsys.readouterr().out))


@pytest.mark.parametrize(
    "name", ["two_actuators", "pump_speed", "water_hammer", "circuit_position_servo"]
)
def test_circuit(name, capsys):
    path = EXAMPLES / f"{name}.toml"
    res = simulate(build(load_circuit(path).replace(duration=0.05)))
    assert_units_in_names("CircuitResult.columns()", res.columns())
    e = res.energy()
    assert_units_in_names("CircuitResult.energy()", e)
    by_name = res.component_energies()
    assert e == {f"{k}_energy_j": v for k, v in by_name.items()}
    assert main(["simulate", "--config", str(path), "--metrics", "--duration", "0.05 s"]) == 0
    assert_units_in_names("simulate --metrics (circuit)", json.loads(capsys.readouterr().out))


@pytest.mark.parametrize("name", ["boom", "hydraulic_leg"])
def test_mechanism(name):
    circuit = load_circuit(EXAMPLES / f"{name}.toml").replace(duration=0.05)
    res = simulate(build(circuit))
    assert_units_in_names("mechanism columns()", res.columns())
    assert_units_in_names("mechanism energy()", res.energy())
    assert "mechanism_energy_j" in res.energy()


def test_arm():
    res = simulate_arm(load_arm(EXAMPLES / "ucl-arm.toml").replace(duration=0.4, record_every=50))
    moving = [n for n in res.names if np.ptp(res.angle(n)) > math.radians(5)]
    m = res.joint_metrics(moving[0])
    assert_units_in_names("ArmResult.joint_metrics()", m)
    assert (
        m["saturation_velocity_rad_s"] == res.joint_metric_values(moving[0])["saturation_velocity"]
    )
    assert_units_in_names("ArmResult.energy()", res.energy())
    assert_units_in_names("ArmResult.power_traces()", res.power_traces())
    assert_units_in_names("ArmResult.to_pandas()", dict(res.to_pandas().items()))


SWEEP = """
[scenario.joint]
parameter_set = "paper-calibrated"
[scenario.load]
builtin = 6
[scenario.input]
direction = "raise"
[scenario.solver]
duration = "0.3 s"
[grid]
weight = ["10 N", "20 N"]
trapped_volume = ["3 cm**3", "4 cm**3"]
"""


def _value(text: str):
    """A CSV field as a number, or as the text it is (True, False, a reason)."""
    try:
        return float(text)
    except ValueError:
        return text


def test_sweep_file_and_summary(tmp_path):
    sw = parse_sweep(parse_toml(SWEEP, "sweep"))
    out = run_sweep(sw, tmp_path / "s.csv", progress=lambda *a: None)
    with open(out, newline="") as fh:
        rows = list(csv.DictReader(fh))
    header = list(rows[0])
    assert header[:3] == ["scenario", "weight_n", "trapped_volume_m3"]
    assert_units_in_names("sweep columns", {k: _value(rows[0][k]) for k in header})
    assert_units_in_names("sweep summary", summary(out))
