"""Energy bookkeeping of a simulated trace: hydraulic energy in = work on the load + losses.

From eq. (1) multiplied by p and eq. (3) multiplied by θ̇₂ (kinematic torque arm, where
A·p·ẋ = T_act·θ̇₂ holds exactly)::

    ∫p·Q_valve dt = Δ(½Iω²) + Δ(W·X·sin(θ₂ − θ_h))          kinetic + potential
                  + ∫(2L·p + q_0)·p dt + Δ(V·p²/(2β))        leakage + oil compression
                  + ∫T_f·|ω| dt + ∫b·ẋ² dt                   dry + viscous friction
                  + ∫p·q_cav dt                              flow lost to cavitation

where q_0 is the valve's leakage at null (option O6, ``null_leakage_flow``) and q_cav the
flow that cannot compress the oil while the load pressure sits on the orifice option's
cavitation floor |p| = p_s + 2·p_atm (the jack runs away from a void).

The paper's eq. (3) torque arm r/n does not satisfy A·p·ẋ = T_act·θ̇₂ (it misses cos φ), so
its energy does not close by the factor cos φ: use ``torque_arm = "kinematic"`` to check.
"""

from __future__ import annotations

import numpy as np

from ..core.equations import (
    dry_friction_trace,
    jack_position_trace,
    jack_velocity_trace,
    null_leakage_trace,
    pressure_limit,
    valve_flow_trace,
    valve_opening,
)


def _trap(f, t):
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t)))


def energy_balance(result) -> dict:
    """Terms of the energy balance [J] of a [`SimulationResult`][hydroarm.SimulationResult], each
    name ending in ``_j`` (``hydraulic_in_j``, ``kinetic_j``, …).

    ``residual_j`` = input − (all other terms); ``relative_residual`` (a fraction) =
    residual / the sum of the magnitudes of all terms (the energy throughput). The
    trace should be recorded at every step (``record_every = 1``) for the quadrature.
    """
    sc = result.scenario
    j, ld = sc.joint, sc.load
    P = j.params()
    t, th, om, p, y = result.t, result.theta, result.omega, result.p, result.y
    x = jack_position_trace(th, P)
    xd = jack_velocity_trace(th, om, P)
    e = valve_opening(y, x, P)
    q = valve_flow_trace(e, p, P)
    tf = dry_friction_trace(th, p, P)
    tf = np.where(om != 0.0, tf, 0.0)
    e_in = _trap(p * q, t)
    kinetic = 0.5 * ld.inertia * (om[-1] ** 2 - om[0] ** 2)
    potential = (
        ld.weight
        * ld.arm
        * (np.sin(th[-1] - j.horizontal_angle) - np.sin(th[0] - j.horizontal_angle))
    )
    q_leak = 2.0 * j.leakage_coefficient * p
    if j.null_leakage_coefficient != 0.0:
        q_leak = q_leak + null_leakage_trace(e, p, P)
    leak = _trap(q_leak * p, t)
    comp = j.trapped_volume / (2 * j.bulk_modulus) * (p[-1] ** 2 - p[0] ** 2)
    dry = _trap(tf * np.abs(om), t)
    visc = _trap(j.viscous_friction * xd**2, t)
    if j.valve_model == "orifice":
        floor = np.abs(np.abs(p) - pressure_limit(P)) <= 1e-9 * pressure_limit(P)
        q_cav = np.where(floor, q - j.piston_area * xd - q_leak, 0.0)
        cav = _trap(p * q_cav, t)
    else:
        cav = 0.0
    out = {
        "hydraulic_in_j": e_in,
        "kinetic_j": kinetic,
        "potential_j": float(potential),
        "leakage_j": leak,
        "compression_j": comp,
        "dry_friction_j": dry,
        "viscous_j": visc,
        "cavitation_j": cav,
    }
    out["residual_j"] = e_in - sum(v for k, v in out.items() if k != "hydraulic_in_j")
    scale = sum(abs(v) for v in out.values())  # energy throughput
    out["relative_residual"] = out["residual_j"] / scale if scale else 0.0
    return out
