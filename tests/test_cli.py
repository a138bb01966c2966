"""The command line: outputs and one-line errors with exit status 2."""

import io
import json
import subprocess
import sys

import pytest

from hydroarm.cli import main, print_spacing


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


def _table_times(out):
    return [
        float(ln.split()[0]) for ln in out.splitlines() if ln and ln[0] == " " and "[" not in ln
    ]


def test_interactive(monkeypatch, capsys):
    # the paper's dialogue: W, X, I, T, iterations, number of values to print, direction
    monkeypatch.setattr(sys, "stdin", io.StringIO("18.73\n276\n146\n0.01\n100000\n11\nraise\n"))
    code, out, err = run(["simulate", "--interactive"], capsys)
    assert code == 0
    times = _table_times(out)
    assert len(times) == 11  # the 11 values asked for: every 10000th of 100000 iterations
    assert times[0] == 0 and times[-1] == pytest.approx(1.0)  # the start and the end
    assert "W, load weight" in err and "number of solution values to print" in err
    assert "note:" not in err


def test_interactive_nearest_count(monkeypatch, capsys):
    """11 values do not divide 15 iterations evenly: 8 printed (one every 2), and said so."""
    monkeypatch.setattr(sys, "stdin", io.StringIO("18.73\n276\n146\n0.01\n15\n11\nraise\n"))
    code, out, err = run(["simulate", "--interactive"], capsys)
    assert code == 0
    times = _table_times(out)
    assert len(times) == 8
    assert times[1] - times[0] == pytest.approx(2e-5)
    assert "note: 11 values cannot be spread evenly over 15 iterations; printing 8" in err


@pytest.mark.parametrize(
    "iterations, values, every, printed",
    [
        (100000, 11, 10000, 11),  # exact, the end included
        (100, 4, 33, 4),  # exact count; iterations 0, 33, 66, 99
        (10, 11, 1, 11),  # every iteration
        (15, 11, 2, 8),  # 16 (K = 1) or 8 (K = 2): 8 is nearer
        (10, 7, 2, 6),  # 11 or 6: 6 is nearer
        (13, 6, 2, 7),  # 7 (K = 2) or 5 (K = 3): a tie, the larger count
        (2, 3, 1, 3),
    ],
)
def test_print_spacing(iterations, values, every, printed):
    assert print_spacing(iterations, values) == every
    assert iterations // every + 1 == printed


def test_print_spacing_is_nearest():
    """Against a search over every spacing: no K prints a count nearer to the one asked for."""
    for n in range(2, 80):
        for v in range(3, n + 2):
            k = print_spacing(n, v)
            best = min(abs(n // j + 1 - v) for j in range(1, n + 1) if n // j + 1 >= 3)
            assert abs(n // k + 1 - v) == best, (n, v, k)


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


def test_warmup_compiles_every_kernel(capsys):
    from hydroarm import cli
    from hydroarm.integrators.registry import compiled_on_disk

    assert main(["warmup"]) == 0
    assert "simulation kernels ready" in capsys.readouterr().out
    assert {"paper joint", "arm", "component servo", "circuit", "mechanism"} <= set(
        cli.WARMUP_KERNELS
    )
    for kind, kernels in cli.WARMUP_KERNELS.items():
        assert all(compiled_on_disk(k) for k in kernels), kind
    # a component servo runs its circuit only: the servo kernel is a test oracle, not warmed
    servo = {k.__module__ for k in cli.WARMUP_KERNELS["component servo"]}
    old = ("hydroarm.reference",)
    assert not any(m.startswith(old) for m in servo)
