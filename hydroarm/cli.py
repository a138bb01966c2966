"""Command-line interface: ``hydroarm simulate | linearize | reproduce | validate | arm | sweep |
fit | evaluate | sensitivity | fmu | explore | params | warmup | examples``.

Bad input gives one line ``hydroarm: error: <field>: <problem>`` on stderr and exit status 2;
an interruption (Ctrl-C, SIGTERM) one line ``hydroarm: interrupted`` and exit status 130;
an unexpected failure (a bug) one line ``hydroarm: internal error: ...`` and exit status 1.
Output paths are checked before any work starts (`hydroarm.files`). See docs/errors.md.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import select
import signal
import sys
import threading
import time
import tomllib
from importlib.metadata import version
from pathlib import Path

import numpy as np

from .analysis.circuit_linear import linearize_circuit
from .analysis.design import design, read_design_file
from .analysis.evaluate import card_lines as evaluation_card_lines
from .analysis.evaluate import read_evaluation_file
from .analysis.fit import MAX_STARTS, STARTS_WHY, fit, read_fit_file
from .analysis.frequency import MAX_FREQUENCIES, default_amplitudes, frequency_response
from .analysis.linear import linear_variation, linear_variation_figure, linearize
from .analysis.mechanism_card import mechanism_card
from .analysis.sensitivity import read_sensitivity_file, sensitivity
from .analysis.systems import (
    check_system_doc,
    evaluate_system,
    read_study_doc,
    read_system_design,
    read_system_evaluation,
    run_system_design,
)
from .analysis.targets import loo_groups
from .arm.config import load_arm_text
from .arm.expand import expand_file, simulate_arm, simulate_motion
from .arm.mechanism_run import run_mechanism
from .arm.stepper import ArmStepper
from .batch.circuit_sweep import CircuitSweep, circuit_summary
from .batch.saturation import passes_horizontal
from .batch.servo_sweep import ServoSweep, servo_summary
from .batch.sweep import load_sweep, run_sweep, summary
from .batch.tables import EXPORT_SUFFIXES, check_export
from .batch.traces import run_traces, scenario_traces
from .core import tree as tree_kernel
from .core.circuit import system as circuit_kernel
from .core.servo import FEEDBACK_MECHANICAL, LOAD_MASS, P_FEEDBACK, P_LOAD
from .errors import HydroarmError
from .explore import launch as explore_launch
from .explore.pages import page_url, session_token
from .files import (
    Interrupted,
    atomic_write_text,
    check_output_file,
    check_output_folder,
    shown_path,
)
from .fmu import export_fmu
from .fmu.check import check_fmu
from .integrators import observers as observer_kernel
from .integrators import system as system_kernel
from .integrators.fixed import integrate
from .integrators.registry import METHODS, CompileNotice, fixed_step_methods
from .integrators.system import STEPPERS as CIRCUIT_STEPPERS
from .io.catalog import DEFAULT_SET, paper_load, parameter_set_info, parameter_set_names
from .io.circuit import circuit_from_doc, is_circuit_path, is_mechanism_path, load_circuit
from .io.examples import copy_examples, examples_folder, list_examples
from .io.progress import Progress
from .io.schema import load_scenario, load_scenario_text, parameter_set, weight_quantity
from .io.sections import MAX_RECORDED, check_run_size, read_toml_file, whole_number
from .io.servo_circuit import circuit_toml
from .io.system import reference_target
from .io.units import quantity
from .metrics.online import run_many
from .model.circuit import Circuit, observe_many, output_sources, simulate_many
from .model.circuit import build as build_circuit
from .model.circuit import simulate as simulate_circuit
from .model.circuit_steady import project as circuit_project
from .model.circuit_steady import rhs as circuit_rhs
from .model.circuit_steady import signal_values as circuit_signals
from .model.circuit_stepper import CircuitStepper
from .model.joint import Load
from .model.scenario import saturation_test, simulate
from .model.servo import ServoScenario, servo_metrics_table
from .paper import arm_card, arm_validation
from .paper import card as paper_card
from .paper.reproduce import reproduce
from .paper.validate import validate
from .paper.validation import friction_torque_unpressurised
from .plotting.design import display
from .plotting.joint import save_figure
from .plotting.mechanism import stick_points

EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
EXIT_INTERNAL = 1
# a sweep above this many scenario-steps needs --force (10¹² scenario-steps: about 3 hours at
# 9·10⁷ scenario-steps/s, docs/batch.md); one scenario is limited to 10⁸ steps when it is read
# (hydroarm.io.sections.check_run_size)
MAX_SWEEP_WORK = 10**12
RECORD_BYTES = 5 * 8 * 3  # five float64 series per kept step, ~3 copies (result, table, text)


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line naming the option, no usage dump
        message = message.splitlines()[0] if message else "invalid arguments"
        field, problem = self.prog, message
        if m := re.match(r"argument ([^:]+): (.*)", message):
            field, problem = m.group(1).split("/")[0], m.group(2)
        elif m := re.match(r"unrecognized arguments: (\S+)", message):
            field, problem = m.group(1), "unrecognized argument"
        elif m := re.match(r"the following arguments are required: ([^,\s]+)", message):
            field, problem = m.group(1), "is required"
        raise HydroarmError(field, f"{problem} (see '{self.prog} --help')")


def _option(dest: str) -> str:
    """The option that sets ``dest`` (``step_response``: ``--step-response``)."""
    return "--" + dest.replace("_", "-")


def _q(field, text, dim, **kw):
    return quantity(field, text, dim, **kw)


def _frequencies(text: str) -> int:
    """``--frequencies``: a whole number from 1 to MAX_FREQUENCIES (the sweep's budget)."""
    v = _positive_int(text)
    if v > MAX_FREQUENCIES:
        raise argparse.ArgumentTypeError(
            f"{v} is above the budget of {MAX_FREQUENCIES} (each frequency is a simulated run)"
        )
    return v


def _positive_int(text: str) -> int:
    """An option's whole number ≥ 1 (argparse reports the option and this message)."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number ≥ 1, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number ≥ 1, got {text!r}")
    return v


def _results_file(text: str) -> str:
    """A sweep's results file: ``.csv`` or ``.parquet`` (checked before the sweep is read)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("is empty")
    if os.path.splitext(text)[1].lower() not in (".csv", ".parquet"):
        raise argparse.ArgumentTypeError(f"must end in .csv or .parquet, got {text!r}")
    return text


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="hydroarm",
        description="Hydraulic servo prosthetic-arm simulation "
        "(UCL hydraulic arm paper, Appendix I).",
    )
    p.add_argument("--version", action="version", version="hydroarm " + _version())
    sub = p.add_subparsers(dest="command", parser_class=_Parser)

    s = sub.add_parser("simulate", help="run one scenario of the shoulder-elevation servo")
    src = s.add_argument_group("scenario (one of)")
    src.add_argument("--load", help="built-in load 1-10 of Appendix I")
    src.add_argument("--weight", help='load weight W with unit, e.g. "18.73 N" or "4.2 lbf"')
    src.add_argument("--arm", help='centre-of-mass distance X, e.g. "276 mm"')
    src.add_argument("--inertia", help='moment of inertia I, e.g. "146 N*mm*s**2"')
    src.add_argument("--config", help="scenario TOML file (units on every quantity)")
    src.add_argument(
        "--interactive",
        action="store_true",
        help="ask for W, X, I, T, iterations and values to print, as the original program did",
    )
    s.add_argument(
        "--direction",
        choices=("raise", "lower"),
        default=None,
        help="saturation test: raise from hanging (-60°) to +60°, or lower back",
    )
    s.add_argument(
        "--parameter-set",
        default=None,
        help="built-in joint parameters (default paper-calibrated; see 'hydroarm params')",
    )
    s.add_argument("--method", choices=tuple(METHODS), default=None)
    s.add_argument("--step", help='fixed step T with unit, e.g. "10 us" (default 10 us)')
    s.add_argument("--duration", help='simulated time with unit, e.g. "1.5 s"')
    s.add_argument(
        "--print-every",
        type=_positive_int,
        default=None,
        metavar="K",
        help="keep every K-th step in the printed table and the CSV",
    )
    s.add_argument(
        "--out",
        help="write the run's columns to this CSV file, each name ending in its unit (the "
        "paper's joint: t_s, x_mm, theta_deg, p_bar, xdot_mm_s; a component servo: "
        "position_m or angle_rad, pressures in bar, …; a circuit: every node's pressure, "
        "every component's flow and power, every signal)",
    )
    s.add_argument(
        "--metrics",
        action="store_true",
        help="print the paper's metrics as one JSON object on stdout",
    )
    s.add_argument(
        "--plot",
        help="save a plot (PNG) of the run against time (the joint: θ₂, x and p; a servo: "
        "position, pressures, spool; a circuit: its pressures, flows and positions)",
    )

    li = sub.add_parser(
        "linearize",
        help="linear analysis about an operating point: poles, ω_h, ζ_h, K_v, margins, "
        "bandwidth (docs/linear.md)",
    )
    lsrc = li.add_argument_group("servo (one of)")
    lsrc.add_argument("--load", help="built-in load 1-10 of Appendix I (the paper's joint)")
    lsrc.add_argument(
        "--config", help="scenario TOML file (the paper's joint or a component servo)"
    )
    li.add_argument(
        "--angle",
        help='joint angle θ₂ (or a rotary servo\'s angle) to hold, e.g. "30 deg" (default: '
        "the horizontal for --load, the target of --config)",
    )
    li.add_argument("--position", help='position of a linear servo to hold, e.g. "0.7 m"')
    li.add_argument(
        "--input",
        help="circuit files: the input, a signal source (default: the reference) or "
        "<component>.<parameter>",
    )
    li.add_argument(
        "--output",
        help="circuit files: the output, any output column (default: the controlled "
        "position, e.g. load_position_m)",
    )
    li.add_argument(
        "--loop",
        help="circuit files with several control loops: the controller whose loop to break "
        "for the margins (the others closed; default: each loop's margins in a table)",
    )
    li.add_argument(
        "--parameter-set",
        default=None,
        help="built-in joint parameters with --load (default paper-calibrated)",
    )
    li.add_argument("--bode", help="save open- and closed-loop Bode plots (PNG)")
    li.add_argument(
        "--sweep",
        help="frequency response by simulation: sine runs of the nonlinear model, their gain "
        "and phase on the linear Bode (PNG; docs/linear.md)",
    )
    li.add_argument(
        "--amplitude",
        action="append",
        help='sine amplitude of the lever (reference) for --sweep, e.g. "0.1 mm"; repeat for '
        "a family of curves (default for the joint: e_o/40, e_o and 10·e_o)",
    )
    li.add_argument(
        "--frequencies",
        type=_frequencies,
        default=15,
        help="number of frequencies of --sweep, log-spaced from ω_h/20 to 3·ω_h (default 15)",
    )
    li.add_argument("--poles", help="save the pole map (PNG) with the ω_h circle and damping lines")
    li.add_argument(
        "--step-response",
        metavar="FILE.png",
        help="save the small-signal step response (PNG), normalised, rise, overshoot and "
        "settling marked (--step names an integration step in the other commands)",
    )
    li.add_argument(
        "--vary",
        help="save ω_h, ζ_h and the margins against angle, one line per load (PNG; the "
        "paper's joint: --parameter-set, --loads, --angles)",
    )
    li.add_argument(
        "--loads",
        help="loads of --vary, comma-separated Appendix I numbers (default: --load, or 1,6,10)",
    )
    li.add_argument(
        "--angles",
        help='angles of --vary: FROM,TO,N, e.g. "-60 deg,60 deg,25" (the default)',
    )
    li.add_argument("--json", action="store_true", help="print one JSON object on stdout")

    r = sub.add_parser("reproduce", help="reproduce the paper's tables, figures and report")
    r.add_argument("--out", default="reproduction", help="output folder (default ./reproduction)")

    v = sub.add_parser(
        "validate",
        help="physics model against the measured arm (Table I, "
        "stall, time constant, friction tests) with design what-ifs",
    )
    v.add_argument("--out", default="validation", help="output folder (default: validation)")
    ar = sub.add_parser(
        "arm",
        help="the whole multi-function arm from a config file: joint "
        "time series, hand trajectory, plots, animation, arm validation",
    )
    ar.add_argument(
        "--config",
        required=True,
        help="arm TOML (e.g. examples/ucl-arm.toml) or any mechanism file (a [mechanism] "
        "section, e.g. examples/excavator.toml)",
    )
    ar.add_argument("--out", default="arm-run", help="output folder (default: arm-run)")
    ar.add_argument("--no-animation", action="store_true", help="skip the GIF")
    ar.add_argument(
        "--mechanism",
        action="store_true",
        help="kept for scripts that name it: an arm file always runs as one mechanism "
        "(what hydroarm expand writes) on the system kernel (docs/arm.md)",
    )
    ar.add_argument(
        "--card",
        action="store_true",
        help="a mechanism file's evaluation card (card.md, card.csv, card.png): each driven "
        "joint's valve fully open each way (a servo jack's lever stepped end to end), "
        "speeds, time constants, stall payload, pressures, energy, and the file's own task "
        "(docs/evaluate.md)",
    )
    sw = sub.add_parser(
        "sweep",
        help="grid or Monte Carlo sweep of scenario parameters on "
        "the batch engine (CSV or Parquet, one row per scenario)",
    )
    sw.add_argument("--config", required=True, help="sweep TOML (e.g. examples/throughput.toml)")
    sw.add_argument(
        "--out", required=True, type=_results_file, help="results file, .csv or .parquet"
    )
    sw.add_argument("--resume", action="store_true", help="continue an interrupted sweep")
    sw.add_argument(
        "--export",
        action="append",
        choices=("netcdf", "mat"),
        default=[],
        help="also write the rows beside --out: netcdf (OUT.nc, an xarray dataset; needs "
        "pip install 'hydroarm[xarray]') or mat (OUT.mat, for MATLAB); repeat for both",
    )
    sw.add_argument(
        "--force",
        action="store_true",
        help=f"run a sweep above {MAX_SWEEP_WORK:.0e} scenario-steps",
    )
    sw.add_argument(
        "--chunk", type=_positive_int, default=256, help="scenarios per chunk (default 256)"
    )
    sw.add_argument("--executor", choices=("local", "dask"), default="local")
    sw.add_argument(
        "--scheduler",
        default=None,
        help="Dask scheduler address; without it a LocalCluster on this machine",
    )
    fi = sub.add_parser(
        "fit",
        help="fit the parameters of a joint, a component servo or any system ([system] file: "
        "a circuit, a mechanism) and trigger delays to measured traces and scalar targets "
        "(estimates, standard errors, bootstrap and profile-likelihood intervals, warnings "
        "where the linearised intervals are not to be trusted, correlations; docs/fit.md)",
    )
    fi.add_argument("--config", required=True, help="fit TOML (docs/fit.md)")
    fi.add_argument(
        "--starts",
        type=int,
        default=None,
        help="multi-start from N Sobol points inside the bounds (replaces [fit] starts)",
    )
    fi.add_argument("--out", default="fit", help="output folder (default: fit)")
    fi.add_argument(
        "--leave-one-out",
        action="store_true",
        help="also refit without each group of traces or targets and report the prediction "
        "of the one left out (fit_report.md, leave_one_out.csv)",
    )
    de = sub.add_parser(
        "design",
        help="design study of any system (the paper's joint, a circuit, a component servo): "
        "sample its parameters, keep the designs that meet the requirements, Pareto front of "
        "the objectives (docs/design.md)",
    )
    de.add_argument("--config", required=True, help="design TOML (docs/design.md)")
    de.add_argument("--out", default="design", help="output folder (default: design)")
    de.add_argument(
        "--samples",
        type=_positive_int,
        default=None,
        help="number of Sobol designs (overrides [design] samples)",
    )
    de.add_argument(
        "--no-refine", action="store_true", help="skip the refinement ([design] refine)"
    )
    ev = sub.add_parser(
        "evaluate",
        help="the evaluation card of a joint (time constant, effective delay, stall mass, "
        "speeds, backlash error beside requirements and the paper) or of any system "
        "(statistics of its named outputs against requirements; docs/evaluate.md)",
    )
    ev.add_argument("--config", required=True, help="evaluation TOML (docs/evaluate.md)")
    ev.add_argument("--out", default="evaluation", help="output folder (default: evaluation)")
    fm = sub.add_parser(
        "fmu",
        help="export a joint (scenario file), the whole arm (arm file), a component servo "
        "(servo file) or a circuit (circuit file) as an FMI 2.0 co-simulation FMU (pythonfmu; "
        "the target needs Python with hydroarm; docs/fmu.md)",
    )
    fm.add_argument("--config", default=None, help="scenario, arm, servo or circuit TOML")
    fm.add_argument("--out", default="hydroarm.fmu", help="FMU file (default: hydroarm.fmu)")
    fm.add_argument(
        "--step", help='internal fixed step with unit, e.g. "10 us" (default: the file\'s)'
    )
    fm.add_argument(
        "--method",
        choices=list(dict.fromkeys([*fixed_step_methods(), *CIRCUIT_STEPPERS])),
        default=None,
        help="default: the file's (heun and midpoint: circuits only)",
    )
    fm.add_argument(
        "--outputs",
        help="a circuit's outputs, comma-separated names of simulate's columns "
        "(default: every one)",
    )
    se = sub.add_parser(
        "sensitivity",
        help="global sensitivity of a joint's metrics to uncertain parameters (Sobol "
        "indices or Morris screening on the batch engine; docs/sensitivity.md)",
    )
    se.add_argument("--config", required=True, help="sensitivity TOML (docs/sensitivity.md)")
    se.add_argument("--out", default="sensitivity", help="output folder (default: sensitivity)")
    se.add_argument(
        "--export",
        action="append",
        choices=("netcdf", "mat"),
        default=[],
        help="also write the samples and indices into --out as sensitivity.nc (netcdf, an "
        "xarray dataset; needs pip install 'hydroarm[xarray]') or sensitivity.mat (mat, for "
        "MATLAB); repeat for both",
    )
    ex = sub.add_parser(
        "explore",
        help="the arm live in a browser: the single joint's sliders and plots, the whole "
        "arm from a lever box, the block-stacking task; or any system file's parameters as "
        "sliders and its outputs as curves (docs/explore.md)",
    )
    ex.add_argument(
        "--config",
        default=None,
        help="arm TOML, or any system file: circuit, mechanism, component servo, or a study "
        "naming one (default: the UCL arm)",
    )
    ex.add_argument(
        "--port",
        type=_positive_int,
        default=explore_launch.DEFAULT_PORT,
        help=f"port to listen on (default: {explore_launch.DEFAULT_PORT})",
    )
    ex.add_argument(
        "--host",
        default=explore_launch.HOST,
        help="address to listen on (default: 127.0.0.1, this machine only; any other asks "
        "for the token in the printed URL: docs/explore.md)",
    )
    ex.add_argument("--no-browser", action="store_true", help="do not open a browser (serve only)")
    ex.add_argument(
        "--out",
        default="explore",
        help="folder for the arm page's recorded attempts (default: explore)",
    )
    xp = sub.add_parser(
        "expand",
        help="write the circuit a component servo file or a joint file stands for, as a "
        'circuit file (docs/components.md "A servo file as a circuit"); an arm file as one '
        'mechanism file (docs/mechanism.md "The UCL arm as a mechanism")',
    )
    xp.add_argument(
        "--config",
        required=True,
        help="component servo TOML ([actuator] …), joint TOML or arm TOML ([joints.<name>])",
    )
    xp.add_argument("--out", default=None, help="circuit TOML to write (default: print it)")
    pa = sub.add_parser("params", help="show a built-in parameter set with derived values")
    pa.add_argument("name", nargs="?", default=None)
    sub.add_parser(
        "warmup",
        help="compile the simulation kernels now: joint, arm, component servo, circuit and "
        "mechanism (once per installation; later runs load them)",
    )
    _add_ecosystem_parsers(sub, fm)
    return p


