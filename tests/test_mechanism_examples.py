"""The mechanism examples (issue 30), each run as a user runs it: ``hydroarm arm --config
examples/<name>.toml``. examples/excavator.toml: a boom, stick and bucket following a
dig-and-dump cycle under PID joint loops on one pressure-compensated pump;
examples/hydraulic_leg.toml: a HyQ-like hip and knee following a walking-like swing on one
supply. What is checked is what the examples claim (docs/mechanism.md, "Examples")."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from hydroarm.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
BAR = 1e5


def _run(name: str, out: Path, animation: bool = True) -> tuple[pd.DataFrame, dict[str, float]]:
    argv = ["arm", "--config", str(EXAMPLES / f"{name}.toml"), "--out", str(out)]
    assert main(argv + ([] if animation else ["--no-animation"])) == 0
    files = ("joints.csv", "energy.csv", "joints.png", "frames.png")
    for f in files + (("mechanism.gif",) if animation else ()):
        assert (out / f).stat().st_size > 0
    df = pd.read_csv(out / "joints.csv")
    with open(out / "energy.csv") as fh:
        energy = {r["component"]: float(r["energy_j"]) for r in csv.DictReader(fh)}
    return df, energy


def _at(df: pd.DataFrame, column: str, t: float) -> float:
    return float(np.interp(t, df["t_s"], df[column]))


@pytest.fixture(scope="module")
def excavator(tmp_path_factory):
    # the animation is checked on the leg; the excavator's 19 s would draw 380 frames
    return _run("excavator", tmp_path_factory.mktemp("excavator"), animation=False)


@pytest.fixture(scope="module")
def leg(tmp_path_factory):
    return _run("hydraulic_leg", tmp_path_factory.mktemp("leg"))


def _way_points() -> dict[str, list[tuple[float, float]]]:
    """The cycle's way points: (time, angle in deg) at the end of each hold of
    examples/excavator_cycle.csv (a hold: the reference flat for at least 1 s)."""
    cyc = pd.read_csv(EXAMPLES / "excavator_cycle.csv")
    return {
        j: [(t, float(np.interp(t, cyc["t_s"], cyc[f"{j}_deg"]))) for t in (5.5, 11.0, 14.5, 19.0)]
        for j in ("boom", "stick", "bucket")
    }


@pytest.mark.slow
def test_excavator_reaches_each_pose_of_the_cycle(excavator):
    """At the end of each hold (dig done, lifted, dumped, back) every joint is within 3 deg of
    its way point. The loops are slow on purpose (their gains sit below the oil column's
    resonance, see the example), so they lag during the moves (up to 21 deg for the stick)
    and catch up in the holds; the slowest, the stick's, is measured 2.3 deg short at the
    end of the dump hold, the others within 0.5 deg."""
    df, _ = excavator
    assert not df.isna().any().any()
    for joint, points in _way_points().items():
        for t, ref in points:
            assert _at(df, f"{joint}_angle_deg", t) == pytest.approx(ref, abs=3.0), (joint, t)
    # and it moves: the boom sweeps its 55 deg of the cycle, the bucket its 95 deg
    assert np.ptp(df["boom_angle_deg"]) > 50.0
    assert np.ptp(df["bucket_angle_deg"]) > 90.0


@pytest.mark.slow
def test_excavator_pressures_stay_under_the_relief_setting(excavator):
    """The pump's compensator (290 bar, 12.5 bar band) keeps the supply under the main relief's
    310 bar, which never opens (measured peak 303 bar: the compensator's 40 ms lag lets the
    pressure pass its deadhead 302.5 bar when the valves close); no chamber exceeds it
    either (measured 293 bar), and none falls below 0 bar absolute (the cavitation floor)."""
    df, energy = excavator
    assert df["P_pressure_bar"].max() < 310.0
    assert energy["main_relief"] < 1.0  # J
    for j in ("boom", "stick", "bucket"):
        for side in ("a", "b"):
            p = df[f"{j}_{side}_pressure_bar"]
            assert p.max() < 310.0 and p.min() >= 0.0


@pytest.mark.slow
def test_excavator_energy_account_closes(excavator):
    """What the pump delivers is what the valves, cylinders, lines and the mechanism absorb:
    the account's closure is at rounding level (measured 1e-9 J of 1.8 MJ); 1e-9 of the
    pump's energy leaves room for the sum's rounding over 380 000 steps."""
    _, energy = excavator
    pump = abs(energy["pump"])
    assert pump > 1e5
    assert abs(energy["closure"]) < 1e-9 * pump
    # most of it is throttled in the valves: the supply sits near 290 bar whatever the loads
    valves = sum(energy[f"{j}_valve"] for j in ("boom", "stick", "bucket"))
    assert valves > 0.9 * pump


@pytest.mark.slow
def test_leg_tracks_its_gait(leg):
    """After the first half stride (the start from rest), both joints follow the walking-like
    swing within 4 deg (measured 3.2 deg hip, 3.5 deg knee: the loops' phase lag at 0.5 Hz
    with a 36 rad/s closed-loop bandwidth, plus the oil column's ringing at the swing's
    ends); the swing spans the references' 50 deg each."""
    df, _ = leg
    assert not df.isna().any().any()
    late = df["t_s"] > 1.0
    for j in ("hip", "knee"):
        err = np.degrees(df[f"{j}_ref_signal"]) - df[f"{j}_angle_deg"]
        assert err[late].abs().max() < 4.0, j
        assert np.ptp(df.loc[late, f"{j}_angle_deg"]) > 45.0


@pytest.mark.slow
def test_leg_supply_and_energy(leg):
    """The relief holds the supply at 160 bar (measured 160.3 bar with the pump's whole 10
    L/min over it; a 2 bar margin); the chambers stay between 0 bar and the supply; the
    energy account closes to rounding (1e-9 of the pump's energy)."""
    df, energy = leg
    assert df["P_pressure_bar"].max() < 162.0
    assert df["P_pressure_bar"].min() > 155.0
    for j in ("hip", "knee"):
        for side in ("a", "b"):
            p = df[f"{j}_{side}_pressure_bar"]
            assert 0.0 <= p.min() and p.max() < 160.5
    pump = abs(energy["pump"])
    assert abs(energy["closure"]) < 1e-9 * pump
    # a constant-pressure supply: most of the pump's energy goes over the relief
    assert energy["relief"] > 0.5 * pump
