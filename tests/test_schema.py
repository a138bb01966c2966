"""One schema for scenario, arm and sweep files: the same readers, the same error lines,
every sweep row validated as a scenario would be, [metrics] honoured everywhere."""

import csv
import dataclasses

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.arm.config import load_arm_text
from hydroarm.batch.engine import run_scenarios
from hydroarm.batch.sweep import GOVERNING_ROWS, parse_sweep, run_sweep
from hydroarm.cli import main
from hydroarm.errors import HydroarmError, StabilityError
from hydroarm.io.schema import load_scenario_text
from hydroarm.io.sections import parse_toml
from hydroarm.metrics.step import MetricOptions, step_metrics
from hydroarm.model.rules import FIELD_RULES, check_rows

SCENARIO = """
[joint]
parameter_set = "paper-calibrated"
{joint}
[physics]
{physics}
[load]
builtin = 6
[input]
direction = "raise"
[solver]
duration = "0.5 s"
{solver}
{metrics}
"""

ARM = """
[joints.shoulder_elevation]
parameter_set = "paper-calibrated"
{joint}
{physics}
[inputs.shoulder_elevation]
type = "step"
to = "10 deg"
[solver]
duration = "0.1 s"
{solver}
"""

SWEEP = """
[scenario.joint]
parameter_set = "paper-calibrated"
{joint}
[scenario.physics]
{physics}
[scenario.load]
builtin = 6
[scenario.input]
direction = "raise"
[scenario.solver]
duration = "0.5 s"
{solver}
{metrics}
[grid]
weight = ["10 N", "20 N"]
{grid}
[monte_carlo]
n = 3
seed = 1
{mc}
"""


def _text(template, **parts):
    keys = ("joint", "physics", "solver", "metrics", "grid", "mc")
    if "parameter_set" in parts.get("joint", ""):
        template = template.replace('parameter_set = "paper-calibrated"\n', "", 1)
    return template.format(**{k: parts.get(k, "") for k in keys})


def _error(load, text) -> str:
    with pytest.raises(HydroarmError) as exc:
        load(text)
    return str(exc.value)


def _sweep_text(text):
    return parse_sweep(parse_toml(text, "sweep"))


# section -> (path in a scenario file, in an arm file, in a sweep file)
PATHS = {
    "joint": ("joint", "joints.shoulder_elevation", "scenario.joint"),
    "physics": ("physics", "joints.shoulder_elevation", "scenario.physics"),
    "solver": ("solver", "solver", "scenario.solver"),
}


@pytest.mark.parametrize(
    "section, line, key, problem",
    [
        (
            "joint",
            'supply_pressure = "-5 bar"',
            "supply_pressure",
            "must be positive, got '-5 bar'",
        ),
        ("joint", 'crank_radius = "3 bar"', "crank_radius", "is not a length"),
        ("joint", "gear_ratio = 0", "gear_ratio", "must be positive, got 0.0"),
        ("joint", 'piston_area = "3"', "piston_area", "has no unit"),
        ("joint", 'bogus = "1 m"', "bogus", "unknown key (allowed: "),
        ("joint", 'parameter_set = "nope"', "parameter_set", "unknown parameter set 'nope'"),
        (
            "physics",
            'coulomb_friction = "20 N"\nstatic_friction = "10 N"',
            "static_friction",
            "must not be below the Coulomb friction",
        ),
        ("physics", "gearbox_loss_at_stall = 1.5", "gearbox_loss_at_stall", "must be below 1"),
        ("physics", 'viscous_friction = "-1 N*s/m"', "viscous_friction", "must not be negative"),
        ("solver", 'step = "-1 us"', "step", "must be positive, got '-1 us'"),
        ("solver", "record_every = 0", "record_every", "must be a whole number ≥ 1, got 0"),
    ],
)
def test_same_bad_value_same_error_in_every_file(section, line, key, problem):
    lines = [
        _error(load_scenario_text, _text(SCENARIO, **{section: line})),
        _error(load_arm_text, _text(ARM, **{section: line})),
        _error(_sweep_text, _text(SWEEP, **{section: line})),
    ]
    for path, msg in zip(PATHS[section], lines, strict=True):
        assert msg.startswith(f"{path}.{key}: "), msg
        assert problem in msg, msg
    # the problem text is the same wherever the section sits
    assert len({m.split(": ", 1)[1] for m in lines}) == 1


