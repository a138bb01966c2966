"""Sweeps and tolerance studies of servos built from components (issue 14): the batch's
on-the-fly metrics equal the single run's bit for bit, grid sweeps write the expected file
with the trends the physics gives, the example runs (docs/batch.md "Component servos")."""

import csv
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hydroarm.batch.servo_sweep import ServoSweep
from hydroarm.batch.sweep import parse_sweep, run_sweep
from hydroarm.cli import main
from hydroarm.core.servo import S_E_SUPPLY, S_PS, S_Q, S_V
from hydroarm.errors import HydroarmError
from hydroarm.io.schema import load_scenario_text
from hydroarm.io.sections import parse_toml
from hydroarm.metrics.servo import METRIC_INDEX, METRICS, metric_columns, step_of
from hydroarm.model.servo import servo_metrics_table
from hydroarm.reference import metrics_on_servo_kernel

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "position_servo.toml"
STUDY = ROOT / "examples" / "servo_tolerance.toml"


EPS = np.finfo(float).eps


def _servo(duration="0.25 s"):
    """The position servo example, one step 0 → 0.2 m, shortened."""
    text = EXAMPLE.read_text()
    text = text.replace('times = ["0 s", "1 s"]', 'times = ["0 s"]')
    text = text.replace('values = ["0.2 m", "0.7 m"]', 'values = ["0.2 m"]')
    text = re.sub(r'(?m)^duration = "[^"]+"', f'duration = "{duration}"', text)
    return load_scenario_text(text, EXAMPLE.parent)


def _sweep_text(extra: str, duration: str = "0.2 s") -> str:
    """The servo_tolerance example's [scenario] with other [grid]/[monte_carlo] sections."""
    text = STUDY.read_text()
    scenario = text[text.index("[scenario.") :]
    scenario = re.sub(r'(?m)^duration = "[^"]+"', f'duration = "{duration}"', scenario)
    return extra + "\n" + scenario


def test_batch_metrics_equal_single_bit_for_bit():
    base = _servo()
    rows = [
        dict(mass=80.0),
        dict(lap_pa=0.5e-4, lap_at=0.5e-4, lap_pb=0.5e-4, lap_bt=0.5e-4, bulk_modulus=1.2e9),
        dict(mass=130.0, proportional_gain=0.02, pump_flow=6e-3),
    ]
    scs = [base.replace(**r) for r in rows]
    batch = servo_metrics_table(scs, band=0.05)  # the example rings by about ±7 mm
    assert batch.shape == (3, len(METRICS))
    for i, sc in enumerate(scs):
        single = sc.metrics_vector(0.05)
        assert single.tobytes() == batch[i].tobytes()  # bit for bit, NaNs included
        res = sc.run()  # the servo's circuit on the system kernel, its trace kept
        m = res.metrics(band=0.05)
        cols = metric_columns(batch[i : i + 1], linear=True)
        expected = {k: (bool(v[0]) if v.dtype == bool else float(v[0])) for k, v in cols.items()}
        assert repr(m) == repr(expected)  # repr: exact floats, NaN equal to NaN
        # the same steps as the trace run: its final state and energy account, exactly
        assert m["final_position_m"] == res.states[-1, S_Q]
        assert m["final_velocity_m_s"] == res.states[-1, S_V]
        assert m["final_supply_pressure_bar"] == res.states[-1, S_PS] / 1e5
        # an energy: the terms' finals minus their starts, summed (the trace: the sums'
        # final minus start): equal up to that order's rounding, the energy's ε
        e = res.states[-1, S_E_SUPPLY] - res.states[0, S_E_SUPPLY]
        assert abs(m["supply_energy_j"] - e) <= 4 * EPS * abs(e)
        # the servo kernel's metrics (metrics/servo.py) to the two codings' round-off: 1e-9
        # of the position's range, of the supplied energy (tests/test_circuit_observers.py)
        old = metrics_on_servo_kernel(sc, 0.05)
        assert abs(m["final_position_m"] - old[METRIC_INDEX["final_position"]]) <= 1e-9 * 0.2
        e_old = old[METRIC_INDEX["supply_energy"]]
        assert abs(m["supply_energy_j"] - e_old) <= 1e-9 * abs(e_old)
        # peaks over every step bound those of the kept records (record_every = 100)
        assert m["peak_speed_m_s"] >= np.abs(res.states[:, S_V]).max()
        assert not m["failed"]
        assert 0.0 < m["settling_time_s"] < 0.25
    # the rows differ: the parameters did reach the kernel
    assert len({batch[i, METRIC_INDEX["peak_speed"]] for i in range(3)}) == 3


