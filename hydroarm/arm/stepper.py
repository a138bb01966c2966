"""The whole arm advanced piece by piece, its four levers set between the pieces.

`ArmStepper` is `simulate_arm` for a caller that owns the
clock (a co-simulation master, a live application): it takes whole steps of the arm's own
kernel (`arm_integrate`, resumed from the stepper's state at each
call, recording only the last step), the pose loads and the shared pump's supply pressure
computed in the step as in the whole run. (A step function factored out of the kernel's
loop, called by the loop and the stepper, cost the whole arm 12-37 % in
benchmarks/arm_speed.py; resuming the loop costs it nothing.) Time and inputs as
[`hydroarm.model.stepper.JointStepper`][hydroarm.JointStepper]: whole steps t = k·h, the part of a
step left over carried to the next call, each lever held over the steps a call takes (zero-order
hold). A lever trace that is constant over each call's span (a step lever, a lever held
between communication points) gives ``simulate_arm``'s trajectory bit for bit.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.equations import actuator_torque, jack_position
from ..core.params import J_SUPPLY, L_INERTIA, L_TORQUE, joint_at
from ..core.servo import P_FORCE, P_MASS, S_Q, S_V, actuator_force, actuator_motion
from ..errors import HydroarmError
from ..integrators import registry
from ..model.stepper import StepClock
from ..model.stepper import finite as _finite
from .energy import component_flow_traces, flow_traces
from .model import ArmScenario, _component_pressure, arm_integrate, kernel_inputs

# per-joint outputs of ArmStepper.outputs(): name, unit, meaning
JOINT_OUTPUTS: tuple[tuple[str, str, str], ...] = (
    ("angle", "rad", "articulation angle (servo angle + offset)"),
    ("theta", "rad", "servo angle θ₂"),
    ("omega", "rad/s", "angular velocity"),
    ("x", "m", "jack (actuator) position"),
    ("x_dot", "m/s", "jack (actuator) velocity"),
    ("p", "Pa", "load pressure (a component joint: force-equivalent A_A·p_A − A_B·p_B over A_A)"),
    ("torque", "N.m", "actuator torque at the joint"),
    ("supply_flow", "m3/s", "flow the joint's valve draws from the supply"),
)
# outputs of the whole arm
ARM_OUTPUTS: tuple[tuple[str, str, str], ...] = (
    ("supply_pressure", "Pa", "supply pressure of the last step (the shared pump's)"),
    ("valve_flow", "m3/s", "flow the valves draw from the supply, all joints"),
    ("pump_flow", "m3/s", "flow the pump delivers (the rest goes over the relief valve)"),
)


class ArmStepper(StepClock):
    """The whole arm of an `ArmScenario` advanced in fixed steps
    from its start, its levers set between calls (module doc).

    Parameters
    ----------
    sc : the arm (joints, geometry, power pack, initial angles; its lever inputs give the
        levers' start positions, at t = 0)
    method, step : the fixed-step method and step h [s] (default: the scenario's)
    """

    def __init__(self, sc: ArmScenario, *, method: str | None = None, step: float | None = None):
        method = sc.method if method is None else method
        if method not in registry.fixed_step_methods():
            raise HydroarmError(
                "solver.method",
                f"must be {' or '.join(registry.fixed_step_methods())}, got {method!r}",
            )
        h = sc.step if step is None else _finite("solver.step", step)
        if not h > 0:
            raise HydroarmError("solver.step", f"must be a positive time, got {step!r}")
        self.scenario = sc
        self.method = method
        self.step = h
        self._code = registry.method(method).code
        self.names = [j.name for j in sc.joints]
        k = kernel_inputs(sc)
        self._k_in = k
        nj = len(self.names)
        self._pump_flow = float(sc.power_pack.pump_flow)
        self._p_relief = float(sc.power_pack.supply_pressure)
        self._th = k["TH0"].copy()
        self._om = np.zeros(nj)
        self._pp = k["PP0"].copy()
        self._cs = k["CS0"].copy()
        self._PM = k["PM"]
        self._CP = k["CP"]
        # one-point lever tables (a value at every time), set from the levers before a call
        self._TT = np.full((nj, 1), -math.inf)
        self._TY = np.array([[float(sc.inputs[n](0.0)[0])] for n in self.names])
        self._NT = np.ones(nj, dtype=np.int64)
        self._SINE = np.zeros((nj, 3))
        self._k = 0
        self._requested = 0.0
        self._ps = self._p_relief
        self._failed = False
        self._kernel(0, resume=False)  # the run's start: supplies, pose loads (no step)

    # inputs ----------------------------------------------------------------------------
    @property
    def levers(self) -> dict[str, float]:
        """Lever positions [m] (jack coordinates) by joint name, held until set again.
        Assigning a dictionary sets the joints it names (a copy is returned: set through
        assignment or `set_lever`)."""
        return {n: float(self._TY[j, 0]) for j, n in enumerate(self.names)}

    @levers.setter
    def levers(self, values: dict) -> None:
        new = {}
        for n, y in dict(values).items():
            if n not in self.names:
                raise HydroarmError(
                    "levers", f"no joint {n!r} in this arm ({', '.join(self.names)})"
                )
            new[n] = _finite(f"levers.{n}", y)
        for n, y in new.items():
            self._TY[self.names.index(n), 0] = y

    def set_lever(self, name: str, y: float) -> None:
        """Set joint ``name``'s lever position y [m]."""
        self.levers = {name: y}

    def lever_for_angle(self, name: str, angle: float) -> float:
        """The lever position [m] that holds joint ``name`` at articulation angle ``angle``
        [rad] (as an arm file's inputs in degrees are read)."""
        return float(self.scenario.joint(name).lever_for_angle(angle))

    @property
    def hand_mass(self) -> float:
        """The payload at the hand point [kg] (`ArmGeometry.hand_mass`, the scenario's at the
        start). Assigning it changes the mass the pose loads (gravity torques and inertias) carry
        from the next step on: an entry of the geometry the kernel takes, the kernel not recompiled.
        It is a parameter, not part of `get_state`."""
        return float(self._k_in["G"].hand_mass)

    @hand_mass.setter
    def hand_mass(self, mass: float) -> None:
        m = _finite("arm.hand_mass", mass)
        if m < 0:
            raise HydroarmError("arm.hand_mass", f"must not be negative, got {mass!r}")
        self._k_in["G"] = self._k_in["G"]._replace(hand_mass=m)

    def servo_angles(self) -> np.ndarray:
        """The joints' servo angles θ [rad] now (a copy; articulation angle = θ + offset)."""
        return self._th.copy()

    def stop_joints(self, theta, joints) -> None:
        """Stop the joints ``joints`` (indices) at servo angles ``theta[j]`` [rad] at rest:
        their angle set, their angular velocity zero, their pressures (and a component
        joint's other states) kept; an inelastic stop at a contact, applied between calls."""
        for j in joints:
            a = _finite(f"theta.{self.names[j]}", theta[j])
            self._th[j] = a
            self._om[j] = 0.0
            if self._k_in["comp"][j]:
                self._cs[j, S_Q] = a
                self._cs[j, S_V] = 0.0

    # time ------------------------------------------------------------------------------
    def _steps(self, n: int) -> tuple[int, bool]:
        return self._kernel(n, resume=True)

    def _failure(self) -> str:
        return (
            f"the run left the physical bounds at t = {self.t:.6g} s (a state non-finite, "
            "past a crank's dead centre or beyond the pressure bound): reduce the step"
        )

    def _kernel(self, n: int, resume: bool) -> tuple[int, bool]:
        """``n`` steps of the arm's kernel (`arm_integrate`, resumed
        from this state, recording only the last); the state taken from its last record.
        Returns (steps taken, whether the run left the physical bounds)."""
        k = self._k_in
        t, th, om, pp, _, ps, bad, cs = arm_integrate(
            self._code,
            self._th,
            self._om,
            self._pp,
            self._k * self.step,
            self.step,
            n,
            max(n, 1),
            self._TT,
            self._TY,
            self._NT,
            self._SINE,
            self._PM,
            k["kinds"],
            k["pose"],
            k["offsets"],
            k["own_inertia"],
            k["G"],
            self._pump_flow,
            self._p_relief,
            k["comp"],
            self._cs,
            self._CP,
            -1,
            0.0,
            0.0,
            math.inf,
            resume,
            k["PP0"],
        )
        if bad >= 0:  # the kernel stops before recording the failed step: its start state
            return int(bad), True
        self._th[:] = th[-1]
        self._om[:] = om[-1]
        self._pp[:] = pp[-1]
        for j in np.flatnonzero(k["comp"]):
            self._cs[j] = cs[-1, j]
        if n > 0:
            self._ps = float(ps[-1])
        return n, False

    # outputs ---------------------------------------------------------------------------
    def outputs(self) -> dict:
        """``{joint name: {output: value}}`` (`JOINT_OUTPUTS`) and the arm's
        `ARM_OUTPUTS` at the top level; SI floats."""
        k = self._k_in
        nj = len(self.names)
        PM = self._PM.copy()
        _, QS, XD, _, _ = flow_traces(
            self._th[None, :],
            self._om[None, :],
            self._pp[None, :],
            self._TY[:, 0][None, :].copy(),
            np.array([self._ps]),
            PM,
        )
        out: dict = {}
        for j, n in enumerate(self.names):
            th, om, p = float(self._th[j]), float(self._om[j]), float(self._pp[j])
            if k["comp"][j]:
                s, P = self._cs[j], self._CP[j]
                qs, _, _, _, xd = component_flow_traces(s[None, :].copy(), P)
                x, v_x, arm = actuator_motion(s[S_Q], s[S_V], P)
                row = {
                    "x": float(x),
                    "x_dot": float(xd[0]),
                    "p": float(_component_pressure(s, P)),
                    "torque": float(actuator_force(s, v_x, P) * arm),
                    "supply_flow": float(qs[0]),
                }
            else:
                J = joint_at(PM, j)
                row = {
                    "x": float(jack_position(th, J)),
                    "x_dot": float(XD[0, j]),
                    "p": p,
                    "torque": float(actuator_torque(th, p, J)),
                    "supply_flow": float(QS[0, j]),
                }
            out[n] = {
                "angle": th + float(k["offsets"][j]),
                "theta": th,
                "omega": om,
                **row,
            }
        qv = sum(out[n]["supply_flow"] for n in self.names)
        out["supply_pressure"] = self._ps
        out["valve_flow"] = qv
        out["pump_flow"] = self._pump_flow if math.isfinite(self._pump_flow) else max(qv, 0.0)
        assert len(out) == nj + len(ARM_OUTPUTS)
        return out

    # state -----------------------------------------------------------------------------
    def get_state(self) -> np.ndarray:
        """The complete state as one float array: step count, requested time, last supply
        pressure, failed flag; per joint (θ, ω, p, lever, the parameter table's supply, pose
        torque and inertia, the component load entries) and the component states.
        `set_state` restores it exactly."""
        head = np.array([float(self._k), self._requested, self._ps, float(self._failed)])
        per = np.column_stack(
            [
                self._th,
                self._om,
                self._pp,
                self._TY[:, 0],
                self._PM[:, J_SUPPLY],
                self._PM[:, L_TORQUE],
                self._PM[:, L_INERTIA],
                self._CP[:, P_FORCE],
                self._CP[:, P_MASS],
            ]
        )
        return np.concatenate([head, per.ravel(), self._cs.ravel()])

    @property
    def state_size(self) -> int:
        nj = len(self.names)
        return 4 + 9 * nj + self._cs.size

    def set_state(self, s) -> None:
        """Restore a state from `get_state` (of a stepper of the same arm)."""
        s = np.asarray(s, dtype=float)
        if s.shape != (self.state_size,):
            raise HydroarmError("state", f"must hold {self.state_size} numbers, got {s.shape}")
        nj = len(self.names)
        self._k = int(s[0])
        self._requested = float(s[1])
        self._ps = float(s[2])
        self._failed = bool(s[3])
        per = s[4 : 4 + 9 * nj].reshape(nj, 9)
        self._th[:] = per[:, 0]
        self._om[:] = per[:, 1]
        self._pp[:] = per[:, 2]
        self._TY[:, 0] = per[:, 3]
        self._PM[:, J_SUPPLY] = per[:, 4]
        self._PM[:, L_TORQUE] = per[:, 5]
        self._PM[:, L_INERTIA] = per[:, 6]
        self._CP[:, P_FORCE] = per[:, 7]
        self._CP[:, P_MASS] = per[:, 8]
        self._cs[:] = s[4 + 9 * nj :].reshape(self._cs.shape)
