"""Result of a whole-arm run: per-joint traces, supply pressure, the arm's 3-D pose."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.arm_kinematics import JOINT_NAMES, arm_points
from ..files import atomic_write_text
from ..metrics.step import step_metrics
from ..plotting import arm as arm_plots


@dataclass
class ArmResult:
    t: np.ndarray  # [s]
    theta: np.ndarray  # servo angles (n, joints) [rad]
    omega: np.ndarray  # [rad/s]
    p: np.ndarray  # load pressures [Pa]
    y: np.ndarray  # lever positions [m]
    supply_pressure: np.ndarray  # [Pa]
    scenario: object

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
        """(n, 4) articulation angles (α, ψ, ε, ρ); joints not in the arm stay at 0."""
        q = np.zeros((self.t.size, 4))
        for n in self.names:
            q[:, JOINT_NAMES.index(n)] = self.angle(n)
        return q

    def points(self) -> np.ndarray:
        """(n, 3, 3) positions [m] of elbow, wrist and hand against time."""
        G = self.scenario.geometry.params()
        q = self.articulation_angles()
        out = np.empty((self.t.size, 3, 3))
        for k in range(self.t.size):
            out[k] = arm_points(q[k], G)[:3]
        return out

    def joint_metrics(self, name: str, **kw) -> dict:
        """The paper's metrics of one joint's motion, on its articulation angle [rad]."""
        return step_metrics(self.t, self.angle(name), **kw)

    def to_csv(self, joints_path, hand_path) -> None:
        """Per-joint time series and the elbow/wrist/hand trajectory (atomic writes)."""
        head = ["t_s", "supply_pressure_bar"]
        for n in self.names:
            head += [f"{n}_deg", f"{n}_rate_deg_s", f"{n}_pressure_bar", f"{n}_lever_mm"]
        rows = [",".join(head)]
        ang = {n: np.degrees(self.angle(n)) for n in self.names}
        for k in range(self.t.size):
            r = [f"{self.t[k]:.6g}", f"{self.supply_pressure[k] * 1e-5:.6g}"]
            for i, n in enumerate(self.names):
                r += [
                    f"{ang[n][k]:.6g}",
                    f"{math.degrees(self.omega[k, i]):.6g}",
                    f"{self.p[k, i] * 1e-5:.6g}",
                    f"{self.y[k, i] * 1e3:.6g}",
                ]
            rows.append(",".join(r))
        atomic_write_text(joints_path, "\n".join(rows) + "\n")
        pts = self.points()
        rows = [
            "t_s,elbow_x_m,elbow_y_m,elbow_z_m,wrist_x_m,wrist_y_m,wrist_z_m,"
            "hand_x_m,hand_y_m,hand_z_m"
        ]
        for k in range(self.t.size):
            rows.append(",".join([f"{self.t[k]:.6g}"] + [f"{v:.6g}" for v in pts[k].ravel()]))
        atomic_write_text(hand_path, "\n".join(rows) + "\n")

    def to_pandas(self):
        import pandas as pd

        d = {"t_s": self.t, "supply_pressure_bar": self.supply_pressure * 1e-5}
        for i, n in enumerate(self.names):
            d[f"{n}_deg"] = np.degrees(self.angle(n))
            d[f"{n}_pressure_bar"] = self.p[:, i] * 1e-5
        return pd.DataFrame(d)

    def plot(self):
        """Every joint's angle (dashed: its lever) and the load and supply pressures."""
        return arm_plots.fig_joints(self)
