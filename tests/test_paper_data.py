"""One home per datum: the paper's measured values in hydroarm/data/paper/measurements.csv."""

import re
from pathlib import Path

import pytest

from hydroarm.errors import HydroarmError
from hydroarm.paper import data
from hydroarm.paper.data import measurement, measurement_rows, measurements

PACKAGE = Path(__file__).parents[1] / "hydroarm"
PAPER = next(
    (
        p / "paper" / "ucl-hydraulic-arm-prosthesis.txt"
        for p in (Path(__file__).parents[1] / "shared", Path(__file__).parents[2] / "shared")
        if (p / "paper" / "ucl-hydraulic-arm-prosthesis.txt").is_file()
    ),
    None,
)


def test_measurements_file():
    rows = measurement_rows()
    names = [r["quantity"] for r in rows]
    assert len(names) == len(set(names)), "one row per datum"
    for r in rows:
        assert set(r) == {"quantity", "value", "unit", "source"}
        assert isinstance(r["value"], float) and r["unit"] and r["source"]
    assert dict(measurements()) == {r["quantity"]: r["value"] for r in rows}


def test_no_load_time_constants():
    taus = data.no_load_time_constants_ms()
    assert taus == (25.0, 28.0, 24.0, 26.0)
    # the paper prints the mean as 25.8 ms (25.75 rounded): the printed value is used
    assert measurement("no_load_time_constant_ms") == 25.8
    assert round(sum(taus) / len(taus), 1) == 25.8


def test_values_as_printed():
    m = measurements()
    assert m["stall_hand_mass_kg"] == 0.45 and m["stall_torque_Nm"] == 5.09
    assert m["stall_torque_lbf_in"] == 45.0 and m["expected_output_torque_Nm"] == 9.4
    assert (m["mean_raise_mm_s"], m["mean_lower_mm_s"], m["lower_over_raise_pct"]) == (
        22.6,
        34.7,
        53.5,
    )
    assert (m["piston_stiction_N"], m["piston_coulomb_N"]) == (30.0, 18.0)
    assert m["gearbox_efficiency_half_stall"] == 0.35
    assert (m["elbow_reach_raise_rad_s"], m["elbow_reach_lower_rad_s"]) == (2.4, 2.8)
    assert (m["shoulder_rotation_time_s"], m["elbow_stall_mass_kg"]) == (0.6, 0.9)


def test_unknown_measurement_is_a_one_line_error():
    with pytest.raises(HydroarmError, match="no_such"):
        measurement("no_such")


@pytest.mark.skipif(PAPER is None, reason="the paper's text (shared/paper) is not beside the repo")
def test_every_value_is_printed_in_the_paper():
    text = PAPER.read_text(encoding="utf-8")
    printed = {float(x) for x in re.findall(r"\d+(?:\.\d+)?", text)}
    for r in measurement_rows():
        v = r["value"]
        # fractions are printed as percentages (the efficiency 0.35 as "35%")
        assert v in printed or 100 * v in printed, r


def test_no_other_home_for_measured_values():
    # the dictionaries that used to hold (disagreeing) copies of the paper's values are gone
    for path in (PACKAGE / "paper").glob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"^MEASURED\s*=", text, re.M), path
        assert "25.75" not in text, path
