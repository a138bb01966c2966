"""hydroarm: simulation and evaluation of hydraulic servo-actuated prosthetic limbs.

Implements the digital simulation of the UCL hydraulic arm prosthesis (shoulder elevation,
Appendix I of the paper) as a general hydraulic servo joint, with the paper's evaluation
methods as functions that work on simulated and measured traces alike.

Quick start::

    import hydroarm as ha
    joint = ha.shoulder_elevation()            # built-in 'paper-calibrated' parameters
    sc = ha.saturation_test(joint, ha.paper_load(6), "raise")
    res = ha.simulate(sc)
    res.summary()["saturation_velocity_mm_s"]  # ≈ 24.8 (Table III: 25.1)

    servo = ha.load_scenario("examples/position_servo.toml")  # a servo built from components
    servo.run().summary()["final_position_m"]
"""

from importlib.metadata import version as _version

# first, before any kernel is decorated: numba's disk cache follows the sources each
# kernel imports (installed by importing it)
from .core import jit_cache as _jit_cache  # noqa: F401

# isort: split
from .analysis.design import DesignResult, DesignStudy, design, read_design_file
from .analysis.evaluate import Card, Evaluation, read_evaluation_file
from .analysis.fit import FitProblem, FitResult, Trace, fit, read_fit_file
from .analysis.frequency import FrequencyResponse, frequency_response
from .analysis.linear import LinearModel, linear_variation, linearize
from .analysis.sensitivity import (
    SensitivityResult,
    SensitivityStudy,
    read_sensitivity_file,
    sensitivity,
)
from .analysis.targets import Target
from .errors import HydroarmError, StabilityError
from .fmu import export_fmu
from .io.catalog import no_load, paper_load, parameter_set_names
from .io.schema import load_scenario, parameter_set, shoulder_elevation
from .metrics.step import MetricOptions, saturation_velocity, step_metrics, time_constants
from .model.joint import Load, ServoJoint
from .model.lever import LeverInput, ramp, sine, step
from .model.result import SimulationResult
from .model.scenario import METHODS, Scenario, saturation_test, simulate
from .model.servo import ServoResult, ServoScenario, run_servos
from .model.stepper import JointStepper
from .paper.card import evaluate

__version__ = _version("hydroarm")

__all__ = [
    "Card",
    "DesignResult",
    "DesignStudy",
    "Evaluation",
    "FitProblem",
    "FitResult",
    "FrequencyResponse",
    "HydroarmError",
    "JointStepper",
    "LeverInput",
    "LinearModel",
    "Load",
    "METHODS",
    "MetricOptions",
    "Scenario",
    "SensitivityResult",
    "SensitivityStudy",
    "ServoJoint",
    "ServoResult",
    "ServoScenario",
    "SimulationResult",
    "StabilityError",
    "Target",
    "design",
    "evaluate",
    "export_fmu",
    "fit",
    "frequency_response",
    "linear_variation",
    "linearize",
    "load_scenario",
    "no_load",
    "paper_load",
    "parameter_set",
    "parameter_set_names",
    "ramp",
    "read_design_file",
    "read_evaluation_file",
    "read_fit_file",
    "read_sensitivity_file",
    "run_servos",
    "saturation_test",
    "saturation_velocity",
    "sensitivity",
    "shoulder_elevation",
    "simulate",
    "sine",
    "step",
    "step_metrics",
    "time_constants",
    "Trace",
]
