"""A reference file (``[system] file = …`` with values beside it: the ``fitted.toml`` that
``hydroarm fit`` writes for a mechanism or a component servo) is a system file for
``hydroarm simulate`` and ``hydroarm linearize`` too, not only for the studies (issue 29:
"fit writes its result as a system file that loads back")."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from hydroarm.cli import main
from hydroarm.io.system import reference_target, system_of
from hydroarm.model.circuit import Circuit
from hydroarm.model.circuit import simulate as simulate_circuit
from hydroarm.model.servo import ServoScenario

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _reference(tmp_path: Path, system: str, fields: str) -> Path:
    path = tmp_path / "fitted.toml"
    path.write_text(f'[system]\nfile = "{(EXAMPLES / system).as_posix()}"\n{fields}')
    return path


def test_simulate_runs_a_mechanism_reference_as_the_system_it_names(tmp_path, capsys):
    ref = _reference(
        tmp_path,
        "boom.toml",
        'duration = "0.1 s"\n"lift_cylinder.viscous_friction" = "3000 N*s/m"\n',
    )
    target = reference_target(ref)
    assert isinstance(target, Circuit)
    spec = next(c for c in target.components if c.name == "lift_cylinder")
    assert spec.values["viscous_friction"] == 3000.0
    out = tmp_path / "run.csv"
    assert main(["simulate", "--config", str(ref), "--out", str(out)]) == 0
    capsys.readouterr()
    got = pd.read_csv(out)
    # the same system through the studies' reader, on the same kernel: equal to the CSV's
    # 10 significant digits (the CSV's %.10g: at most a relative 5e-10 of rounding)
    expected = simulate_circuit(system_of("system", {"file": "fitted.toml"}, tmp_path))
    cols = expected.columns()
    for name in ("t_s", "lift_angle_deg", "A_pressure_bar"):
        assert np.allclose(got[name], cols[name], rtol=1e-9, atol=1e-12), name
    # and the value set in the reference changed the run against the file's own 2000 N·s/m
    plain = tmp_path / "plain.csv"
    assert main(["simulate", "--config", str(EXAMPLES / "boom.toml"), "--duration", "0.1 s",
                 "--out", str(plain)]) == 0  # fmt: skip
    assert not np.array_equal(pd.read_csv(plain)["lift_angle_deg"], got["lift_angle_deg"])


def test_simulate_and_linearize_run_a_component_servo_reference(tmp_path, capsys):
    ref = _reference(tmp_path, "position_servo.toml", 'duration = "0.05 s"\nmass = "130 kg"\n')
    target = reference_target(ref)
    assert isinstance(target, ServoScenario)
    assert target.parameters["mass"] == 130.0
    out = tmp_path / "run.csv"
    assert main(["simulate", "--config", str(ref), "--out", str(out)]) == 0
    got = pd.read_csv(out)
    cols = target.run().columns()
    # the CSV's 9 significant digits (csv_lines' .9g: at most a relative 5e-9 of rounding)
    assert np.allclose(got["position_m"], cols["position_m"], rtol=1e-8, atol=1e-15)
    capsys.readouterr()
    assert main(["linearize", "--config", str(ref)]) == 0
    text = capsys.readouterr().out
    assert "nan" not in text.lower()


def test_a_broken_reference_is_one_line(tmp_path, capsys):
    ref = _reference(tmp_path, "position_servo.toml", 'masss = "130 kg"\n')
    assert main(["simulate", "--config", str(ref)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hydroarm: error: system.masss:"), err
