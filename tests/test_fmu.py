"""`hydroarm fmu` (issue 19): the exported FMUs pass FMPy's validation, and FMPy (an FMI tool
nobody here wrote) running them gives hydroarm's own trajectories.

The FMUs run in a Python with hydroarm (pythonfmu's binary embeds the interpreter it finds),
here this test's own, each in a process of its own (tests/fmu_worker.py says why); a target
machine needs the same (docs/fmu.md)."""

import json
import pathlib
import re
import subprocess
import sys
import zipfile
from xml.etree import ElementTree as ET

import numpy as np
import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

import hydroarm as ha  # noqa: E402
from hydroarm.arm.config import load_arm  # noqa: E402
from hydroarm.arm.model import simulate_arm  # noqa: E402
from hydroarm.cli import main  # noqa: E402
from hydroarm.errors import HydroarmError  # noqa: E402
from hydroarm.io.schema import load_scenario_text  # noqa: E402
from hydroarm.model.lever import LeverInput  # noqa: E402

HERE = pathlib.Path(__file__).parent
EXAMPLES = HERE.parent / "examples"
RAISE = EXAMPLES / "load6_raise.toml"
ARM = EXAMPLES / "ucl-arm.toml"
STOP = 0.2  # [s] of the raise test (the jack under way at saturation speed)
ARM_STEP = 20e-6  # [s]: Euler, within the arm's stability limit
ARM_STOP = 0.6  # [s]: the levers start moving at 0.3 s (examples/block_stacking.csv)
ARM_COMM = 5e-3  # [s]
LBF = 4.4482216152605  # [N]


