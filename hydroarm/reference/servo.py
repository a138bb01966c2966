"""A [`ServoScenario`][hydroarm.ServoScenario] on the servo's own hand-fused kernel: the test
oracle of its circuit on the system kernel (`hydroarm.reference`). No stability check; the
same `ServoResult` columns, summary and energy account as
[`ServoScenario.run`][hydroarm.ServoScenario.run]."""

from __future__ import annotations

import numpy as np

from ..errors import HydroarmError
from ..integrators import registry
from ..metrics.servo import DEFAULT_BAND, N_METRICS
from ..model.servo import ServoResult, ServoScenario
from ..model.servo_rows import check_metrics_request
from .servo_adaptive import integrate_servo_adaptive
from .servo_kernel import has_dry_friction, integrate
from .servo_metrics import row_metrics


def run_on_servo_kernel(scenario: ServoScenario) -> ServoResult:
    """Integrate ``scenario`` on the servo kernel (`hydroarm.reference.servo_kernel.integrate`;
    the adaptive method: Radau on its right-hand side,
    `hydroarm.reference.servo_adaptive.integrate_servo_adaptive`)."""
    P = scenario.vector()
    s0 = scenario.initial_state()
    ref = scenario.reference
    m = registry.method(scenario.method)
    if m.fixed_step:
        t, states, r, bad = integrate(
            m.code,
            s0,
            0.0,
            scenario.step,
            scenario.nsteps,
            scenario.record_every,
            ref.times,
            ref.positions,
            ref.sine,
            P,
        )
        if bad >= 0:
            raise HydroarmError(
                "solver.step",
                f"the run left the physical bounds at t = {bad * scenario.step:.6g} s (a "
                "state not finite): reduce the step",
            )
        return ServoResult(scenario, t, states, r)
    if has_dry_friction(P):
        raise HydroarmError(
            "solver.method",
            "'adaptive' cannot integrate dry friction (non-smooth); use euler or rk4",
        )
    n = scenario.nsteps // scenario.record_every
    t = np.arange(n + 1) * scenario.step * scenario.record_every
    states = integrate_servo_adaptive(
        s0, 0.0, float(t[-1]), t, ref.times, ref.positions, ref.sine, P
    )
    return ServoResult(scenario, t, states, ref(t))


def metrics_on_servo_kernel(scenario: ServoScenario, band: float = DEFAULT_BAND) -> np.ndarray:
    """The on-the-fly metrics of ``scenario`` (`hydroarm.metrics.servo.METRICS`, SI) on the
    servo kernel (the compiled `hydroarm.reference.servo_metrics.row_metrics`): the oracle of
    [`ServoScenario.metrics_vector`][hydroarm.ServoScenario.metrics_vector]."""
    check_metrics_request(scenario.method, band)
    m = registry.method(scenario.method)
    t_step, step_from = scenario.step_reference()
    ref = scenario.reference
    M = np.empty(N_METRICS)
    row_metrics(
        m.code,
        scenario.initial_state(),
        0.0,
        scenario.step,
        scenario.nsteps,
        ref.times,
        ref.positions,
        ref.sine,
        scenario.vector(),
        t_step,
        step_from,
        band,
        M,
    )
    return M
