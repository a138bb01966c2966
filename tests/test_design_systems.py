"""`hydroarm design` and `hydroarm evaluate` on any system (issue 29): a component servo and
a circuit named by ``[system] file``, requirements on their named outputs. The winners are
re-run by ``simulate`` (the system file with the chosen values) and checked on that run;
the card's numbers are those of a ``simulate`` run; bad input is one line, exit 2, nothing
written."""

import csv
import math
import pathlib

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.analysis import systems as S
from hydroarm.analysis.design import OUTPUT_FILES
from hydroarm.cli import main
from hydroarm.io.circuit import load_circuit
from hydroarm.io.sections import parse_toml
from hydroarm.metrics.trace import trace_statistic
from hydroarm.model.circuit import simulate as simulate_circuit

EXAMPLES = pathlib.Path(__file__).resolve().parent.parent / "examples"
SERVO = (EXAMPLES / "position_servo.toml").as_posix()
CIRCUIT = (EXAMPLES / "circuit_position_servo.toml").as_posix()

# the component servo, short: the step at 1 s and 0.6 s after it
SERVO_DESIGN = f"""name = "servo gains"
[system]
file = "{SERVO}"
duration = "1.6 s"
[requirements]
peak = {{ output = "pressure_a_bar", statistic = "max", after = "1 s", limit = "<= 250 bar" }}
[requirements.settling]
output = "position_m"
statistic = "settling_time"
after = "1 s"
limit = "<= 0.5 s"
[design]
samples = 6
seed = 3
objectives = ["min settling"]
[design.variables]
"feedback.proportional_gain" = ["0.008 m/m", "0.014 m/m"]
integral_gain = ["0 m/(m*s)", "0.0003 m/(m*s)"]
"""

CIRCUIT_DESIGN = f"""name = "circuit gains"
[system]
file = "{CIRCUIT}"
duration = "1.6 s"
[requirements]
peak = {{ output = "A_pressure_bar", statistic = "max", after = "1 s", limit = "<= 300 bar" }}
[requirements.settling]
output = "load_position_m"
statistic = "settling_time"
after = "1 s"
limit = "<= 0.7 s"
[design]
samples = 4
seed = 3
[design.variables]
"controller.proportional_gain" = ["0.008 m/m", "0.014 m/m"]
"""


def _write(tmp_path, text, name="study.toml") -> pathlib.Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _servo_columns(values: dict, duration: float) -> dict:
    """``hydroarm simulate``'s run of the servo file with the chosen values."""
    sc = ha.load_scenario(SERVO)
    params = dict(sc.parameters)
    for k, v in values.items():
        params[k] = v
    return sc.replace(parameters=params, duration=duration).run().columns()


