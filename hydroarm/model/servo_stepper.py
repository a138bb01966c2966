"""A component servo advanced piece by piece, its inputs set between the pieces (issue 29).

`ServoStepper` is [`run`][hydroarm.ServoScenario.run] for a caller that
owns the clock: a co-simulation master (the servo FMU of `hydroarm.fmu`), a live
application. It steps what ``run`` steps (issue 28): the servo's circuit
([`ServoScenario.energy_circuit`][hydroarm.ServoScenario.energy_circuit]) on the system kernel
through a `hydroarm.model.circuit_stepper.CircuitStepper`, its states read back into the
servo's (`hydroarm.model.servo.servo_states`). It starts from the state ``run`` starts from, so
that a run with no input set gives ``hydroarm simulate``'s trajectory bit for bit at the same
step, whatever pieces the run is cut into (the time bookkeeping is `StepClock`'s: step k
starts at t0 + k·h).

Two inputs, held over every step until set again (zero-order hold):

* ``reference``: the reference r(t) the feedback compares with (the lever [m] in the
  actuator's coordinates for mechanical feedback, the position [m] or angle [rad] for
  electronic feedback). Until it is set the file's reference runs (its steps, ramp, sine or
  table); once set it is that value at every stage of every step, as a constant reference
  written into the file would be (set before the first step, it acts from the start): on the
  circuit, the input ``reference.value`` of its signal source;
* ``external_force``: the load's external force [N] (a rotary or crank load: torque [N m]),
  opposing positive motion: the parameter ``external_force`` of the kernel's vector, the
  same law as the file's ``[load] external_force``: on the circuit, the load's ``force``
  (``torque``) input, negated (the circuit's load force pushes positive motion).

Outputs are the columns of [`ServoResult`][hydroarm.ServoResult] at the current state,
with the same names, units and numbers as ``simulate``'s (``position_m``,
``pressure_a_bar``, ``relief_flow_l_min``, …).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.lever import evaluate
from ..core.servo import LOAD_MASS, P_FORCE, P_LOAD
from ..errors import HydroarmError
from ..integrators import registry
from .circuit import CircuitResult
from .circuit_stepper import CircuitStepper
from .servo import ServoResult, ServoScenario, servo_states
from .stepper import StepClock, finite

_NO_SINE = np.zeros(3)
_ALWAYS = np.array([-math.inf])  # a one-point reference table: its value at every time
_HEAD = 6  # get_state's leading numbers: t0, steps, requested, failed, reference set, held


class ServoStepper(StepClock):
    """A component servo advanced in fixed steps from its start, with its reference and an
    external force set between calls (module doc).

    Parameters
    ----------
    scenario : the servo (its parameters, initial state and reference; its duration and
        recording are not used)
    method : a fixed-step method (``"euler"``, ``"rk4"``; default: the scenario's)
    step : internal fixed step h [s] (default: the scenario's); checked for stability as
        ``run`` checks it, unless the scenario says not to
    """

    def __init__(
        self, scenario: ServoScenario, *, method: str | None = None, step: float | None = None
    ):
        method = scenario.method if method is None else method
        m = registry.method(method)
        if not m.fixed_step:
            raise HydroarmError(
                "solver.method",
                f"must be {' or '.join(registry.fixed_step_methods())} (a servo stepped "
                f"piece by piece takes fixed steps), got {method!r}",
            )
        h = scenario.step if step is None else finite("solver.step", step)
        if not h > 0:
            raise HydroarmError("solver.step", f"must be a positive time, got {step!r}")
        sc = scenario.replace(method=method, step=h, duration=max(scenario.duration, h))
        if sc.check_stability:
            sc.check_step()
        self.scenario = sc
        self.method = method
        self.step = h
        self._t0 = 0.0  # simulate's start
        self._k = 0
        self._requested = 0.0
        self._failed = False
        self.P = sc.vector()  # the servo's parameters (the external force set included)
        self._held: float | None = None  # the reference set (None: the file's runs)
        #: the servo's circuit stepped on the system kernel
        self.circuit = CircuitStepper(sc.energy_circuit, method=method, step=h)
        load = self.circuit.inputs
        self._force_input = "load.force" if "load.force" in load else "load.torque"

    def _circuit(self) -> CircuitStepper:
        """The circuit's stepper, its step count this stepper's (the one clock)."""
        c = self.circuit
        c._k = self._k
        return c

    def _tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self._held is None:
            ref = self.scenario.reference
            return ref.times, ref.positions, ref.sine
        return _ALWAYS, np.array([self._held]), _NO_SINE

    # inputs ----------------------------------------------------------------------------
    @property
    def linear(self) -> bool:
        """Whether the load moves along a line (m, N) or turns (rad, N m)."""
        return int(self.P[P_LOAD]) == LOAD_MASS

    @property
    def reference(self) -> float:
        """The reference r at the current time [m or rad]: the one set, else the file's."""
        return float(evaluate(self.t, *self._tables()))

    @reference.setter
    def reference(self, r: float) -> None:
        self._held = finite("reference", r)
        # at step 0 the circuit's start is taken again with it (as simulate's)
        self._circuit().set_input("reference.value", self._held)

    @property
    def reference_set(self) -> bool:
        """Whether the reference has been set (else the file's runs)."""
        return self._held is not None

    @property
    def external_force(self) -> float:
        """External force [N] (torque [N m]) on the load, opposing positive motion."""
        return float(self.P[P_FORCE])

    @external_force.setter
    def external_force(self, f: float) -> None:
        f = finite("external_force", f)
        self._circuit().set_input(self._force_input, -f)
        self.P[P_FORCE] = f

    # time ------------------------------------------------------------------------------
    def _steps(self, n: int) -> tuple[int, bool]:
        return self._circuit()._steps(n)

    def _failure(self) -> str:
        return (
            f"the run left the physical bounds at t = {self.t:.6g} s (a state not "
            f"finite): reduce the step ({self.step:g} s)"
        )

    # outputs ---------------------------------------------------------------------------
    def servo_state(self) -> np.ndarray:
        """The state now in the servo kernel's layout (`hydroarm.core.servo.STATES`; on the
        circuit, read back by `servo_states`): a copy."""
        c = self.circuit
        t = np.array([self.t])
        res = CircuitResult(c.compiled, t, c._s[None, :], -1, c.P)
        return servo_states(self.scenario, res)[0]

    def _result(self) -> ServoResult:
        # the columns follow from the state and the components (no column shows the force)
        r = np.array([self.reference])
        return ServoResult(self.scenario, np.array([self.t]), self.servo_state()[None, :], r)

    def outputs(self) -> dict[str, float]:
        """Every column of [`ServoResult`][hydroarm.ServoResult] at the current state
        (its names, its display units: bar, L/min, degrees), ``t_s`` left out."""
        return {k: float(v[0]) for k, v in self._result().columns().items() if k != "t_s"}

    def output_units(self) -> dict[str, str]:
        """Each output's unit in pint's syntax
        ([`ServoResult.display_units`][hydroarm.ServoResult.display_units])."""
        return {k: u for k, u in self._result().display_units().items() if k != "t_s"}

    # state -----------------------------------------------------------------------------
    def _vectors(self) -> list[np.ndarray]:
        """The arrays a state holds beside its head: the state vector and the kernel's
        parameter vector (on the circuit: its state, its parameters with the inputs set,
        and the servo's)."""
        return [self.circuit._s, self.circuit.P, self.P]

    def get_state(self) -> np.ndarray:
        """The complete state as floats: t0, steps, requested time, failed, whether the
        reference is set and its value, the state vector, the parameter vector (the external
        force included; on the circuit, its state and parameter vectors then the servo's
        parameters); `set_state` restores it exactly."""
        held = 0.0 if self._held is None else self._held
        set_ = float(self._held is not None)
        head = [self._t0, float(self._k), self._requested, float(self._failed), set_, held]
        return np.concatenate([head, *self._vectors()])

    def set_state(self, state) -> None:
        """Restore a state from `get_state` (of a stepper of the same servo)."""
        s = np.asarray(state, dtype=float)
        sizes = [v.size for v in self._vectors()]
        want = _HEAD + sum(sizes)
        if s.shape != (want,):
            raise HydroarmError("state", f"must hold {want} numbers, got {s.shape}")
        self._t0, self._k, self._requested = float(s[0]), int(s[1]), float(s[2])
        self._failed = bool(s[3])
        self._held = float(s[5]) if s[4] else None
        parts = np.split(s[_HEAD:], np.cumsum(sizes)[:-1])
        c = self.circuit
        c._s, c.P, self.P = (p.copy() for p in parts)