def test_sweep_rows_equal_single_runs():
    """A parsed sweep's chunk (the sweep's own kernel call) against its rows run alone."""
    text = _sweep_text(
        "[monte_carlo]\nn = 3\nseed = 5\n"
        'overlap = { distribution = "normal", relative_sd = 0.2 }\n'
        'mass = { distribution = "uniform", relative = 0.2 }\n'
    )
    sw = parse_sweep(parse_toml(text, "sweep"), STUDY.parent)
    assert isinstance(sw, ServoSweep)
    fn, args = sw.jobs()(slice(0, 3))
    M = fn(*args)
    for i in range(3):
        sc = sw.scenario(i)
        assert sc.parameters["lap_bt"] == sw.values[i, 0]
        assert sc.metrics_vector(sw.band).tobytes() == M[i].tobytes()


def test_grid_sweep_file_and_trend(tmp_path):
    """More mass on the rod: a lower peak speed (the same pump flow and valve accelerate a
    heavier load more slowly over the first, acceleration-limited part of the step; the
    example's 200-row study gives a correlation of −0.99 between the two)."""
    text = _sweep_text(
        '[grid]\nmass = ["50 kg", "100 kg", "200 kg"]\noverlap = ["0.05 mm", "0.1 mm"]\n'
    )
    cfg = tmp_path / "grid.toml"
    cfg.write_text(text)
    out = tmp_path / "grid.csv"
    assert main(["sweep", "--config", str(cfg), "--out", str(out), "--chunk", "4"]) == 0
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    header = list(rows[0])
    metric_names = list(metric_columns(np.zeros((1, len(METRICS))), True))
    assert header == ["scenario", "mass_kg", "overlap_m", *metric_names]
    assert len(rows) == 6
    assert [r["scenario"] for r in rows] == [str(i) for i in range(6)]
    assert {float(r["mass_kg"]) for r in rows} == {50.0, 100.0, 200.0}
    assert all(r["failed"] == "False" for r in rows)
    for lap in (0.05e-3, 0.1e-3):
        sel = sorted((float(r["mass_kg"]), r) for r in rows if float(r["overlap_m"]) == lap)
        speed = [float(r["peak_speed_m_s"]) for _, r in sel]
        assert speed[0] > speed[1] > speed[2], speed
    assert not (tmp_path / "grid.csv.parts").exists()


def test_sweep_resumes_to_the_same_file(tmp_path):
    text = _sweep_text(
        "[monte_carlo]\nn = 5\nseed = 2\nbulk_modulus = "
        '{ distribution = "normal", relative_sd = 0.1 }\n',
        duration="0.05 s",
    )
    sw = parse_sweep(parse_toml(text, "sweep"), STUDY.parent)
    whole = tmp_path / "whole.csv"
    run_sweep(sw, whole, chunk=2, progress=lambda *a: None)
    part = tmp_path / "part.csv"
    with pytest.raises(HydroarmError, match="--resume"):
        run_sweep(sw, part, chunk=2, progress=lambda *a: None, stop_after=1)
    assert (tmp_path / "part.csv.parts").is_dir()
    run_sweep(sw, part, chunk=2, resume=True, progress=lambda *a: None)
    assert part.read_bytes() == whole.read_bytes()


def test_convenience_names_set_every_entry():
    text = _sweep_text(
        '[grid]\noverlap = ["0.2 mm"]\npiston_area = ["2e-3 m**2"]\ndead_volume = ["4e-4 m**3"]\n'
    )
    sw = parse_sweep(parse_toml(text, "sweep"), STUDY.parent)
    p = sw.scenario(0).parameters
    assert [p[f"lap_{e}"] for e in ("pa", "at", "pb", "bt")] == [2e-4] * 4
    assert p["area_a"] == p["area_b"] == 2e-3
    assert p["dead_volume_a"] == p["dead_volume_b"] == 4e-4
    assert np.array_equal(sw.table[0], sw.scenario(0).vector())


def test_step_of_reference_tables():
    assert step_of([0.0, 1.0, 1.0], [0.2, 0.2, 0.7]) == (1.0, 0.2)
    t, y0 = step_of([0.0], [0.2])
    assert t == 0.0 and np.isnan(y0)
    assert np.isnan(step_of([0.0, 1.0], [0.0, 1.0])[0])  # a ramp
    assert np.isnan(step_of([0.0], [0.0], sine_amplitude=0.1)[0])


