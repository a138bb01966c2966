"""Units at the boundary, scenario files, inputs."""

import math

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.errors import HydroarmError
from hydroarm.io.schema import load_scenario_text
from hydroarm.io.units import quantity


def test_si_and_imperial_agree():
    assert quantity("a", "0.469 in**2", "area") == pytest.approx(303e-6, rel=2e-3)
    assert quantity("p", "450 psi", "pressure") == pytest.approx(31e5, rel=2e-3)
    assert quantity("L", "2e-4 in**5/s/lbf", "leakage") == pytest.approx(475e-15, rel=0.01)
    # the paper's own SI/imperial pair for load 6 differs by 0.5 %
    assert quantity("I", "1.286 lbf*in*s**2", "inertia") == pytest.approx(0.146, rel=6e-3)
    assert quantity("t", "10 us", "time") == pytest.approx(1e-5)
    assert quantity("t", "10 µs", "time") == pytest.approx(1e-5)


@pytest.mark.parametrize(
    "value, dim, words",
    [
        ("3 bar", "length", "not a length"),
        ("12", "length", "no unit"),
        ("nan mm", "length", "finite"),
        ("-1 mm", "length", "positive"),
        ("abc", "length", "cannot read"),
    ],
)
def test_bad_quantities(value, dim, words):
    with pytest.raises(HydroarmError, match=words):
        quantity("f", value, dim, positive=True)


def test_paper_loads_imperial_columns_consistent():
    from hydroarm.io.catalog import loads_table

    for r in loads_table():
        # each SI entry matches its imperial twin to the print's 3 significant figures
        assert r["W_N"] == pytest.approx(quantity("W", f"{r['W_lb']} lbf", "force"), rel=0.006)
        assert r["X_mm"] / 1e3 == pytest.approx(
            quantity("X", f"{r['X_in']} in", "length"), rel=0.006
        )
        assert r["I_N_mm_s2"] / 1e3 == pytest.approx(
            quantity("I", f"{r['I_lb_in_s2']} lbf*in*s**2", "inertia"), rel=0.006
        )


BASE = """
[joint]
parameter_set = "paper-calibrated"
supply_pressure = "450 psi"
[load]
weight = "4.2 lbf"
arm = "10.87 in"
inertia = "1.286 lbf*in*s**2"
"""


def test_scenario_file_step_and_units():
    sc = load_scenario_text(
        BASE + '[input]\ntype = "step"\ndirection = "raise"\n'
        '[solver]\nstep = "10 us"\nduration = "1.5 s"\n'
    )
    assert sc.joint.supply_pressure == pytest.approx(31.03e5, rel=1e-3)
    assert sc.initial_angle == pytest.approx(math.radians(-60))
    v = ha.simulate(sc).summary()["saturation_velocity_mm_s"]
    assert v == pytest.approx(25.1, rel=0.03)


def test_scenario_inputs_ramp_sine_csv(tmp_path):
    sc = load_scenario_text(
        BASE + '[input]\ntype = "ramp"\nfrom = "-60 deg"\nto = "5 mm"\nend = "2 s"\n'
    )
    res = ha.simulate(sc)
    # a slow ramp (5 of 29 mm/s) is followed: the jack ends near 5 mm
    assert res.x[-1] * 1e3 == pytest.approx(5.0, abs=0.3)
    sc = load_scenario_text(
        BASE + '[input]\ntype = "sine"\namplitude = "0.5 mm"\n'
        'frequency = "2 Hz"\n[solver]\nduration = "1 s"\n'
    )
    assert np.ptp(ha.simulate(sc).x) > 0
    csvf = tmp_path / "lever.csv"
    csvf.write_text("t,y\n0,-10\n0.1,-10\n0.8,10\n")
    sc = load_scenario_text(
        BASE + f'[input]\ntype = "csv"\nfile = "{csvf.name}"\n', base_dir=tmp_path
    )
    assert ha.simulate(sc).x[-1] * 1e3 == pytest.approx(10, abs=0.5)


