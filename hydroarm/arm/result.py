"""Result of a whole-arm run: per-joint traces, supply pressure, the arm's 3-D pose."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.arm_kinematics import JOINT_NAMES, arm_points
from ..display import Summarised, fmt, span
from ..errors import HydroarmError
from ..files import atomic_write_text
from ..metrics.step import step_metrics, with_units
from ..model.result import Column, csv_lines, plain_metrics, select_columns
from ..plotting import arm as arm_plots
from . import energy as arm_energy

if TYPE_CHECKING:  # for annotations only (model.py imports this module)
    import pandas as pd

    from ..model.circuit import CircuitResult
    from .model import ArmScenario

# The column specification of a whole-arm result. Per-joint columns are named
# ``{joint}_{suffix}``; their accessor gets (result, joint index, joint name).
ARM_COLUMNS: tuple[Column, ...] = (
    Column("t_s", "s", "time", lambda r: r.t),
    Column("supply_pressure_bar", "bar", "supply pressure", lambda r: r.supply_pressure * 1e-5),
)
JOINT_COLUMNS: tuple[Column, ...] = (
    Column("deg", "deg", "articulation angle", lambda r, i, n: np.degrees(r.angle(n))),
    Column("rate_deg_s", "deg/s", "servo angular rate", lambda r, i, n: np.degrees(r.omega[:, i])),
    Column("pressure_bar", "bar", "load pressure", lambda r, i, n: r.p[:, i] * 1e-5),
    Column("lever_mm", "mm", "lever position", lambda r, i, n: r.y[:, i] * 1e3),
)
POINTS = ("elbow", "wrist", "hand")
HAND_COLUMNS: tuple[Column, ...] = (
    Column("t_s", "s", "time", lambda r, pts: r.t),
    *(
        Column(f"{p}_{a}_m", "m", f"{p} position, {a} axis", lambda r, pts, k=k, j=j: pts[:, k, j])
        for k, p in enumerate(POINTS)
        for j, a in enumerate("xyz")
    ),
)


@dataclass(repr=False)
class ArmResult(Summarised):
    t: np.ndarray  # [s]
    theta: np.ndarray  # servo angles (n, joints) [rad]
    omega: np.ndarray  # [rad/s]
    p: np.ndarray  # load pressures [Pa]
    y: np.ndarray  # lever positions [m]
    supply_pressure: np.ndarray  # [Pa]
    scenario: ArmScenario
    # the component servo states (n, joints, hydroarm.core.servo.STATES) of the joints built
    # from components (rows of the other joints zero) of a run of the decoupled model
    # (hydroarm.reference.arm_decoupled.simulate_decoupled); None when no joint is, and on
    # the system kernel
    component_states: np.ndarray | None = None
    # the run on the system kernel (hydroarm.arm.expand.simulate_arm): the arm's mechanism
    # and circuits, every output by name and the energy account; None from the decoupled model
    circuit: CircuitResult | None = None

    def _summary(self) -> list[tuple[str, str]]:
        sc = self.scenario
        p = self.supply_pressure / 1e5
        return [
            ("arm", sc.name),
            ("run", f"{span(self.t)}, {sc.method}, step {fmt(sc.step * 1e6)} us"),
            ("joints", ", ".join(self.names)),
            ("supply pressure", f"{fmt(np.min(p))} … {fmt(np.max(p), 'bar')}"),
        ]

    def _trace_columns(self):
        cols = {f"{n}_deg": np.degrees(self.angle(n)) for n in self.names}
        cols["supply_pressure_bar"] = self.supply_pressure / 1e5
        return cols, {}

    @property
    def names(self) -> list[str]:
        return [j.name for j in self.scenario.joints]

    def index(self, name: str) -> int:
        return self.names.index(name)

    def angle(self, name: str) -> np.ndarray:
        """Articulation angle of joint ``name`` [rad] (servo angle + offset)."""
        j = self.scenario.joint(name)
        return self.theta[:, self.index(name)] + j.angle_offset

    def articulation_angles(self) -> np.ndarray:
        """(n, 4) articulation angles (α, ψ, ε, ρ) of the arm's pose: joints not in the arm
        stay at 0, a joint with a fixed load (on a bench, off the arm's tree:
        `hydroarm.arm.expand.arm_circuit`) at its initial angle."""
        q = np.zeros((self.t.size, 4))
        for j in self.scenario.joints:
            k = JOINT_NAMES.index(j.name)
            if j.fixed_load is None:
                q[:, k] = self.angle(j.name)
            else:
                q[:, k] = self.scenario.initial_angles[j.name]
        return q

    def points(self, rows=None) -> np.ndarray:
        """(n, 3, 3) positions [m] of elbow, wrist and hand against time (at the samples
        ``rows``, an index array, if given)."""
        G = self.scenario.geometry.params()
        q = self.articulation_angles()
        if rows is not None:
            q = q[rows]
        out = np.empty((q.shape[0], 3, 3))
        for k in range(q.shape[0]):
            out[k] = arm_points(q[k], G)[:3]
        return out

    def joint_metrics(self, name: str, **kw) -> dict:
        """The paper's metrics of one joint's motion, on its articulation angle, plain Python
        numbers, each name with its SI unit (``saturation_velocity_rad_s``,
        ``time_constant_end_s``, ``stall_position_rad``; `with_units`): `joint_metric_values` for a
        user."""
        return with_units(self.joint_metric_values(name, **kw), angular=True)

    def joint_metric_values(self, name: str, **kw) -> dict:
        """The paper's metrics of one joint's motion keyed by their identifiers
        ([`step_metrics`][hydroarm.step_metrics] on the articulation angle: [rad],
        [rad/s], [s]; plain Python numbers)."""
        return plain_metrics(step_metrics(self.t, self.angle(name), **kw))

    def column_spec(self) -> dict[str, Column]:
        """{name: Column} of this arm's time series: t, supply pressure, then per joint its
        angle, rate, load pressure and lever. The accessor takes the result."""
        spec = {c.name: c for c in ARM_COLUMNS}
        for i, n in enumerate(self.names):
            for c in JOINT_COLUMNS:
                spec[f"{n}_{c.name}"] = Column(
                    f"{n}_{c.name}",
                    c.unit,
                    f"{n}: {c.description}",
                    lambda r, c=c, i=i, n=n: c.accessor(r, i, n),
                )
        return spec

    def table(self, columns=None) -> np.ndarray:
        """Rows of the ``columns`` (names of `column_spec`; default: all of them)."""
        spec = self.column_spec()
        return np.column_stack([c.accessor(self) for c in select_columns(spec, columns, spec)])

    def to_pandas(self, columns=None) -> pd.DataFrame:
        """A DataFrame of the ``columns`` (default: all of `column_spec`)."""
        spec = self.column_spec()
        cols = select_columns(spec, columns, spec)
        import pandas as pd  # lazy: pandas costs ~0.2 s of start-up, most runs never need it

        return pd.DataFrame({c.name: c.accessor(self) for c in cols})

    def hand_table(self) -> np.ndarray:
        """Rows of t [s] and the elbow, wrist and hand positions x, y, z [m]."""
        pts = self.points()
        return np.column_stack([c.accessor(self, pts) for c in HAND_COLUMNS])

    def to_csv(self, joints_path, hand_path, columns=None) -> None:
        """The time series of ``columns`` (default: all) and the elbow/wrist/hand trajectory
        (atomic writes)."""
        spec = self.column_spec()
        cols = select_columns(spec, columns, spec)
        atomic_write_text(
            joints_path, csv_lines([c.name for c in cols], self.table(columns), ".6g")
        )
        atomic_write_text(
            hand_path, csv_lines([c.name for c in HAND_COLUMNS], self.hand_table(), ".6g")
        )

    def power_traces(self) -> dict:
        """The power pack's power [W] and cumulative energy [J] against time, and the flows
        behind them, from the circuit's recorded outputs
        (`hydroarm.arm.energy.power_traces`), each name with its unit (``t_s``,
        ``pump_w``, ``cumulative_pump_j``, ``q_pump_m3_per_s``;
        `hydroarm.arm.energy.TRACE_UNITS`)."""
        return arm_energy.traces_with_units(arm_energy.power_traces(self))

    def energy(self, cycles: float = 1.0) -> dict:
        """The run's hydraulic energies [J] from pump to jacks, from the circuit's energy
        account, and, with the power pack's efficiencies and battery, its electric energy,
        energy per task cycle (the run being ``cycles`` cycles: by default the run is one
        cycle), cycles and run time per charge [s] (`hydroarm.arm.energy.energy_summary`;
        plain floats), each name with its unit (``pump_hydraulic_j``, ``duration_s``,
        ``mean_electric_power_w``; `hydroarm.arm.energy.ENERGY_UNITS`)."""
        return arm_energy.with_units(arm_energy.energy_summary(self, cycles=cycles))

    def plot(self, kind: str = "joints", **kwargs):
        """A figure of the run (`hydroarm.plotting.arm`): ``"joints"`` — every joint's
        angle (dashed: its lever) and the load and supply pressures; ``"frames"`` — stick-figure
        frames of the arm moving; ``"energy"`` — the power pack's cumulative energies. The
        backend is the caller's choice."""
        if kind == "joints":
            return arm_plots.fig_joints(self, **kwargs)
        if kind == "frames":
            return arm_plots.fig_frames(self, **kwargs)
        if kind == "energy":
            return arm_plots.fig_energy(self, **kwargs)
        raise HydroarmError("kind", f"must be 'joints', 'frames' or 'energy', got {kind!r}")
