"""The old kernels, held apart as references (issue 28: one physics).

Every product path steps the system kernel (`hydroarm.core.circuit`,
`hydroarm.integrators.system`). What is kept here is the hand-fused servo kernel's
driver, the test oracle and benchmark reference the circuit's runs are compared with:

    servo   `run_on_servo_kernel` / `metrics_on_servo_kernel`: a
            [`ServoScenario`][hydroarm.ServoScenario] on the servo kernel
            (`hydroarm.integrators.servo`, `hydroarm.reference.servo_metrics.row_metrics`,
            Radau on its right-hand side for the adaptive method)

No product package imports this one (an import-linter ``forbidden`` contract in
pyproject.toml); the tests and benchmarks do.
"""

from __future__ import annotations

from .servo import metrics_on_servo_kernel, run_on_servo_kernel

__all__ = ["metrics_on_servo_kernel", "run_on_servo_kernel"]
