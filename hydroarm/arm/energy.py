"""Energy of a whole-arm run on the system kernel (`hydroarm.arm.expand.simulate_arm`),
from the circuit's energy account (`hydroarm.model.circuit.CircuitResult.energies`:
each component's absorbed energy integrated by the run's own method, pressures counted
from the tank's) and its recorded powers and flows: the power pack's hydraulic energy,
where it goes, and its electric side. Chain of the balance (docs/arm.md, "Power pack: the
electric side"):

    pump        =  relief  +  supply compression  +  valves  +  supply_residual
    valves      =  joint losses  +  jack work
    jack work   =  potential energy gained by arm and payload  +  mechanical losses

``valves`` is what the joints drew from the supply: the energy every component of the
joints absorbed (`hydroarm.arm.expand.arm_circuit` names them ``<joint>_<part>``) plus
the mechanism's; ``joint losses`` that of the joints' hydraulic components (a paper
joint's servo jack: its valve's metering, its leakage, oil compression and piston
friction; a joint built from components: its valve's metering, its cylinder's compression,
leakage and piston friction), ``jack work`` the rest (the cranks, the joints' own
inertias and the mechanism: kinetic, potential, friction). The first line closes to the
account's ``balance`` (zero but for a chamber held at a cavitation floor:
``supply_residual``).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.arm_kinematics import potential_energy
from ..core.circuit import declare
from ..errors import HydroarmError
from ..metrics import power as power_

#: the power pack's components in `hydroarm.arm.expand.arm_circuit` (a pump's: pump,
#: relief valve, supply line; an unlimited pump's: a source at the supply pressure)
PACK = ("tank", "source", "pump", "relief", "supply_line")

# the SI unit of each series of `power_traces` as a name's suffix in a result
# (`hydroarm.arm.result.ArmResult.power_traces`; docs/model.md "Units in names")
TRACE_UNITS: dict[str, str | None] = {
    "t": "s",
    **dict.fromkeys(("q_pump", "q_relief", "q_valves", "q_supply"), "m3_per_s"),
    **dict.fromkeys(("pump", "relief", "supply_compression", "valves", "jacks", "electric"), "w"),
    **{
        f"cumulative_{k}": "j"
        for k in ("pump", "relief", "supply_compression", "valves", "jacks", "electric")
    },
}


def traces_with_units(traces: dict) -> dict:
    """`power_traces` with each name's SI unit appended (``pump_w``,
    ``cumulative_pump_j``, ``q_pump_m3_per_s``, ``t_s``)."""
    return {(f"{k}_{u}" if (u := TRACE_UNITS[k]) else k): v for k, v in traces.items()}


def _circuit(res):
    """The system kernel's result of an arm run (refused for a decoupled model's run)."""
    if res.circuit is None:
        raise HydroarmError(
            "energy", "the arm's energy is read from its run on the system kernel (simulate_arm)"
        )
    return res.circuit


def _joint_parts(res) -> dict[str, list[tuple[int, bool]]]:
    """{joint: [(component index, whether it has a hydraulic port)]} of the arm's circuit."""
    compiled = _circuit(res).compiled
    parts: dict[str, list[tuple[int, bool]]] = {j.name: [] for j in res.scenario.joints}
    for c, (spec, decl) in enumerate(zip(compiled.circuit.components, compiled.decls, strict=True)):
        if spec.name in PACK:
            continue
        joint = next(n for n in parts if spec.name.startswith(f"{n}_"))
        parts[joint].append((c, any(p.domain == declare.HYDRAULIC for p in decl.ports)))
    return parts


def power_traces(res) -> dict:
    """Time series of a run's power pack [W] and their cumulative energies [J] (arrays),
    from the circuit's powers and flows at the records: ``t``; ``pump`` (the hydraulic
    power the pump delivers), ``relief`` (lost over the relief valve),
    ``supply_compression`` (into the supply line's oil), ``valves`` (drawn by the joints:
    the rest of the pump's), ``jacks`` (what the joints' hydraulic components hand to the
    cranks and the arm), ``electric`` (None without efficiencies), and
    ``cumulative_<name>`` of each; the flows [m³/s] ``q_pump``, ``q_relief``, ``q_valves``
    and per joint (columns in the order of the joints) ``q_supply``, drawn from the
    supply."""
    cres = _circuit(res)
    compiled = cres.compiled
    flows, power, _, _ = cres._quantities
    specs = compiled.circuit.components
    index = {c.name: k for k, c in enumerate(specs)}
    t = res.t
    n = t.size
    zero = np.zeros(n)

    def absorbed(name: str) -> np.ndarray:
        return power[:, index[name]] if name in index else zero

    def into(c: int, node: str) -> np.ndarray:
        """The flow into component c at its ports on ``node``."""
        ports = [p.name for p in compiled.decls[c].ports]
        q = np.zeros(n)
        for k, port in enumerate(ports):
            if specs[c].ports.get(port) == node:
                q = q + flows[:, c, k]
        return q

    pump = -(absorbed("pump") + absorbed("source"))
    relief = absorbed("relief")
    compression = absorbed("supply_line")
    valves = pump - relief - compression - absorbed("tank")
    parts = _joint_parts(res)
    losses = np.zeros(n)
    q_supply = np.zeros((n, len(parts)))
    for j, name in enumerate(parts):
        for c, hydraulic in parts[name]:
            q_supply[:, j] += into(c, "supply")
            if hydraulic:
                losses += power[:, c]
    q_pump = -into(index["pump"], "supply") if "pump" in index else -into(index["source"], "supply")
    q_relief = into(index["relief"], "supply") if "relief" in index else zero
    out = {
        "t": t,
        "q_pump": q_pump,
        "q_relief": q_relief,
        "q_valves": q_supply.sum(axis=1),
        "q_supply": q_supply,
        "pump": pump,
        "relief": relief,
        "supply_compression": compression,
        "valves": valves,
        "jacks": valves - losses,
        "electric": None,
    }
    pk = res.scenario.power_pack
    if pk.electric:
        out["electric"] = pump / (pk.pump_efficiency * pk.motor_efficiency)
    for k in ("pump", "relief", "supply_compression", "valves", "jacks", "electric"):
        out[f"cumulative_{k}"] = None if out[k] is None else power_.cumulative(t, out[k])
    return out


