"""`hydroarm design` and hydroarm.analysis.design (issue 17): feasible designs meet every
requirement when re-simulated alone, Pareto designs are not dominated, the CLI writes its
outputs, the example runs."""

import csv
import dataclasses
import math
import pathlib

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.analysis import design as D
from hydroarm.analysis import requirements as R
from hydroarm.batch.saturation import stall_mass
from hydroarm.cli import main
from hydroarm.io.sections import parse_toml

EXAMPLES = pathlib.Path(__file__).resolve().parent.parent / "examples"

# a small study: the measured arm with a stronger pump and a better gearbox; loose enough
# that some of the 6 designs meet every requirement and some do not
STUDY = """name = "small"
[joint]
parameter_set = "ucl-arm-measured"
[[load_case]]
name = "hand"
load = { mass = "0.5 kg" }
directions = ["raise"]
[[load_case]]
name = "arm"
load = 1
directions = ["lower"]
[requirements]
stall_mass = ">= 0.8 kg"
time_constant = "<= 60 ms"
saturation_angular_velocity = { limit = ">= 2 rad/s", cases = ["hand"] }
[design]
samples = 6
seed = 3
objectives = ["max stall_mass", "min supply_pressure", "min pump_flow"]
[design.variables]
supply_pressure = ["25 bar", "60 bar"]
gearbox_loss_at_stall = [0.0, 0.96]
"""


@pytest.fixture(scope="module")
def result():
    study = D.design_from_doc(parse_toml(STUDY, "small.toml"))
    return D.run_design(study, progress=lambda label: None)


def test_study_has_both_kinds(result):
    """The test below is not vacuous: some designs are feasible and some are not."""
    assert 0 < result.feasible.sum() < len(result.feasible)
    assert result.pareto.sum() >= 1
    assert np.all(result.feasible[result.pareto])  # Pareto designs are feasible ones


def test_feasible_designs_meet_every_requirement_alone(result):
    """Every design reported feasible, re-simulated alone (hydroarm.simulate one scenario at
    a time, stall_mass of the one joint), meets every requirement; and every infeasible
    one misses one."""
    study, ev = result.study, result.evaluation
    joints = study.joints(ev.x)
    for i, joint in enumerate(joints):
        alone: dict = {}
        for c in study.cases:
            for d in c.directions:
                sc = ha.saturation_test(
                    joint, c.load, d, step=float(ev.steps[i]), duration=R.motion_duration(joint)
                )
                m = ha.simulate(sc).metric_values()
                alone[(c.name, d)] = R.motion_values(joint, sc, m, None)
        alone[(None, None)] = {"stall_mass": stall_mass(joint, step=float(ev.steps[i]))}
        rows = R.check(study.requirements, alone)
        assert len(rows) == 4  # stall mass, two time constants, one velocity
        assert all(r["met"] for r in rows) == bool(ev.feasible[i]), (i, rows)
        # the same worst values as the batch
        for k, r in enumerate(study.requirements):
            a, b = R.worst(r, alone), ev.worst[i, k]
            assert a == b or (math.isnan(a) and math.isnan(b))


def test_pareto_designs_not_dominated(result):
    """No sampled feasible design dominates a Pareto design, and every feasible design off
    the front is dominated by one on it. (An infeasible design never dominates a feasible
    one: constrained domination, docs/design.md.)"""
    senses = [o.sense for o in result.study.objectives]
    obj = result.evaluation.objectives
    feas = np.nonzero(result.feasible)[0]
    for i in np.nonzero(result.pareto)[0]:
        assert not any(D.dominates(obj[k], obj[i], senses) for k in feas if k != i)
    for i in feas:
        if not result.pareto[i]:
            assert any(D.dominates(obj[k], obj[i], senses) for k in np.nonzero(result.pareto)[0])


