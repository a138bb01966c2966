"""Load cases of a system study (issue 29; docs/design.md "Load cases of a system",
docs/evaluate.md): ``[[case]]`` tables in design and evaluation files with ``[system] file``.
Every candidate runs in every case on the batch engine; the values of each case are those of
``simulate`` on the system file with the case's overrides (re-run here), a requirement is
judged on its worst case over the cases it covers; bad input is one line, exit 2, before any
run."""

import csv
import math
import pathlib
from dataclasses import replace

import pytest

from hydroarm import load_scenario
from hydroarm.analysis import systems as S
from hydroarm.cli import main
from hydroarm.io.circuit import load_circuit
from hydroarm.io.sections import parse_toml
from hydroarm.io.system import servo_with
from hydroarm.metrics.trace import trace_statistic
from hydroarm.model.circuit import simulate as simulate_circuit

EXAMPLES = pathlib.Path(__file__).resolve().parent.parent / "examples"
EXAMPLE = EXAMPLES / "design_circuit_servo_cases.toml"
CIRCUIT = (EXAMPLES / "circuit_position_servo.toml").as_posix()

EVALUATION = f"""name = "two loads"
[system]
file = "{CIRCUIT}"
duration = "1.3 s"
[[case]]
name = "light"
[[case]]
name = "heavy, longer"
"payload.mass" = "250 kg"
duration = "1.5 s"
[requirements]
peak = {{ output = "A_pressure_bar", statistic = "max", after = "1 s", limit = "<= 400 bar" }}
final = {{ output = "load_position_m", statistic = "final", limit = ">= 0.6 m", cases = ["light"] }}
[metrics]
speed = {{ output = "load_velocity_m_s", statistic = "max_abs" }}
"""


def _simulated(values: dict, duration: float) -> dict:
    """``hydroarm simulate``'s columns of the circuit file with ``values`` set."""
    circuit = load_circuit(CIRCUIT).with_values(values).replace(duration=duration)
    return simulate_circuit(circuit).columns()


