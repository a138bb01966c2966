"""The result of one simulation: time series, metrics, tables and plots."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING

import numpy as np

from ..core.equations import jack_position_trace, jack_velocity_trace, valve_opening
from ..core.lever import play_operator
from ..display import Summarised, fmt, span
from ..errors import HydroarmError
from ..files import atomic_write_text
from ..integrators import registry
from ..metrics.energy import energy_balance
from ..metrics.online import on_the_fly, scenario_metrics, scenarios_metrics
from ..metrics.step import MetricOptions, step_metrics, with_units
from ..plotting.joint import plot_result

if TYPE_CHECKING:  # for annotations only (scenario.py imports this module)
    import pandas as pd

    from .scenario import Scenario


@dataclass(frozen=True)
class Column:
    """One output column of a result: its name, unit, meaning and how it is computed."""

    name: str
    unit: str
    description: str
    accessor: Callable[..., np.ndarray]


COLUMNS: tuple[Column, ...] = (
    Column("t_s", "s", "time", lambda r: r.t),
    Column("x_mm", "mm", "jack position from mid-stroke", lambda r: r.x * 1e3),
    Column(
        "theta_deg",
        "deg",
        "joint angle θ₂ from the Appendix I datum",
        lambda r: np.degrees(r.theta),
    ),
    Column("p_bar", "bar", "load pressure", lambda r: r.p * 1e-5),
    Column("xdot_mm_s", "mm/s", "jack velocity", lambda r: r.xdot * 1e3),
    Column("omega_rad_s", "rad/s", "joint angular velocity", lambda r: r.omega),
    Column("e_mm", "mm", "valve opening", lambda r: r.e * 1e3),
    Column("y_mm", "mm", "lever input", lambda r: r.y * 1e3),
)
COLUMN = {c.name: c for c in COLUMNS}
# the columns of table() and to_csv() unless others are asked for (to_pandas: all of them)
DEFAULT_COLUMNS = ("t_s", "x_mm", "theta_deg", "p_bar", "xdot_mm_s")
CSV_COLUMNS = DEFAULT_COLUMNS


def select_columns(spec: dict, columns, default) -> tuple:
    """The `Column` objects named by ``columns`` (default ``default``), in that order."""
    names = tuple(default if columns is None else columns)
    unknown = [n for n in names if n not in spec]
    if unknown or not names:
        raise HydroarmError(
            "columns", f"unknown {unknown!r}; choose from {', '.join(spec)}" if unknown else "empty"
        )
    return tuple(spec[n] for n in names)


_THRESHOLDS = tuple(f.name for f in fields(MetricOptions))
# a run thinned by record_every whose metrics cannot be observed during the run is run again
# at full resolution to measure it, if its trace is at most this long [rows]
METRIC_TRACE_LIMIT = 10**7


def plain_metrics(m: dict) -> dict:
    """A metric dictionary with plain Python numbers (no numpy scalars), tuples kept."""
    return {k: _plain(v) for k, v in m.items()}


def _plain(v):
    if isinstance(v, tuple):
        return tuple(_plain(x) for x in v)
    if isinstance(v, np.bool_):
        return bool(v)
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.floating):
        return float(v)
    return v


def csv_lines(names, rows, fmt: str = ".9g") -> str:
    """CSV text of a header and numeric rows."""
    lines = [",".join(names)]
    lines += [",".join(f"{v:{fmt}}" for v in row) for row in rows]
    return "\n".join(lines) + "\n"


@dataclass(repr=False)
class SimulationResult(Summarised):
    """Time series of one run, in SI units.

    Derived: ``x`` (jack position from mid-stroke [m]), ``xdot`` [m/s], ``e`` (valve opening
    [m]).

    Parameters
    ----------
    t : numpy.ndarray
        Times [s].
    theta : numpy.ndarray
        Joint angle θ₂ [rad] from the Appendix I datum.
    omega : numpy.ndarray
        Joint angular velocity [rad/s].
    p : numpy.ndarray
        Load pressure [Pa].
    y : numpy.ndarray
        Lever input [m].
    scenario : Scenario
        The [`Scenario`][hydroarm.Scenario] run.
    """

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    p: np.ndarray
    y: np.ndarray
    scenario: Scenario
    _metrics: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def _summary(self) -> list[tuple[str, str]]:
        sc = self.scenario
        return [
            ("scenario", sc.name),
            ("run", f"{span(self.t)}, {sc.method}, step {fmt(sc.step * 1e6)} us"),
            ("θ₂", f"{fmt(np.degrees(self.theta[0]))} → {fmt(np.degrees(self.theta[-1]), 'deg')}"),
            ("peak load pressure", fmt(np.max(self.p) / 1e5, "bar")),
            ("load", f"W {fmt(sc.load.weight, 'N')}, X {fmt(sc.load.arm * 1e3, 'mm')}"),
        ]

    def _trace_columns(self):
        return {
            "theta_deg": np.degrees(self.theta),
            "x_mm": self.x * 1e3,
            "xdot_mm_s": self.xdot * 1e3,
            "p_bar": self.p / 1e5,
        }, {}

    @property
    def x(self) -> np.ndarray:
        return jack_position_trace(self.theta, self.scenario.params[0])

    @property
    def xdot(self) -> np.ndarray:
        return jack_velocity_trace(self.theta, self.omega, self.scenario.params[0])

    @property
    def e(self) -> np.ndarray:
        return valve_opening(self.y, self.x, self.scenario.params[0])

    @property
    def arm_angle(self) -> np.ndarray:
        """Angle of the arm itself [rad]: the joint angle θ₂ through the gearbox backlash
        (play operator, `hydroarm.core.lever.play_operator`); θ₂ when there is none."""
        b = self.scenario.joint.backlash
        if b == 0:
            return self.theta
        return play_operator(self.theta, b)

    def energy_balance(self) -> dict:
        """Energy bookkeeping terms [J] (`hydroarm.metrics.energy.energy_balance`)."""
        return energy_balance(self)

    def metrics(self, **kwargs) -> dict:
        """Paper metrics in SI, plain Python numbers, each name with its unit
        (``saturation_velocity_m_s``, ``time_constant_start_s``, ``peak_pressure_pa``,
        ``final_x_m``; ``stalled``, ``direction`` and ``stall_reason`` without):
        [`metric_values`][hydroarm.SimulationResult.metric_values] under the names of
        `with_units` (docs/model.md "Units in names")."""
        return with_units(self.metric_values(**kwargs))

    def metric_values(self, **kwargs) -> dict:
        """Paper metrics in SI keyed by their identifiers (``saturation_velocity``, the
        names that requirement, fit and sweep files use; see `hydroarm.metrics.step`),
        plain Python numbers, measured on the full-resolution run whatever the run kept
        (``record_every``).

        A step lever run with a fixed step is observed at every step by the kernels of
        `hydroarm.metrics.online` (as the batch engine does: one definition, and
        ``peak_pressure`` [Pa] and ``final_x`` [m] besides); other runs are measured on their
        trace, re-run at full resolution when it was thinned. Keyword arguments are those of
        [`step_metrics`][hydroarm.step_metrics]; thresholds alone (``middle``,
        ``threshold``, ``stall_tolerance``) keep the on-the-fly path."""
        sc = self.scenario
        thresholds = {k: kwargs.pop(k) for k in list(kwargs) if k in _THRESHOLDS}
        options = MetricOptions(**{**sc.metric_options.as_kwargs(), **thresholds})
        if not kwargs and on_the_fly(sc):
            if options not in self._metrics:
                self._metrics[options] = scenario_metrics(sc.replace(metric_options=options))
            return plain_metrics(self._metrics[options])
        full = self
        if sc.record_every > 1 and registry.method(sc.method).fixed_step:
            if sc.nsteps + 2 > METRIC_TRACE_LIMIT:
                raise HydroarmError(
                    "metrics",
                    f"measuring this run needs its full trace of {sc.nsteps:.3g} steps (at "
                    f"most {METRIC_TRACE_LIMIT:.0e}): use a step lever, whose metrics are "
                    "observed during the run, or a larger step",
                )
            full = sc.integrate(record_every=1)
        return full._trace_metrics(options, **kwargs)

    def _trace_metrics(self, options: MetricOptions, **kwargs) -> dict:
        sc = self.scenario
        lev = sc.lever
        opts = dict(
            valve_opening=sc.joint.valve_saturation,
            target=sc.target,
            full_opening_velocity=sc.joint.no_load_velocity,
        )
        if lev.description == "step":
            opts["t_start"] = float(lev.times[0])
        opts.update(options.as_kwargs())
        opts.update(kwargs)
        m = step_metrics(self.t, self.x, **opts)
        m["peak_pressure"] = float(np.max(np.abs(self.p)))
        m["final_x"] = float(self.x[-1])
        return plain_metrics(m)

    def summary(self) -> dict:
        """Metrics in the paper's units (mm/s, ms, bar) for JSON output."""
        m = self.metric_values()
        sc = self.scenario

        def r(v, scale):
            return None if v is None or not math.isfinite(v) else round(v * scale, 6)

        stroke_per_rad = (
            (self.x[-1] - self.x[0]) / (self.theta[-1] - self.theta[0])
            if self.theta[-1] != self.theta[0]
            else math.nan
        )
        return {
            "saturation_velocity_mm_s": r(m["saturation_velocity"], 1e3),
            "time_constant_start_ms": r(m["time_constant_start"], 1e3),
            "time_constant_start_velocity_ms": r(m["time_constant_start_velocity"], 1e3),
            "time_constant_end_ms": r(m["time_constant_end"], 1e3),
            "stalled": m["stalled"],
            "stall_reason": m["stall_reason"],
            "stall_position_mm": r(m["stall_position"], 1e3),
            "angular_velocity_rad_s": r(m["saturation_velocity"] / abs(stroke_per_rad), 1.0)
            if math.isfinite(stroke_per_rad)
            else None,
            "peak_pressure_bar": r(m["peak_pressure"], 1e-5),
            "no_load_time_constant_ms": r(sc.joint.no_load_time_constant, 1e3),
            "method": sc.method,
            "step_s": sc.step,
            "load": sc.load.name,
            "direction": sc.direction,
        }

    columns = COLUMNS  # the column specification of table(), to_csv() and to_pandas()

    def table(self, columns=None) -> np.ndarray:
        """Rows of the ``columns`` (names of `COLUMNS`; default: t [s], x [mm],
        θ₂ [deg], p [bar], ẋ [mm/s])."""
        cols = select_columns(COLUMN, columns, DEFAULT_COLUMNS)
        return np.column_stack([c.accessor(self) for c in cols])

    def to_csv(self, path, columns=None) -> None:
        """Write the ``columns`` (default ``t_s,x_mm,theta_deg,p_bar,xdot_mm_s``) atomically
        (no half-written file)."""
        cols = select_columns(COLUMN, columns, DEFAULT_COLUMNS)
        atomic_write_text(path, csv_lines([c.name for c in cols], self.table(columns)))

    def to_pandas(self, columns=None) -> pd.DataFrame:
        """A DataFrame of the ``columns`` (default: every column of `COLUMNS`)."""
        cols = select_columns(COLUMN, columns, COLUMN)
        import pandas as pd  # lazy: pandas costs ~0.2 s of start-up, most runs never need it

        return pd.DataFrame({c.name: c.accessor(self) for c in cols})

    def plot(self, ax=None, **kwargs):
        return plot_result(self, ax=ax, **kwargs)


def measure_together(results) -> None:
    """Measure the metrics of many results at once: those whose metrics are observed on the
    fly (a step lever, a fixed step) go through the batch engine, one run per group sharing
    method, step, duration, step time and metric options; each result keeps its metrics, so
    that its [`SimulationResult.metrics`][hydroarm.SimulationResult.metrics] returns them without
    running it again (the same kernel: the same numbers)."""
    groups: dict = {}
    for r in results:
        sc = r.scenario
        if on_the_fly(sc) and sc.metric_options not in r._metrics:
            key = (sc.method, sc.step, sc.nsteps, float(sc.lever.times[0]), sc.metric_options)
            groups.setdefault(key, []).append(r)
    for rs in groups.values():
        for r, m in zip(rs, scenarios_metrics([r.scenario for r in rs]), strict=True):
            r._metrics[r.scenario.metric_options] = m
