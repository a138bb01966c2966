"""What a component servo's single run and its batch paths share (issue 28): the check of a
metrics request, the mapping of its circuit's energy terms onto the servo's six, and the
checks that scenarios can run as one batch. Apart from `hydroarm.model.servo` so that the
observers (`hydroarm.model.servo_observers`), which that module runs, need not import it."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..core.servo import S_E_ACT, S_E_COMP, S_E_LEAK, S_E_RELIEF, S_E_SUPPLY, S_E_THROTTLE
from ..errors import HydroarmError, check_number
from ..integrators import registry

if TYPE_CHECKING:
    from .servo import ServoScenario


def check_metrics_request(method: str, band: float) -> None:
    """Refuse on-the-fly metrics that cannot be observed: a method without a fixed step (its
    steps are not the run's records) or a settling band that is not a positive number.

    Parameters
    ----------
    method : str
        The solver's method name (``solver.method``).
    band : float
        The settling band [–], a fraction of the last step's size.
    """
    if not registry.method(method).fixed_step:
        raise HydroarmError(
            "solver.method",
            f"on-the-fly metrics need a fixed-step method "
            f"({' or '.join(registry.fixed_step_methods())})",
        )
    check_number("band", band, positive=True)


ENERGY_TERMS = {
    S_E_RELIEF: ("relief.energy",),
    S_E_THROTTLE: ("valve.throttle",),
    S_E_LEAK: ("actuator.leakage", "pump.leakage"),
    S_E_COMP: ("actuator.compression", "supply_line.energy", "accumulator.energy"),
}
SUPPLY_TERMS = ("pump.shaft", "source.energy")  # delivered: the supply's energy, negated


def add_energy_terms(energy: dict, out: np.ndarray) -> None:
    """Add a circuit's energy terms ``energy`` ({term: values}, `CompiledCircuit.energy_states`'
    names) into the servo's (the last axis of ``out``, `hydroarm.core.servo.STATES`) as
    `ENERGY_TERMS` and `SUPPLY_TERMS` map them; every other term is work on the actuator."""
    used: set[str] = set()
    for i, names in ENERGY_TERMS.items():
        for k in names:
            if k in energy:
                out[..., i] += energy[k]
                used.add(k)
    for k in SUPPLY_TERMS:
        if k in energy:
            out[..., S_E_SUPPLY] -= energy[k]
            used.add(k)
    for k, e in energy.items():
        if k not in used:
            out[..., S_E_ACT] += e


def check_same_run(scenarios: list[ServoScenario]) -> None:
    first = scenarios[0]
    for sc in scenarios[1:]:
        same = (
            sc.method == first.method
            and sc.step == first.step
            and sc.duration == first.duration
            and sc.record_every == first.record_every
            and sc.reference == first.reference
        )
        if not same:
            raise HydroarmError("scenarios", "must share reference, method, step and duration")


def same_net(a: tuple, b: tuple) -> bool:
    """Whether two compiled circuits' nets are equal (one batch runs them: only P differs)."""
    return len(a) == len(b) and all(
        np.array_equal(x, y) if isinstance(x, np.ndarray) else same_net(x, y)
        for x, y in zip(a, b, strict=True)
    )