@pytest.mark.parametrize(
    "text, field",
    [
        ('[joint]\nfoo = "1 mm"\n[load]\nbuiltin = 6\n', "joint.foo"),
        ("[load]\nbuiltin = 11\n", "load.builtin"),
        ('[load]\nweight = "1 N"\narm = "1 bar"\ninertia = "1 kg*m**2"\n', "load.arm"),
        ('[load]\nweight = "1 N"\narm = "1 m"\ninertia = "0 kg*m**2"\n', "load.inertia"),
        ('[load]\nweight = "-1 N"\narm = "1 m"\ninertia = "1 kg*m**2"\n', "load.weight"),
        ('[load]\nmass = "0 kg"\narm = "1 m"\ninertia = "1 kg*m**2"\n', "load.mass"),
        ('[load]\nmass = "-2 lb"\narm = "1 m"\ninertia = "1 kg*m**2"\n', "load.mass"),
        ('[joint]\npiston_area = "0 mm**2"\n[load]\nbuiltin = 6\n', "joint.piston_area"),
        ('[joint]\nbulk_modulus = "nan bar"\n[load]\nbuiltin = 6\n', "joint.bulk_modulus"),
        ('[joint]\npiston_area = "-3 mm**2"\n[load]\nbuiltin = 6\n', "joint.piston_area"),
        (
            '[load]\nbuiltin = 6\n[input]\ntype = "step"\ndirection = "raise"\n[solver]\n'
            'step = "0 s"\n',
            "solver.step",
        ),
        ('[load]\nbuiltin = 6\n[input]\ntype = "wave"\n', "input.type"),
        ("[load\n", "scenario"),
    ],
)
def test_scenario_errors_name_the_field(text, field):
    with pytest.raises(HydroarmError) as exc:
        load_scenario_text(text)
    assert str(exc.value).startswith(field)


def test_appendix1_parameter_columns():
    # The two printed columns agree (within the imperial print's precision) where the file
    # says "legible", and disagree where the reading notes call the entry garbled.
    from hydroarm.io.catalog import read_data_csv
    from hydroarm.io.units import registry

    ureg = registry()
    tol = {"r": 0.02, "M_6": 0.01}  # 0.8 in is 20.3 mm (1 s.f. after the point)
    for row in read_data_csv("appendix1_parameters.csv"):
        if not row["si_unit"]:
            continue
        si = ureg.Quantity(float(row["si_value"]), row["si_unit"])
        imp = ureg.Quantity(float(row["imperial_value"]), row["imperial_unit"])
        if row["symbol"].startswith("M_"):
            # printed 'lb s²/in' is a mass (lbf·s²/in); compare as kg
            rel = abs(si.to("kg").magnitude / imp.to("kg").magnitude - 1)
        else:
            rel = abs(si.to_base_units().magnitude / imp.to(si.units).to_base_units().magnitude - 1)
        if row["legible"] == "yes":
            # 1-2 significant figures in the imperial print: within 6 %
            assert rel < tol.get(row["symbol"], 0.06), (row["symbol"], rel)
        else:
            assert rel > 0.06, (row["symbol"], rel)


def test_printed_set_is_the_legible_appendix(printed):
    from hydroarm.io.catalog import read_data_csv
    from hydroarm.io.units import quantity

    rows = {r["symbol"]: r for r in read_data_csv("appendix1_parameters.csv")}
    assert printed.flow_coefficient == pytest.approx(
        quantity(
            "K", f"{rows['V']['imperial_value']} {rows['V']['imperial_unit']}", "flow_coefficient"
        )
    )
    lam = quantity("l", f"{rows['lambda_o']['imperial_value']} lbf/in", "stiffness")
    assert printed.hydraulic_stiffness == pytest.approx(lam)
    assert printed.piston_area == pytest.approx(float(rows["A"]["si_value"]) * 1e-6)


def test_overriding_bulk_modulus_keeps_the_volume(calibrated):
    sc = load_scenario_text(
        '[joint]\nbulk_modulus = "1000 MPa"\n[load]\nbuiltin = 6\n[input]\ndirection = "raise"\n'
    )
    assert sc.joint.trapped_volume == pytest.approx(calibrated.trapped_volume)
    assert sc.joint.hydraulic_stiffness > 2.9 * calibrated.hydraulic_stiffness
    sc = load_scenario_text(
        '[joint]\nhydraulic_stiffness = "1e7 N/m"\n[load]\nbuiltin = 6\n'
        '[input]\ndirection = "raise"\n'
    )
    assert sc.joint.hydraulic_stiffness == pytest.approx(1e7)
