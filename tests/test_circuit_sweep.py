"""Sweeps of any circuit by its system file (hydroarm.batch.circuit_sweep) and the trace
statistics they measure (hydroarm.metrics.trace)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from hydroarm.batch.circuit_sweep import run_circuit_chunk, run_study_chunk, traced_chunk
from hydroarm.batch.sweep import load_sweep, run_sweep
from hydroarm.cli import main
from hydroarm.metrics.trace import step_statistics, trace_statistic
from hydroarm.model.circuit import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CBV = EXAMPLES / "counterbalance.toml"

STUDY = f"""
name = "test study"
[system]
file = "{CBV.as_posix()}"
duration = "0.5 s"
record_every = 200
[grid]
"payload.mass" = ["500 kg", "900 kg"]
[monte_carlo]
n = 2
seed = 3
"cbv.pilot_ratio" = {{ distribution = "uniform", low = 2.0, high = 4.0 }}
"payload.initial_position" = {{ distribution = "normal", mean = "0.4 m", sd = "1 cm" }}
[metrics]
peak = {{ output = "cap_pressure_bar", statistic = "max" }}
drop = {{ output = "load_position_m", statistic = "peak_to_peak" }}
speed = {{ output = "load_velocity_m_s", statistic = "min", after = "0.1 s" }}
relief = {{ output = "cbv_flow_lpm", statistic = "integral" }}
"""


@pytest.fixture
def study(tmp_path):
    path = tmp_path / "study.toml"
    path.write_text(STUDY)
    return path


def test_rows_equal_single_runs_bit_for_bit(study, tmp_path):
    """Each row's metrics on the batch engine are those of the same circuit run alone
    through simulate() (the same kernel, stepper and statistics): compared with ==; the
    study's, observed at every step, those of the run recorded at every step."""
    sw = load_sweep(study)
    assert sw.size == 4 and sw.names == ["payload.mass", "cbv.pilot_ratio",
                                         "payload.initial_position"]  # fmt: skip
    # the initial position is a parameter that sets a state: each row starts there
    j = sw.compiled.state_names.index(("load.position", "m"))
    assert np.array_equal(sw.initial[:, j], sw.values[:, 2])
    out = run_sweep(sw, tmp_path / "r.csv", progress=lambda *a: None)
    header = out.read_text().splitlines()[0].split(",")
    assert header == [
        "scenario", "payload.mass_kg", "cbv.pilot_ratio", "payload.initial_position_m", "failed",
        "peak_bar", "drop_m", "speed_m_s", "relief_lpm_s",
    ]  # fmt: skip
    chunk = traced_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    at_records = run_circuit_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    eps = np.finfo(float).eps
    for r in range(sw.size):
        cols = simulate(sw.row_circuit(r)).columns()
        alone = [m.of(cols) for m in sw.metrics]
        assert chunk[r, 0] == 0.0
        assert list(chunk[r, 1:]) == alone
        # observed at the samples simulate records (a design's rows): the same numbers, the
        # integral's trapezoid summed in another order (tests/test_circuit_observers.py)
        assert at_records[r, 0] == 0.0
        for j, m in enumerate(sw.metrics):
            if m.statistic != "integral":
                assert at_records[r, 1 + j] == alone[j], m.name
                continue
            t, y = cols["t_s"], cols[m.output]
            terms = np.sum(np.abs(np.diff(t) * (y[1:] + y[:-1]) / 2.0))
            bound = (129 + np.log2(len(t))) * eps * terms
            assert abs(at_records[r, 1 + j] - alone[j]) <= bound
    # the sweep itself observes every step (hydroarm.integrators.observers): its rows are
    # those of the same circuit run alone and recorded at every step, the integral's
    # trapezoid summed in another order (the bound of tests/test_circuit_observers.py)
    observed = run_study_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    for r in range(sw.size):
        cols = simulate(dataclasses.replace(sw.row_circuit(r), record_every=1)).columns()
        for j, m in enumerate(sw.metrics):
            ref = m.of(cols)
            if m.statistic != "integral":
                assert observed[r, 1 + j] == ref, m.name
                continue
            t, y = cols["t_s"], cols[m.output]
            terms = np.sum(np.abs(np.diff(t) * (y[1:] + y[:-1]) / 2.0))
            assert abs(observed[r, 1 + j] - ref) <= (129 + np.log2(len(t))) * eps * terms
    # and the file holds them
    rows = [line.split(",") for line in out.read_text().splitlines()[1:]]
    assert float(rows[1][5]) == pytest.approx(observed[1, 1], rel=1e-9)  # written to 10 digits


