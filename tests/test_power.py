"""The power pack's energy functions (hydroarm/metrics/power.py, issue 14) against hand
arithmetic."""

import math

import numpy as np
import pytest

from hydroarm.errors import HydroarmError
from hydroarm.metrics import power


def test_trapezoid_and_cumulative():
    t = np.linspace(0.0, 2.0, 2001)
    assert power.trapezoid(t, 3.0 * t) == pytest.approx(6.0, rel=1e-12)  # exact for a line
    c = power.cumulative(t, 3.0 * t)
    assert c[0] == 0.0 and c[-1] == pytest.approx(6.0, rel=1e-12)
    assert power.trapezoid([1.0], [5.0]) == 0.0


def test_supply_energies_of_a_known_demand():
    # 31 bar, pump 1e-5 m³/s for 2 s; the valves draw 4e-6 for the first second, 1e-5 after
    t = np.array([0.0, 1.0, 1.0 + 1e-12, 2.0])
    qv = np.array([4e-6, 4e-6, 1e-5, 1e-5])
    e = power.supply_energies(t, np.full(4, 31e5), 1e-5, qv)
    assert e["pump"] == pytest.approx(31e5 * 1e-5 * 2, rel=1e-9)
    assert e["relief"] == pytest.approx(31e5 * 6e-6 * 1, rel=1e-9)
    assert e["valves"] == pytest.approx(31e5 * (4e-6 + 1e-5), rel=1e-9)
    assert e["residual"] == pytest.approx(0.0, abs=1e-9)


def test_relief_flow_never_negative():
    assert list(power.relief_flow(1e-5, np.array([0.0, 1e-5, 2e-5]))) == [1e-5, 0.0, 0.0]


def test_electric_energy_and_battery():
    assert power.electric_energy(42.0, 0.6, 0.7) == pytest.approx(100.0)
    wh = power.battery_energy(energy=14.4 * 3600, usable_fraction=0.8)
    ah = power.battery_energy(charge=1.2 * 3600, voltage=12.0, usable_fraction=0.8)
    assert wh == pytest.approx(ah) == pytest.approx(41472.0)
    assert power.cycles_per_charge(41472.0, 648.0) == pytest.approx(64.0)
    assert power.run_time_per_charge(41472.0, 72.0) == pytest.approx(576.0)
    assert power.cycles_per_charge(1.0, 0.0) == math.inf


def test_electric_summary():
    s = power.electric_summary(
        252.0, 9.0, pump_efficiency=0.6, motor_efficiency=0.7, usable_battery_energy=36000.0
    )
    assert s["electric_energy"] == pytest.approx(600.0)
    assert s["mean_electric_power"] == pytest.approx(600.0 / 9.0)
    assert s["energy_per_cycle"] == pytest.approx(600.0)
    assert s["cycles_per_charge"] == pytest.approx(60.0)
    assert s["run_time_per_charge"] == pytest.approx(540.0)  # 60 cycles of 9 s
    assert "cycles_per_charge" not in power.electric_summary(
        1.0, 1.0, pump_efficiency=1.0, motor_efficiency=1.0
    )


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda: power.electric_energy(1.0, 1.2, 0.7), "pump_efficiency"),
        (lambda: power.electric_energy(1.0, 0.6, 0.0), "motor_efficiency"),
        (lambda: power.battery_energy(charge=4320.0), "battery_voltage"),
        (lambda: power.battery_energy(energy=1.0, voltage=12.0), "battery_voltage"),
        (lambda: power.battery_energy(), "battery_capacity"),
        (lambda: power.battery_energy(energy=1.0, usable_fraction=1.5), "usable_fraction"),
    ],
)
def test_bad_values(call, field):
    with pytest.raises(HydroarmError) as info:
        call()
    assert info.value.field == field