# the SI unit of each entry of `energy_summary` as a name's suffix in a result
# (`hydroarm.arm.result.ArmResult.energy`; docs/model.md "Units in names"); None: a count
ENERGY_UNITS: dict[str, str | None] = {
    "duration": "s",
    **dict.fromkeys(
        (
            "pump_hydraulic",
            "relief_loss",
            "supply_compression",
            "valves",
            "supply_residual",
            "joint_losses",
            "jack_work",
            "potential",
            "mechanical_losses",
        ),
        "j",
    ),
    "cycles": None,
    **power_.ELECTRIC_UNITS,
}


def with_units(summary: dict) -> dict:
    """An `energy_summary` with each name's SI unit appended (``pump_hydraulic_j``,
    ``duration_s``; ``cycles`` and ``cycles_per_charge`` as they are)."""
    return {(f"{k}_{u}" if (u := ENERGY_UNITS[k]) else k): v for k, v in summary.items()}


def energy_summary(res, cycles: float = 1.0) -> dict:
    """The run's energies [J] from the circuit's energy account (plain floats; see the
    module doc for the chain), and with the efficiencies its electric side:
    ``electric_energy`` [J], ``mean_electric_power`` [W], ``energy_per_cycle`` [J]
    (electric, the run being ``cycles`` task cycles), and with a battery
    ``battery_usable_energy`` [J], ``cycles_per_charge``, ``run_time_per_charge`` [s]."""
    cres = _circuit(res)
    account = cres.energies()
    specs = cres.compiled.circuit.components

    def of(c: int) -> float:
        name = specs[c].name
        return math.fsum(v for k, v in account.items() if k.split(".")[0] == name)

    index = {c.name: k for k, c in enumerate(specs)}

    def named(name: str) -> float:
        return of(index[name]) if name in index else 0.0

    pump = -(named("pump") + named("source"))
    relief = named("relief")
    compression = named("supply_line")
    parts = _joint_parts(res)
    joints = math.fsum(of(c) for name in parts for c, _ in parts[name])
    valves = joints + account.get("mechanism.energy", 0.0)
    losses = math.fsum(of(c) for name in parts for c, hydraulic in parts[name] if hydraulic)
    jack = valves - losses
    G = res.scenario.geometry.params()
    q = res.articulation_angles()
    potential = float(potential_energy(q[-1], G) - potential_energy(q[0], G))
    potential += _bench_potential(res)
    duration = float(res.t[-1] - res.t[0])
    out = {
        "duration": duration,
        "pump_hydraulic": pump,
        "relief_loss": relief,
        "supply_compression": compression,
        "valves": valves,
        "supply_residual": pump - relief - compression - valves - named("tank"),
        "joint_losses": losses,
        "jack_work": jack,
        "potential": potential,
        "mechanical_losses": jack - potential,
        "cycles": float(cycles),
    }
    pk = res.scenario.power_pack
    if pk.electric and duration > 0.0:
        out.update(
            power_.electric_summary(
                pump,
                duration,
                pump_efficiency=float(pk.pump_efficiency),
                motor_efficiency=float(pk.motor_efficiency),
                usable_battery_energy=pk.usable_battery_energy,
                cycles=cycles,
            )
        )
    return out


def _bench_potential(res) -> float:
    """The potential energy [J] the joints' fixed loads (on a bench, off the arm's tree)
    gained over the run: W·X·sin(θ − θ_h) from the first to the last record (their
    gravity torque W·X·cos(θ − θ_h), θ the servo angle)."""
    out = 0.0
    for i, j in enumerate(res.scenario.joints):
        if j.fixed_load is not None:
            th = res.theta[[0, -1], i] - j.servo.horizontal_angle
            out += j.fixed_load.gravity_torque * float(np.sin(th[1]) - np.sin(th[0]))
    return out


# name, unit, scale from SI, description: the rows of power.csv and the printed summary
SUMMARY_ROWS = (
    ("duration", "s", 1.0, "run (one task cycle)"),
    ("pump_hydraulic", "J", 1.0, "hydraulic energy delivered by the pump"),
    ("relief_loss", "J", 1.0, "lost over the relief valve"),
    ("supply_compression", "J", 1.0, "stored in the supply line's oil"),
    ("valves", "J", 1.0, "drawn by the joints' valves"),
    ("joint_losses", "J", 1.0, "lost in the joints' valves and jacks (metering, leakage, oil)"),
    ("jack_work", "J", 1.0, "mechanical work of the jacks on the cranks and the arm"),
    ("potential", "J", 1.0, "potential energy gained by arm and payload"),
    ("mechanical_losses", "J", 1.0, "friction, gearbox and kinetic (jack work − potential)"),
    ("supply_residual", "J", 1.0, "pump − relief − supply compression − valves (account)"),
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
