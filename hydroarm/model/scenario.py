"""Scenarios and the single-scenario simulation entry point."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..core.equations import crank_reach, holding_pressure, pressure_bound
from ..core.kinematics import crank_angle
from ..core.params import JointParams, LoadParams
from ..errors import HydroarmError, StabilityError
from ..integrators import registry
from ..integrators.fixed import (
    FAILURES,
    OUT_OF_BOUNDS,
    PAST_DEAD_CENTRE,
    UNSTABLE,
    failure_code,
)
from ..integrators.stability import (
    largest_stable_step_for,
    oscillation_growth_rate,
    scenario_jacobians,
    stable_step_limit,
)
from ..metrics.step import DEFAULT_METRIC_OPTIONS, MetricOptions
from .joint import Load, ServoJoint, pack
from .lever import LeverInput, step
from .result import SimulationResult

METHODS = registry.method_names()  # ("euler", "rk4", "adaptive"): hydroarm.METHODS
DEFAULT_STEP = 10e-6  # [s]
MAX_STEPS = 10**9  # a run needing more fixed steps is refused: the step is too small


@dataclass(frozen=True)
class Scenario:
    """Everything one simulation of the paper's joint needs, in SI units.

    Parameters
    ----------
    joint : ServoJoint
        The servo joint.
    load : Load
        Its load.
    lever : LeverInput
        Lever input y(t) [m].
    initial_angle : float
        θ₂ at t = t0 [rad]; the jack starts at rest.
    initial_pressure : float, optional
        Load pressure at t0 [Pa] (default: the pressure that holds the load).
    duration : float
        Simulated time [s].
    method : str
        ``"euler"`` (the paper's eqs. 5–7), ``"rk4"`` or ``"adaptive"``.
    step : float
        Fixed step T [s] (``adaptive``: the output interval).
    record_every : int
        Keep every K-th step [-] (the paper's "number of values to print").
    t0 : float
        Start time [s].
    direction : str, optional
        ``"raise"``/``"lower"`` for the paper's saturation tests, else None.
    name : str
        Label.
    metric_options : MetricOptions
        Thresholds of the step metrics ([`MetricOptions`][hydroarm.MetricOptions]).
    meta : dict
        Where the scenario came from (a file's sections), for reports.
    """

    joint: ServoJoint
    load: Load
    lever: LeverInput
    initial_angle: float
    initial_pressure: float | None = None
    duration: float = 1.5
    method: str = "euler"
    step: float = DEFAULT_STEP
    record_every: int = 1
    t0: float = 0.0
    direction: str | None = None
    name: str = "scenario"
    metric_options: MetricOptions = DEFAULT_METRIC_OPTIONS
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        registry.method(self.method)  # an unknown name: one clear error
        for f in ("duration", "step"):
            v = getattr(self, f)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise HydroarmError(f"solver.{f}", f"must be a positive finite time, got {v!r}")
        if self.step > self.duration:
            raise HydroarmError("solver.step", "is longer than the duration")
        if not (isinstance(self.record_every, int) and self.record_every >= 1):
            raise HydroarmError(
                "solver.record_every", f"must be a whole number ≥ 1, got {self.record_every!r}"
            )
        if not math.isfinite(self.initial_angle):
            raise HydroarmError("initial.angle", "is not a finite number")
        if abs(self.initial_angle) >= self.joint.max_angle:
            raise HydroarmError("initial.angle", "is beyond the crank's reach (|θ₂| < n·90°)")
        if not isinstance(self.metric_options, MetricOptions):
            raise HydroarmError("metrics", "must be a MetricOptions")

    @property
    def params(self) -> tuple[JointParams, LoadParams]:
        """(joint, load) as the compiled kernels take them."""
        return self.joint.params(), self.load.params()

    @property
    def row(self) -> np.ndarray:
        """The scenario's row of a batch table (`pack`)."""
        return pack(self.joint, self.load)

    @property
    def nsteps(self) -> int:
        return int(round(self.duration / self.step))

    @property
    def target(self) -> float:
        """Final lever position [m]."""
        return self.lever.final

    def replace(self, **changes) -> Scenario:
        return replace(self, **changes)

    def start_pressure(self) -> float:
        if self.initial_pressure is not None:
            return self.initial_pressure
        return float(holding_pressure(self.initial_angle, *self.params))

    def target_angle(self) -> float:
        return float(
            crank_angle(self.target, self.joint.crank_radius, self.joint.gear_ratio, 0.999)
        )

    def integrate(self, record_every: int | None = None) -> SimulationResult:
        """Run the scenario (no step checks: [`simulate`][hydroarm.simulate] makes them), keeping
        every ``record_every``-th state (default: the scenario's)."""
        J, L = self.params
        lev = self.lever
        p0 = self.start_pressure()
        t, th, om, pp, y, bad = registry.run(
            self.method,
            self.initial_angle,
            0.0,
            p0,
            self.t0,
            self.step,
            self.nsteps,
            self.record_every if record_every is None else record_every,
            lev.times,
            lev.positions,
            lev.sine,
            J,
            L,
        )
        if bad >= 0:
            raise run_failure(self, float(t[-1]), float(th[-1]), float(om[-1]), float(pp[-1]), p0)
        return SimulationResult(t=t, theta=th, omega=om, p=pp, y=y, scenario=self)

    def largest_stable_step(self, method: str | None = None) -> float:
        """Largest stable fixed step [s] of ``method`` for this scenario."""
        method = method or self.method
        if not registry.method(method).fixed_step:
            return math.inf
        J = scenario_jacobians(
            self.initial_angle, self.target_angle(), *self.params, self.joint.valve_saturation
        )
        return largest_stable_step_for(method, J)

    def check_step_count(self) -> None:
        """Refuse a step so small that the run needs more than `MAX_STEPS` steps."""
        if self.nsteps > MAX_STEPS:
            raise HydroarmError(
                "solver.step",
                f"{format_time(self.step)} is too small: {self.duration:g} s would take "
                f"{self.nsteps:.3g} steps (at most {MAX_STEPS:.0e})",
            )

    def check_step(self) -> None:
        """Refuse a fixed step above the method's stability limit, or so small that the run
        needs more than `MAX_STEPS` steps (one clear error)."""
        self.check_step_count()
        if not registry.method(self.method).fixed_step:
            return
        h = stable_step_limit(
            self.method, self.step, self.initial_angle, self.target_angle(), *self.params
        )
        if h is None:
            return
        raise StabilityError(
            "solver.step",
            f"{format_time(self.step)} is too large to be stable with method "
            f"'{self.method}' for this scenario; the largest stable step is {format_time(h)}",
            h,
        )


def format_time(s: float) -> str:
    if s >= 1:
        return f"{s:.4g} s"
    if s >= 1e-3:
        return f"{s * 1e3:.4g} ms"
    return f"{s * 1e6:.4g} us"


def saturation_test(
    joint: ServoJoint,
    load: Load,
    direction: str,
    *,
    low_angle: float = math.radians(-60.0),
    high_angle: float = math.radians(60.0),
    **kwargs,
) -> Scenario:
    """The paper's saturation-velocity test: the lever moved at once over the full range.

    Parameters
    ----------
    joint : ServoJoint
        The joint.
    load : Load
        Its load.
    direction : str
        ``"raise"``: from hanging (θ₂ = −60°) to 30° above horizontal (θ₂ = +60°);
        ``"lower"``: back.
    low_angle : float
        The hanging angle θ₂ [rad] (−60°).
    high_angle : float
        The raised angle θ₂ [rad] (+60°).
    **kwargs
        Further fields of the [`Scenario`][hydroarm.Scenario] (``method``, ``step`` [s],
        ``duration`` [s]: by default long enough for the motion and its settling).

    Returns
    -------
    Scenario
        The test, named after the load and the direction.
    """
    if direction not in ("raise", "lower"):
        raise HydroarmError("direction", f"must be 'raise' or 'lower', got {direction!r}")
    a0, a1 = (low_angle, high_angle) if direction == "raise" else (high_angle, low_angle)
    for name, a in (("low_angle", low_angle), ("high_angle", high_angle)):
        if abs(a) >= joint.max_angle:
            raise HydroarmError(name, "is beyond the crank's reach")
    y0, y1 = joint.jack_position(a0), joint.jack_position(a1)
    if "duration" not in kwargs:
        kwargs["duration"] = default_duration(joint, abs(y1 - y0))
    return Scenario(
        joint=joint,
        load=load,
        lever=step(y0, y1, 0.0),
        initial_angle=a0,
        direction=direction,
        name=f"{load.name} {direction}",
        **kwargs,
    )


def default_duration(joint: ServoJoint, travel: float) -> float:
    """Long enough for a full-speed motion at half the no-load velocity and its settling."""
    return round(2.0 * travel / joint.no_load_velocity + 12 * joint.no_load_time_constant, 2)


def simulate(
    scenario: Scenario,
    *,
    check_stability: bool = True,
    metric_options: MetricOptions | None = None,
):
    """Run one scenario.

    Parameters
    ----------
    scenario : Scenario
        The scenario (the paper's joint).
    check_stability : bool
        Refuse, before the run, a fixed step too large for the joint (a
        [`StabilityError`][hydroarm.StabilityError]).
    metric_options : MetricOptions, optional
        Thresholds of the step metrics, in place of the scenario's (used by ``.metrics()`` and
        ``.metric_values()``).

    Returns
    -------
    SimulationResult
        The trajectory (t [s], θ₂ [rad], ω [rad/s], p [Pa], y [m]) and its metrics.
    """
    sc = scenario if metric_options is None else scenario.replace(metric_options=metric_options)
    if check_stability:
        sc.check_step()
    else:
        sc.check_step_count()
    return sc.integrate()


# the bound a diverging run crossed, for the error text (followed by the bound in bar)
FAILURE_TEXT = {
    UNSTABLE: "a non-finite state; the pressure bound is",
    OUT_OF_BOUNDS: "|p| above the pressure bound",
}


def run_failure(
    sc: Scenario, t: float, theta: float, omega: float, p: float, p0: float
) -> HydroarmError:
    """The error of a run that left the physical bounds at time t in state (θ₂, ω, p)."""
    J, L = sc.params
    th_max = float(crank_reach(J))
    p_max = float(pressure_bound(p0, J, L))
    code = failure_code(theta, omega, p, th_max, p_max)
    h = sc.largest_stable_step()
    rate = (
        oscillation_growth_rate(sc.initial_angle, sc.target_angle(), J, L)
        if sc.step <= h
        else -math.inf
    )
    if rate > 0:  # the step is stable: the model itself diverges
        no_leak = sc.joint.leakage_coefficient == 0
        crossed = (
            f"past the crank's reach, its dead centre |θ₂| = n·90° = {math.degrees(th_max):.4g}°"
            if code == PAST_DEAD_CENTRE
            else f"{FAILURE_TEXT[code]} {p_max * 1e-5:.4g} bar"
        )
        return StabilityError(
            "joint.leakage_coefficient" if no_leak else "joint",
            f"the servo loop is unstable: held at rest its oscillation grows at {rate:.3g}/s, "
            f"so the run diverged and left the physical bounds at t = {t:.6g} s (θ₂ = "
            f"{math.degrees(theta):.6g}°, p = {p * 1e-5:.6g} bar; {crossed}); "
            + (
                "with no leakage nothing damps the oil column: give the joint leakage "
                "(the paper's model needs it) or viscous friction"
                if no_leak
                else "damp the joint (leakage, viscous friction) or lower its flow gain"
            )
            + f" (the step, {format_time(sc.step)}, is not the cause)",
            h,
        )
    hint = (
        f"reduce the step (largest stable estimate {format_time(h)})"
        if sc.step > h
        else "the load carries the joint there: lighten the load or raise the supply pressure"
    )
    if code == PAST_DEAD_CENTRE:
        return StabilityError(
            "solver.step" if sc.step > h else "load",
            f"the joint swung past the crank's dead centre (|θ₂| = n·90° = "
            f"{math.degrees(th_max):.4g}°) at t = {t:.6g} s (θ₂ = {math.degrees(theta):.6g}°, "
            f"p = {p * 1e-5:.6g} bar), where the model ends: {hint}",
            h,
        )
    return StabilityError(
        "solver.step",
        f"the run left the physical bounds at t = {t:.6g} s (p = {p * 1e-5:.6g} bar, "
        f"θ₂ = {math.degrees(theta):.6g}°; {FAILURES[code]}): reduce the step "
        f"(largest stable estimate {format_time(h)})",
        h,
    )
