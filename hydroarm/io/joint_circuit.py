"""The paper's joint as the circuit it stands for (issue 28: the paper's lumped joint is a
preset of the system kernel).

`joint_circuit` writes a checked [`Scenario`][hydroarm.Scenario] of the
paper's joint (a joint file ``[joint] [load] [input]``) as circuit components joined at
named nodes::

    T, supply   the return and the supply (tanks: the return at atmospheric pressure, the
                supply p_s above it)
    rod         the jack's rod (servo_jack: the valve riding on the jack, its load pressure)
    joint       the joint (crank_linkage with the gearbox's friction; inertia with the load)
    lever       the lever input (signal_source), jack_force the jack's force signal

The paper's own kernel (`hydroarm.integrators.fixed`) stays the fast path of the
joint's commands; ``tests/test_joint_circuit.py`` holds it to this circuit on the system
kernel, run by run. ``hydroarm expand --config joint.toml`` writes the circuit as a file.
"""

from __future__ import annotations

import math

from ..errors import HydroarmError
from ..model.circuit import Circuit, ComponentSpec
from ..model.joint import ServoJoint
from ..model.scenario import Scenario
from .components import is_component_file
from .schema import scenario_from_doc
from .sections import read_toml_file
from .servo_circuit import reference_source, servo_circuit


def crank_stop(j: ServoJoint) -> float:
    """The servo angle [rad] at which a joint stops: its end stop, or the crank's dead
    centre n·90° where it has none (the paper's kernel stops a run there:
    `hydroarm.integrators.fixed.in_bounds`)."""
    reach = j.gear_ratio * 0.5 * math.pi
    return reach if j.end_stop_angle is None else min(j.end_stop_angle, reach)


def jack_values(j: ServoJoint, start_pressure: float) -> dict[str, float | str]:
    """The ``servo_jack`` of joint ``j`` (SI), its load pressure ``start_pressure`` [Pa] at
    t = 0."""
    return {
        "piston_area": j.piston_area,
        "flow_coefficient": j.flow_coefficient,
        "valve_saturation": j.valve_saturation,
        "leakage_coefficient": j.leakage_coefficient,
        "trapped_volume": j.trapped_volume,
        "bulk_modulus": j.bulk_modulus,
        "valve_model": j.valve_model,
        "transition_pressure": j.transition_pressure,
        "null_leakage_coefficient": j.null_leakage_coefficient,
        "viscous_friction": j.viscous_friction,
        "rated_supply_pressure": j.supply_pressure,
        "atmospheric_pressure": j.atmospheric_pressure,
        "initial_pressure": start_pressure,
    }


def crank_values(j: ServoJoint) -> dict[str, float | str]:
    """The ``crank_linkage`` of joint ``j`` (SI): its crank, gearbox and the joint's piston
    and gearbox friction, the gearbox loss rated at the jack's stall force A·p_s."""
    static = j.coulomb_friction if j.static_friction is None else j.static_friction
    return {
        "crank_radius": j.crank_radius,
        "gear_ratio": j.gear_ratio,
        "torque_arm": j.torque_arm,
        "coulomb_friction": j.coulomb_friction,
        "breakaway_friction": static,
        "gearbox_friction_torque": j.gearbox_friction_torque,
        "gearbox_loss_at_stall": j.gearbox_loss_at_stall,
        "gearbox_loss_exponent": j.gearbox_loss_exponent,
        "rated_force": j.piston_area * j.supply_pressure,
    }


def joint_circuit(scenario: Scenario) -> Circuit:
    """The circuit of the paper's joint in ``scenario`` (module doc)."""
    j, load = scenario.joint, scenario.load
    if j.backlash != 0.0:
        raise HydroarmError(
            "joint.backlash", "the gearbox's backlash (a play on the output) has no circuit form"
        )
    p_atm, p_s = j.atmospheric_pressure, j.supply_pressure
    stop = crank_stop(j)
    jack = jack_values(j, scenario.start_pressure())
    crank = crank_values(j)
    inertia: dict[str, float | str] = {
        "inertia": load.inertia,
        "gravity_moment": load.weight * load.arm,
        "gravity_angle": j.horizontal_angle,
        "angle_min": -stop,
        "angle_max": stop,
        "initial_angle": scenario.initial_angle,
    }
    components = (
        ComponentSpec("tank", "tank", {"port": "T"}, {"pressure": p_atm}),
        ComponentSpec("tank", "source", {"port": "supply"}, {"pressure": p_atm + p_s}),
        ComponentSpec(
            "servo_jack",
            "jack",
            {"P": "supply", "T": "T", "rod": "rod", "lever": "lever", "force": "jack_force"},
            jack,
        ),
        ComponentSpec(
            "crank_linkage",
            "crank",
            {"joint": "joint", "rod": "rod", "drive_force": "jack_force"},
            crank,
        ),
        ComponentSpec("inertia", "load", {"body": "joint"}, inertia),
        reference_source(scenario.lever, "lever"),
    )
    return Circuit(
        name=scenario.name,
        components=components,
        initial_pressure=p_atm,
        method=scenario.method,
        step=scenario.step,
        duration=scenario.duration,
        record_every=scenario.record_every,
    )


def load_joint_or_servo_circuit(path) -> tuple[Circuit, str]:
    """The circuit a component servo file or a paper-joint file (``[joint] [load]``) stands
    for, and which kind of file it was (``hydroarm expand``)."""
    doc, p = read_toml_file(path)
    if is_component_file(doc):
        return servo_circuit(doc, p.parent, p.stem), "component servo"
    if "load" not in doc:
        raise HydroarmError(
            p.name, "neither a component servo file ([actuator]) nor a joint file ([load])"
        )
    return joint_circuit(scenario_from_doc(doc, p.parent, p.stem)), "paper joint"