def _version():
    return version("hydroarm")


# ------------------------------------------- examples, fmu --check (issue 33) ---
def _add_ecosystem_parsers(sub, fm) -> None:
    """``hydroarm examples [--copy DIR]`` and ``hydroarm fmu --check FILE.fmu``."""
    eg = sub.add_parser(
        "examples",
        help="list the example files (one line each) or copy them into a folder, so that the "
        "docs' commands run from an installed wheel: hydroarm examples --copy ex, then "
        "hydroarm simulate --config ex/position_servo.toml --metrics",
    )
    eg.add_argument(
        "--copy",
        metavar="DIR",
        default=None,
        help="copy every example into DIR (created if missing; refuses to overwrite a file)",
    )
    fm.add_argument(
        "--check",
        metavar="FILE",
        default=None,
        help="check that this machine can run an exported FMU: load it in a fresh process "
        "(FMPy) and list what the target lacks, one line each (exit 2 if it cannot run)",
    )


def cmd_examples(a) -> int:
    if a.copy is not None:
        written = copy_examples(a.copy)
        print(f"{len(written)} example files copied to {a.copy}")
        return 0
    items = list_examples()
    width = max(len(e.name) for e in items)
    print(f"example files ({examples_folder()}; copy them: hydroarm examples --copy DIR):")
    for e in items:
        print(f"  {e.name:<{width}}  {e.description}")
    return 0


