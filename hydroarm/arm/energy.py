"""Energy of a whole-arm run, from its recorded traces (after the run; the kernel is not
touched): the power pack's hydraulic energy, where it goes, and its electric side.

At each recorded sample the valve flows are evaluated again from the recorded state
(servo angle, rate, load pressure, lever) and supply pressure, with the kernel's own
equations (`valve_flow` and the leakage of eq. (1)); the
energies are the integrals of `hydroarm.metrics.power` over those samples. Chain of
the balance (docs/arm.md, "Power pack: the electric side"):

    pump ∫p_s·Q_p  =  relief ∫p_s·(Q_p − D)⁺  +  valves ∫p_s·D           D = Σ_i Q_s,i
    valves         =  throttling (valve metering losses)  +  actuators Σ ∫p_i·Q_i
    actuators      =  jack work Σ ∫A·p_i·ẋ_i  +  leakage Σ ∫q_leak,i·p_i
                      + compression Σ Δ(V·p_i²/(2β))  +  cavitation Σ ∫p_i·q_cav,i
    jack work      =  potential energy gained by arm and payload  +  friction, gearbox, kinetic

where Q_s,i = sgn(e_i)·Q_i is valve i's supply-edge flow (the flow of the kernel's supply
balance) and Q_i its load flow. The first and third lines close up to the quadrature of the
recorded samples (``supply_residual``, ``actuator_residual``); the second and the last
define the throttling and the mechanical losses.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.arm_kinematics import potential_energy
from ..core.equations import (
    jack_position,
    jack_velocity,
    null_leakage_flow,
    pressure_limit,
    supply_flow,
    valve_flow,
    valve_opening,
)
from ..core.params import J_SUPPLY, N_ROW, VALVE_ORIFICE, joint_at
from ..core.servo import (
    P_AREA_A,
    P_AREA_B,
    P_LEAK_EXT_A,
    P_LEAK_EXT_B,
    P_LEAK_INT,
    P_P_TANK,
    S_E_COMP,
    S_PA,
    S_PB,
    S_Q,
    S_V,
    S_XV,
    actuator_motion,
    valve_flows,
)
from ..metrics import power
from ..model.joint import Load, pack

# a placeholder load for the parameter table (the hydraulic terms do not use it)
_NO_LOAD = Load(weight=0.0, arm=0.0, inertia=1.0)


@njit(cache=True, nogil=True)
def flow_traces(TH, OM, PP, Y, PS, PM):
    """Per recorded sample k and joint j: load flow Q [m³/s], supply-edge flow Q_s [m³/s],
    jack velocity ẋ [m/s], leakage flow q_leak [m³/s] (2L·p + the valve's at null) and
    whether the load pressure sits on the orifice valve's cavitation floor. PM: the
    parameter table (its supply column is overwritten with each sample's p_s)."""
    n, nj = TH.shape
    Q = np.empty((n, nj))
    QS = np.empty((n, nj))
    XD = np.empty((n, nj))
    QL = np.empty((n, nj))
    FLOOR = np.zeros((n, nj), dtype=np.bool_)
    for k in range(n):
        for j in range(nj):
            PM[j, J_SUPPLY] = PS[k]
            J = joint_at(PM, j)
            th, p = TH[k, j], PP[k, j]
            e = valve_opening(Y[k, j], jack_position(th, J), J)
            q = valve_flow(e, p, J)
            Q[k, j] = q
            QS[k, j] = supply_flow(e, p, J)
            XD[k, j] = jack_velocity(th, OM[k, j], J)
            ql = 2.0 * J.leakage_coefficient * p
            if J.null_leakage_coefficient != 0.0:
                ql += null_leakage_flow(e, p, J)
            QL[k, j] = ql
            if J.valve_model == VALVE_ORIFICE:
                lim = pressure_limit(J)
                FLOOR[k, j] = abs(abs(p) - lim) <= 1e-9 * lim
    return Q, QS, XD, QL, FLOOR


@njit(cache=True, nogil=True)
def component_flow_traces(S, P):
    """Per recorded state (rows of S, the component servo's states) of a joint built from
    components with parameters P: supply-edge flow Q_P [m³/s], the power into the actuator
    (p_A − p_T)·Q_A + (p_B − p_T)·Q_B, the jack's (A_A·(p_A − p_T) − A_B·(p_B − p_T))·ẋ and
    the leakage's [W], and ẋ [m/s] (`valve_flows`; the terms of
    `servo_rhs`'s energies)."""
    n = S.shape[0]
    QS = np.empty(n)
    ACT = np.empty(n)
    JACK = np.empty(n)
    LEAK = np.empty(n)
    XD = np.empty(n)
    p_t = P[P_P_TANK]
    for k in range(n):
        s = S[k]
        q_a, q_b, q_p, _ = valve_flows(s[S_XV], s, P)
        _, v_x, _ = actuator_motion(s[S_Q], s[S_V], P)
        ga = s[S_PA] - p_t
        gb = s[S_PB] - p_t
        QS[k] = q_p
        ACT[k] = ga * q_a + gb * q_b
        JACK[k] = (P[P_AREA_A] * ga - P[P_AREA_B] * gb) * v_x
        dp = s[S_PA] - s[S_PB]
        LEAK[k] = P[P_LEAK_INT] * dp * dp + P[P_LEAK_EXT_A] * ga * ga + P[P_LEAK_EXT_B] * gb * gb
        XD[k] = v_x
    return QS, ACT, JACK, LEAK, XD


def _table(sc) -> np.ndarray:
    PM = np.empty((len(sc.joints), N_ROW))
    for j, aj in enumerate(sc.joints):
        PM[j] = pack(aj.servo.replace(supply_pressure=sc.power_pack.supply_pressure), _NO_LOAD)
    return PM


# the SI unit of each series of `power_traces` as a name's suffix in a result
# (`hydroarm.arm.result.ArmResult.power_traces`; docs/model.md "Units in names")
TRACE_UNITS: dict[str, str | None] = {
    "t": "s",
    **dict.fromkeys(("q_pump", "q_valves", "q_load", "q_supply", "q_leak"), "m3_per_s"),
    "xdot": "m_s",
    "floor": None,  # at the cavitation floor: booleans
    **dict.fromkeys(
        ("pump", "relief", "valves", "actuators", "jack", "leak_power", "electric"), "w"
    ),
    **{
        f"cumulative_{k}": "j"
        for k in ("pump", "relief", "valves", "actuators", "jack", "electric")
    },
}


def traces_with_units(traces: dict) -> dict:
    """`power_traces` with each name's SI unit appended (``pump_w``,
    ``cumulative_pump_j``, ``q_pump_m3_per_s``, ``t_s``)."""
    return {(f"{k}_{u}" if (u := TRACE_UNITS[k]) else k): v for k, v in traces.items()}


def power_traces(res) -> dict:
    """Time series of a run's power pack [W] and their cumulative energies [J] (arrays):
    ``t``, ``pump``, ``relief``, ``valves``, ``actuators``, ``jack`` (Σ A·p·ẋ), ``leak_power``,
    ``electric``
    (None without efficiencies), and ``cumulative_<name>`` of each; ``q_pump``, ``q_valves``
    [m³/s]; per joint (columns in the order of the joints) ``q_load``, ``q_supply``,
    ``xdot``, ``q_leak``, ``floor``."""
    sc = res.scenario
    pk = sc.power_pack
    Q, QS, XD, QL, FLOOR = flow_traces(
        np.ascontiguousarray(res.theta),
        np.ascontiguousarray(res.omega),
        np.ascontiguousarray(res.p),
        np.ascontiguousarray(res.y),
        np.ascontiguousarray(res.supply_pressure),
        _table(sc),
    )
    t, ps = res.t, res.supply_pressure
    area = np.array([aj.servo.piston_area for aj in sc.joints])
    act = res.p * Q
    jack = area * res.p * XD
    leak = QL * res.p
    for j, aj in enumerate(sc.joints):
        if aj.component is None or res.component_states is None:
            continue
        P = aj.component_vector(pk.supply_pressure, aj.fixed_load)
        qs, a, w, lk, xd = component_flow_traces(
            np.ascontiguousarray(res.component_states[:, j]), P
        )
        QS[:, j], act[:, j], jack[:, j], leak[:, j], XD[:, j] = qs, a, w, lk, xd
        Q[:, j] = QS[:, j]
        QL[:, j] = 0.0
        FLOOR[:, j] = False
    qv = QS.sum(axis=1)
    # an unlimited pump is an ideal pressure source: it delivers what the valves draw
    qp = np.full(t.size, pk.pump_flow) if math.isfinite(pk.pump_flow) else np.maximum(qv, 0.0)
    out = {
        "t": t,
        "q_pump": qp,
        "q_valves": qv,
        "q_load": Q,
        "q_supply": QS,
        "xdot": XD,
        "q_leak": QL,
        "floor": FLOOR,
        "pump": power.hydraulic_power(ps, qp),
        "relief": power.hydraulic_power(ps, power.relief_flow(qp, qv)),
        "valves": power.hydraulic_power(ps, qv),
        "actuators": act.sum(axis=1),
        "jack": jack.sum(axis=1),
        "leak_power": leak.sum(axis=1),
        "electric": None,
    }
    if pk.electric:
        out["electric"] = out["pump"] / (pk.pump_efficiency * pk.motor_efficiency)
    for k in ("pump", "relief", "valves", "actuators", "jack", "electric"):
        out[f"cumulative_{k}"] = None if out[k] is None else power.cumulative(t, out[k])
    return out


# the SI unit of each entry of `energy_summary` as a name's suffix in a result
# (`hydroarm.arm.result.ArmResult.energy`; docs/model.md "Units in names"); None: a count
ENERGY_UNITS: dict[str, str | None] = {
    "duration": "s",
    **dict.fromkeys(
        (
            "pump_hydraulic",
            "relief_loss",
            "valves",
            "supply_residual",
            "throttling",
            "actuators",
            "jack_work",
            "leakage",
            "compression",
            "cavitation",
            "actuator_residual",
            "potential",
            "mechanical_losses",
        ),
        "j",
    ),
    "cycles": None,
    **power.ELECTRIC_UNITS,
}


def with_units(summary: dict) -> dict:
    """An `energy_summary` with each name's SI unit appended (``pump_hydraulic_j``,
    ``duration_s``; ``cycles`` and ``cycles_per_charge`` as they are)."""
    return {(f"{k}_{u}" if (u := ENERGY_UNITS[k]) else k): v for k, v in summary.items()}


def energy_summary(res, traces: dict | None = None, cycles: float = 1.0) -> dict:
    """The run's energies [J] (plain floats; see the module doc for the chain), and with the
    efficiencies its electric side: ``electric_energy`` [J], ``mean_electric_power`` [W],
    ``energy_per_cycle`` [J] (electric, the run being ``cycles`` task cycles), and with a
    battery ``battery_usable_energy`` [J], ``cycles_per_charge``, ``run_time_per_charge``
    [s]."""
    tr = power_traces(res) if traces is None else traces
    sc = res.scenario
    pk = sc.power_pack
    t = res.t
    sup = power.supply_energies(t, res.supply_pressure, tr["q_pump"], tr["q_valves"])
    p = res.p
    actuators = power.trapezoid(t, tr["actuators"])
    jack = power.trapezoid(t, tr["jack"])
    leakage = power.trapezoid(t, tr["leak_power"])
    compression = 0.0
    cavitation = 0.0
    for j, aj in enumerate(sc.joints):
        s = aj.servo
        if aj.component is not None and res.component_states is not None:
            # the integrated ∫(p − p_T)·(V/β_e)·ṗ of the servo's chambers
            e = res.component_states[:, j, S_E_COMP]
            compression += float(e[-1] - e[0])
            continue
        compression += s.trapped_volume / (2.0 * s.bulk_modulus) * (p[-1, j] ** 2 - p[0, j] ** 2)
        q_cav = np.where(
            tr["floor"][:, j],
            tr["q_load"][:, j] - s.piston_area * tr["xdot"][:, j] - tr["q_leak"][:, j],
            0.0,
        )
        cavitation += power.trapezoid(t, p[:, j] * q_cav)
    G = sc.geometry.params()
    q = res.articulation_angles()
    potential = float(potential_energy(q[-1], G) - potential_energy(q[0], G))
    duration = float(t[-1] - t[0])
    out = {
        "duration": duration,
        "pump_hydraulic": sup["pump"],
        "relief_loss": sup["relief"],
        "valves": sup["valves"],
        "supply_residual": sup["residual"],
        "throttling": sup["valves"] - actuators,
        "actuators": actuators,
        "jack_work": jack,
        "leakage": leakage,
        "compression": float(compression),
        "cavitation": cavitation,
        "actuator_residual": actuators - jack - leakage - compression - cavitation,
        "potential": potential,
        "mechanical_losses": jack - potential,
        "cycles": float(cycles),
    }
    if pk.electric and duration > 0.0:
        out.update(
            power.electric_summary(
                sup["pump"],
                duration,
                pump_efficiency=float(pk.pump_efficiency),
                motor_efficiency=float(pk.motor_efficiency),
                usable_battery_energy=pk.usable_battery_energy,
                cycles=cycles,
            )
        )
    return out


# name, unit, scale from SI, description: the rows of power.csv and the printed summary
SUMMARY_ROWS = (
    ("duration", "s", 1.0, "run (one task cycle)"),
    ("pump_hydraulic", "J", 1.0, "hydraulic energy delivered by the pump"),
    ("relief_loss", "J", 1.0, "lost over the relief valve"),
    ("valves", "J", 1.0, "drawn by the valves"),
    ("throttling", "J", 1.0, "lost in the valves' metering edges"),
    ("actuators", "J", 1.0, "into the actuators"),
    ("jack_work", "J", 1.0, "mechanical work of the jacks"),
    ("leakage", "J", 1.0, "lost to leakage"),
    ("compression", "J", 1.0, "stored in oil compression"),
    ("cavitation", "J", 1.0, "lost at the cavitation floor"),
    ("potential", "J", 1.0, "potential energy gained by arm and payload"),
    ("mechanical_losses", "J", 1.0, "friction, gearbox and kinetic (jack work − potential)"),
    ("supply_residual", "J", 1.0, "pump − relief − valves (quadrature)"),
    ("actuator_residual", "J", 1.0, "actuators − jack − leakage − compression − cavitation"),
    ("electric_energy", "J", 1.0, "electric energy drawn from the battery"),
    ("mean_electric_power", "W", 1.0, "mean electric power"),
    ("energy_per_cycle", "J", 1.0, "electric energy per task cycle"),
    ("battery_usable_energy", "W*h", 1 / 3600.0, "usable battery energy per charge"),
    ("cycles_per_charge", "", 1.0, "task cycles per charge"),
    ("run_time_per_charge", "min", 1 / 60.0, "run time per charge"),
)


def summary_rows(summary: dict) -> list[tuple]:
    """(quantity, value, unit, description) rows of an `energy_summary`, values in the
    listed units, only those the summary has."""
    return [(k, summary[k] * s, u, d) for k, u, s, d in SUMMARY_ROWS if k in summary]
