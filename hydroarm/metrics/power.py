"""Power pack energy: hydraulic energy of the pump, relief and valves, the electric energy
drawn from the battery, and how far one charge goes (issue 14).

Plain functions of SI floats and arrays (pressures [Pa], flows [m³/s], times [s], energies
[J], powers [W]), shared by the whole arm (`hydroarm.arm.energy`) and any other path
that records a supply pressure and flows. Equations and sources (docs/arm.md, "Power pack:
the electric side"):

* Hydraulic power of a flow Q delivered at a pressure p above tank: P = p·Q (Merritt 1967,
  *Hydraulic Control Systems*, §3.2 and §5.2); energy E = ∫P dt (trapezoidal rule on the
  recorded samples).
* A fixed-displacement pump of delivered flow Q_p into a supply at p_s gives the hydraulic
  energy E_pump = ∫p_s·Q_p dt. What the valves do not draw, Q_p − D, passes the relief valve
  at p_s and is lost as heat: E_relief = ∫p_s·(Q_p − D)⁺ dt (Merritt 1967, §3.3: the
  constant-pressure supply with a relief valve). So E_pump = E_relief + E_valves, with
  E_valves = ∫p_s·D dt, up to the recording's quadrature (`supply_energies`).
* Electric energy: E_el = E_pump / (η_pump·η_motor), with η_pump the pump's overall
  efficiency (volumetric × hydro-mechanical: hydraulic power out / shaft power in) and
  η_motor the motor's (shaft power out / electric power in) (Ivantysyn & Ivantysynova 2001,
  *Hydrostatic Pumps and Motors*, ch. 1). **Each efficiency is a constant**: a fixed-
  displacement pump at fixed speed works at one operating point (its relief pressure) for
  most of a run; efficiency maps against pressure and speed are not modelled.
* Battery: nominal energy E_bat = capacity as energy [J], or charge C [C] × nominal voltage
  V [V] (Linden & Reddy 2002, *Handbook of Batteries*, §1.3: theoretical energy = voltage ×
  capacity); usable energy = E_bat × usable fraction (the depth of discharge that the cells
  and the rate allow).
* Cycles per charge N = E_usable / E_el,cycle; run time per charge t = E_usable / P̄_el, the
  run's mean electric power (`electric_summary`).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import HydroarmError, check_number


def trapezoid(t, f) -> float:
    """∫f dt [f·s] by the trapezoidal rule on the samples ``f`` at the times ``t`` [s]."""
    t = np.asarray(t, dtype=float)
    f = np.asarray(f, dtype=float)
    if t.size < 2:
        return 0.0
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t)))


def cumulative(t, power) -> np.ndarray:
    """Cumulative energy [J] of ``power`` [W] at the times ``t`` [s] (0 at t[0]; trapezoidal,
    so that its last value is `trapezoid`)."""
    t = np.asarray(t, dtype=float)
    power = np.asarray(power, dtype=float)
    out = np.zeros(t.size)
    if t.size > 1:
        out[1:] = np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(t))
    return out


def hydraulic_power(pressure, flow) -> np.ndarray:
    """p·Q [W] of a flow [m³/s] at a pressure [Pa] above tank."""
    return np.asarray(pressure, dtype=float) * np.asarray(flow, dtype=float)


def relief_flow(q_pump, q_valves) -> np.ndarray:
    """Flow through the relief valve [m³/s]: what the valves leave of the pump's flow,
    (Q_p − D)⁺. While the valves would draw more than the pump gives, the supply pressure
    falls until they draw Q_p (D = Q_p) and the relief valve is shut."""
    return np.maximum(np.asarray(q_pump, dtype=float) - np.asarray(q_valves, dtype=float), 0.0)


def supply_energies(t, p_supply, q_pump, q_valves) -> dict:
    """Hydraulic energies [J] of a pump with a relief valve feeding valves.

    ``t`` [s], ``p_supply`` [Pa], ``q_pump`` [m³/s] (the pump's delivered flow; an array or
    a float), ``q_valves`` [m³/s] (D, the flow the valves draw from the supply). Returns
    ``pump`` = ∫p_s·Q_p, ``relief`` = ∫p_s·(Q_p − D)⁺, ``valves`` = ∫p_s·D and ``residual`` =
    pump − relief − valves (zero where the recording keeps D ≤ Q_p; otherwise the flow the
    valves drew beyond the pump's, which a pump-limited supply keeps at D = Q_p).
    """
    t = np.asarray(t, dtype=float)
    ps = np.asarray(p_supply, dtype=float)
    qp = np.broadcast_to(np.asarray(q_pump, dtype=float), t.shape)
    qv = np.asarray(q_valves, dtype=float)
    pump = trapezoid(t, hydraulic_power(ps, qp))
    relief = trapezoid(t, hydraulic_power(ps, relief_flow(qp, qv)))
    valves = trapezoid(t, hydraulic_power(ps, qv))
    return {"pump": pump, "relief": relief, "valves": valves, "residual": pump - relief - valves}


def check_efficiency(field: str, value) -> float:
    """An efficiency η with 0 < η ≤ 1 (a plain float), else a one-line error on ``field``."""
    v = check_number(field, value, positive=True)
    if v > 1.0:
        raise HydroarmError(field, f"must be at most 1 (an efficiency), got {value!r}")
    return v


def electric_energy(hydraulic: float, pump_efficiency: float, motor_efficiency: float) -> float:
    """Electric energy [J] drawn to deliver ``hydraulic`` [J] from the pump:
    E_hyd / (η_pump·η_motor), both efficiencies constant (module doc)."""
    check_efficiency("pump_efficiency", pump_efficiency)
    check_efficiency("motor_efficiency", motor_efficiency)
    return hydraulic / (pump_efficiency * motor_efficiency)


def battery_energy(
    *,
    energy: float | None = None,
    charge: float | None = None,
    voltage: float | None = None,
    usable_fraction: float = 1.0,
) -> float:
    """Usable energy of a battery [J]: its nominal ``energy`` [J], or its ``charge`` [C]
    (1 A·h = 3600 C) times its nominal ``voltage`` [V], times ``usable_fraction`` (0 < f ≤ 1,
    the depth of discharge one charge allows)."""
    if (energy is None) == (charge is None):
        raise HydroarmError("battery_capacity", "give the capacity as an energy or as a charge")
    if charge is not None:
        if voltage is None:
            raise HydroarmError("battery_voltage", "is needed for a capacity given as a charge")
        nominal = check_number("battery_capacity", charge, positive=True) * check_number(
            "battery_voltage", voltage, positive=True
        )
    else:
        if voltage is not None:
            raise HydroarmError(
                "battery_voltage", "is only for a capacity given as a charge (e.g. A*h)"
            )
        nominal = check_number("battery_capacity", energy, positive=True)
    f = check_number("usable_fraction", usable_fraction, positive=True)
    if f > 1.0:
        raise HydroarmError("usable_fraction", f"must be at most 1, got {usable_fraction!r}")
    return nominal * f


def cycles_per_charge(usable_energy: float, energy_per_cycle: float) -> float:
    """N = E_usable / E_cycle [cycles] (inf for a cycle that draws nothing)."""
    if energy_per_cycle <= 0.0:
        return math.inf
    return usable_energy / energy_per_cycle


def run_time_per_charge(usable_energy: float, mean_power: float) -> float:
    """t = E_usable / P̄ [s] at the mean electric power ``mean_power`` [W] (inf at none)."""
    if mean_power <= 0.0:
        return math.inf
    return usable_energy / mean_power


# the SI unit of each entry of `electric_summary` as a name's suffix in a result
# (docs/model.md "Units in names"); None: a count
ELECTRIC_UNITS: dict[str, str | None] = {
    "electric_energy": "j",
    "mean_electric_power": "w",
    "energy_per_cycle": "j",
    "battery_usable_energy": "j",
    "cycles_per_charge": None,
    "run_time_per_charge": "s",
}


def electric_summary(
    pump_energy: float,
    duration: float,
    *,
    pump_efficiency: float,
    motor_efficiency: float,
    usable_battery_energy: float | None = None,
    cycles: float = 1.0,
) -> dict:
    """The electric side of a run of ``duration`` [s] whose pump delivered ``pump_energy``
    [J] of hydraulic energy and which performed ``cycles`` task cycles.

    Returns (plain floats) ``electric_energy`` [J], ``mean_electric_power`` [W],
    ``energy_per_cycle`` [J] (electric) and, with ``usable_battery_energy`` [J],
    ``battery_usable_energy`` [J], ``cycles_per_charge`` and ``run_time_per_charge`` [s].
    """
    check_number("duration", duration, positive=True)
    check_number("cycles", cycles, positive=True)
    e_el = electric_energy(pump_energy, pump_efficiency, motor_efficiency)
    out = {
        "electric_energy": e_el,
        "mean_electric_power": e_el / duration,
        "energy_per_cycle": e_el / cycles,
    }
    if usable_battery_energy is not None:
        out["battery_usable_energy"] = float(usable_battery_energy)
        out["cycles_per_charge"] = cycles_per_charge(usable_battery_energy, e_el / cycles)
        out["run_time_per_charge"] = run_time_per_charge(usable_battery_energy, e_el / duration)
    return out
