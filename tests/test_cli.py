"""The command line: outputs and one-line errors with exit status 2."""

import json
import subprocess
import sys

import pytest

from hydroarm.cli import main


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_metrics_json(capsys):
    code, out, err = run(["simulate", "--load", "6", "--direction", "raise", "--metrics"], capsys)
    assert code == 0
    d = json.loads(out)
    for k in (
        "saturation_velocity_mm_s",
        "time_constant_start_ms",
        "time_constant_end_ms",
        "stalled",
    ):
        assert k in d
    assert d["saturation_velocity_mm_s"] == pytest.approx(25.1, rel=0.03)
    assert d["stalled"] is False


def test_csv_and_plot(tmp_path, capsys):
    out_csv, png = tmp_path / "r.csv", tmp_path / "r.png"
    code, _, _ = run(
        [
            "simulate",
            "--weight",
            "18.73 N",
            "--arm",
            "276 mm",
            "--inertia",
            "146 N*mm*s**2",
            "--direction",
            "lower",
            "--step",
            "10 us",
            "--duration",
            "1.5 s",
            "--out",
            str(out_csv),
            "--plot",
            str(png),
        ],
        capsys,
    )
    assert code == 0
    lines = out_csv.read_text().splitlines()
    assert lines[0] == "t_s,x_mm,theta_deg,p_bar,xdot_mm_s"
    first = [float(v) for v in lines[1].split(",")]
    assert first[1] == pytest.approx(10.0) and first[2] == pytest.approx(60.0)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_interactive(monkeypatch, capsys):
    import io

    monkeypatch.setattr(sys, "stdin", io.StringIO("18.73\n276\n146\n0.01\n100000\n10000\nraise\n"))
    code, out, err = run(["simulate", "--interactive"], capsys)
    assert code == 0
    rows = [ln for ln in out.splitlines() if ln and ln[0] == " "]
    assert len(rows) == 12  # header + 11 printed values (every 10000th of 100000)
    assert "W, load weight" in err


@pytest.mark.parametrize(
    "args, words",
    [
        (
            [
                "simulate",
                "--weight",
                "0 N",
                "--arm",
                "1 m",
                "--inertia",
                "0 kg*m**2",
                "--direction",
                "raise",
            ],
            "--inertia",
        ),
        (
            [
                "simulate",
                "--weight",
                "1 N",
                "--arm",
                "-1 m",
                "--inertia",
                "1 kg*m**2",
                "--direction",
                "raise",
            ],
            "--arm",
        ),
        (["simulate", "--load", "6", "--direction", "raise", "--step", "-1 us"], "--step"),
        (["simulate", "--load", "6", "--direction", "raise", "--step", "nan us"], "--step"),
        (
            [
                "simulate",
                "--weight",
                "1 N",
                "--arm",
                "3 bar",
                "--inertia",
                "1 kg*m**2",
                "--direction",
                "raise",
            ],
            "not a length",
        ),
        (
            ["simulate", "--load", "6", "--direction", "raise", "--step", "20 ms"],
            "largest stable step",
        ),
        (["simulate", "--load", "6"], "--direction"),
        (
            [
                "simulate",
                "--weight",
                "0 kg",
                "--arm",
                "1 m",
                "--inertia",
                "1 kg*m**2",
                "--direction",
                "raise",
            ],
            "--weight: must be positive",
        ),
        (["simulate", "--load", "6", "--direction", "raise", "--step", "0 s"], "--step"),
        (["simulate", "--config", "/nonexistent.toml"], "not found"),
    ],
)
def test_bad_input_one_line_exit_2(args, words, capsys):
    code, out, err = run(args, capsys)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("hydroarm: error:")
    assert words in err
    assert out == ""


def test_malformed_toml_subprocess(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[joint\n")
    p = subprocess.run(
        [sys.executable, "-m", "hydroarm.cli", "simulate", "--config", str(bad)],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 2
    assert "Traceback" not in p.stderr
    assert p.stderr.strip().count("\n") == 0 and "malformed TOML" in p.stderr


def test_unknown_key_subprocess(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[joint]\nsupply = "31 bar"\n[load]\nbuiltin = 6\n')
    out_csv = tmp_path / "never.csv"
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "hydroarm.cli",
            "simulate",
            "--config",
            str(bad),
            "--out",
            str(out_csv),
        ],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 2 and "joint.supply: unknown key" in p.stderr
    assert not out_csv.exists()