def test_blocks_do_not_change_rows(study, monkeypatch):
    """A chunk of recorded traces run in blocks of one row (the memory bound) gives the same
    rows."""
    sw = load_sweep(study)
    whole = traced_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    monkeypatch.setattr("hydroarm.batch.circuit_sweep.MAX_BLOCK_BYTES", 1)
    assert np.array_equal(traced_chunk(sw.circuit, sw.table, sw.initial, sw.metrics), whole)


BAD = [
    ("unknown component", ('"payload.mass" = [', '"weight.mass" = ['), "grid.weight.mass",
     "no component 'weight'"),
    ("unknown parameter", ('"payload.mass" = [', '"payload.weight" = ['), "grid.payload.weight",
     "has no parameter 'weight'"),
    ("rule of the parameter", ('["500 kg", "900 kg"]', '["500 kg", "-1 kg"]'),
     "grid.payload.mass", "> 0"),
    ("unit", ('["500 kg", "900 kg"]', '["500 kg", "900 m"]'), "grid.payload.mass", "units of kg"),
    ("drawn row against the rule", ("low = 2.0, high = 4.0", "low = -4.0, high = 4.0"),
     "monte_carlo.cbv.pilot_ratio", "row 0: must be > 0"),
    ("no such output", ('output = "cap_pressure_bar"', 'output = "cap_pressure"'),
     "metrics.peak.output", "did you mean cap_pressure_bar"),
    ("statistic", ('statistic = "max"', 'statistic = "biggest"'), "metrics.peak.statistic",
     "one of max"),
    ("system file", ('counterbalance.toml"', 'nothing.toml"'), "system.file", ""),
    ("override", ('duration = "0.5 s"', 'duration = "0.5 kg"'), "system.duration", ""),
    ("override by name", ('duration = "0.5 s"', '"payload.mass" = "-3 kg"'),
     "system.payload.mass", "> 0"),
]  # fmt: skip


