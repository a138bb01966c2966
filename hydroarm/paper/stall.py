"""The paper's stall and gearbox-efficiency arithmetic, as functions of its inputs.

All functions take SI floats. "Stall Load Tests" and "Gearbox Efficiency Test" sections of
the paper; Table II.
"""

from __future__ import annotations

import math

from ..core.params import STANDARD_GRAVITY as G0


def stall_force(piston_area: float, supply_pressure: float) -> float:
    """Theoretical actuator stall force A·p_s [N] (paper: 0.94 kN)."""
    return piston_area * supply_pressure


def crank_torque(force: float, crank_radius: float) -> float:
    """Torque at the gearbox input F·r [N m] (paper: 18.8 N m)."""
    return force * crank_radius


def output_torque(input_torque: float, gear_ratio: float, efficiency: float = 1.0) -> float:
    """Gearbox output torque η·T_in/n [N m] (paper: 9.4 N m expected at η = 1)."""
    return efficiency * input_torque / gear_ratio


def torque_loss(expected: float, measured: float) -> tuple[float, float]:
    """(absolute [N m], fraction) lost between expected and measured torque (4.31 N m, 46 %)."""
    return expected - measured, (expected - measured) / expected


def gravity_torque(mass: float, distance: float, angle_from_horizontal: float = 0.0) -> float:
    """m·g·d·cos(angle) [N m]."""
    return mass * G0 * distance * math.cos(angle_from_horizontal)


def gearbox_input_torque(w_in: float, crank_radius: float, crank_angle: float) -> float:
    """T_in = W_in·r·cos φ [N m]: spring-balance force W_in on the drive link at crank angle φ."""
    return w_in * crank_radius * math.cos(crank_angle)


def gearbox_output_torque(w_out: float, arm_length: float, arm_angle: float) -> float:
    """T_out = W·x·sin θ [N m]: load W at distance x, arm angle θ measured from vertical."""
    return w_out * arm_length * math.sin(arm_angle)


def gearbox_efficiency(t_in: float, t_out: float, gear_ratio: float = 2.0) -> float:
    """Torque efficiency η = n·T_out/T_in (the paper's η = 2·T_out/T_in for n = 2)."""
    return gear_ratio * t_out / t_in


def input_stall_ratio(w_in: float, stall_force_: float = 940.0) -> float:
    """γ = W_in / stall force (the paper's γ = W_in/940 N), as a fraction."""
    return w_in / stall_force_


def hand_mass_for_torque(torque: float, base_torque: float, hand_distance: float) -> float:
    """Mass [kg] at ``hand_distance`` [m] that raises a gravity torque from ``base_torque`` to
    ``torque`` (arm horizontal)."""
    return (torque - base_torque) / (G0 * hand_distance)


def table2(loads, stall_torque_theory: float, reference_load: int = 5) -> list[dict]:
    """Table II recomputed: output torque W·X, γ against theory and against the real stall.

    ``loads``: iterable of (number, weight [N], arm [m]). The real stall torque is that of
    ``reference_load`` (load 5 stalls the arm at the horizontal).
    """
    rows = [(k, w * x) for k, w, x in loads]
    real = dict(rows)[reference_load]
    return [
        {
            "load": k,
            "output_torque_Nm": t,
            "gamma_theory_pct": 100 * t / stall_torque_theory,
            "gamma_real_pct": 100 * t / real,
        }
        for k, t in rows
    ]