def cmd_fmu_check(a) -> int:
    problems, facts = check_fmu(a.check)
    for line in facts:
        print(line)
    for line in problems:
        print(f"hydroarm: error: {a.check}: {line}", file=sys.stderr)
    if problems:
        return EXIT_USAGE
    print(f"{a.check}: runs on this machine")
    return 0


# ---------------------------------------------------------------- simulate ---
LOAD_OPTIONS = ("--weight", "--arm", "--inertia")


def _scenario_from_args(a):
    sc = _scenario_of_args(a)
    try:
        sc.check_step()
    except HydroarmError as exc:  # the step came from --step or the default: name the option
        if a.config is not None and a.step is None:
            raise
        raise _renamed(exc, {"solver.step": "--step"}) from None
    return sc


def _scenario_of_args(a):
    load_args = [a.weight, a.arm, a.inertia]
    options = [("--config", a.config), ("--load", a.load)]
    options += list(zip(LOAD_OPTIONS, load_args, strict=True))
    given = [name for name, v in options if v is not None]
    if not given:
        raise HydroarmError(
            "simulate", "give one of --load, --weight/--arm/--inertia, --config or --interactive"
        )
    kinds = [("--weight" if g in LOAD_OPTIONS else g) for g in given]
    if len(set(kinds)) > 1:
        second = next(g for g, k in zip(given, kinds, strict=True) if k != kinds[0])
        raise HydroarmError(second, f"cannot be combined with {given[0]} (give one scenario)")
    if a.config is not None:
        for name, v in (("--direction", a.direction), ("--parameter-set", a.parameter_set)):
            if v is not None:
                raise HydroarmError(
                    name, "cannot be combined with --config (the scenario file sets it)"
                )
        sc = _scenario_of(a.config)
    else:
        joint = parameter_set(
            DEFAULT_SET if a.parameter_set is None else a.parameter_set, "--parameter-set"
        )
        if a.load is not None:
            load = paper_load(a.load, field="--load")
        else:
            for name, v in zip(("--weight", "--arm", "--inertia"), load_args, strict=True):
                if v is None:
                    raise HydroarmError(name, "is missing (give --weight, --arm and --inertia)")
            load = Load(
                weight=weight_quantity("--weight", a.weight),
                arm=_q("--arm", a.arm, "length", nonnegative=True),
                inertia=_q("--inertia", a.inertia, "inertia", positive=True),
                name="custom load",
            )
        if a.direction is None:
            raise HydroarmError("--direction", "is missing (raise or lower)")
        sc = saturation_test(joint, load, a.direction)
    return _apply_solver_args(sc, a)


# a Scenario field -> the option or the dialogue's value that set it
SOLVER_OPTIONS = {
    "solver.step": "--step",
    "solver.duration": "--duration",
    "solver.record_every": "--print-every",
}
DIALOGUE_FIELDS = {
    "solver.step": "T",
    "solver.duration": "number of iterations",
    "solver.record_every": "number of values to print",
    "load.weight": "W",
    "load.arm": "X",
    "load.inertia": "I",
}


def _renamed(exc: HydroarmError, names: dict) -> HydroarmError:
    """The error with its field named as the user gave it (``solver.step`` -> ``--step``)."""
    if exc.field in names:
        return HydroarmError(names[exc.field], exc.problem)
    return exc