def test_design_example_every_case_equals_simulate_and_worst_case_judges(
    tmp_path, monkeypatch, capsys
):
    """The example through the command line (2 Sobol designs of its 16; the file is read
    whole): each case's numbers are a ``simulate`` run's with the case's overrides, the
    requirement's value is the worst of the cases it covers."""
    study = S.read_system_design(parse_toml(EXAMPLE.read_text(), "d"), "d", EXAMPLE.parent)
    assert [c.name for c in study.cases] == ["100 kg", "300 kg", "relief at 120 bar"]
    assert study.requirements[1].cases == ("100 kg", "300 kg")
    monkeypatch.chdir(tmp_path)
    args = ["design", "--config", str(EXAMPLE), "--out", "o", "--samples", "2", "--no-refine"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "2 designs of the circuit 'position servo as a circuit' in 3 load cases" in out
    assert "cases.csv" in out
    designs = list(csv.DictReader(open(tmp_path / "o" / "designs.csv")))
    cases = list(csv.DictReader(open(tmp_path / "o" / "cases.csv")))
    assert len(designs) == 2
    # 2 designs × 3 cases × (settling, overshoot) + 2 × 2 mass cases × peak
    assert len(cases) == 2 * 3 * 2 + 2 * 2
    d = designs[0]
    values = {
        "controller.proportional_gain": float(d["controller.proportional_gain"]),
        "controller.integral_gain": float(d["controller.integral_gain"]),
    }
    overrides = {
        "100 kg": ({}, 1.6),
        "300 kg": ({"payload.mass": 300.0}, 1.6),
        "relief at 120 bar": ({"relief.cracking_pressure": 120e5}, 2.0),
    }
    settling, peak = {}, {}
    for case, (extra, duration) in overrides.items():
        cols = _simulated(values | extra, duration)
        t = cols["t_s"]
        settling[case] = trace_statistic(t, cols["load_position_m"], "settling_time", after=1.0)
        peak[case] = trace_statistic(t, cols["A_pressure_bar"], "max", after=1.0)
        row = {r["quantity"]: r for r in cases if r["design"] == "1" and r["case"] == case}
        # the same kernel and steps as the batch: equal to print precision (csv: 6 digits)
        assert math.isclose(float(row["settling"]["value"]), settling[case], rel_tol=1e-5)
        if case != "relief at 120 bar":
            assert math.isclose(float(row["peak_chamber_a"]["value"]), peak[case], rel_tol=1e-5)
        else:
            assert "peak_chamber_a" not in row  # the requirement does not cover it
    worst_settling = max(settling, key=settling.get)
    worst_peak = max(("100 kg", "300 kg"), key=peak.get)
    assert d["worst_case_settling"] == worst_settling
    assert d["worst_case_peak_chamber_a"] == worst_peak
    assert math.isclose(float(d["worst_settling_s"]), settling[worst_settling], rel_tol=1e-5)
    assert math.isclose(float(d["worst_peak_chamber_a_bar"]), peak[worst_peak], rel_tol=1e-5)
    feasible = settling[worst_settling] <= 0.6 and peak[worst_peak] <= 450.0
    assert (d["feasible"] == "true") == feasible
    report = (tmp_path / "o" / "design_report.md").read_text()
    assert "## Load cases" in report and "payload.mass = 300 kg" in report


def test_evaluate_cases_equal_simulate_and_the_worst_case_is_marked(tmp_path, capsys):
    cfg = tmp_path / "e.toml"
    cfg.write_text(EVALUATION)
    assert main(["evaluate", "--config", str(cfg), "--out", str(tmp_path / "card")]) == 0
    out = capsys.readouterr().out
    assert "(worst)" in out
    rows = list(csv.DictReader(open(tmp_path / "card" / "card.csv")))
    runs = {"light": _simulated({}, 1.3), "heavy, longer": _simulated({"payload.mass": 250.0}, 1.5)}
    assert runs["heavy, longer"]["t_s"][-1] == pytest.approx(1.5)
    peaks = {}
    for r in rows:
        cols = runs[r["case"]]
        spec = {"peak": ("A_pressure_bar", "max", 1.0), "final": ("load_position_m", "final",
                -math.inf), "speed": ("load_velocity_m_s", "max_abs", -math.inf)}  # fmt: skip
        output, stat, after = spec[r["quantity"]]
        want = trace_statistic(cols["t_s"], cols[output], stat, after=after)
        assert math.isclose(float(r["value"]), want, rel_tol=1e-5), r
        if r["quantity"] == "peak":
            peaks[r["case"]] = want
    assert sorted(r["case"] for r in rows if r["quantity"] == "final") == ["light"]
    worst = max(peaks, key=peaks.get)
    marked = [r["case"] for r in rows if r["quantity"] == "peak" and r["worst"] == "True"]
    assert marked == [worst]
    assert "**" + worst + "**" in (tmp_path / "card" / "card.md").read_text()


# fmt: off
BAD = [
    # (text added to EVALUATION's cases or replacing a line, words in the error)
    ('[[case]]\nname = "light"', "case[2].name: 'light' is used by another case"),
    ('[[case]]\nname = "x"\n"payload.mas" = "1 kg"', "case[2].payload.mas"),
    ('[[case]]\nname = "x"\n"payload.mass" = "-1 kg"', "case[2].payload.mass"),
    ('[[case]]\nname = "x"\n"payload.mass" = "1 m"', "case[2].payload.mass"),
    ('[[case]]\nname = "x"\n"reference.waveform" = 1', "not a parameter a study may vary"),
    ('[[case]]\nname = "x"\nstep = "1 us"', "case[2].step: a case may change the duration only"),
    ('[[case]]\nname = "x"\nduration = "1e6 s"', "case[2].duration"),
    ('[[case]]\n"payload.mass" = "1 kg"', "case[2].name: is missing"),
]
# fmt: on


@pytest.mark.parametrize("added, words", BAD)
def test_bad_cases_are_one_line_before_any_run(tmp_path, capsys, added, words):
    for command in ("evaluate", "design"):
        text = EVALUATION.replace("[requirements]", added + "\n[requirements]")
        if command == "design":
            text += '[design]\nsamples = 2\n[design.variables]\n"controller.integral_gain" = ' \
                    '["0 m/(m*s)", "0.001 m/(m*s)"]\n'  # fmt: skip
        cfg = tmp_path / "s.toml"
        cfg.write_text(text)
        code = main([command, "--config", str(cfg), "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert code == 2, err
        assert err.count("\n") == 1 and err.startswith("hydroarm: error:"), err
        assert words in err, err
        assert not (tmp_path / "o").exists()


def test_bad_case_names_in_requirements_and_design_conflicts(tmp_path, capsys):
    def refused(text: str, command: str = "evaluate") -> str:
        cfg = tmp_path / "s.toml"
        cfg.write_text(text)
        assert main([command, "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("hydroarm: error:"), err
        return err

    err = refused(EVALUATION.replace('cases = ["light"]', 'cases = ["lite"]'))
    assert "requirements.final.cases: unknown case 'lite'" in err and "light" in err
    no_cases = EVALUATION.split("[[case]]")[0] + "[requirements]" + EVALUATION.split(
        "[requirements]")[1]  # fmt: skip
    assert "has no [[case]]" in refused(no_cases)
    design = EVALUATION + '[design]\nsamples = 2\n[design.variables]\n"payload.mass" = ' \
        '["50 kg", "150 kg"]\n'  # fmt: skip
    assert "a case may not set a design variable" in refused(design, "design")
    # the budget counts every case: 1 025 024 candidates × 2 cases × ~1.4e5 steps > 2e11
    budget = EVALUATION + '[design]\nsamples = 2\nobjectives = ["min peak"]\nrefine = { ' \
        'generations = 1000, population = 1024 }\n[design.variables]\n' \
        '"controller.integral_gain" = ["0 m/(m*s)", "0.001 m/(m*s)"]\n'  # fmt: skip
    assert "2 cases" in refused(budget, "design")


EXCAVATOR = (EXAMPLES / "excavator.toml").as_posix()
PAYLOAD_DESIGN = f"""name = "excavator: boom gain, full or light bucket"
[system]
file = "{EXCAVATOR}"
duration = "0.2 s"
[[case]]
name = "full bucket"
[[case]]
name = "light bucket"
"mechanism.payload.soil.mass" = "200 kg"
[requirements]
boom_peak = {{ output = "boom_a_pressure_bar", statistic = "max", limit = "<= 400 bar" }}
[design]
samples = 2
[design.variables]
"boom_controller.proportional_gain" = ["0.004 m/rad", "0.006 m/rad"]
"""


def test_a_case_sets_a_mechanism_payload_mass(tmp_path):
    """The excavator's soil payload at 200 kg instead of 1980 kg: the batch's numbers (each
    row started from its own equilibrium) are ``simulate``'s of the circuit with that
    payload; the light bucket needs less pressure to hold and move the boom."""
    study = S.read_system_design(parse_toml(PAYLOAD_DESIGN, "d"), "d", tmp_path)
    assert study.cases[1].payloads == (("soil", 200.0),)
    res = S.run_system_design(study, None, progress=lambda label: None)
    kp = float(res.evaluation.x[0, 0])
    base = load_circuit(EXCAVATOR).with_values({"boom_controller.proportional_gain": kp})
    mech = base.mechanism
    assert mech is not None
    light = replace(mech, payloads=tuple(replace(p, mass=200.0) for p in mech.payloads))
    peaks = {}
    for case, circuit in (("full bucket", base), ("light bucket", base.replace(mechanism=light))):
        cols = simulate_circuit(circuit.replace(duration=0.2)).columns()
        peaks[case] = float(cols["boom_a_pressure_bar"].max())
        # the same kernel, steps and equilibrium start as the batch: equal to rounding
        got = res.evaluation.metrics[0]["cases"][case]["boom_peak"]
        assert math.isclose(got, peaks[case], rel_tol=1e-9), (case, got, peaks[case])
    assert peaks["light bucket"] < peaks["full bucket"]
    assert res.evaluation.metrics[0]["worst_case"]["boom_peak"] == "full bucket"


@pytest.mark.parametrize(
    "key, value, words",
    [
        ("mechanism.payload.sand.mass", '"200 kg"', "unknown payload 'sand'"),
        ("mechanism.payload.soil.mass", '"-2 kg"', "mechanism.payload.soil.mass"),
        ("mechanism.payload.soil.point", '"1 m"', "a case sets a payload's mass"),
    ],
)
def test_bad_payload_cases(tmp_path, capsys, key, value, words):
    cfg = tmp_path / "s.toml"
    cfg.write_text(PAYLOAD_DESIGN.replace('"200 kg"', value).replace(
        "mechanism.payload.soil.mass", key))  # fmt: skip
    assert main(["design", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("hydroarm: error: case[1]."), err
    assert words in err, err
    # a system without a mechanism has no payload
    text = EVALUATION.replace("[requirements]", '[[case]]\nname = "x"\n'
                              '"mechanism.payload.soil.mass" = "1 kg"\n[requirements]')  # fmt: skip
    cfg.write_text(text)
    assert main(["evaluate", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    assert "has no mechanism payload" in capsys.readouterr().err


SERVO = (EXAMPLES / "position_servo.toml").as_posix()
SERVO_CASES = f"""name = "component servo over two loads"
[system]
file = "{SERVO}"
duration = "1.3 s"
[[case]]
name = "100 kg"
[[case]]
name = "250 kg, relief at 150 bar"
"load.mass" = "250 kg"
relief_pressure = "15 MPa"
[requirements]
peak = {{ output = "pressure_a_bar", statistic = "max", after = "1 s", limit = "<= 250 bar" }}
[design]
samples = 2
[design.variables]
"feedback.proportional_gain" = ["0.008 m/m", "0.014 m/m"]
"""


def test_cases_of_a_component_servo_equal_simulate(tmp_path):
    """A component servo's cases set its parameters by their sweep names (``load.mass``,
    ``relief_pressure``): the servo batch engine's numbers are ``simulate``'s."""
    study = S.read_system_design(parse_toml(SERVO_CASES, "d"), "d", tmp_path)
    res = S.run_system_design(study, None, progress=lambda label: None)
    for i in range(2):
        kp = float(res.evaluation.x[i, 0])
        for case, extra in (("100 kg", {}), ("250 kg, relief at 150 bar",
                            {"mass": 250.0, "relief_pressure": 15e6})):  # fmt: skip
            sc = servo_with(load_scenario(SERVO), {"proportional_gain": kp, **extra})
            cols = sc.replace(duration=1.3).run().columns()
            want = trace_statistic(cols["t_s"], cols["pressure_a_bar"], "max", after=1.0)
            got = res.evaluation.metrics[i]["cases"][case]["peak"]
            assert math.isclose(got, want, rel_tol=1e-9), (i, case, got, want)


def test_a_servo_case_above_its_stable_step_is_refused_before_any_run(tmp_path, capsys):
    """A case's servo is held to the study's step as the file's is (its stable limit from
    the initial state): a 1e7 rad/s spool needs a step of 2.5e-7 s, not the file's 10 µs."""
    cfg = tmp_path / "e.toml"
    cfg.write_text(
        f'[system]\nfile = "{SERVO}"\nduration = "0.2 s"\n[[case]]\nname = "fast spool"\n'
        'spool_frequency = "1e7 rad/s"\n[metrics]\n'
        'x = { output = "position_m", statistic = "max" }\n'
    )
    assert main(["evaluate", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("hydroarm: error: case[0].solver.step: ") and "stable" in err, err
    assert not (tmp_path / "o").exists()


REFERENCE_CASES = f"""name = "two reference steps"
[system]
file = "{CIRCUIT}"
duration = "1.3 s"
[[case]]
name = "0.5 m step"
[[case]]
name = "0.1 m step at 0.5 s"
"reference.times" = ["0 s", "0.5 s"]
"reference.values" = ["0.2 m", "0.3 m"]
duration = "0.9 s"
[metrics]
final = {{ output = "load_position_m", statistic = "final" }}
peak = {{ output = "A_pressure_bar", statistic = "max" }}
"""


def test_a_case_sets_a_step_references_table(tmp_path, capsys):
    """A case's ``reference.times`` and ``reference.values`` (a ``steps`` source's tables,
    as long as the file's): its run is ``simulate``'s of the circuit with those tables."""
    cfg = tmp_path / "e.toml"
    cfg.write_text(REFERENCE_CASES)
    assert main(["evaluate", "--config", str(cfg), "--out", str(tmp_path / "card")]) == 0
    capsys.readouterr()
    rows = list(csv.DictReader(open(tmp_path / "card" / "card.csv")))
    base = load_circuit(CIRCUIT)
    small = base.replace(
        duration=0.9,
        components=tuple(
            replace(c, arrays={"times": (0.0, 0.5), "values": (0.2, 0.3)})
            if c.name == "reference"
            else c
            for c in base.components
        ),
    )
    for case, circuit in (("0.5 m step", base.replace(duration=1.3)), ("0.1 m step at 0.5 s",
                          small)):  # fmt: skip
        cols = simulate_circuit(circuit).columns()
        got = {r["quantity"]: float(r["value"]) for r in rows if r["case"] == case}
        assert math.isclose(got["final"], float(cols["load_position_m"][-1]), rel_tol=1e-5)
        assert math.isclose(got["peak"], float(cols["A_pressure_bar"].max()), rel_tol=1e-5)
    # the small step ends near 0.3 m (the PI loop's limit cycle: within a few mm)
    assert abs(got["final"] - 0.3) < 0.02
    for text, words in (
        ('"reference.values" = ["0.2 m"]', "must be a list of 2 entries"),
        ('"reference.times" = ["0.5 s", "0 s"]', "must increase"),
        ('"reference.values" = ["0.2 m", "1.3 m"]', "outside the stroke of jack"),
        ('"reference.values" = "0.3 m"', "case[1].reference.values: must be a list of 2"),
    ):
        key = text.split(" = ")[0]
        lines = [ln if not ln.startswith(key) else text for ln in REFERENCE_CASES.splitlines()]
        cfg.write_text("\n".join(lines) + "\n")
        assert main(["evaluate", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("hydroarm: error: case[1]"), err
        assert words in err, err
