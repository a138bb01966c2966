"""The result of one simulation: time series, metrics, tables and plots."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.equations import jack_position_trace, jack_velocity_trace, valve_opening
from ..core.lever import play_operator
from ..files import atomic_write_text
from ..metrics.energy import energy_balance
from ..metrics.step import step_metrics
from ..plotting.joint import plot_result

CSV_COLUMNS = ("t_s", "x_mm", "theta_deg", "p_bar", "xdot_mm_s")


@dataclass
class SimulationResult:
    """Time series of one run, in SI units.

    Attributes
    ----------
    t : [s]; theta : joint angle θ₂ [rad] from the Appendix I datum; omega : [rad/s];
    p : load pressure [Pa]; y : lever input [m]; scenario : the :class:`Scenario` run.
    Derived: x (jack position from mid-stroke [m]), xdot [m/s], e (valve opening [m]).
    """

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    p: np.ndarray
    y: np.ndarray
    scenario: object

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
        (play operator, :func:`hydroarm.core.inputs.play_operator`); θ₂ when there is none."""
        b = self.scenario.joint.backlash
        if b == 0:
            return self.theta
        return play_operator(self.theta, b)

    def energy_balance(self) -> dict:
        """Energy bookkeeping terms [J] (:func:`hydroarm.analysis.energy.energy_balance`)."""
        return energy_balance(self)

    def metrics(self, **kwargs) -> dict:
        """Paper metrics in SI (see :func:`hydroarm.analysis.metrics.step_metrics`)."""
        sc = self.scenario
        lev = sc.lever
        opts = dict(
            valve_opening=sc.joint.valve_saturation,
            target=sc.target,
            full_opening_velocity=sc.joint.no_load_velocity,
        )
        if lev.description == "step":
            opts["t_start"] = float(lev.times[0])
        opts.update(sc.metric_options.as_kwargs())
        opts.update(kwargs)
        return step_metrics(self.t, self.x, **opts)

    def summary(self) -> dict:
        """Metrics in the paper's units (mm/s, ms, bar) for JSON output."""
        m = self.metrics()
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
            "time_constant_end_ms": r(m["time_constant_end"], 1e3),
            "stalled": m["stalled"],
            "stall_position_mm": r(m["stall_position"], 1e3),
            "angular_velocity_rad_s": r(m["saturation_velocity"] / abs(stroke_per_rad), 1.0)
            if math.isfinite(stroke_per_rad)
            else None,
            "peak_pressure_bar": r(float(np.max(np.abs(self.p))), 1e-5),
            "no_load_time_constant_ms": r(sc.joint.no_load_time_constant, 1e3),
            "method": sc.method,
            "step_s": sc.step,
            "load": sc.load.name,
            "direction": sc.direction,
        }

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(
            {
                "t_s": self.t,
                "x_mm": self.x * 1e3,
                "theta_deg": np.degrees(self.theta),
                "p_bar": self.p * 1e-5,
                "xdot_mm_s": self.xdot * 1e3,
                "omega_rad_s": self.omega,
                "e_mm": self.e * 1e3,
                "y_mm": self.y * 1e3,
            }
        )

    def table(self) -> np.ndarray:
        """Rows of (t [s], x [mm], θ₂ [deg], p [bar], ẋ [mm/s])."""
        return np.column_stack(
            [self.t, self.x * 1e3, np.degrees(self.theta), self.p * 1e-5, self.xdot * 1e3]
        )

    def to_csv(self, path) -> None:
        """Write ``t_s,x_mm,theta_deg,p_bar,xdot_mm_s`` atomically (no half-written file)."""
        rows = self.table()
        lines = [",".join(CSV_COLUMNS)]
        lines += [",".join(f"{v:.9g}" for v in row) for row in rows]
        atomic_write_text(path, "\n".join(lines) + "\n")

    def plot(self, ax=None, **kwargs):
        return plot_result(self, ax=ax, **kwargs)
