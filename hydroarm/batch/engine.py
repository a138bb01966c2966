"""The batch engine: many step-input scenarios at compiled speed, metrics on the fly.

The engine is the on-the-fly metric kernel of `hydroarm.metrics.online` (which a
single run's [`metrics`][hydroarm.SimulationResult.metrics] also uses, so that the
two share one definition of every metric), run over many scenarios in parallel."""

from ..metrics.online import (
    LANES,
    METRICS,
    N_METRICS,
    failure_reason,
    run_batch,
    run_many,
    run_scenarios,
)

__all__ = [
    "LANES",
    "METRICS",
    "N_METRICS",
    "failure_reason",
    "run_batch",
    "run_many",
    "run_scenarios",
]