def test_same_error_line_through_the_cli(tmp_path, capsys):
    bad = 'supply_pressure = "-5 bar"'
    files = {
        "scenario.toml": _text(SCENARIO, joint=bad),
        "arm.toml": _text(ARM, joint=bad),
        "sweep.toml": _text(SWEEP, joint=bad),
    }
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    runs = [
        (["simulate", "--config", str(tmp_path / "scenario.toml")], "joint"),
        (
            ["arm", "--config", str(tmp_path / "arm.toml"), "--out", str(tmp_path / "o")],
            "joints.shoulder_elevation",
        ),
        (
            ["sweep", "--config", str(tmp_path / "sweep.toml"), "--out", str(tmp_path / "s.csv")],
            "scenario.joint",
        ),
    ]
    for args, path in runs:
        capsys.readouterr()
        assert main(args) == 2
        err = capsys.readouterr().err
        assert err == (f"hydroarm: error: {path}.supply_pressure: must be positive, got '-5 bar'\n")


def test_grid_value_read_as_in_a_scenario():
    msg = _error(_sweep_text, _text(SWEEP, grid='supply_pressure = ["30 bar", "-5 bar"]'))
    assert msg == "grid.supply_pressure: must be positive, got '-5 bar'"


def test_monte_carlo_bad_row_reported_with_its_number():
    mc = 'inertia = { distribution = "normal", mean = "0.02 kg*m**2", sd = "0.02 kg*m**2" }'
    text = _text(SWEEP, mc=mc).replace("n = 3", "n = 500")
    msg = _error(_sweep_text, text)
    draws = np.random.default_rng(1).normal(0.02, 0.02, 2 * 500)
    row = int(np.argmax(draws <= 0))
    assert msg == f"monte_carlo.inertia: row {row}: must be positive, got {float(draws[row])!r}"


def test_monte_carlo_cross_rule_row():
    mc = 'coulomb_friction = { distribution = "uniform", low = "0 N", high = "40 N" }'
    text = _text(SWEEP, physics='static_friction = "30 N"', mc=mc).replace("n = 3", "n = 50")
    msg = _error(_sweep_text, text)
    draws = np.random.default_rng(1).uniform(0.0, 40.0, 100)
    row = int(np.argmax(draws > 30.0))
    assert msg == (
        f"monte_carlo.coulomb_friction: row {row}: static friction must not be below the "
        "Coulomb friction"
    )


def test_grid_point_built_as_a_servo_joint():
    # 1.2 passes the sign rule of the reader; ServoJoint's own validation refuses it
    msg = _error(_sweep_text, _text(SWEEP, grid="gearbox_loss_at_stall = [0.5, 1.2]"))
    # grid points: weight x loss = (10, .5) (10, 1.2) ...; 3 Monte Carlo rows each
    assert msg == "grid.gearbox_loss_at_stall: row 3: must be below 1"


def test_check_rows_shares_the_servo_joint_rules():
    j = ha.parameter_set("paper-calibrated")
    for name, (section, _rule) in FIELD_RULES.items():
        if section == "load" or name == "hydraulic_stiffness":
            continue
        with pytest.raises(HydroarmError) as single:
            j.replace(**{name: np.nan})
        cols = {k: getattr(j, k) for k in FIELD_RULES if hasattr(j, k)}
        cols[name] = np.array([1.0, np.nan])
        with pytest.raises(HydroarmError) as rows:
            check_rows(cols, {name: f"grid.{name}"})
        assert single.value.problem in str(rows.value), name
        assert str(rows.value).startswith(f"grid.{name}: row 1: "), name


GOVERNED = """
[scenario.joint]
parameter_set = "paper-calibrated"
[scenario.load]
builtin = 6
[scenario.input]
direction = "raise"
[scenario.solver]
duration = "0.5 s"
step = "1 ms"
"""


def test_governing_row_step_refused():
    # the base is stable at 1 ms (its limit is about 11 ms), the grid point with the
    # smallest trapped volume is not (about 0.3 ms)
    text = GOVERNED + '[grid]\ntrapped_volume = ["2.8 cm**3", "0.05 cm**3", "1 cm**3"]\n'
    _sweep_text(GOVERNED + '[grid]\ntrapped_volume = ["2.8 cm**3", "1 cm**3"]\n')
    with pytest.raises(StabilityError) as exc:
        _sweep_text(text)
    msg = str(exc.value)
    assert msg.startswith("scenario.solver.step: 1 ms is too large to be stable with method")
    assert "for row 1 (trapped_volume = 5e-08); the largest stable step" in msg
    assert exc.value.largest_stable_step < 1e-3


def test_governing_rows_found_among_many():
    mc = (
        "[monte_carlo]\nn = 4000\nseed = 1\n"
        'trapped_volume = { distribution = "uniform", low = "0.05 cm**3", high = "3 cm**3" }\n'
    )
    with pytest.raises(StabilityError) as exc:
        _sweep_text(GOVERNED + mc)
    draws = np.random.default_rng(1).uniform(0.05e-6, 3e-6, 4000)
    assert f"for row {int(np.argmin(draws))} " in str(exc.value)
    assert GOVERNING_ROWS < 4000
    # a step stable for every row passes
    _sweep_text(GOVERNED.replace('"1 ms"', '"100 us"') + mc)


