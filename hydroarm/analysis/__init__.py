"""Analyses of a servo built on the model layer: linearisation about an operating point,
transfer functions, margins and bandwidth on python-control (issue 15; docs/linear.md)."""

from .frequency import FrequencyResponse, frequency_response
from .linear import LinearModel, linear_variation, linearize

__all__ = [
    "FrequencyResponse",
    "LinearModel",
    "frequency_response",
    "linear_variation",
    "linearize",
]