@pytest.mark.parametrize("old_new, field, words", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_study_is_one_line(old_new, field, words, tmp_path, monkeypatch, capsys):
    old, new = old_new
    assert old in STUDY
    (tmp_path / "s.toml").write_text(STUDY.replace(old, new, 1))
    monkeypatch.chdir(tmp_path)
    code = main(["sweep", "--config", "s.toml", "--out", "r.csv"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and err.startswith("hydroarm: error: " + field), err
    assert words in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]  # nothing written


def test_a_structural_parameter_is_not_swept(tmp_path, monkeypatch, capsys):
    """A line's wave buffer sets the state vector's layout: not a study parameter."""
    text = f"""
[system]
file = "{(EXAMPLES / "water_hammer.toml").as_posix()}"
[grid]
"pipe.buffer_length" = [64, 128]
[metrics]
peak = {{ output = "valve_P_flow_lpm", statistic = "max" }}
"""
    (tmp_path / "s.toml").write_text(text)
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "--config", "s.toml", "--out", "r.csv"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "hydroarm: error: grid.pipe.buffer_length: is not a parameter a study may vary"


def test_cli_example_study(tmp_path, capsys):
    """The example study runs and prints each metric's spread."""
    code = main([
        "sweep", "--config", str(EXAMPLES / "counterbalance_study.toml"),
        "--out", str(tmp_path / "s.csv"),
    ])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0
    assert "9 scenarios (0 failed)" in out and "peak_cap_pressure_bar" in out


# ------------------------------------------------------------- trace statistics ---
def test_first_order_step_statistics():
    """y = 1 − e^(−t/τ): the 2 % settling time is τ·ln 50, the 10–90 % rise time τ·ln 9,
    no overshoot; to the sampling interval (the trace runs to 20·τ so that its last value,
    taken as the final one, is the asymptote to e^−20)."""
    tau = 0.2
    t = np.linspace(0.0, 20 * tau, 40001)
    y = 3.0 + 2.0 * (1.0 - np.exp(-t / tau))
    dt = t[1]
    s = step_statistics(t, y)
    assert s["settling_time"] == pytest.approx(tau * math.log(50), abs=2 * dt)
    assert s["rise_time"] == pytest.approx(tau * math.log(9), abs=2 * dt)
    assert s["overshoot"] == pytest.approx(0.0, abs=1e-9)


def test_second_order_overshoot_and_peak():
    """An underdamped second-order step: overshoot 100·exp(−πζ/√(1−ζ²)) % at the peak time
    π/ω_d (Ogata, Modern Control Engineering, §5-3); to the sampling interval."""
    zeta, wn = 0.3, 10.0
    wd = wn * math.sqrt(1 - zeta**2)
    t = np.linspace(0.0, 5.0, 50001)
    y = 1 - np.exp(-zeta * wn * t) * (
        np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t)
    )
    s = step_statistics(t, y)
    mp = 100 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))
    assert s["overshoot"] == pytest.approx(mp, rel=1e-3)
    assert s["peak_time"] == pytest.approx(math.pi / wd, abs=2 * t[1])


def test_window_and_plain_statistics():
    t = np.linspace(0.0, 2.0, 2001)
    y = np.sin(2 * math.pi * t)
    assert trace_statistic(t, y, "rms") == pytest.approx(1 / math.sqrt(2), rel=1e-5)
    assert trace_statistic(t, y, "mean") == pytest.approx(0.0, abs=1e-9)
    assert trace_statistic(t, y, "max", after=0.5) == pytest.approx(1.0)
    assert trace_statistic(t, y, "time_of_min", before=1.0) == pytest.approx(0.75)
    assert trace_statistic(t, y, "integral", before=0.5) == pytest.approx(1 / math.pi, rel=1e-5)
    assert math.isnan(trace_statistic(t, y, "max", after=3.0))  # an empty window
    assert math.isnan(step_statistics(t, np.ones_like(t))["settling_time"])  # no motion


def test_equilibrium_rows_start_as_single_runs(tmp_path):
    """With [initial] equilibrium the static state is solved for each row, as simulate()
    solves it for the same circuit alone: the rows' metrics are equal bit for bit."""
    text = CBV.read_text().replace("[initial]\n", "[initial]\nequilibrium = true\n")
    (tmp_path / "cbv.toml").write_text(text)
    (tmp_path / "s.toml").write_text(
        """
[system]
file = "cbv.toml"
duration = "0.2 s"
[grid]
"payload.mass" = ["500 kg", "900 kg"]
[metrics]
drop = { output = "load_position_m", statistic = "peak_to_peak" }
cap = { output = "cap_pressure_bar", statistic = "initial" }
"""
    )
    sw = load_sweep(tmp_path / "s.toml")
    chunk = run_circuit_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    for r in range(sw.size):
        alone = [m.of(simulate(sw.row_circuit(r)).columns()) for m in sw.metrics]
        assert list(chunk[r, 1:]) == alone
    # held where it starts: the heavier load needs the higher cap pressure (m·g/A_a more)
    assert chunk[0, 1] < 1e-6 and chunk[1, 1] < 1e-6
    assert chunk[1, 2] - chunk[0, 2] == pytest.approx(400 * 9.81 / 19.635e-4 / 1e5, rel=1e-3)