def test_metrics_section_in_scenario_files():
    sc = load_scenario_text(_text(SCENARIO, metrics="[metrics]\nmiddle = 0.5\nthreshold = 0.5"))
    assert sc.metric_options == MetricOptions(middle=0.5, threshold=0.5)
    r = ha.simulate(sc)
    m = r.metrics()
    ref = step_metrics(
        r.t,
        r.x,
        valve_opening=sc.joint.valve_saturation,
        target=sc.target,
        full_opening_velocity=sc.joint.no_load_velocity,
        t_start=float(sc.lever.times[0]),
        middle=0.5,
        threshold=0.5,
    )
    assert m["saturation_velocity_m_s"] == ref["saturation_velocity"]
    assert m["time_constant_start_s"] == ref["time_constant_start"]
    default = ha.simulate(sc.replace(metric_options=MetricOptions())).metrics()
    assert default["saturation_velocity_m_s"] != m["saturation_velocity_m_s"]
    # simulate(metric_options=...) sets them for one run
    m2 = ha.simulate(sc.replace(metric_options=MetricOptions()), metric_options=sc.metric_options)
    assert m2.metrics()["saturation_velocity_m_s"] == m["saturation_velocity_m_s"]


@pytest.mark.parametrize(
    "load, text, field",
    [
        (load_scenario_text, _text(SCENARIO, metrics="[metrics]\nmiddle = 1.5"), "metrics.middle"),
        (load_scenario_text, _text(SCENARIO, metrics="[metrics]\nmedian = 0.5"), "metrics.median"),
        (
            _sweep_text,
            _text(SWEEP, metrics="[scenario.metrics]\nmiddle = 1.5"),
            "scenario.metrics.middle",
        ),
        (_sweep_text, _text(SWEEP) + "[metrics]\nthreshold = 0\n", "metrics.threshold"),
    ],
)
def test_bad_metrics_section(load, text, field):
    msg = _error(load, text)
    assert msg.startswith(f"{field}: "), msg


def test_metrics_section_in_sweep_files(tmp_path):
    sw = _sweep_text(_text(SWEEP) + "\n[metrics]\nmiddle = 0.5\nstall_tolerance = 0.1\n")
    assert sw.base.metric_options == MetricOptions(middle=0.5, stall_tolerance=0.1)
    sw2 = _sweep_text(_text(SWEEP, metrics="[scenario.metrics]\nmiddle = 0.5"))
    assert sw2.base.metric_options.middle == 0.5
    with pytest.raises(HydroarmError, match="not both"):
        _sweep_text(_text(SWEEP, metrics="[scenario.metrics]\nmiddle = 0.5") + "[metrics]\n")
    # the batch engine uses the scenario's options, as a single run does
    sc = sw.base.replace(duration=0.3)
    mb = run_scenarios([sc])[0]
    ms = ha.simulate(sc).metrics()
    assert mb["saturation_velocity"] == pytest.approx(ms["saturation_velocity_m_s"], rel=1e-12)
    # and so does a sweep run: each row's metrics with the file's thresholds
    text = GOVERNED.replace('"1 ms"', '"10 us"').replace('"0.5 s"', '"0.3 s"')
    text += '[grid]\nweight = ["10 N", "20 N"]\n[metrics]\nmiddle = 0.5\n'
    sw = _sweep_text(text)
    out = run_sweep(sw, tmp_path / "m.csv", progress=lambda *a: None)
    with open(out, newline="") as fh:
        rows = list(csv.DictReader(fh))
    for row, w in zip(rows, (10.0, 20.0), strict=True):
        sc = sw.base.replace(load=dataclasses.replace(sw.base.load, weight=w))
        ms = ha.simulate(sc).metrics()
        assert float(row["saturation_velocity_m_s"]) == pytest.approx(
            ms["saturation_velocity_m_s"], rel=1e-9
        )
        default = ha.simulate(sc, metric_options=MetricOptions()).metrics()
        v = ms["saturation_velocity_m_s"]
        assert default["saturation_velocity_m_s"] != pytest.approx(v, rel=1e-6)


def test_cross_rule_names_the_field_the_file_gave():
    # the parameter set has static friction 30 N; the file raises Coulomb friction above it
    text = _text(
        SCENARIO, joint='parameter_set = "ucl-arm-measured"', physics='coulomb_friction = "40 N"'
    )
    assert _error(load_scenario_text, text) == (
        "physics.coulomb_friction: static friction must not be below the Coulomb friction"
    )