def test_pareto_mask_hand_made():
    # maximise a, minimise b: (3, 1) dominates (2, 2); (1, 0) is on the front; (5, 0) is
    # infeasible and dominates everything but does not count
    obj = np.array([[3.0, 1.0], [2.0, 2.0], [1.0, 0.0], [5.0, 0.0], [3.0, 1.0]])
    feas = np.array([True, True, True, False, True])
    got = D.pareto_mask(obj, ["max", "min"], feas)
    assert got.tolist() == [True, False, True, False, True]  # equal points: both on the front
    # an infinite value (a stall mass above the search's 20 kg) is the best, not left out
    obj[1] = [np.inf, 1.0]  # dominates (3, 1) twice
    assert D.pareto_mask(obj, ["max", "min"], feas).tolist() == [False, True, True, False, False]


def test_sobol_points_within_ranges(result):
    x = D.sobol_points(result.study)
    for k, v in enumerate(result.study.variables):
        assert np.all((x[:, k] >= v.low) & (x[:, k] <= v.high))
    assert np.array_equal(x, D.sobol_points(result.study))  # seeded: the same points


def test_report_and_csv(result, tmp_path):
    out = result.write(tmp_path / "o")
    names = sorted(p.name for p in out.iterdir())
    assert set(D.OUTPUT_FILES) <= set(names)
    rows = list(csv.DictReader(open(out / "designs.csv")))
    assert len(rows) == len(result.evaluation.x)
    assert {"supply_pressure_pa", "gearbox_loss_at_stall", "worst_stall_mass_kg"} <= set(rows[0])
    assert {"margin_time_constant", "feasible", "pareto"} <= set(rows[0])
    # the variables at full precision: the design can be re-run from the file
    x0 = result.evaluation.x[0]
    assert float(rows[0]["supply_pressure_pa"]) == x0[0]
    assert [r["feasible"] == "true" for r in rows] == result.feasible.tolist()
    rep = (out / "design_report.md").read_text()
    assert "Recommended designs" in rep and "designs·cases per second" in rep
    best = result.recommended(1)[0]
    assert f"| {best + 1} |" in rep
    assert not list(tmp_path.glob(".hydroarm-stage-*"))  # the staging folder is gone


def test_refine_is_vectorised_and_feasible(result):
    """The refinement: each generation one batch (its designs evaluated together), the
    population started from the Sobol designs; the best refined feasible design is no worse
    in its objective than the best Sobol one."""
    study = dataclasses.replace(
        result.study,
        refine=D.Refine(D.Objective("min", "supply_pressure"), generations=1, population=5),
        requirements=result.study.requirements[1:],  # no stall mass: keep the test fast
        objectives=(D.Objective("min", "supply_pressure"),),
        samples=4,
    )
    calls = []
    res = D.run_design(study, progress=calls.append)
    src = np.array(res.evaluation.source)
    # the first generation is the 4 Sobol designs (not simulated again) and 1 random point,
    # the second 5 new trial designs
    assert (src == "sobol").sum() == 4 and (src == "refine").sum() == 1 + 5
    assert sum("refine generation" in c for c in calls) == 2
    x = res.evaluation.x[:, 0]
    f = res.feasible
    if f[src == "sobol"].any():
        assert x[f].min() <= x[(src == "sobol") & f].min()


def test_cli_runs_the_example(tmp_path, monkeypatch, capsys):
    """examples/redesign_shoulder.toml, reduced to 4 Sobol designs and no refinement."""
    monkeypatch.chdir(tmp_path)
    code = main(
        [
            "design",
            "--config",
            str(EXAMPLES / "redesign_shoulder.toml"),
            "--out",
            "o",
            "--samples",
            "4",
            "--no-refine",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert "4 designs x 2 load cases" in out and "written to o/designs.csv" in out
    files = {p.name for p in (tmp_path / "o").iterdir()}
    assert set(D.OUTPUT_FILES) <= files
    rows = list(csv.DictReader(open(tmp_path / "o" / "designs.csv")))
    assert len(rows) == 4
    for r in rows:
        assert 15e5 <= float(r["supply_pressure_pa"]) <= 80e5
        margins = [float(r[k]) for k in r if k.startswith("margin_")]
        assert (r["feasible"] == "true") == all(m >= 0 for m in margins)
        assert math.isclose(float(r["smallest_margin"]), min(margins), rel_tol=1e-5)  # .6g
