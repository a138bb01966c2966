"""A paper joint advanced piece by piece, its inputs set between the pieces.

[`JointStepper`][hydroarm.JointStepper] is the joint of [`simulate`][hydroarm.simulate] for a caller
that owns the clock: a co-simulation master (the FMU of `hydroarm.fmu`), a live
application. It takes whole fixed steps of the same step kernel
(`step_once`, through
`advance_steps`), so that a lever held over the run gives
``simulate``'s trajectory bit for bit at the same step, whatever pieces the run is cut into.

Time. The stepper counts whole steps k from t0; it is at t = t0 + k·h (exactly the times
``simulate`` records). ``advance(d)`` moves the requested time on by d and takes every whole
step up to it; the part of a step left over is carried to the next call (a step is taken
once the requested time reaches its end, to within 10⁻⁶ of a step, so that communication
steps that are multiples of h in floating point take exactly their steps).

Inputs are held over each step (zero-order hold): the lever position [m], the supply
pressure [Pa] the valve sees and an external load torque [N m] set before ``advance`` act on
every step that call takes. The supply pressure changes only the momentary supply (the
valve's flow); the rated supply of the gearbox load fraction and the cavitation floor stay
the joint's (as on the whole arm's sagging pump).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.equations import (
    holding_pressure,
    jack_position,
    joint_outputs,
    pressure_bound,
)
from ..errors import HydroarmError
from ..integrators import registry
from ..integrators.fixed import advance_steps
from .joint import Load, ServoJoint
from .scenario import DEFAULT_STEP, Scenario

# a step is taken once the requested time reaches its end to within this fraction of a step
STEP_TOLERANCE = 1e-6
# names, units and meanings of JointStepper.outputs(), in order
OUTPUTS: tuple[tuple[str, str, str], ...] = (
    ("theta", "rad", "joint angle θ₂ from the Appendix I datum"),
    ("omega", "rad/s", "joint angular velocity"),
    ("x", "m", "jack position from mid-stroke"),
    ("x_dot", "m/s", "jack velocity"),
    ("p", "Pa", "load pressure"),
    ("torque", "N.m", "actuator torque at the joint"),
    ("supply_flow", "m3/s", "flow drawn from the supply"),
    ("valve_opening", "m", "valve opening e = y − x, saturated"),
)
# the layout of get_state(): time and step bookkeeping, the state, the inputs
STATE_FIELDS = (
    "t0",
    "steps",
    "requested",
    "theta",
    "omega",
    "p",
    "lever",
    "supply_pressure",
    "external_torque",
    "failed",
)
_NO_SINE = np.zeros(3)
_ALWAYS = np.array([-math.inf])  # a one-point lever table: its value at every time


def finite(field: str, v) -> float:
    """``v`` as a finite float, else a one-line error naming ``field``."""
    if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)):
        raise HydroarmError(field, f"must be a number, got {v!r}")
    v = float(v)
    if not math.isfinite(v):
        raise HydroarmError(field, f"must be finite, got {v!r}")
    return v


_finite = finite


class StepClock:
    """The time bookkeeping of a stepper: the time asked for since ``_t0`` and the whole
    fixed steps ``step`` taken towards it (a step is taken once the requested time reaches
    its end, to `STEP_TOLERANCE`); ``_run`` takes them through each stepper's
    ``_steps`` (its kernel's loop), and a run that leaves the physical bounds stays failed.
    Shared by [`JointStepper`][hydroarm.JointStepper], `hydroarm.arm.stepper.ArmStepper`,
    `CircuitStepper` and
    `ServoStepper`."""

    step: float
    _t0: float = 0.0
    _k: int = 0
    _requested: float = 0.0
    _failed: bool = False

    @property
    def t(self) -> float:
        """Time of the state [s]: t0 + k·h after k whole steps."""
        return self._t0 + self._k * self.step

    @property
    def steps(self) -> int:
        """Whole steps taken since t0."""
        return self._k

    @property
    def remainder(self) -> float:
        """Requested time not yet stepped [s] (less than one step)."""
        return self._requested - self._k * self.step

    def advance(self, duration: float) -> None:
        """Move the requested time on by ``duration`` [s] and take every whole step up to it."""
        d = finite("duration", duration)
        if d < 0:
            raise HydroarmError("duration", f"must not be negative, got {d!r}")
        self._requested += d
        self._run()

    def advance_to(self, t: float) -> None:
        """Take every whole step up to time ``t`` [s] (a master's communication point)."""
        t = finite("t", t)
        if t - self._t0 < self._requested - STEP_TOLERANCE * self.step:
            raise HydroarmError("t", f"{t!r} s is before the time already asked for")
        self._requested = max(t - self._t0, self._requested)
        self._run()

    def _run(self) -> None:
        if self._failed:
            raise HydroarmError("solver.step", "the run has left the physical bounds already")
        n = int(math.floor(self._requested / self.step + STEP_TOLERANCE)) - self._k
        if n <= 0:
            return
        taken, bad = self._steps(n)
        self._k += int(taken)
        if bad:
            self._failed = True
            raise HydroarmError("solver.step", self._failure())

    def _steps(self, n: int) -> tuple[int, bool]:  # pragma: no cover - each stepper's own
        """Take ``n`` steps from the state; (steps taken, whether it left the bounds)."""
        raise NotImplementedError

    def _failure(self) -> str:  # pragma: no cover - each stepper's own
        """What to say when a step leaves the physical bounds (at `t`)."""
        raise NotImplementedError


class JointStepper(StepClock):
    """A paper joint advanced in fixed steps from a state, with inputs set between calls.

    One physics: it calls the same step kernel as [`simulate`][hydroarm.simulate];
    advancing a scenario's lever input through it gives ``simulate``'s trajectory bit for bit
    at the same step (module doc).

    Parameters
    ----------
    joint : ServoJoint
        The servo joint.
    load : Load
        Its load.
    method : str
        A fixed-step method (``"euler"``, ``"rk4"``).
    step : float, optional
        Internal fixed step h [s] (default `DEFAULT_STEP`).
    initial_angle : float, optional
        θ₂ at the start [rad] (default 0); the joint starts at rest.
    lever : float, optional
        Lever position [m] (default: the jack position at the initial angle, holding it).
    initial_pressure : float, optional
        Load pressure at the start [Pa] (default: the one holding the load).
    t0 : float
        Start time [s].
    """

    def __init__(
        self,
        joint: ServoJoint,
        load: Load,
        *,
        method: str = "rk4",
        step: float | None = None,
        initial_angle: float | None = None,
        lever: float | None = None,
        initial_pressure: float | None = None,
        t0: float = 0.0,
    ):
        m = registry.method(method)
        if not m.fixed_step:
            raise HydroarmError(
                "solver.method",
                f"must be {' or '.join(registry.fixed_step_methods())}, got {method!r}",
            )
        self.joint = joint
        self.load = load
        self.method = method
        self._code = m.code
        h = DEFAULT_STEP if step is None else _finite("solver.step", step)
        if not h > 0:
            raise HydroarmError("solver.step", f"must be a positive time, got {step!r}")
        self.step = h
        theta = 0.0 if initial_angle is None else _finite("initial.angle", initial_angle)
        if abs(theta) >= joint.max_angle:
            raise HydroarmError("initial.angle", "is beyond the crank's reach (|θ₂| < n·90°)")
        self._J = joint.params()
        self._L = load.params()
        p = (
            float(holding_pressure(theta, self._J, self._L))
            if initial_pressure is None
            else _finite("initial.pressure", initial_pressure)
        )
        self._p_max = float(pressure_bound(p, self._J, self._L))
        self._t0 = _finite("t0", t0)
        self._k = 0
        self._requested = 0.0  # time asked for since t0 [s]
        self._theta, self._omega, self._p = theta, 0.0, p
        self._lever = float(jack_position(theta, self._J)) if lever is None else lever
        self.lever = self._lever  # validated
        self._supply = self._J.supply_pressure
        self._torque = 0.0
        self._failed = False

    @classmethod
    def from_scenario(cls, sc: Scenario) -> JointStepper:
        """The stepper at a scenario's start (its joint, load, method, step, initial angle and
        pressure, t0; the lever at the scenario's lever input at t0)."""
        return cls(
            sc.joint,
            sc.load,
            method=sc.method,
            step=sc.step,
            initial_angle=sc.initial_angle,
            initial_pressure=sc.start_pressure(),
            lever=float(sc.lever(sc.t0)[0]),
            t0=sc.t0,
        )

    # inputs ----------------------------------------------------------------------------
    @property
    def lever(self) -> float:
        """Lever (valve input) position y [m] in jack coordinates, held until set again."""
        return self._lever

    @lever.setter
    def lever(self, y: float) -> None:
        self._lever = _finite("lever", y)

    @property
    def supply_pressure(self) -> float:
        """Momentary supply pressure the valve sees [Pa] (default: the joint's)."""
        return self._supply

    @supply_pressure.setter
    def supply_pressure(self, ps: float) -> None:
        ps = _finite("supply_pressure", ps)
        if not ps > 0:
            raise HydroarmError("supply_pressure", f"must be positive, got {ps!r}")
        self._supply = ps

    @property
    def external_torque(self) -> float:
        """External load torque at the joint [N m], added to the load's gravity torque
        W·X·cos(θ₂ − θ_h) (positive: it pulls the way gravity does)."""
        return self._torque

    @external_torque.setter
    def external_torque(self, T: float) -> None:
        self._torque = _finite("external_torque", T)

    # time ------------------------------------------------------------------------------
    def _steps(self, n: int) -> tuple[int, bool]:
        J = self._params()
        L = self._L._replace(torque=self._torque) if self._torque != 0.0 else self._L
        th, om, p, taken, bad = advance_steps(
            self._code,
            self._t0,
            self._k,
            self.step,
            n,
            self._theta,
            self._omega,
            self._p,
            self._p_max,
            _ALWAYS,
            np.array([self._lever]),
            _NO_SINE,
            J,
            L,
        )
        self._theta, self._omega, self._p = float(th), float(om), float(p)
        return int(taken), bool(bad)

    def _failure(self) -> str:
        return (
            f"the run left the physical bounds at t = {self.t:.6g} s (θ₂ = "
            f"{math.degrees(self._theta):.6g}°, p = {self._p * 1e-5:.6g} bar): reduce "
            "the step, or the load carries the joint past the crank's reach"
        )

    def _params(self):
        J = self._J
        return J if self._supply == J.supply_pressure else J._replace(supply_pressure=self._supply)

    # outputs ---------------------------------------------------------------------------
    def outputs(self) -> dict:
        """The state and what follows from it, SI floats (names and units: `OUTPUTS`)."""
        th, om, p = self._theta, self._omega, self._p
        x, xd, torque, q, e = joint_outputs(th, om, p, self._lever, self._params())
        return {
            "theta": th,
            "omega": om,
            "x": float(x),
            "x_dot": float(xd),
            "p": p,
            "torque": float(torque),
            "supply_flow": float(q),
            "valve_opening": float(e),
        }

    # state -----------------------------------------------------------------------------
    def get_state(self) -> np.ndarray:
        """The complete state as floats (`STATE_FIELDS`): time bookkeeping, (θ₂, ω, p),
        the inputs held; [`set_state`][hydroarm.JointStepper.set_state] restores it exactly."""
        return np.array(
            [
                self._t0,
                float(self._k),
                self._requested,
                self._theta,
                self._omega,
                self._p,
                self._lever,
                self._supply,
                self._torque,
                float(self._failed),
            ]
        )

    def set_state(self, s) -> None:
        """Restore a state from [`get_state`][hydroarm.JointStepper.get_state] (of a stepper of the
        same joint)."""
        s = np.asarray(s, dtype=float)
        if s.shape != (len(STATE_FIELDS),):
            raise HydroarmError("state", f"must hold {len(STATE_FIELDS)} numbers, got {s.shape}")
        if not np.all(np.isfinite(s)):
            raise HydroarmError("state", "must be finite numbers")
        self._t0 = float(s[0])
        self._k = int(s[1])
        self._requested = float(s[2])
        self._theta, self._omega, self._p = float(s[3]), float(s[4]), float(s[5])
        self._lever = float(s[6])
        self._supply = float(s[7])
        self._torque = float(s[8])
        self._failed = bool(s[9])
