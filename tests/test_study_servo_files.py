"""One servo file for every study (issue 29): a sweep and a sensitivity study name a component
servo by ``[system] file``, as design, evaluate and fit do, and run it as the circuit
``hydroarm expand`` writes for it (equal to the servo's own kernel to 1e-9 of the range:
tests/test_servo_circuit.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from hydroarm.cli import main
from hydroarm.io.system import study_circuit
from hydroarm.model.circuit import simulate

SERVO = (Path(__file__).resolve().parents[1] / "examples" / "position_servo.toml").as_posix()

SWEEP = f"""name = "servo mass sweep"
[system]
file = "{SERVO}"
duration = "0.2 s"
[grid]
"load.mass" = ["80 kg", "120 kg"]
[metrics]
peak = {{ output = "A_pressure_bar", statistic = "max" }}
"""

SENSITIVITY = f"""name = "servo sensitivity"
[system]
file = "{SERVO}"
duration = "0.2 s"
[sensitivity]
method = "sobol"
samples = 8
seed = 1
[sensitivity.parameters]
"load.mass" = {{ distribution = "normal", relative_sd = 0.1 }}
"actuator.bulk_modulus" = {{ distribution = "uniform", relative = 0.15 }}
[metrics]
peak = {{ output = "A_pressure_bar", statistic = "max" }}
"""


def test_a_sweep_of_a_servo_file_equals_simulate_of_its_circuit(tmp_path, capsys):
    (tmp_path / "sweep.toml").write_text(SWEEP)
    out = tmp_path / "s.csv"
    assert main(["sweep", "--config", str(tmp_path / "sweep.toml"), "--out", str(out)]) == 0
    capsys.readouterr()
    rows = pd.read_csv(out)
    assert list(rows["load.mass_kg"]) == [80.0, 120.0]
    circuit = study_circuit("system", {"file": SERVO, "duration": "0.2 s"}, tmp_path)
    for mass, peak in zip(rows["load.mass_kg"], rows["peak_bar"], strict=True):
        run = simulate(circuit.with_values({"load.mass": mass}).replace(record_every=1))
        expected = float(np.max(run.columns()["A_pressure_bar"]))
        # the statistic the row observed at every step against simulate's of the same circuit
        # recorded at every step (the same kernel and steps: tests/test_circuit_observers.py
        # holds them equal with ==); the CSV's %.10g is a relative 5e-10 at most
        assert abs(peak - expected) <= 1e-9 * abs(expected), (mass, peak, expected)
    # the mass changes the peak: the row is the row's servo, not the file's
    assert rows["peak_bar"][0] != rows["peak_bar"][1]


def test_a_sensitivity_study_of_a_servo_file_runs(tmp_path, capsys):
    (tmp_path / "sens.toml").write_text(SENSITIVITY)
    out = tmp_path / "sens"
    assert main(["sensitivity", "--config", str(tmp_path / "sens.toml"), "--out", str(out)]) == 0
    capsys.readouterr()
    indices = pd.read_csv(out / "sensitivity.csv")
    assert {"load.mass", "actuator.bulk_modulus"} <= set(indices["parameter"])


def test_a_servo_name_that_is_no_circuit_parameter_is_one_line(tmp_path, capsys):
    (tmp_path / "sweep.toml").write_text(SWEEP.replace('"load.mass"', "mass"))
    assert main(["sweep", "--config", str(tmp_path / "sweep.toml"), "--out", "x.csv"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hydroarm: error: grid.mass:"), err
