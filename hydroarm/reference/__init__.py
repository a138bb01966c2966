"""The old kernels, held apart as references (issue 28: one physics).

Every product path steps the system kernel (`hydroarm.core.circuit`,
`hydroarm.integrators.system`). What is kept here are the old kernels' drivers, the test
oracles and benchmark references the circuit's runs are compared with:

    servo           `run_on_servo_kernel` / `metrics_on_servo_kernel`: a
                    [`ServoScenario`][hydroarm.ServoScenario] on the servo kernel
                    (`hydroarm.reference.servo_kernel`)
    servo_metrics   the servo kernel's on-the-fly metrics (`row_metrics`,
                    `run_many_metrics`)
    servo_adaptive  Radau on the servo's right-hand side (the adaptive method's oracle)
    arm_decoupled   the decoupled arm model's loop (`arm_integrate`, `simulate_decoupled`)

No product package imports this one (an import-linter ``forbidden`` contract in
pyproject.toml); the tests and benchmarks do.
"""

from __future__ import annotations

from .servo import metrics_on_servo_kernel, run_on_servo_kernel

__all__ = ["metrics_on_servo_kernel", "run_on_servo_kernel"]