def _apply_solver_args(sc, a):
    changes = {}
    if a.method:
        changes["method"] = a.method
    if a.step is not None:
        changes["step"] = _q("--step", a.step, "time", positive=True)
    if a.duration is not None:
        changes["duration"] = _q("--duration", a.duration, "time", positive=True)
    if a.print_every is not None:
        if a.print_every < 1:
            raise HydroarmError("--print-every", f"must be ≥ 1, got {a.print_every}")
        changes["record_every"] = a.print_every
    elif (a.out or a.metrics or a.plot) and not isinstance(sc, ServoScenario):
        step = changes.get("step", sc.step)
        changes["record_every"] = max(1, int(round(1e-4 / step)))  # ~0.1 ms output spacing
    if not changes:
        return sc
    try:
        sc = sc.replace(**changes)
    except HydroarmError as exc:
        if exc.field == "solver.step" and a.step is None:  # only --duration was given
            raise HydroarmError("--duration", f"is shorter than the step ({sc.step:g} s)") from None
        raise _renamed(exc, SOLVER_OPTIONS) from None
    if a.print_every is None and sc.nsteps // sc.record_every < 2 <= sc.nsteps:
        sc = sc.replace(record_every=max(1, sc.nsteps // 2))  # a short run: keep 3 points
    check_run_size(
        sc.duration,
        sc.step,
        sc.record_every,
        duration_field="--duration",
        record_field="--print-every" if a.print_every is not None else "solver.record_every",
    )
    return sc


def _ask(field, prompt, stream_in, stream_out):
    stream_out.write(prompt)
    stream_out.flush()
    try:
        line = stream_in.readline()
    except UnicodeDecodeError:
        raise HydroarmError(field, "the typed text is not UTF-8") from None
    if not line:
        if hasattr(stream_in, "isatty") and stream_in.isatty():
            stream_out.write("\n")  # Ctrl-D leaves the prompt's line open
        raise HydroarmError(field, "input ended before a value was given")
    return line.strip()


def _with_default_unit(text, unit):
    try:
        float(text)
        return f"{text} {unit}"
    except ValueError:
        return text


def _whole(field, text) -> int:
    try:
        v = int(text)
    except ValueError:
        raise HydroarmError(field, f"must be a whole number, got {text!r}") from None
    if v < 1:
        raise HydroarmError(field, f"must be ≥ 1, got {v}")
    return v


VALUES = "number of values to print"  # the dialogue's name for its last number


def print_spacing(iterations: int, values: int) -> int:
    """Every how many iterations the dialogue keeps a value so that it prints ``values`` of them,
    evenly spaced from the start (iteration 0, K, 2K, ...: ``iterations // K + 1`` values).

    K is ``iterations // (values − 1)``, the largest spacing that keeps ``values`` values; where
    no spacing keeps exactly that many (11 asked of 15 iterations: K = 1 keeps 16, K = 2 keeps
    8), the count nearest to the one asked for wins, the larger one on a tie. Refuses fewer than
    3 values (the saturation velocity needs 3 points) or more than the run has."""
    if values < 3:
        raise HydroarmError(
            VALUES, f"must be at least 3 (the saturation velocity needs 3 points), got {values}"
        )
    if values > iterations + 1:
        raise HydroarmError(
            VALUES,
            f"{iterations} iterations give at most {iterations + 1} values (the start and "
            f"every iteration), got {values}",
        )
    if values - 1 > MAX_RECORDED:
        raise HydroarmError(VALUES, f"must be at most {MAX_RECORDED + 1:.0f}, got {values}")
    k = iterations // (values - 1)
    more, fewer = iterations // k + 1, iterations // (k + 1) + 1
    if more != values and fewer >= 3 and values - fewer < more - values:
        return k + 1
    return k


def _interactive(a, stream_in=None, stream_out=None):
    """The original program's dialogue: W, X, I, T, iterations, values to print.

    Each answer is checked as soon as it is typed; an error names the value asked for."""
    # prompts go to stderr so that stdout carries only the table
    stream_in = stream_in or sys.stdin
    stream_out = stream_out or sys.stderr
    try:
        return _dialogue(a, stream_in, stream_out)
    except HydroarmError:
        if not (hasattr(stream_in, "isatty") and stream_in.isatty()):
            stream_out.write("\n")  # typed input echoes its newline; piped input does not
        raise


def _dialogue(a, stream_in, stream_out):
    def ask(field, prompt):
        return _ask(field, prompt, stream_in, stream_out)

    w = weight_quantity("W", _with_default_unit(ask("W", "W, load weight [N]: "), "N"))
    x = _q(
        "X",
        _with_default_unit(ask("X", "X, centre of mass distance [mm]: "), "mm"),
        "length",
        nonnegative=True,
    )
    i = _q(
        "I",
        _with_default_unit(ask("I", "I, moment of inertia [N mm s^2]: "), "N*mm*s**2"),
        "inertia",
        positive=True,
    )
    t = _q(
        "T",
        _with_default_unit(ask("T", "T, iteration step size [ms]: "), "ms"),
        "time",
        positive=True,
    )
    n = _whole("number of iterations", ask("number of iterations", "number of iterations: "))
    check_run_size(n * t, t, None, duration_field="number of iterations", steps="iterations")
    values = _whole(
        VALUES, ask(VALUES, "number of solution values to print (the start included): ")
    )
    k = print_spacing(n, values)
    kept = n // k + 1
    d = a.direction or (ask("direction", "direction (raise/lower) [raise]: ") or "raise")
    if d not in ("raise", "lower"):
        raise HydroarmError("direction", f"must be raise or lower, got {d!r}")
    joint = parameter_set(
        DEFAULT_SET if a.parameter_set is None else a.parameter_set, "--parameter-set"
    )
    try:
        sc = saturation_test(
            joint,
            Load(w, x, i, name="typed load"),
            d,
            step=t,
            duration=n * t,
            record_every=k,
            method=a.method or "euler",
        )
        sc.check_step()
    except HydroarmError as exc:
        raise _renamed(exc, DIALOGUE_FIELDS) from None
    if kept != values:
        every = "every iteration" if k == 1 else f"one every {k} iterations"
        stream_out.write(
            f"note: {values} values cannot be spread evenly over {n} iterations; "
            f"printing {kept}, {every}\n"
        )
    return sc


def _print_table(res, out=None, max_rows=None):
    out = out or sys.stdout
    rows = res.table()
    if max_rows and len(rows) > max_rows:
        idx = sorted(set([*range(0, len(rows), max(1, len(rows) // max_rows)), len(rows) - 1]))
        rows = rows[idx]
    out.write(
        f"{'t [s]':>10} {'x [mm]':>10} {'theta [deg]':>12} {'p [bar]':>10} {'xdot [mm/s]':>12}\n"
    )
    for r in rows:
        out.write(f"{r[0]:10.5f} {r[1]:10.4f} {r[2]:12.4f} {r[3]:10.4f} {r[4]:12.4f}\n")


def memory_limit() -> int:
    """Bytes a job may use for its results: half of the memory now available."""
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 2
    except (ValueError, OSError, AttributeError):
        return 2**33


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB"


FIT_HINT = "shorten --duration or keep every K-th step with --print-every K"


def _check_records_fit(sc, field, fix=FIT_HINT) -> None:
    """Refuse, before it starts, a run whose kept steps would not fit in memory."""
    kept = sc.nsteps // sc.record_every + 1
    need = kept * RECORD_BYTES
    limit = memory_limit()
    if need > limit:
        raise HydroarmError(
            field,
            f"{kept:.3g} kept steps need about {_gb(need)} of memory, above the limit of "
            f"{_gb(limit)} (half the available memory); {fix}",
        )


def _check_outputs(a) -> None:
    """Every output path of a command, checked before any work starts."""
    if a.command == "linearize":
        for name in ("bode", "poles", "step_response", "vary", "sweep"):
            if getattr(a, name) is not None:
                check_output_file(_option(name), getattr(a, name))
    elif a.command == "simulate":
        if a.out is not None:
            check_output_file("--out", a.out)
        if a.plot is not None:
            check_output_file("--plot", a.plot)
    elif a.command == "sweep" or (a.command == "fmu" and a.check is None):
        check_output_file("--out", a.out)
    elif a.command == "expand" and a.out is not None:
        check_output_file("--out", a.out)
    elif a.command in ("reproduce", "validate", "arm", "fit", "evaluate", "sensitivity", "design"):
        check_output_folder("--out", a.out)


OUTPUT_OPTIONS = ("out", "plot", "bode", "poles", "step_response", "vary", "sweep")


def _named_output(exc: HydroarmError, a) -> HydroarmError:
    """A write that failed (a full disk: `hydroarm.files.write_error`) names the
    option that gave its path (``--out: <path>: cannot write: ...``), not only the path."""
    path = exc.path
    if a is None or path is None or exc.os_error is None:
        return exc
    if exc.field.startswith("--"):
        return exc
    target = os.path.abspath(path)
    for name in OUTPUT_OPTIONS:
        given = getattr(a, name, None)
        if not isinstance(given, str) or not given:
            continue
        mine = os.path.abspath(given)
        if target == mine or target.startswith(mine.rstrip(os.sep) + os.sep):
            named = HydroarmError(_option(name), f"{shown_path(path)}: {exc.problem}")
            named.path, named.os_error = exc.path, exc.os_error
            return named
    return exc


def _scenario_of(path):
    """The scenario of a joint or component-servo file, or the servo a reference file names
    (``fitted.toml`` of a component servo's fit, its fitted values set)."""
    ref = reference_target(path)
    if isinstance(ref, ServoScenario):
        return ref
    try:
        doc, p = read_toml_file(path)
    except HydroarmError:
        doc, p = {}, Path(path)  # the scenario reader says what is wrong with it
    if isinstance(doc.get("joints"), dict) and "load" not in doc:
        raise HydroarmError(
            "--config",
            f"{p.name} is an arm file ([joints.<name>] tables): run it with hydroarm arm "
            f"--config {path}",
        )
    return load_scenario(path)


def _circuit_of(path) -> Circuit:
    """The circuit of a circuit file, or of a reference file naming one (``fitted.toml``)."""
    ref = reference_target(path)
    return ref if isinstance(ref, Circuit) else load_circuit(path)


def _circuit_config(path) -> bool:
    """Whether ``--config`` names a circuit: a circuit file, or a reference file naming one
    (as ``hydroarm fit`` writes ``fitted.toml`` for a mechanism)."""
    return is_circuit_path(path) or isinstance(reference_target(path), Circuit)


def cmd_simulate(a) -> int:
    if a.config is not None and not a.interactive and _circuit_config(a.config):
        return _simulate_circuit(a)
    if a.interactive:
        if a.config or a.load or a.weight or a.arm or a.inertia:
            raise HydroarmError("--interactive", "cannot be combined with another scenario")
        sc = _interactive(a)
    else:
        sc = _scenario_from_args(a)
    if a.interactive:
        _check_records_fit(sc, VALUES, "print fewer values")
    else:
        _check_records_fit(sc, "--duration")
    if isinstance(sc, ServoScenario):
        return _simulate_servo(sc, a)
    res = simulate(sc)
    summary = _write_run(res, a)
    if not a.metrics and not a.out and not a.plot:
        _print_table(res, max_rows=None if (a.interactive or a.print_every) else 30)
        v = summary["saturation_velocity_mm_s"]
        shown = "— (no motion to measure)" if v is None or v != v else f"{v:.2f} mm/s"
        print(
            f"# saturation velocity (middle 80 %): {shown}"
            + ("  [stalled]" if summary["stalled"] else "")
        )
    return 0


def _write_run(res, a) -> dict:
    """The run's outputs that ``simulate`` was asked for (--out CSV, --plot PNG, --metrics
    JSON on stdout); returns its summary."""
    summary = res.summary()
    if a.out is not None:
        res.to_csv(a.out)
    if a.plot is not None:
        save_figure(res.plot(), a.plot)
    if a.metrics:
        print(json.dumps(_jsonable(summary)))
    return summary


def _simulate_servo(sc: ServoScenario, a) -> int:
    """``simulate`` of a servo built from components (docs/components.md)."""
    progress = Progress(2)
    progress(f"checking the step and simulating {sc.name}: {sc.nsteps:,} steps of {sc.method}")
    res = sc.run()
    progress("writing the results")
    summary = _write_run(res, a)
    if not a.metrics and not a.out and not a.plot:
        frame = res.to_pandas()
        every = max(1, len(frame) // 30)
        print(frame.iloc[::every].to_string(index=False, float_format=lambda v: f"{v:.6g}"))
        for k, v in summary.items():
            print(f"# {k}: {v:.6g}")
    return 0


def _simulate_circuit(a) -> int:
    """``simulate`` of a circuit file (``[[component]]`` entries; docs/components.md)."""
    for name in ("load", "weight", "arm", "inertia", "direction", "parameter_set"):
        if getattr(a, name) is not None:
            raise HydroarmError(f"--{name.replace('_', '-')}", "is not for a circuit file")
    circuit = _circuit_of(a.config)
    changes: dict = {}
    if a.method is not None:
        if a.method not in (*CIRCUIT_STEPPERS, "adaptive"):
            raise HydroarmError("--method", f"a circuit runs {', '.join(CIRCUIT_STEPPERS)}")
        changes["method"] = a.method
    if a.step is not None:
        changes["step"] = _q("--step", a.step, "time", positive=True)
    if a.duration is not None:
        changes["duration"] = _q("--duration", a.duration, "time", positive=True)
    if a.print_every is not None:
        changes["record_every"] = a.print_every
    circuit = circuit.replace(**changes)
    check_run_size(
        circuit.duration, circuit.step, circuit.record_every, duration_field="--duration"
    )
    compiled = build_circuit(circuit)
    nsteps = int(round(circuit.duration / circuit.step))
    progress = Progress(2)
    progress(f"simulating {circuit.name}: {nsteps:,} steps of {circuit.method}")
    res = simulate_circuit(compiled)
    if res.bad_step >= 0:
        raise HydroarmError(
            "solver.step",
            f"the run left finite numbers at step {res.bad_step} "
            f"(t = {res.bad_step * circuit.step:.4g} s); reduce the step",
        )
    progress("writing the results")
    if a.out is not None:
        res.to_csv(a.out)
    if a.plot is not None:
        save_figure(res.plot(), a.plot)
    frame = res.to_pandas()
    if a.metrics:
        final = {k: float(v) for k, v in frame.iloc[-1].items()}
        print(json.dumps(_jsonable({**final, **res.energy()})))
    elif a.out is None and a.plot is None:
        every = max(1, len(frame) // 30)
        cols = [
            c for c in frame.columns if c.endswith(("_pressure_bar", "_position_m", "_angle_deg"))
        ]
        print(
            frame.iloc[::every][["t_s", *cols]].to_string(
                index=False, float_format=lambda v: f"{v:.6g}"
            )
        )
    return 0


def _jsonable(d):
    out = {}
    for k, v in d.items():
        if isinstance(v, float) and not math.isfinite(v):
            v = None
        elif hasattr(v, "item"):
            v = v.item()
        out[k] = v
    return out


# -------------------------------------------------------------- linearize ---
DEFAULT_VARY_LOADS = "1,6,10"
DEFAULT_VARY_ANGLES = "-60 deg,60 deg,25"


def _variation_of_args(a):
    """(joint, loads, angles [rad]) of ``hydroarm linearize --vary``, checked before any work."""
    if a.vary is None:
        for name in ("loads", "angles"):
            if getattr(a, name) is not None:
                raise HydroarmError(f"--{name}", "is for --vary (give --vary FILE.png)")
        return None
    if a.config is not None:
        raise HydroarmError("--vary", "is for the paper's joint (--parameter-set), not --config")
    joint = parameter_set(
        DEFAULT_SET if a.parameter_set is None else a.parameter_set, "--parameter-set"
    )
    text = a.loads if a.loads is not None else (a.load or DEFAULT_VARY_LOADS)
    loads = []
    for part in str(text).split(","):
        paper_load(part.strip(), field="--loads")
        loads.append(int(part.strip()))
    parts = [x.strip() for x in (a.angles or DEFAULT_VARY_ANGLES).split(",")]
    if len(parts) != 3:
        raise HydroarmError("--angles", f'must be FROM,TO,N (e.g. "{DEFAULT_VARY_ANGLES}")')
    lo = _q("--angles", parts[0], "angle")
    hi = _q("--angles", parts[1], "angle")
    try:
        n = int(parts[2])
    except ValueError:
        raise HydroarmError("--angles", f"N must be a whole number, got {parts[2]!r}") from None
    if not 2 <= n <= 1000:
        raise HydroarmError("--angles", f"N must be between 2 and 1000, got {n}")
    if not hi > lo:
        raise HydroarmError("--angles", "TO must be above FROM")
    if max(abs(lo), abs(hi)) >= joint.max_angle:
        raise HydroarmError("--angles", "reaches beyond the crank's reach (|θ₂| < n·90°)")
    return joint, loads, np.linspace(lo, hi, n)


def _linear_model_of_args(a):
    """The servo and operating point of ``hydroarm linearize``, checked before any work."""
    given = [name for name, v in (("--config", a.config), ("--load", a.load)) if v is not None]
    if not given:
        if a.vary is not None:
            return None
        raise HydroarmError("linearize", "give one of --load or --config (or --vary)")
    if len(given) > 1:
        raise HydroarmError("--load", "cannot be combined with --config (give one servo)")
    if a.angle is not None and a.position is not None:
        raise HydroarmError("--position", "cannot be combined with --angle")
    at = None
    if a.angle is not None:
        at = _q("--angle", a.angle, "angle")
    if a.config is not None:
        if a.parameter_set is not None:
            raise HydroarmError(
                "--parameter-set", "cannot be combined with --config (the scenario file sets it)"
            )
        sc = _scenario_of(a.config)
        linear_servo = isinstance(sc, ServoScenario) and sc.vector()[P_LOAD] == LOAD_MASS
        if a.position is not None:
            if not linear_servo:
                raise HydroarmError(
                    "--position", "is for a servo with a linear load; give --angle for a joint"
                )
            at = _q("--position", a.position, "length")
        elif a.angle is not None and linear_servo:
            raise HydroarmError(
                "--angle", "is for a joint or rotary servo; give --position for this linear servo"
            )
    else:
        if a.position is not None:
            raise HydroarmError("--position", "is for a component servo (--config); give --angle")
        joint = parameter_set(
            DEFAULT_SET if a.parameter_set is None else a.parameter_set, "--parameter-set"
        )
        load = paper_load(a.load, field="--load")
        sc = saturation_test(joint, load, "raise")
        if at is None:
            at = joint.horizontal_angle
    field = "--position" if a.position is not None else "--angle"
    if a.sweep is None and a.amplitude is not None:
        raise HydroarmError("--amplitude", "is for --sweep (the frequency response by simulation)")
    try:
        return sc, linearize(sc, at=at)
    except HydroarmError as exc:
        if exc.field == "at" or exc.field.startswith("at."):
            raise HydroarmError(field, exc.problem) from None
        if exc.field == "load" and a.load is not None:
            raise HydroarmError("--load", exc.problem) from None
        raise


def _sweep_amplitudes(a, sc) -> list[float] | None:
    """The --amplitude values of ``linearize --sweep`` in SI (None: the joint's default),
    checked before any work: a length for the joint's lever and a mechanical servo's, the
    load's position unit (length or angle) for an electronic servo's reference."""
    if a.amplitude is None:
        if a.sweep is not None and isinstance(sc, ServoScenario):
            raise HydroarmError("--amplitude", "give the reference's sine amplitude for a servo")
        return None
    if a.sweep is None:
        raise HydroarmError("--amplitude", "is for --sweep (the frequency response by simulation)")
    dim = "length"
    if isinstance(sc, ServoScenario):
        P = sc.vector()
        if P[P_FEEDBACK] != FEEDBACK_MECHANICAL and P[P_LOAD] != LOAD_MASS:
            dim = "angle"
    return [_q("--amplitude", text, dim, positive=True) for text in a.amplitude]


def _sweep(a, sc, model, amplitudes):
    """``linearize --sweep``: the frequency response by simulation about the same point."""
    q = model.quantities
    w_h = q.get("hydraulic_natural_frequency_rad_s", math.nan)
    if not (isinstance(w_h, float) and math.isfinite(w_h) and w_h > 0):
        wn = np.abs(model.poles)
        w_h = float(wn.max()) if wn.size and wn.max() > 0 else 1.0
    w = np.logspace(math.log10(w_h / 20), math.log10(3 * w_h), a.frequencies)
    if amplitudes is None:
        amplitudes = default_amplitudes(sc)
    try:
        op = model.operating_point
        at = op["angle"] if model.kind == "joint" else op["position"]
        return frequency_response(sc, w, amplitudes, at=at)
    except HydroarmError as exc:
        if exc.field == "amplitude":
            raise HydroarmError("--amplitude", exc.problem) from None
        raise


def _linearize_circuit(a) -> int:
    """``linearize`` of a circuit file (docs/linear.md "Circuits")."""
    for name in ("load", "parameter_set", "vary", "sweep", "amplitude", "poles", "step_response"):
        if getattr(a, name) is not None:
            raise HydroarmError(_option(name), "is not for a circuit file")
    circuit = _circuit_of(a.config)
    compiled = build_circuit(circuit)
    at = None
    if a.position is not None:
        at = _q("--position", a.position, "length")
    elif a.angle is not None:
        at = _q("--angle", a.angle, "angle")
    model = linearize_circuit(compiled, input=a.input, output=a.output, position=at, loop=a.loop)
    if a.bode is not None:
        save_figure(model.bode_figure(), a.bode)
    if a.json:
        print(json.dumps(_json_value(_complex_free(model.summary()))))
    else:
        print(model.report())
        if a.bode is not None:
            print(f"bode plot written to {a.bode}")
    return 0


def _complex_free(v):
    if isinstance(v, dict):
        return {k: _complex_free(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_complex_free(x) for x in v]
    if isinstance(v, complex):
        return [v.real, v.imag]
    return v


def cmd_linearize(a) -> int:
    if a.config is not None and _circuit_config(a.config):
        return _linearize_circuit(a)
    for name in ("input", "output", "loop"):
        if getattr(a, name) is not None:
            raise HydroarmError(f"--{name}", "is for circuit files ([[component]] entries)")
    variation = _variation_of_args(a)
    got = _linear_model_of_args(a)
    sc, model = got if got is not None else (None, None)
    if model is None:
        for name in ("bode", "poles", "step_response", "sweep"):
            if getattr(a, name) is not None:
                raise HydroarmError(_option(name), "needs a servo: give --load or --config")
    elif a.step_response is not None:
        shown = model.nearest if model.open_loop_reason and model.nearest else model
        if (shown.kind == "joint" and np.max(shown.poles.real) >= 0) or (
            shown.kind == "servo" and (shown.unstable() or shown.open_loop_reason)
        ):
            where = "here" if shown is model else "at the nearest operating point with flow"
            raise HydroarmError(
                "--step-response",
                f"the closed loop is unstable {where} (a pole right of the imaginary axis): "
                "no step to settle",
            )
    amplitudes = _sweep_amplitudes(a, sc) if sc is not None else None
    written = []
    if model is not None:
        for name, make in (
            ("bode", model.bode_figure),
            ("poles", model.pole_figure),
            ("step_response", model.step_figure),
        ):
            if getattr(a, name) is not None:
                save_figure(make(), getattr(a, name))
                written.append(f"{name.replace('_', ' ')} plot written to {getattr(a, name)}")
    fr = None
    if a.sweep is not None:
        fr = _sweep(a, sc, model, amplitudes)
        save_figure(fr.plot(), a.sweep)
        written.append(f"frequency response written to {a.sweep}")
    frame = None
    if variation is not None:
        joint, loads, angles = variation
        frame = linear_variation(joint, loads, angles)
        title = f"{joint.name}: linear quantities against angle, loads {', '.join(map(str, loads))}"
        save_figure(linear_variation_figure(frame, title=title), a.vary)
        written.append(f"variation plot written to {a.vary}")
    if a.json:
        out = model.summary() if model is not None else {}
        if fr is not None:
            out["frequency_response"] = fr.to_pandas().to_dict(orient="records")
        if frame is not None:
            out["variation"] = frame.to_dict(orient="records")
        print(json.dumps(_json_value(out)))
    else:
        if model is not None:
            print(model.report())
        elif frame is not None:
            print(frame.to_string(index=False, float_format=lambda v: f"{v:.5g}"))
        if fr is not None:
            table = fr.to_pandas()[
                ["amplitude", "frequency_rad_s", "gain_db", "phase_deg"]
                + ["linear_gain_db", "linear_phase_deg"]
            ]
            print(
                f"frequency response by simulation ({fr.input} → {fr.output}; "
                f"{len(table)} sine runs in {fr.seconds:.3g} s):"
            )
            print(table.to_string(index=False, float_format=lambda v: f"{v:.5g}"))
        for line in written:
            print(line)
    return 0


def _json_value(v):
    """A summary as JSON: non-finite floats as null, numpy scalars as Python numbers."""
    if isinstance(v, dict):
        return {k: _json_value(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_value(x) for x in v]
    if hasattr(v, "item"):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


# ----------------------------------------------------------------- expand ---
def cmd_expand(a) -> int:
    circuit, kind = expand_file(a.config)
    docs = "docs/mechanism.md" if kind == "arm" else "docs/components.md"
    text = circuit_toml(
        circuit,
        f"The circuit that the {kind} file {Path(a.config).name} stands for\n"
        f"(hydroarm expand; every value in SI, {docs}).",
    )
    if a.out is None:
        print(text, end="")
        return 0
    atomic_write_text(a.out, text)
    print(f"{len(circuit.components)} components; written to {a.out}")
    return 0


# ----------------------------------------------------------------- params ---
def cmd_params(a) -> int:
    names = [a.name] if a.name is not None else parameter_set_names()
    for n in names:
        j = parameter_set(n, "params")
        info = parameter_set_info(n)
        print(f"[{n}] {info.get('description', '')}")
        print(f"  piston_area          A   = {j.piston_area * 1e6:.4g} mm²")
        print(f"  flow_coefficient     K   = {j.flow_coefficient:.5g} m² s⁻¹ Pa^-½")
        print(f"  valve_saturation     e_o = {j.valve_saturation * 1e3:.4g} mm")
        print(f"  leakage_coefficient  L   = {j.leakage_coefficient * 1e15:.4g} mm⁵ s⁻¹ N⁻¹")
        print(f"  trapped_volume       V   = {j.trapped_volume * 1e6:.4g} cm³")
        print(f"  bulk_modulus         β   = {j.bulk_modulus * 1e-6:.4g} MPa")
        print(f"  supply_pressure      p_s = {j.supply_pressure * 1e-5:.4g} bar")
        print(f"  crank_radius         r   = {j.crank_radius * 1e3:.4g} mm")
        print(f"  gear_ratio           n   = {j.gear_ratio:.4g}")
        print(f"  torque_arm               = {j.torque_arm}")
        print(f"  -> flow gain K_q = K·√(p_s/2) = {j.flow_gain:.5g} m²/s")
        print(f"  -> no-load time constant A/K_q = {j.no_load_time_constant * 1e3:.3f} ms")
        print(f"  -> no-load velocity K_q·e_o/A = {j.no_load_velocity * 1e3:.3f} mm/s")
        print(
            f"  -> stall force A·p_s = {j.stall_force:.1f} N, "
            f"stall torque A·p_s·r/n = {j.stall_torque:.3f} N m"
        )
        if not j.is_paper_model:
            print(
                f"  physics: valve_model = {j.valve_model}, coulomb_friction = "
                f"{j.coulomb_friction:.4g} N, static_friction = {j.breakaway_friction:.4g} N, "
                f"viscous_friction = {j.viscous_friction:.4g} N s/m"
            )
            print(
                f"           gearbox_friction_torque = {j.gearbox_friction_torque:.4g} N m, "
                f"gearbox loss c(γ) = {j.gearbox_loss_at_stall:.4g}·γ^"
                f"{j.gearbox_loss_exponent:g}, end_stop_angle = "
                f"{'none' if j.end_stop_angle is None else f'{j.end_stop_angle:.4g} rad'}, "
                f"backlash = {j.backlash:.4g} rad"
            )
            print(
                "           null_leakage_coefficient L₀ = "
                f"{j.null_leakage_coefficient * 1e15:.4g} mm⁵ s⁻¹ N⁻¹"
            )
    return 0


def cmd_reproduce(a) -> int:
    data = reproduce(a.out)
    print("Table III, Model 2 saturation velocity (mm/s): hydroarm against the paper")
    for r in data["table3"]:
        if r["paper_mm_s"] is not None:
            print(
                f"  load {r['load']:>2} {r['direction']:<5}  {r['model_mm_s']:6.1f}"
                f"  (paper {r['paper_mm_s']:.1f})"
            )
    print(f"written to {a.out}/ (report.md, report.html, tables, figures)")
    return 0


def cmd_validate(a) -> int:
    res = validate(a.out, progress=Progress(5))
    for r in res["rows"][:8]:
        print(
            f"{r['quantity']:<28} measured {r['measured']:8.4g}  hydroarm {r['hydroarm']:8.4g}"
            f"  ({100 * r['rel_error']:+.1f} %)"
        )
    print(f"written to {a.out}/validation.csv (+ plots and validation.html)")
    return 0


def cmd_mechanism(a) -> int:
    """``hydroarm arm``: a mechanism file, or an arm file as its mechanism, on the system
    kernel (`hydroarm.arm.mechanism_run`); an arm file with its validation and card."""
    res = run_mechanism(
        a.config,
        a.out,
        progress=Progress(3 if is_mechanism_path(a.config) else 9),
        animation=not a.no_animation,
        validation=arm_validation.validation_rows,
        card=arm_card.arm_card,
        mechanism_card=mechanism_card if a.card else None,
    )
    for r in res["validation"] or ():
        err = r["rel_error"]
        print(
            f"{r['quantity']:<32} measured {r['measured']:7.4g}  model {r['model']:7.4g}"
            + ("" if err != err else f"  ({100 * err:+.1f} %)")
        )
    if res["power"] is not None:
        for line in energy_lines(res["power"]):
            print(line)
    else:
        mech = res["result"].compiled.mechanism
        for name, kind in zip(mech.joint_names, mech.joint_types, strict=True):
            v = res["final"][name]
            shown = f"{v:.4g} m" if kind == "prismatic" else f"{math.degrees(v):.4g} deg"
            print(f"{name:<24} final {shown}")
    e = res["energy"]
    if "mechanism" in e:
        into = f"{e['mechanism']:.4g} J (closure {e['closure']:.2g} J)"
        print(f"{'energy into the mechanism':<24} {into}")
    if res["card"] is not None:
        for line in arm_card.card_lines(res["card"]):
            print(line)
    if res["mechanism_card"] is not None:
        for line in res["mechanism_card"].lines():
            print(line)
    print(f"written to {a.out}/ ({', '.join(res['files'])})")
    return 0


def cmd_arm(a) -> int:
    """``hydroarm arm``: every file on the system kernel (``--mechanism``: the same, kept
    for the files and scripts that name it)."""
    return cmd_mechanism(a)


def energy_lines(e: dict) -> list[str]:
    """The power pack's summary lines of ``hydroarm arm`` (an energy summary of
    `hydroarm.arm.energy.energy_summary`)."""
    lines = [
        f"hydraulic energy (pump)          {e['pump_hydraulic']:9.4g} J over {e['duration']:.4g} s"
        f" (relief valve {e['relief_loss']:.4g} J, valves {e['valves']:.4g} J,"
        f" jacks {e['jack_work']:.4g} J)"
    ]
    if "electric_energy" not in e:
        lines.append(
            "electric energy                  not reported (give power_pack.motor_efficiency "
            "and pump_efficiency)"
        )
        return lines
    lines.append(
        f"electric energy                  {e['electric_energy']:9.4g} J"
        f" (mean {e['mean_electric_power']:.4g} W)"
    )
    lines.append(
        f"energy per cycle                 {e['energy_per_cycle']:9.4g} J"
        f" (the run, {e['duration'] / e['cycles']:.4g} s, as one cycle)"
    )
    if "cycles_per_charge" in e:
        lines.append(
            f"battery: cycles per charge       {e['cycles_per_charge']:9.4g}"
            f" ({e['battery_usable_energy'] / 3600:.4g} W*h usable)"
        )
        lines.append(f"battery: run time per charge     {e['run_time_per_charge'] / 60:9.4g} min")
    return lines


WARMUP_ARM = """
[joints.shoulder_elevation]
parameter_set = "ucl-arm-measured"
[solver]
duration = "0.01 s"
"""


WARMUP_SERVO = """
[actuator]
piston_area = "1 cm**2"
stroke = "0.1 m"
dead_volume = "10 cm**3"
bulk_modulus = "1 GPa"
[valve]
discharge_coefficient = 0.6
density = "870 kg/m**3"
spool_diameter = "5 mm"
max_stroke = "0.5 mm"
[load]
mass = "1 kg"
[supply]
pressure = "100 bar"
[input]
times = ["0 s"]
values = ["0.05 m"]
[solver]
step = "1 us"
duration = "20 us"
record_every = 1
"""


WARMUP_CIRCUIT = """
name = "warmup circuit"
[[component]]
type = "tank"
name = "tank"
ports = { port = "T" }
[[component]]
type = "fixed_pump"
name = "pump"
ports = { inlet = "T", outlet = "supply" }
displacement = "10 cm**3/rev"
speed = "1500 rpm"
[[component]]
type = "volume"
name = "hose"
ports = { port = "supply" }
volume = "1 l"
[[component]]
type = "orifice"
name = "orifice"
ports = { a = "supply", b = "T" }
area = "3 mm**2"
[solver]
step = "100 us"
duration = "1 ms"
record_every = 1
"""


WARMUP_MECHANISM = """
name = "warmup mechanism"
[mechanism]
name = "warmup mechanism"
[[mechanism.link]]
name = "base"
[[mechanism.link]]
name = "bob"
mass = "2 kg"
com = ["0.5 m", "0 m", "0 m"]
ixx = "1e-4 kg*m**2"
iyy = "1e-3 kg*m**2"
izz = "1e-3 kg*m**2"
[[mechanism.joint]]
name = "swing"
type = "continuous"
parent = "base"
child = "bob"
axis = [0, 1, 0]
[solver]
step = "0.2 ms"
duration = "2 ms"
record_every = 1
"""

#: the kernels that numba compiles on first use and `warmup` compiles ahead (cached on
#: disk after): the ones a command calls from Python, by the kind of file that runs them
WARMUP_KERNELS = {
    "paper joint": (integrate, run_many, run_traces),
    # the arm file, the live arm and the arm FMU (ArmStepper) step the arm's circuit on the
    # system kernel (the decoupled loop, simulate_decoupled, is a reference: not warmed)
    "arm": (
        system_kernel.advance,
        system_kernel.advance_records,  # the validation's and card's runs, piece by piece
        system_kernel.start_state,
        circuit_kernel.record_outputs,
    ),
    # a servo file runs its circuit on the system kernel (its observers for metrics)
    "component servo": (
        system_kernel.integrate,
        observer_kernel.observe_many,
    ),
    "circuit": (
        system_kernel.integrate,
        system_kernel.run_many,
        system_kernel.advance,
        system_kernel.start_state,
        system_kernel.derivatives_at,
        observer_kernel.observe_many,
        circuit_kernel.record_outputs,
        circuit_kernel.system_project,
        circuit_kernel.evaluate_signals,
        circuit_kernel.with_derived,
    ),
    "mechanism": (
        tree_kernel.spatial_inertias,
        tree_kernel.make_tree_work,
        tree_kernel.forward_kinematics,
    ),
}

#: the compile notice of the running command (one line on stderr before numba compiles a
#: kernel its disk cache lacks: on a terminal and in a log alike)
_NOTICE = CompileNotice()


def _compile_notice(command: str) -> None:
    """From here on (the command reads and checks its input before its first kernel call),
    one line on stderr when numba starts compiling a kernel that is not in its disk cache,
    naming the kernel the file's kind actually runs
    (`CompileNotice`); for every command but
    ``warmup`` (whose progress says what it compiles); until `_compile_notice_done`.
    ``HYDROARM_COMPILE_NOTICE=0`` silences it (the test suite does, so that its checks of
    stderr hold on the cold cache of a fresh clone)."""
    if command != "warmup" and os.environ.get("HYDROARM_COMPILE_NOTICE", "1") != "0":
        _NOTICE.install()


def _compile_notice_done() -> None:
    _NOTICE.remove()


def warmup(progress=None) -> float:
    """Compile (or load) every simulation kernel: the single joint and the on-the-fly metrics
    for each fixed-step method, with the paper's physics and with options, the whole arm, the
    component servo, and the system kernel of circuits and mechanisms (`WARMUP_KERNELS`
    and the helpers those runs call from Python). Returns the time it took [s]."""
    tick = progress or (lambda label: None)
    t0 = time.perf_counter()
    load = paper_load(6)
    for method in ("euler", "rk4"):
        for name in (DEFAULT_SET, "ucl-arm-measured"):
            sc = saturation_test(parameter_set(name), load, "raise", method=method, duration=0.01)
            res = simulate(sc)
            res.metric_values()
            res.to_pandas()  # the jack's traces
            scenario_traces([sc], [np.array([0.005])])  # the fit's engine
            passes_horizontal(sc)  # the stall-mass search
            friction_torque_unpressurised(sc.joint)  # the validation's friction test
            sc.target_angle(), sc.joint.joint_angle(0.0)  # the crank's kinematics
        tick(f"single joint and batch kernels ({method})")
    warm_arm = load_arm_text(WARMUP_ARM, source="warmup")
    simulate_arm(warm_arm).power_traces()
    simulate_motion(warm_arm)  # the validation's runs: recorded piece by piece
    # the live arm of hydroarm explore and the arm FMU: the arm's circuit (its mechanism, the
    # joints' circuits, the power pack) on the system kernel, its outputs read back
    stepper = ArmStepper(warm_arm)
    stepper.levers = {n: 0.0 for n in stepper.names}
    stepper.advance(0.002)
    stepper.outputs()
    tick("whole-arm kernels")
    servo = load_scenario_text(WARMUP_SERVO, source="warmup")
    for method in ("euler", "rk4"):
        servo.replace(method=method).run().metrics()
        servo_metrics_table([servo.replace(method=method)] * 2)
    tick("component servo kernels (single and batch)")
    for text in (WARMUP_CIRCUIT, WARMUP_MECHANISM):
        compiled = build_circuit(circuit_from_doc(tomllib.loads(text), "warmup"))
        res = simulate_circuit(compiled)  # the system kernel (a mechanism: its tree in it)
        res.to_pandas()  # the recorded outputs (flows, powers, signals)
        two = compiled.P[None, :].repeat(2, axis=0)
        simulate_many(compiled, two)  # sweeps, studies on traces
        first = next(iter(output_sources(compiled)))  # a study's observers, a servo's metrics
        observe_many(compiled, two, compiled.s0[None, :].repeat(2, axis=0),
                     [(first, "max", -math.inf, math.inf)])  # fmt: skip
        CircuitStepper(compiled).advance(2 * compiled.circuit.step)  # explore, FMUs
        for linear_view in (circuit_rhs, circuit_project, circuit_signals):  # linearize
            linear_view(compiled, 0.0, compiled.s0, compiled.P)
        if compiled.mechanism is not None:
            mech = compiled.mechanism
            hyd = len(compiled.hydraulic)
            stick_points(mech, res.states[:, hyd : hyd + mech.n])  # the frames' kinematics
    tick("circuit and mechanism kernels (system kernel, tree)")
    return time.perf_counter() - t0


def cmd_fit(a) -> int:
    problem = read_fit_file(a.config)  # every bad input is reported before any simulation
    starts = (
        problem.starts
        if a.starts is None
        else whole_number("--starts", a.starts, 1, MAX_STARTS, STARTS_WHY)
    )
    loo = True if a.leave_one_out else problem.leave_one_out
    if loo is True and len(loo_groups(problem)) < 2:
        raise HydroarmError("--leave-one-out", "needs at least two groups of traces or targets")
    groups = len(loo_groups(problem)) if loo is True else len(loo or ())
    stages = starts + groups + (1 if problem.bootstrap else 0)
    stages += 1 if "profile" in problem.intervals else 0
    res = fit(problem, a.out, starts=a.starts, leave_one_out=loo, progress=Progress(stages))
    for r in res.table():
        boot = (
            f"; bootstrap ± {r['boot_std_error']:.2g}, 95 % {r['boot_low']:.6g} … "
            f"{r['boot_high']:.6g}"
            if "boot_low" in r
            else ""
        )
        profiles = {p.parameter: p for p in res.profiles or ()}
        if r["parameter"] in profiles:
            boot += f"; profile 95 % {profiles[r['parameter']].describe()}"
        flag = r.get("jacobian_warning", "none")
        untrusted = (
            f"; Jacobian interval not to be trusted: {flag}" if flag not in ("none", "") else ""
        )
        print(
            f"{r['parameter']:<24} {r['estimate']:.6g} ± {r['std_error']:.2g} {r['unit']}"
            f"  (initial {r['initial']:.6g}{boot}{untrusted})"
        )
    for w in res.warnings:
        print(f"warning: {w}")
    for r in res.loo:
        print(
            f"left out {r['group']}: {r['item']}: prediction error {r['prediction_error']:+.4g} "
            f"{r['unit']} (in the full fit {r['fit_error']:+.4g})"
        )
    print(
        f"written to {a.out}/fit.csv (+ correlation.csv, fitted.toml, fit_report.md, "
        "fit_report.html, plots)"
    )
    return 0


def cmd_evaluate(a) -> int:
    doc, path = read_study_doc(a.config)
    if check_system_doc(doc, "evaluate"):  # any system: [system] file = "…"
        sev = read_system_evaluation(doc, path.stem, path.parent)  # checked before any run
        scard = evaluate_system(sev, a.out, progress=Progress(1))
        for line in scard.lines():
            print(line)
        print(f"written to {a.out}/card.csv (+ card.md, card.png)")
        return 0
    ev = read_evaluation_file(a.config)  # every bad input is reported before any simulation
    card = paper_card.evaluate(ev, a.out, progress=Progress(1))
    for line in evaluation_card_lines(card):
        print(line)
    print(f"written to {a.out}/card.csv (+ card.md, card.png)")
    return 0


def cmd_sensitivity(a) -> int:
    check_export(a.export)  # before the file is read
    study = read_sensitivity_file(a.config)  # every bad input is reported before any run
    res = sensitivity(study, a.out, export=a.export)
    key = "ST" if study.plan.method == "sobol" else "mu_star"
    for k in res.outputs:
        rows = [r for r in res.rows if r["metric"] == k and r[key] == r[key]]
        top = sorted(rows, key=lambda r: -r[key])[:3]
        shown = ", ".join(f"{r['parameter']} {r[key]:.3g}" for r in top) or "— (constant)"
        print(f"{k:<32} largest {key}: {shown}")
    for line in res.notes:
        print(line.removeprefix("- "))
    print(
        f"{res.scenarios} scenarios in {res.elapsed_s:.1f} s "
        f"({res.rate:.4g} scenarios/s); written to {a.out}/{res.table_name} "
        "(+ samples.csv, sensitivity_report.md, plots"
        + "".join(f", sensitivity{EXPORT_SUFFIXES[f]}" for f in dict.fromkeys(a.export))
        + ")"
    )
    return 0


def cmd_design(a) -> int:
    t0 = time.perf_counter()
    # every bad input is reported before any simulation
    refine = False if a.no_refine else None
    doc, path = read_study_doc(a.config)
    if check_system_doc(doc, "design"):  # any system: [system] file = "…"
        return _design_system(a, doc, path, refine, t0)
    study = read_design_file(a.config, samples=a.samples, refine=refine)
    res = design(study, a.out, t0=t0)
    n, nf, npar = len(res.evaluation.x), int(res.feasible.sum()), int(res.pareto.sum())
    print(
        f"{n} designs x {len(study.cases)} load cases: {nf} feasible, {npar} on the Pareto "
        f"front ({res.elapsed_s:.1f} s, {res.throughput():.3g} designs·cases/s)"
    )
    rec = res.recommended(1)
    if rec:
        i = rec[0]
        shown = [display(v.unit) for v in study.variables]
        values = ", ".join(
            f"{v.name} = {res.evaluation.x[i, k] * f:.4g} {u}".rstrip()
            for k, (v, (u, f)) in enumerate(zip(study.variables, shown, strict=True))
        )
        print(
            f"recommended: design {i + 1} ({values}; smallest margin "
            f"{res.evaluation.smallest_margin[i]:+.3f})"
        )
    print(f"written to {a.out}/designs.csv (+ design_report.md, pareto.png, feasibility.png)")
    return 0


def _design_system(a, doc, path, refine, t0) -> int:
    study = read_system_design(doc, path.stem, path.parent, samples=a.samples, refine=refine)
    res = run_system_design(study, a.out, t0=t0)
    n, nf, npar = len(res.evaluation.x), int(res.feasible.sum()), int(res.pareto.sum())
    cases = f" in {len(study.cases)} load cases" if study.cases else ""
    print(
        f"{n} designs of the {study.runner.kind} '{study.runner.name}'{cases}: {nf} feasible, "
        f"{npar} on the Pareto front, {res.failed()} failed ({res.elapsed_s:.1f} s, "
        f"{res.throughput():.3g} designs/s)"
    )
    rec = res.recommended(1)
    if rec:
        i = rec[0]
        print(
            f"recommended: design {i + 1} ({res.recommended_values(i)}; smallest margin "
            f"{res.evaluation.smallest_margin[i]:+.3f})"
        )
    else:
        print("no design meets every requirement (design_report.md: the closest)")
    extra = ", cases.csv" if study.cases else ""
    print(
        f"written to {a.out}/designs.csv (+ design_report.md, pareto.png, feasibility.png{extra})"
    )
    return 0


def cmd_fmu(a) -> int:
    if a.check is not None:  # issue 33: hydroarm fmu --check FILE.fmu
        if a.config is not None:
            raise HydroarmError("--check", "checks an FMU: give it without --config")
        return cmd_fmu_check(a)
    if a.config is None:
        raise HydroarmError("--config", "is required (or give --check FILE.fmu)")
    step = _q("--step", a.step, "time", positive=True) if a.step is not None else None
    outputs = None
    if a.outputs is not None:
        outputs = [n.strip() for n in a.outputs.split(",") if n.strip()]
    res = export_fmu(
        a.config, a.out, step=step, method=a.method, outputs=outputs, progress=Progress(2)
    )
    n = {c: sum(1 for v in res["variables"].values() if v == c) for c in ("input", "output")}
    params = sum(1 for v in res["variables"].values() if v == "parameter")
    print(
        f"{res['model_name']} ({res['kind']}): {n['input']} inputs, {n['output']} outputs, "
        f"{params} parameters; written to {res['path']} (FMI 2.0 co-simulation; the target "
        "needs a Python with hydroarm; check it: hydroarm fmu --check FILE; docs/fmu.md)"
    )
    return 0


def cmd_explore(a) -> int:
    """Check the arm or the system, the port and the output folder, then serve until
    interrupted."""
    host = explore_launch.check_host(a.host)
    target = explore_launch.explore_target(a.config, progress=Progress(2))
    token = session_token(host)  # beyond the loopback interface: a token in the URL
    url = f"hydroarm explore: {page_url(host, a.port, token)} (Ctrl-C stops it)"
    if isinstance(target, explore_launch.SystemModel):
        explore_launch.check_system(a.port, host)
        print(url, flush=True)
        explore_launch.serve_system(
            target, port=a.port, show=not a.no_browser, host=host, token=token
        )
        return 0
    sc = target
    out = explore_launch.check(sc, a.port, a.out, progress=Progress(2), host=host)
    print(url, flush=True)
    explore_launch.serve(
        sc, port=a.port, show=not a.no_browser, out_dir=out, host=host, token=token
    )
    return 0


def cmd_warmup(a) -> int:
    took = warmup(Progress(5, enabled=True))
    print(f"simulation kernels ready ({took:.1f} s)")
    return 0


def cmd_sweep(a) -> int:
    check_export(a.export)  # before the file is read
    sw = load_sweep(a.config)
    work = sw.size * sw.base.nsteps
    if sys.stderr.isatty():  # progress, like the bar; keeps an error to one line elsewhere
        print(
            f"{sw.size} scenarios x {sw.base.nsteps} steps ({sw.base.method}, "
            f"{sw.base.step * 1e6:g} us): {work:.3g} scenario-steps",
            file=sys.stderr,
        )
    if not a.force and work > MAX_SWEEP_WORK:
        raise HydroarmError(
            "--config",
            f"{sw.size} scenarios x {sw.base.nsteps:.3g} steps = {work:.3g} scenario-steps is "
            f"above the limit of {MAX_SWEEP_WORK:.0e} scenario-steps (hours of work); "
            "shorten the duration, "
            "use a larger step or fewer scenarios, or give --force",
        )
    out = run_sweep(
        sw,
        a.out,
        chunk=a.chunk,
        resume=a.resume,
        executor=a.executor,
        scheduler=a.scheduler,
        export=a.export,
    )
    _sweep_summary(sw, out)
    for f in dict.fromkeys(a.export):
        print(f"also written to {out.with_suffix(EXPORT_SUFFIXES[f])}")
    return 0


def _sweep_summary(sw, out) -> int:
    if isinstance(sw, ServoSweep):
        return _servo_sweep_summary(out)
    if isinstance(sw, CircuitSweep):
        c = circuit_summary(out, [m.column for m in sw.metrics])
        print(f"{c['scenarios']} scenarios ({c['failed']} failed); written to {out}")
        for k, (rows, mean, sd) in c["metrics"].items():
            print(f"  {k:<32} {mean:10.4g} ± {sd:.3g} over {rows} rows")
        return 0
    s = summary(out)
    velocity = (
        f"saturation velocity {s['saturation_velocity_mm_s_mean']:.4g} ± "
        f"{s['saturation_velocity_mm_s_sd']:.3g} mm/s over {s['measured']} rows"
        if s["measured"]
        else "no row measured a saturation velocity"
    )
    print(
        f"{s['scenarios']} scenarios ({s['failed']} failed, {s['stalled']} stalled): "
        f"{velocity}; written to {out}"
    )
    return 0


def _servo_sweep_summary(out) -> int:
    s = servo_summary(out)
    settled = s["settling_time_s_rows"]
    settling = (
        f"settling time {s['settling_time_s_mean']:.4g} ± {s['settling_time_s_sd']:.3g} s over "
        f"{settled} rows"
        if settled
        else "no row settled"
    )
    print(
        f"{s['scenarios']} scenarios ({s['failed']} failed): {settling}; peak chamber pressure "
        f"{s['peak_pressure_bar_mean']:.4g} ± {s['peak_pressure_bar_sd']:.3g} bar; "
        f"written to {out}"
    )
    return 0


_signalled: list[int] = []  # the signals received by main()'s handler


# Python code where an exception breaks the library's own state: numba boxing a kernel's
# results (a crash with numba 0.68), numba and llvmlite compiling (a half-built llvmlite
# object whose finaliser then complains on stderr after the interrupted line)
_DEFER_IN = ("numba", "llvmlite")


def _on_signal(signum, frame):
    """SIGINT and SIGTERM: the same KeyboardInterrupt wherever the program is, except inside
    numba's or llvmlite's own Python code (`_DEFER_IN`: a compiled kernel that has just
    returned, its results being boxed through numba's helpers, or a kernel being compiled):
    an exception raised there becomes a SystemError, a crash (numba 0.68, a result of
    several arrays) or a half-built object, so the signal is raised again a moment later,
    when the main thread is back in hydroarm's code; if it stays in there (a long
    compilation), the watchdog ends the program after its grace time."""
    if frame is not None and str(frame.f_globals.get("__name__", "")).startswith(_DEFER_IN):
        # not recorded as handled: if the main thread is stuck in the next kernel, the
        # watchdog still ends the program after its grace time
        timer = threading.Timer(0.02, _resend_signal, (signum,))
        timer.daemon = True  # never keeps a finished program alive
        timer.start()
        return
    _signalled.append(signum)
    raise KeyboardInterrupt


def _resend_signal(signum: int) -> None:
    """The deferred signal of `_on_signal`, sent again unless the program has handled
    an interruption meanwhile or no longer listens (its handlers restored on the way out:
    the default action would kill it)."""
    if not _signalled and signal.getsignal(signum) is _on_signal:
        os.kill(os.getpid(), signum)


def _install_signal_handlers() -> dict:
    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            old[sig] = signal.signal(sig, _on_signal)
        except (ValueError, OSError):  # not the main thread: leave the handlers alone
            pass
    return old


def _interruption(exc: BaseException) -> BaseException | None:
    """The KeyboardInterrupt behind ``exc`` (itself, or its cause/context, e.g. a
    SystemError raised when a signal lands inside compiled code), or None."""
    seen = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return e
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return None


def _print_interrupted(exc: BaseException | None) -> int:
    detail = str(exc).splitlines()[0] if isinstance(exc, Interrupted) and str(exc) else ""
    print("hydroarm: interrupted" + (f": {detail}" if detail else ""), file=sys.stderr)
    return EXIT_INTERRUPTED


STUCK_GRACE_S = 3.0  # a signal not handled within this time: the main thread is stuck


class _Watchdog:
    """Ctrl-C inside compiled code: Python runs signal handlers only between bytecodes, so a
    long numba kernel would ignore it until it returns. The C-level handler still writes the
    signal to a wake-up pipe; this thread reads it and, when the main thread has not handled
    the signal within ``STUCK_GRACE_S``, prints the interrupted line and exits with 130
    (finished files are complete: every write is atomic; a staging folder left is removed by
    the next run, a sweep's finished chunks are kept for --resume)."""

    def __init__(self):
        self.stop = threading.Event()
        self.r, self.w = os.pipe()
        os.set_blocking(self.w, False)
        self.old_fd = signal.set_wakeup_fd(self.w, warn_on_full_buffer=False)
        self.thread = threading.Thread(target=self._watch, name="hydroarm-signals", daemon=True)
        self.thread.start()

    def _watch(self):
        while not self.stop.is_set():
            ready, _, _ = select.select([self.r], [], [], 0.2)
            if not ready or self.stop.is_set():
                continue
            os.read(self.r, 64)
            deadline = time.monotonic() + STUCK_GRACE_S
            while time.monotonic() < deadline:
                if self.stop.is_set() or _signalled:
                    break
                time.sleep(0.05)
            else:
                sys.stderr.write("hydroarm: interrupted\n")
                sys.stderr.flush()
                os._exit(EXIT_INTERRUPTED)

    def close(self):
        self.stop.set()
        signal.set_wakeup_fd(self.old_fd)
        try:  # wake the watcher from its select (else the join waits up to 0.2 s)
            os.write(self.w, b"\0")
        except OSError:  # the pipe is full: it is awake anyway
            pass
        self.thread.join()
        os.close(self.r)
        os.close(self.w)


def main(argv=None) -> int:
    # figures are written to files: a non-interactive backend unless the user chose one
    os.environ.setdefault("MPLBACKEND", "Agg")
    old = _install_signal_handlers()
    _signalled.clear()
    watchdog = _Watchdog() if old else None
    try:
        rc = _main(argv)
        if _signalled and rc != EXIT_INTERRUPTED:  # a signal swallowed on the way
            return _print_interrupted(None)
        return rc
    except KeyboardInterrupt as exc:  # a second signal during the handling of the first
        return _print_interrupted(exc)
    finally:
        _compile_notice_done()
        if watchdog is not None:
            watchdog.close()
        for sig, handler in old.items():
            signal.signal(sig, handler)


def _main(argv) -> int:
    parser = build_parser()
    a = None
    try:
        a = parser.parse_args(argv)
        if a.command is None:  # argparse's convention: the usage and the error on stderr
            parser.print_usage(sys.stderr)
            raise HydroarmError("command", "is missing (see 'hydroarm --help')")
        _check_outputs(a)
        _compile_notice(a.command)  # a line before numba compiles, for any command and file
        return {
            "simulate": cmd_simulate,
            "linearize": cmd_linearize,
            "reproduce": cmd_reproduce,
            "params": cmd_params,
            "expand": cmd_expand,
            "validate": cmd_validate,
            "arm": cmd_arm,
            "sweep": cmd_sweep,
            "warmup": cmd_warmup,
            "fit": cmd_fit,
            "design": cmd_design,
            "evaluate": cmd_evaluate,
            "sensitivity": cmd_sensitivity,
            "fmu": cmd_fmu,
            "explore": cmd_explore,
            "examples": cmd_examples,
        }[a.command](a)
    except HydroarmError as exc:
        if _signalled:
            return _print_interrupted(None)
        exc = _named_output(exc, a)
        msg = str(exc).splitlines()[0] if str(exc) else "invalid input"
        print(f"hydroarm: error: {msg}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt as exc:
        return _print_interrupted(exc)
    except MemoryError:
        print(
            "hydroarm: error: out of memory (shorten --duration, keep fewer steps with "
            "--print-every, or run fewer scenarios)",
            file=sys.stderr,
        )
        return EXIT_USAGE
    except Exception as exc:  # an unexpected failure: still one line unless debugging
        ki = _interruption(exc)
        if ki is not None or _signalled:
            return _print_interrupted(ki)
        if os.environ.get("HYDROARM_DEBUG"):
            raise
        msg = str(exc).splitlines()[0] if str(exc) else ""
        print(
            f"hydroarm: internal error: {type(exc).__name__}: {msg} "
            "(set HYDROARM_DEBUG=1 for a traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