@pytest.mark.slow
def test_servo_tolerance_example(tmp_path):
    """examples/servo_tolerance.toml through the CLI, cut to 24 scenarios."""
    text = STUDY.read_text()
    small = re.sub(r"(?m)^n = \d+", "n = 24", text)
    assert small != text
    config = tmp_path / "study.toml"
    config.write_text(small)
    out = tmp_path / "study.csv"
    cmd = [sys.executable, "-m", "hydroarm.cli", "sweep", "--config", str(config)]
    done = subprocess.run(
        [*cmd, "--out", str(out)],
        check=True,
        capture_output=True,
        text=True,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )
    assert "24 scenarios (0 failed)" in done.stdout
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 24
    assert list(rows[0])[1:4] == ["overlap_m", "bulk_modulus_pa", "mass_kg"]
    assert all(r["settling_time_s"] for r in rows)  # every unit settles within ±5 %


@pytest.mark.slow
def test_dask_executor_matches_local(tmp_path):
    text = _sweep_text(
        '[monte_carlo]\nn = 6\nseed = 3\nmass = { distribution = "normal", relative_sd = 0.1 }\n',
        duration="0.05 s",
    )
    sw = parse_sweep(parse_toml(text, "sweep"), STUDY.parent)
    local, dask = tmp_path / "local.csv", tmp_path / "dask.csv"
    run_sweep(sw, local, chunk=2, progress=lambda *a: None)
    run_sweep(sw, dask, chunk=2, executor="dask", progress=lambda *a: None)
    assert dask.read_bytes() == local.read_bytes()


def test_every_row_runs_on_the_system_kernel():
    """Air at a non-standard atmosphere (once a servo-kernel row) and a PID derivative gain
    are observed over their circuits with the others, in one table: each row its scenario's
    `metrics_vector` bit for bit, and the air's row the servo kernel's metrics (the oracle,
    `hydroarm.reference`) to 1e-9 of the supplied energy and of the position's range
    (the two codings' round-off, tests/test_servo_system_kernel.py)."""
    base = _servo(duration="0.05 s")
    air = base.replace(air_fraction=0.002, atmospheric_pressure=9.0e4)
    scs = [base, air, base.replace(mass=120.0, derivative_gain=1e-6)]
    M = servo_metrics_table(scs, band=0.05)
    for i, sc in enumerate(scs):
        assert sc.metrics_vector(0.05).tobytes() == M[i].tobytes()
    assert not np.isnan(M[:, METRIC_INDEX["supply_energy"]]).any()
    old = metrics_on_servo_kernel(air, 0.05)
    e_old = old[METRIC_INDEX["supply_energy"]]
    assert abs(M[1, METRIC_INDEX["supply_energy"]] - e_old) <= 1e-9 * abs(e_old)
    x = METRIC_INDEX["final_position"]
    assert abs(M[1, x] - old[x]) <= 1e-9 * 0.2  # the example's 0.2 m move
    # the air's reference pressure reached the circuit: not the 1-atm row's numbers
    at_1_atm = base.replace(air_fraction=0.002).metrics_vector(0.05)
    assert M[1].tobytes() != at_1_atm.tobytes()


def test_a_row_above_its_circuits_stable_step_is_refused_before_work():
    """The rows at the extremes of each varied value are checked on their circuits
    (`ServoScenario.step_limit`, the system kernel's Jacobians): a dead volume of 1 mm³
    makes the 10 µs rk4 step unstable, refused with one line naming the row and that row's
    own limit, before any row runs."""
    text = _sweep_text('[grid]\ndead_volume = ["10 cm**3", "0.001 cm**3"]\n', duration="0.01 s")
    with pytest.raises(HydroarmError) as e:
        parse_sweep(parse_toml(text, "sweep"), STUDY.parent)
    assert e.value.field == "scenario.solver.step"
    assert "for row 1 (dead_volume = 1e-09)" in str(e.value)
    base = parse_sweep(
        parse_toml(_sweep_text('[grid]\nmass = ["90 kg"]\n', duration="0.01 s"), "sweep"),
        STUDY.parent,
    ).base
    row = base.replace(dead_volume_a=1e-9, dead_volume_b=1e-9)
    limit = row.step_limit()
    assert limit is not None and f"stable limit {limit:.3g} s" in str(e.value)