def run_fmu(tmp, fmu, runs, state=False):
    """FMPy's runs of ``fmu`` in a fresh process (tests/fmu_worker.py): {run: {var: array}}
    and what the process printed (FMPy prints the FMU's log messages)."""
    tmp.mkdir(parents=True, exist_ok=True)
    spec, out = tmp / "spec.json", tmp / "out.npz"
    spec.write_text(json.dumps({"fmu": str(fmu), "runs": runs, "state": state}))
    p = subprocess.run(
        [sys.executable, str(HERE / "fmu_worker.py"), str(spec), str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    got: dict = {}
    with np.load(out) as z:
        for key in z.files:
            run, var = key.split("/", 1)
            got.setdefault(run, {})[var] = z[key]
    return got, p.stdout + p.stderr


def lever_input(times, signals):
    return {
        "times": list(map(float, times)),
        "signals": {k: list(map(float, v)) for k, v in signals.items()},
    }


def raise_reference(text=None, record_every=100):
    sc = ha.load_scenario(RAISE) if text is None else load_scenario_text(text)
    return sc, ha.simulate(sc.replace(duration=STOP, record_every=record_every))


@pytest.fixture(scope="module")
def joint_fmu(tmp_path_factory):
    return ha.export_fmu(RAISE, tmp_path_factory.mktemp("j") / "joint.fmu")["path"]


@pytest.fixture(scope="module")
def arm_fmu(tmp_path_factory):
    return ha.export_fmu(ARM, tmp_path_factory.mktemp("a") / "arm.fmu")["path"]


@pytest.fixture(scope="module")
def joint_runs(joint_fmu, tmp_path_factory):
    """FMPy's runs of the joint FMU: the raise test at two communication steps, two
    parameters changed, a bad parameter."""
    sc = ha.load_scenario(RAISE)
    y = float(sc.lever(0.0)[0])  # the raise test's lever: stepped at t = 0 to the target
    lever = lever_input([0.0, STOP], {"lever": [y, y]})
    out = ["theta", "omega", "p", "x"]
    runs = [
        {"name": f"comm{c}", "kwargs": {"stop_time": STOP, "output_interval": c,
                                        "input": lever, "output": out}}
        for c in (1e-3, 0.25e-3)  # 100 and 25 internal steps of 10 us
    ] + [
        {"name": "supply", "kwargs": {"stop_time": STOP, "output_interval": 1e-3,
                                      "start_values": {"joint.supply_pressure": 25e5},
                                      "output": out}},
        {"name": "weight", "kwargs": {"stop_time": STOP, "output_interval": 1e-3,
                                      "start_values": {"load.weight": 3 * LBF},
                                      "output": out}},
        {"name": "bad", "kwargs": {"stop_time": 0.01,
                                   "start_values": {"joint.piston_area": -1.0}}},
    ]  # fmt: skip
    return run_fmu(tmp_path_factory.mktemp("jr"), joint_fmu, runs)


def test_fmpy_validates_both(joint_fmu, arm_fmu):
    assert validate_fmu(str(joint_fmu)) == []
    assert validate_fmu(str(arm_fmu)) == []


def test_model_description_has_units_and_descriptions(joint_fmu):
    root = ET.fromstring(zipfile.ZipFile(joint_fmu).read("modelDescription.xml"))
    sv = {v.get("name"): v for v in root.iter("ScalarVariable")}
    assert sv["joint.piston_area"].find("Real").get("unit") == "m2"
    assert sv["joint.piston_area"].get("causality") == "parameter"
    assert "piston area" in sv["joint.piston_area"].get("description")
    assert sv["joint.supply_pressure"].find("Real").get("unit") == "Pa"
    # the file's 450 psi, in Pa (1 psi = 6894.757 Pa)
    assert float(sv["joint.supply_pressure"].find("Real").get("start")) == pytest.approx(
        450 * 6894.757293168361, rel=1e-15
    )
    assert sv["theta"].find("Real").get("unit") == "rad"
    assert sv["lever"].get("causality") == "input"
    # start values round-trip: the file's 10 us as pint converts it, to the last bit
    assert float(sv["solver.step"].find("Real").get("start")) == ha.load_scenario(RAISE).step
    units = {u.get("name") for u in root.find("UnitDefinitions")}
    assert {"m", "Pa", "rad", "N.m", "m3/s"} <= units
    cs = root.find("CoSimulation")
    assert cs.get("canGetAndSetFMUstate") == "true" and cs.get("canSerializeFMUstate") == "true"


@pytest.mark.parametrize("comm", [1e-3, 0.25e-3])
def test_fmpy_raise_test_is_hydroarm_simulate(joint_runs, comm):
    _, ref = raise_reference(record_every=int(round(comm / 1e-5)))
    res = joint_runs[0][f"comm{comm}"]
    assert len(res["time"]) == len(ref.t)
    # the issue asks for 1e-9 relative; the FMU steps the same kernel with the same floats
    # in the same order, so it is exact
    for name, want in (("theta", ref.theta), ("omega", ref.omega), ("p", ref.p), ("x", ref.x)):
        np.testing.assert_allclose(res[name], want, rtol=1e-9, atol=0)
        assert np.array_equal(res[name], want)
    assert res["x"][-1] - res["x"][0] > 0.004  # the jack moved (about 5 mm in 0.2 s)


def test_parameter_through_the_fmu_is_the_file_change(joint_runs):
    text = RAISE.read_text()
    assert 'supply_pressure = "450 psi"' in text and 'weight = "4.20 lbf"' in text
    _, base = raise_reference()
    _, ref = raise_reference(text.replace('"450 psi"', '"25 bar"'))
    res = joint_runs[0]["supply"]
    assert np.array_equal(res["theta"], ref.theta)
    assert not np.array_equal(ref.theta, base.theta)
    # a load parameter, and the start pressure that holds it (as a file's load does)
    _, ref = raise_reference(text.replace('weight = "4.20 lbf"', 'weight = "3 lbf"'))
    res = joint_runs[0]["weight"]
    # pint's lbf and ours may differ in the last bit: the runs agree to rounding
    np.testing.assert_allclose(res["p"], ref.p, rtol=1e-12)
    np.testing.assert_allclose(res["theta"], ref.theta, rtol=1e-12)
    assert not np.allclose(ref.p, base.p, rtol=1e-3)


def test_bad_parameter_is_refused_by_the_fmu(joint_runs):
    runs, log = joint_runs
    assert "ExitInitializationMode failed" in str(runs["bad"]["error"])
    assert "joint.piston_area" in log  # hydroarm's own message, in the FMU's log


def test_fmu_state_get_set_and_serialise(joint_fmu, tmp_path):
    # a process of its own: pythonfmu 0.7 crashed on later resets after a rollback
    st = run_fmu(tmp_path, joint_fmu, [], state=True)[0]["state"]
    assert np.array_equal(st["first"], st["second"])
    assert np.array_equal(st["first"], st["third"])


def test_arm_fmu_runs_the_block_stacking_replay(arm_fmu, tmp_path):
    sc = load_arm(ARM)
    names = [j.name for j in sc.joints]
    tb = np.arange(int(round(ARM_STOP / ARM_COMM)) + 1) * ARM_COMM
    values = {n: sc.inputs[n](tb) for n in names}
    out = [f"{n}.angle" for n in names] + ["supply_pressure", "pump_flow"]
    t1 = np.arange(1001) * 1e-3
    runs = [
        {"name": "euler", "kwargs": {
            "stop_time": ARM_STOP, "output_interval": ARM_COMM,
            "start_values": {"solver.method": 0, "solver.step": ARM_STEP},  # 0: euler
            "input": lever_input(tb, {f"{n}.lever": v for n, v in values.items()}),
            "output": out}},
        {"name": "rk4", "kwargs": {
            "stop_time": 1.0, "output_interval": 1e-3,
            "input": lever_input(t1, {f"{n}.lever": sc.inputs[n](t1) for n in names}),
            "output": out}},
    ]  # fmt: skip
    # one process each: pythonfmu 0.7 crashed resetting the arm's instance
    got = {r["name"]: run_fmu(tmp_path / r["name"], arm_fmu, [r])[0][r["name"]] for r in runs}
    # `hydroarm arm` on the block-stacking levers held over each communication step (what
    # a master gives an FMU): Euler reads the lever at the step's start only, so exact
    held = {n: LeverInput(np.repeat(tb, 2)[1:-1], np.repeat(v[:-1], 2)) for n, v in values.items()}
    ref = simulate_arm(
        sc.replace(
            inputs=held,
            method="euler",
            step=ARM_STEP,
            duration=ARM_STOP,
            record_every=int(round(ARM_COMM / ARM_STEP)),
        )
    )
    res = got["euler"]
    for n in names:
        assert np.array_equal(res[f"{n}.angle"], ref.angle(n))
    assert np.array_equal(res["supply_pressure"][1:], ref.supply_pressure[1:])
    assert np.ptp(res["shoulder_elevation.angle"]) > 0.1  # it moved (rad)
    # the file's RK4 at 1 ms, communicating every step, against `hydroarm arm` on the
    # piecewise-linear traces: the FMU holds each lever over a step where the replay reads it
    # at the step's middle and end too, a lag of about half a step (0.5 ms) of a lever moving
    # at most 60° in 0.1 s: 0.3°; 0.5° allows for the servo's own dynamics
    ref = simulate_arm(sc.replace(duration=1.0, record_every=1))
    res = got["rk4"]
    for n in names:
        assert np.max(np.abs(res[f"{n}.angle"] - ref.angle(n))) < np.radians(0.5), n


def test_cli_writes_the_fmu(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["fmu", "--config", str(RAISE), "--out", "s.fmu", "--method", "rk4"]) == 0
    out = capsys.readouterr().out
    assert "3 inputs, 8 outputs" in out and "s.fmu" in out
    md = read_model_description("s.fmu")
    starts = {v.name: v.start for v in md.modelVariables}
    assert starts["solver.method"] == "1"  # rk4's registry code
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.fmu"]  # nothing else left


def test_export_refuses_before_building(tmp_path):
    with pytest.raises(HydroarmError, match="--step"):
        ha.export_fmu(RAISE, tmp_path / "s.fmu", step=-1.0)
    assert list(tmp_path.iterdir()) == []


def test_example_script(tmp_path):
    # in a process of its own, as the worker (tests/fmu_worker.py)
    p = subprocess.run(
        [sys.executable, str(EXAMPLES / "fmu_fmpy.py")],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    assert "same as hydroarm simulate: True" in p.stdout
    assert (tmp_path / "servo.fmu").is_file()


def python_blocks(md: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", md, re.S)


def test_docs_show_the_example_and_their_stepper_code_runs(tmp_path, monkeypatch, capsys):
    doc = (HERE.parent / "docs" / "fmu.md").read_text()
    blocks = python_blocks(doc)
    example = (EXAMPLES / "fmu_fmpy.py").read_text()
    assert blocks[0] in example  # the FMPy script shown is the example's, as it is
    # the steppers' code of the docs runs (from the repository root, as shown)
    monkeypatch.chdir(HERE.parent)
    exec(compile(blocks[1], "docs/fmu.md", "exec"), {})
    t, theta = capsys.readouterr().out.split()
    assert float(t) == pytest.approx(0.1, abs=1e-9)  # 100 communication steps of 1 ms
    assert -1.05 < float(theta) < 1.05  # moving from -60° towards +60° (rad)


def test_files_a_configuration_reads_are_packed():
    # a joint loaded by reference ([joint] file = "fitted.toml", hydroarm fit's output) must
    # travel inside the FMU like a lever CSV does, or the slave cannot read its configuration
    from hydroarm.fmu.export import referenced_files

    doc = {"joint": {"file": "fit/fitted.toml"}, "input": {"type": "csv", "file": "lever.csv"}}
    assert referenced_files(doc, "joint") == [
        ("input.file", "lever.csv"),
        ("joint.file", "fit/fitted.toml"),
    ]
    arm = {"joints": {"elbow_reach": {"file": "e.toml"}, "wrist_rotation": {}}}
    assert referenced_files(arm, "arm") == [("joints.elbow_reach.file", "e.toml")]