def test_design_on_a_component_servo_winner_meets_requirements_when_simulated(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    cfg = _write(tmp_path, SERVO_DESIGN)
    assert main(["design", "--config", str(cfg), "--out", "o"]) == 0
    out = capsys.readouterr().out
    assert "6 designs of the component servo" in out and "recommended: design" in out
    assert set(OUTPUT_FILES) <= {p.name for p in (tmp_path / "o").iterdir()}
    rows = list(csv.DictReader(open(tmp_path / "o" / "designs.csv")))
    assert len(rows) == 6
    feasible = [r for r in rows if r["feasible"] == "true"]
    assert feasible, "the study's bounds are chosen so that some designs meet the requirements"
    best = min(feasible, key=lambda r: -float(r["smallest_margin"]))
    kp = float(best["feedback.proportional_gain"])
    ki = float(best["integral_gain_hz"])
    cols = _servo_columns({"proportional_gain": kp, "integral_gain": ki}, 1.6)
    t = cols["t_s"]
    settling = trace_statistic(t, cols["position_m"], "settling_time", after=1.0)
    peak = trace_statistic(t, cols["pressure_a_bar"], "max", after=1.0)
    assert settling <= 0.5 and peak <= 250.0
    assert math.isclose(settling, float(best["worst_settling_s"]), rel_tol=1e-6)
    assert math.isclose(peak, float(best["worst_peak_bar"]), rel_tol=1e-5)
    # an infeasible one fails on its own simulate run too
    bad = [r for r in rows if r["feasible"] == "false"]
    for r in bad[:1]:
        c = _servo_columns(
            {
                "proportional_gain": float(r["feedback.proportional_gain"]),
                "integral_gain": float(r["integral_gain_hz"]),
            },
            1.6,
        )
        s = trace_statistic(c["t_s"], c["position_m"], "settling_time", after=1.0)
        p = trace_statistic(c["t_s"], c["pressure_a_bar"], "max", after=1.0)
        assert not (s <= 0.5 and p <= 250.0)


def test_design_on_a_circuit_winner_meets_requirements_when_simulated(tmp_path):
    doc = parse_toml(CIRCUIT_DESIGN, "study")
    study = S.read_system_design(doc, "study", tmp_path)
    res = S.run_system_design(study, tmp_path / "o", progress=lambda label: None)
    assert res.feasible.any()
    i = res.recommended(1)[0]
    kp = float(res.evaluation.x[i, 0])
    circuit = load_circuit(CIRCUIT).with_values({"controller.proportional_gain": kp})
    run = simulate_circuit(circuit.replace(duration=1.6))
    cols = run.columns()
    settling = trace_statistic(cols["t_s"], cols["load_position_m"], "settling_time", after=1.0)
    peak = trace_statistic(cols["t_s"], cols["A_pressure_bar"], "max", after=1.0)
    assert settling <= 0.7 and peak <= 300.0
    assert math.isclose(peak, float(res.evaluation.worst[i, 0]), rel_tol=1e-9)
    assert (tmp_path / "o" / "design_report.md").read_text().count("circuit") >= 1


def test_evaluate_on_a_component_servo_equals_simulate(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    cfg = EXAMPLES / "evaluate_position_servo.toml"
    assert main(["evaluate", "--config", str(cfg), "--out", "card"]) == 0
    assert "written to card/card.csv" in capsys.readouterr().out
    rows = {r["quantity"]: r for r in csv.DictReader(open(tmp_path / "card" / "card.csv"))}
    assert (tmp_path / "card" / "card.png").stat().st_size > 0
    cols = ha.load_scenario(SERVO).run().columns()  # `hydroarm simulate` of the system file
    t = cols["t_s"]
    doc = parse_toml(cfg.read_text(), "e")
    specs = {**doc["requirements"], **doc["metrics"]}
    for name, spec in specs.items():
        after = float(spec["after"].split()[0]) if "after" in spec else -math.inf
        want = trace_statistic(t, cols[spec["output"]], spec["statistic"], after=after)
        assert math.isclose(float(rows[name]["value"]), want, rel_tol=1e-5), name
    # a limit in psi is compared in the output's bar
    assert math.isclose(float(rows["peak_chamber_b"]["limit"]), 2200 * 0.0689476, rel_tol=1e-5)
    met = rows["peak_chamber_b"]["met"] == "True"
    assert met == (float(rows["peak_chamber_b"]["value"]) <= 2200 * 0.0689476)


def test_design_example_runs(tmp_path, monkeypatch, capsys):
    """examples/design_position_servo.toml through the command line, reduced to 4 Sobol
    designs and no refinement (the file itself is read whole)."""
    p = EXAMPLES / "design_position_servo.toml"
    study = S.read_system_design(parse_toml(p.read_text(), "d"), "d", p.parent)
    assert study.keys == ("proportional_gain", "integral_gain", "piston_area")
    assert study.refine is not None and study.samples == 16
    monkeypatch.chdir(tmp_path)
    args = ["design", "--config", str(p), "--out", "o", "--samples", "4", "--no-refine"]
    assert main(args) == 0
    assert "4 designs of the component servo" in capsys.readouterr().out
    rows = list(csv.DictReader(open(tmp_path / "o" / "designs.csv")))
    assert len(rows) == 4 and all(r["source"] == "sobol" for r in rows)
    report = (tmp_path / "o" / "design_report.md").read_text()
    assert "settling_time of position_m <= 0.5 s" in report


# fmt: off
BAD = [
    # (text replacing a line of SERVO_DESIGN or added, words in the error)
    ('file = "nowhere.toml"', "system.file"),
    ('duration = "-1 s"', "system.duration"),
    ('duration = "1.6 s"\n"nonsense_gain" = 3', "system.nonsense_gain"),
    ('peak = { output = "positon_m", statistic = "max", limit = "<= 1 m" }', "positon_m"),
    ('peak = { output = "position_m", statistic = "median", limit = "<= 1 m" }', "median"),
    (
        'peak = { output = "position_m", statistic = "max", limit = "<= 1 bar" }',
        "peak.limit",
    ),
    (
        'peak = { output = "position_m", statistic = "max", limit = "1 m" }',
        "give the comparison",
    ),
    ('peak = { output = "position_m", statistic = "max" }', "peak.limit: is missing"),
    ('integral_gain = ["0 m/(m*s)", "-1 m/(m*s)"]', "design.variables.integral_gain"),
    ('integral_gain = ["0 m", "1 m"]', "design.variables.integral_gain"),
    ('stroke_gain = ["0 m", "1 m"]', "design.variables.stroke_gain"),
    ('objectives = ["min speed"]', "design.objectives[0]"),
    ("samples = 100000", "design.samples: at most"),
    ('objectives = ["min settling"]\nrefine = { generations = 5000 }', "generations: at most"),
    ('"feedback.proportional_gain" = ["0.014 m/m", "0.008 m/m"]', "low must be below high"),
    ('"feedback.proportional_gain" = ["0.008 m/m", "-0.014 m/m"]', "must not be negative"),
]
# fmt: on


def _mutate(line: str) -> str:
    text = SERVO_DESIGN
    key = line.split("=")[0].strip()
    lines = text.splitlines()
    for i, old in enumerate(lines):
        if old.split("=")[0].strip() == key:
            lines[i] = line
            return "\n".join(lines) + "\n"
    return text + line + "\n"


@pytest.mark.parametrize("line, words", BAD)
def test_bad_input_is_one_line_and_nothing_written(tmp_path, monkeypatch, capsys, line, words):
    monkeypatch.chdir(tmp_path)
    cfg = _write(tmp_path, _mutate(line))
    code = main(["design", "--config", str(cfg), "--out", "o"])
    out, err = capsys.readouterr()
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("hydroarm: error:"), err
    assert words in err, err
    assert not (tmp_path / "o").exists()


def test_a_system_file_given_as_the_study_is_refused(tmp_path, capsys):
    for cmd in ("design", "evaluate"):
        assert main([cmd, "--config", SERVO, "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert (
            err.startswith("hydroarm: error: system: this is a system file") and "[system]" in err
        )


def test_evaluate_bad_input(tmp_path, capsys):
    cfg = _write(tmp_path, f'[system]\nfile = "{SERVO}"\n')
    assert main(["evaluate", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    assert "requirements: is missing" in capsys.readouterr().err
    cfg = _write(tmp_path, f'[system]\nfile = "{SERVO}"\nmethod = "adaptive"\n[metrics]\n'
                 'x = { output = "position_m", statistic = "max" }\n')  # fmt: skip
    assert main(["evaluate", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    assert "system.method" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_servo_parameter_names_and_units():
    runner = S.SystemRunner(ha.load_scenario(SERVO))
    assert runner.key("f", "actuator.piston_area") == "piston_area"
    assert runner.unit("piston_area") == "m^2" or runner.unit("piston_area").startswith("m")
    assert np.isfinite(runner.value("f", "piston_area", "10 cm**2"))


def test_servo_batch_rows_are_their_single_runs():
    """A study's servo batch (systems.servo_chunk_columns) steps each row on the kernel its
    run() steps: the circuits on the system kernel's batch path (a crank's dry friction
    among them; air at a non-standard atmosphere, once a servo-kernel case), circuits of
    different nets one by one; every row's columns are its run()'s bit for bit, and a step
    above the stable limit fails the row (None)."""
    path = pathlib.Path(__file__).parent / "data" / "servo_circuit" / "crank_pump.toml"
    sc = ha.load_scenario(path).replace(duration=0.01, record_every=20)
    circuit = [sc, sc.replace(mass=1.2 * sc.parameters.get("mass", 1.0), coulomb_friction=5.0)]
    air = [sc.replace(atmospheric_pressure=9.0e4), sc.replace(atmospheric_pressure=9.5e4)]
    other_net = sc.replace(coulomb_friction=5.0)  # the crank's friction: another net
    for rows in (circuit, air, [air[0], other_net]):
        got = dict(S.servo_chunk_columns(rows))
        assert sorted(got) == list(range(len(rows)))
        for i, s in enumerate(rows):
            want = s.run().columns()
            cols = got[i]
            assert cols is not None and list(cols) == list(want)
            for name, v in want.items():
                assert np.array_equal(cols[name], v), name
    assert dict(S.servo_chunk_columns([sc.replace(step=0.002)])) == {0: None}
