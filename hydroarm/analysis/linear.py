"""Linear analysis of a servo about an operating point (issue 15; docs/linear.md).

[`linearize`][hydroarm.linearize] finds the operating point (the steady state at a given angle or
position and load with the valve at its holding opening, or a state the caller chooses), linearises
the smooth right-hand side there and returns a [`LinearModel`][hydroarm.LinearModel]: a
python-control ``StateSpace`` of the closed loop, the loop broken at the valve opening (the paper's
joint) or the spool demand (a component servo), and the quantities a fluid-power engineer reads
off them (K_q, K_c, hydraulic stiffness, ω_h, ζ_h, K_v, margins, bandwidth, step metrics,
the largest stable step of each fixed-step method).

The paper's joint ([`Scenario`][hydroarm.Scenario]): state (θ₂, ω, p), inputs the
lever y and a load torque T (added to the gravity torque, so positive T opposes raising),
outputs θ₂, p and the jack position x. With the linear valve the Jacobian is analytic
(`joint_jacobian`); with the orifice valve it is by central differences
(`joint_jacobian_fd`, the test's check of the analytic one). Dry friction and end
stops are not part of the smooth right-hand side and are left out (docs/linear.md).

A component servo ([`ServoScenario`][hydroarm.ServoScenario]) is linearised on its circuit
(`hydroarm.model.servo_circuit.scenario_circuit`) and the system kernel: the operating point by
`hydroarm.model.circuit_steady.steady_state`, every Jacobian by central differences of the
kernel's right-hand side, the loop broken by `hydroarm.analysis.circuit_linear.break_loop`. Its
model keeps the servo's names: the states that have dynamics in its configuration (load
position and velocity, both chamber pressures; the spool's with first- or second-order spool
dynamics, the PID integral with an integral gain, the supply pressure with a pump, the relief
opening with a dynamic relief valve; a circuit state with no servo counterpart by its own
name), inputs the reference and the external load force, outputs the position and both
chamber pressures.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..core.equations import (
    derivatives,
    holding_pressure,
    jack_position,
    valve_flow,
)
from ..core.kinematics import crank_angle
from ..core.params import TORQUE_ARM_KINEMATIC, VALVE_LINEAR
from ..core.servo import (
    FEEDBACK_MECHANICAL,
    LOAD_CRANK,
    LOAD_MASS,
    N_STATES,
    P_AREA_A,
    P_AREA_B,
    P_CRANK_N,
    P_CRANK_R,
    P_FB_GAIN,
    P_FEEDBACK,
    P_FORCE,
    P_KP,
    P_LAP_AT,
    P_LAP_BT,
    P_LAP_PA,
    P_LAP_PB,
    P_LOAD,
    P_MASS,
    P_P_TANK,
    P_Q_MAX,
    P_Q_MIN,
    P_SENSOR_GAIN,
    P_SPOOL_MAX,
    P_STROKE_MAX,
    P_STROKE_MIN,
    P_VALVE,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    S_V,
    S_XV,
    STATES,
    VALVE_SPOOL,
)
from ..errors import HydroarmError
from ..integrators.stability import (
    PAPER_EULER_ORDER,
    circuit_euler_order,
    jacobian,
    largest_stable_step_for,
)
from ..integrators.stability import circuit_jacobian as stability_jacobian
from ..io.catalog import paper_load
from ..io.schema import parameter_set
from ..model.circuit import CircuitResult, build
from ..model.circuit_steady import (
    FD_STEP,
    SteadyState,
    compliances,
    component_index,
    frozen_parameters,
    held_states,
    linkage_levers,
    node_positions,
    project,
    source_offset_index,
    state_scales,
    steady_state,
)
from ..model.circuit_steady import floating_levels as circuit_floating_levels
from ..model.circuit_steady import jacobian as circuit_jacobian
from ..model.circuit_steady import rhs as circuit_rhs
from ..model.lever import LeverInput
from ..model.scenario import Scenario, saturation_test
from ..model.servo import ServoScenario, circuit_stems
from ..plotting.linear import bode_figure, pole_figure, step_figure, variation_figure
from . import lti
from .circuit_linear import Loop, break_loop, broken_circuit

if TYPE_CHECKING:
    import control

FIXED_STEP_METHODS = ("euler", "rk4")


def _control():
    """python-control, imported on first use (about 0.8 s: keeps the CLI's start fast)."""
    import control

    return control


# a loop whose gain stays below this at every frequency (10⁻³…10⁶ rad/s) has none: the valve
# passes no flow at this point (a closed overlapped spool), so it has no margins
LOOP_GAIN_FLOOR = 1e-6


# ----------------------------------------------------------------- the model ---
@dataclass
class LinearModel:
    """A servo linearised about an operating point.

    ``system`` is the closed loop as a python-control ``StateSpace``; ``loop`` the loop broken
    at the valve opening (joint) or the spool demand (component servo), input that signal,
    output the fed-back signal, so that ``control.feedback(loop)`` is the closed loop from the
    fed-back signal's reference.

    Parameters
    ----------
    kind : str
        ``"joint"`` (the paper's) or ``"servo"`` (a component servo).
    states, inputs, outputs : tuple of str
        Names of the states, inputs and outputs.
    A, B, C, D : numpy.ndarray
        The closed loop (SI).
    loop_abcd : tuple, optional
        (A, B, C, D) of the broken loop; None where the loop is open at this point.
    reference_output : str
        The output the loop drives.
    operating_point : dict
        The state and inputs there (names → SI).
    quantities : dict
        The closed-form and derived quantities (docs/linear.md).
    step_jacobian : numpy.ndarray
        The Jacobian the fixed-step stability check uses for this state.
    euler_order : tuple
        Its row order.
    steady : bool
        The operating point is a steady state.
    floating : list of str
        A component servo's floating levels removed from the model (structural zeros).
    open_loop_reason : str, optional
        Why the loop is open at this point (its spool inside its overlap).
    nearest : LinearModel, optional
        The model at the nearest operating point with flow.
    notes : list of str
        Notes on the model.
    rotary : bool
        A rotary load: positions in [rad], not [m].
    """

    kind: str  # "joint" or "servo"
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    loop_abcd: tuple[np.ndarray, np.ndarray, np.ndarray, float] | None
    reference_output: str
    operating_point: dict
    quantities: dict
    step_jacobian: np.ndarray
    euler_order: tuple
    steady: bool = True
    floating: list[str] = field(default_factory=list)
    open_loop_reason: str | None = None
    nearest: LinearModel | None = None
    notes: list[str] = field(default_factory=list)
    rotary: bool = False

    @property
    def loop(self) -> control.StateSpace | None:
        """The loop broken at the valve opening / spool demand (``loop_abcd`` as a
        python-control ``StateSpace``, built on first use); None where the loop is open."""
        return None if self.loop_abcd is None else _control().ss(*self.loop_abcd)

    def unstable(self) -> bool:
        """Whether the closed loop has a pole truly right of the imaginary axis
        (`lti.unstable_poles`: beyond the differences' rounding)."""
        return bool(lti.unstable_poles(self.poles).size)

    def loop_unstable(self) -> bool:
        """Whether the broken loop itself (the plant with the valve's command held) has a
        pole truly right of the imaginary axis: its margins then say nothing of stability."""
        if self.loop_abcd is None:
            return False
        return bool(lti.unstable_poles(np.linalg.eigvals(self.loop_abcd[0])).size)

    def loop_margins(self) -> dict | None:
        """[`margins`][hydroarm.LinearModel.margins], or None where they mean nothing: the loop open
        at this point (no flow gain), or the broken loop unstable by itself."""
        if self.loop_abcd is None or self.loop_unstable():
            return None
        return self.margins()

    @property
    def system(self) -> control.StateSpace:
        return _control().ss(
            self.A,
            self.B,
            self.C,
            self.D,
            inputs=list(self.inputs),
            outputs=list(self.outputs),
            states=list(self.states),
        )

    # ---------------------------------------------------------- transfers ---
    def transfer(self, input: str, output: str) -> control.TransferFunction:
        """The transfer function from one input to one output (minimal realisation)."""
        for name, names in ((input, self.inputs), (output, self.outputs)):
            if name not in names:
                raise HydroarmError("linearize", f"{name!r} is not one of {', '.join(names)}")
        i = self.inputs.index(input)
        o = self.outputs.index(output)
        sub = _control().ss(self.A, self.B[:, [i]], self.C[[o], :], self.D[[o]][:, [i]])
        return _control().minreal(_control().ss2tf(sub), verbose=False)

    @property
    def reference_to_position(self) -> control.TransferFunction:
        """Lever (reference) → angle (position)."""
        return self.transfer(self.inputs[0], self.outputs[0])

    @property
    def load_to_position(self) -> control.TransferFunction:
        """Load torque (force) → angle (position)."""
        return self.transfer(self.inputs[1], self.outputs[0])

    @property
    def reference_to_pressure(self) -> control.TransferFunction:
        """Lever (reference) → (load or chamber A) pressure."""
        return self.transfer(self.inputs[0], self.outputs[1])

    @property
    def tracking(self) -> control.StateSpace:
        """Closed loop from the reference to the fed-back signal (DC gain 1, for a servo that
        follows its reference, up to the droop of leakage against a load stiffness): the
        system of the bandwidth (−3 dB below its DC gain) and the step metrics."""
        return _control().ss(*self.tracking_abcd)

    @property
    def tracking_abcd(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """(A, B, C, D) of [`tracking`][hydroarm.LinearModel.tracking]: plain arrays, no
        python-control."""
        o = self.outputs.index(self.reference_output)
        return self.A, self.B[:, [0]], self.C[[o], :], float(self.D[o, 0])

    # ---------------------------------------------------------- quantities ---
    @property
    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A)

    def natural_frequencies(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(ω_n [rad/s], ζ, poles) of each closed-loop pole, as python-control's ``damp``."""
        p = self.poles
        wn = np.abs(p)
        with np.errstate(invalid="ignore", divide="ignore"):
            zeta = np.where(wn > 0, -p.real / np.where(wn > 0, wn, 1.0), -1.0)
        return wn, zeta, p

    def margins(self) -> dict:
        """Gain margin [dB], phase margin [deg] and their crossover frequencies [rad/s] of the
        loop broken at the valve opening / spool demand (inf: no crossover)."""
        nothing = {
            "gain_margin_db": math.inf,
            "phase_margin_deg": math.inf,
            "phase_crossover_rad_s": math.nan,
            "gain_crossover_rad_s": math.nan,
        }
        w = np.logspace(-3, 6, 400)
        if self.loop_abcd is None:
            return nothing  # the loop is open at this point (module doc)
        if np.max(np.abs(lti.freqresp(*self.loop_abcd, w))) < LOOP_GAIN_FLOOR:
            return nothing  # no loop gain at this point (a closed overlapped valve)
        return lti.margins(*self.loop_abcd)

    def bandwidth(self) -> float:
        """Closed-loop −3 dB bandwidth [rad/s] of the reference → fed-back signal."""
        if (self.kind == "joint" and np.max(self.poles.real) >= 0) or (
            self.kind == "servo" and (self.unstable() or self.open_loop_reason is not None)
        ):
            return math.nan  # an unstable loop has none
        return lti.bandwidth(*self.tracking_abcd, dbdrop=-3.0)

    def step_info(self) -> dict:
        """Small-signal step metrics of the reference → fed-back signal (python-control's
        ``step_info`` definitions, `hydroarm.analysis.lti.step_info`: rise 10–90 %,
        settling 2 %, overshoot %, peak and its time)."""
        return lti.step_info(*self.tracking_abcd)

    def step_response(self, t: np.ndarray, amplitude: float = 1.0, input: int = 0):
        """Response of every state to a reference (input 0) or load (1) step of ``amplitude``
        at t = 0: array (len(t) × states) of deviations from the operating point."""
        sys = _control().ss(self.A, self.B[:, [input]], np.eye(len(self.states)), 0)
        r = _control().step_response(sys, T=t)
        return (
            amplitude * np.asarray(r.outputs)[:, 0, :].T
            if np.ndim(r.outputs) == 3
            else (amplitude * np.asarray(r.outputs).T)
        )

    def largest_stable_step(self, method: str) -> float:
        """Largest stable step [s] of ``method`` at this state, from the eigenvalues
        (`hydroarm.integrators.stability.largest_stable_step_for` on the Jacobian the
        step check uses at this state)."""
        if method not in FIXED_STEP_METHODS:
            raise HydroarmError("method", f"must be one of {', '.join(FIXED_STEP_METHODS)}")
        return float(largest_stable_step_for(method, [self.step_jacobian], order=self.euler_order))

    def frequency_grid(self, n: int = 400) -> np.ndarray:
        """Frequencies [rad/s] spanning two decades either side of the poles' range."""
        wn = np.abs(self.poles)
        wn = wn[wn > 1e-6]
        lo, hi = (float(wn.min()), float(wn.max())) if wn.size else (1.0, 1.0)
        return np.logspace(math.log10(lo) - 2, math.log10(hi) + 1, n)

    def bode_figure(self, w=None):
        """Open- and closed-loop Bode plots (`hydroarm.plotting.linear.bode_figure`);
        where the loop is open at this point (a spool inside its overlap), those of the
        nearest operating point with flow."""
        if self.loop_abcd is None and self.nearest is not None:
            return self.nearest.bode_figure(w)
        if self.loop_abcd is None:
            raise HydroarmError("bode", f"the loop is open here: {self.open_loop_reason}")
        w = self.frequency_grid() if w is None else np.asarray(w, float)
        s = 1j * w
        ref = "lever" if self.kind == "joint" else "reference"
        out = self.reference_output.replace("_", " ")
        m = self.margins() if self.kind == "joint" else self.loop_margins()
        bw = self.bandwidth()
        if m is None:
            title = "margins: — (the loop is unstable with the valve's command held)"
        else:
            title = (
                f"gain margin {m['gain_margin_db']:.3g} dB, phase margin "
                f"{m['phase_margin_deg']:.3g}°"
            )
        title += f", bandwidth {bw:.4g} rad/s" if math.isfinite(bw) else ", bandwidth —"
        if self.notes:
            title = "nearest operating point with flow: " + title
        return bode_figure(
            w,
            lti.freqresp(*self.loop_abcd, w),
            self.tracking(s),
            title=title,
            loop_label="open loop (broken at the "
            + ("valve opening" if self.kind == "joint" else "spool demand")
            + ")",
            closed_label=f"closed loop, {ref} → {out}",
        )

    def small_step(self, t=None) -> tuple[np.ndarray, np.ndarray]:
        """(t [s], y): the closed loop's small-signal step, reference → fed-back signal,
        divided by its final value (numpy alone, `hydroarm.analysis.lti.step`); ``t``
        defaults to 1.2 times the settling time or the response's horizon, 2001 points."""
        abcd = self.tracking_abcd
        if t is None:
            info = self.step_info()
            end = info["SettlingTime"]
            if not np.isfinite(end) or end <= 0:
                end = lti.step_horizon(self.A) / 1.2
            t = np.linspace(0.0, 1.2 * end, 2001)
        t = np.asarray(t, float)
        return t, lti.step(*abcd, t) / lti.dc_gain(*abcd)

    def pole_figure(self):
        """Pole map with the ω_h circle and damping lines
        (`hydroarm.plotting.linear.pole_figure`)."""
        q = self.quantities
        w_h, z_h = q["hydraulic_natural_frequency_rad_s"], q["hydraulic_damping_ratio"]
        title = "closed-loop poles"
        if w_h is not None and z_h is not None and math.isfinite(w_h):
            title += f"; hydraulic mode ω_h = {w_h:.4g} rad/s, ζ_h = {z_h:.3g}"
        return pole_figure(self.poles, omega_h=w_h, zeta_h=z_h, title=title)

    def step_figure(self):
        """Small-signal step, normalised, with rise, overshoot and settling marked
        (`hydroarm.plotting.linear.step_figure`); where the loop is open at this point
        (a spool inside its overlap), that of the nearest operating point with flow."""
        if self.open_loop_reason is not None and self.nearest is not None:
            return self.nearest.step_figure()
        if (self.kind == "joint" and np.max(self.poles.real) >= 0) or (
            self.kind == "servo" and (self.unstable() or self.open_loop_reason is not None)
        ):
            raise HydroarmError(
                "step",
                "the closed loop has a pole at or right of the imaginary axis here: "
                "no step to settle",
            )
        info = self.step_info()
        t, y = self.small_step()
        ref = "lever" if self.kind == "joint" else "reference"
        out = self.reference_output.replace("_", " ")
        return step_figure(t, y, info, title=f"small {ref} step → {out} (linear, normalised)")

    def report(self) -> str:
        """A short readable report of [`summary`][hydroarm.LinearModel.summary]."""
        if self.kind == "servo":
            return "\n".join(_servo_report_lines(self))
        d = self.summary()
        op = d["operating_point"]
        lines = []
        if self.kind == "joint":
            lines.append(
                f"operating point: θ₂ = {math.degrees(op['angle']):.4g}°, ω = "
                f"{op['velocity']:.4g} rad/s, p = {op['pressure'] * 1e-5:.4g} bar, lever "
                f"{op['lever'] * 1e3:.4g} mm (valve opening {d['valve_opening_m'] * 1e3:.4g} mm)"
                + ("" if self.steady else " [a chosen state, not steady]")
            )
        else:
            lines.append(
                "operating point: "
                + ", ".join(f"{k} = {v:.6g}" for k, v in op.items())
                + ("" if self.steady else " [a chosen state, not steady]")
            )
        lines.append(
            f"valve: K_q = {d['flow_gain_m2_s']:.4g} m²/s, K_c = "
            f"{d['flow_pressure_coefficient_m3_s_pa']:.4g} m³/(s Pa); hydraulic stiffness "
            f"{d['hydraulic_stiffness_n_m']:.4g} N/m"
        )
        lines.append(
            f"hydraulic mode: ω_h = {d['hydraulic_natural_frequency_rad_s']:.4g} rad/s "
            f"(Merritt {d['merritt_natural_frequency_rad_s']:.4g}), ζ_h = "
            f"{d['hydraulic_damping_ratio']:.3g}"
        )
        ok = "met" if d["criterion_met"] else "NOT met"
        lines.append(
            f"velocity constant K_v = {d['velocity_constant_1_s']:.4g} 1/s; criterion K_v < "
            f"2·ζ_h·ω_h = {d['stability_criterion_1_s']:.4g} 1/s: {ok}"
        )
        lines.append(
            f"loop: gain margin {d['gain_margin_db']:.3g} dB (at "
            f"{d['phase_crossover_rad_s']:.4g} rad/s), phase margin "
            f"{d['phase_margin_deg']:.3g}° (at {d['gain_crossover_rad_s']:.4g} rad/s)"
        )
        lines.append(
            f"closed loop: bandwidth {d['bandwidth_rad_s']:.4g} rad/s; small step: rise "
            f"{d['step_rise_time_s'] * 1e3:.4g} ms, overshoot "
            f"{d['step_overshoot_percent']:.3g} %, settling (2 %) "
            f"{d['step_settling_time_s'] * 1e3:.4g} ms"
        )
        lines.append("poles [1/s]: ω_n, ζ")
        for (re, im), wn, z in zip(
            d["poles"], d["natural_frequencies_rad_s"], d["damping_ratios"], strict=True
        ):
            if im >= 0:
                lines.append(
                    f"  {re:11.5g} {'+' if im >= 0 else '-'} {abs(im):.5g}j   {wn:10.5g} {z:8.3g}"
                )
        lines.append(
            f"largest stable step at this state: euler {d['largest_stable_step_euler_s'] * 1e3:.4g}"
            f" ms, rk4 {d['largest_stable_step_rk4_s'] * 1e3:.4g} ms"
        )
        return "\n".join(lines)

    def summary(self) -> dict:
        """Every quantity as one flat dictionary of plain floats (``--json``); a component
        servo's with None where a quantity is undefined (never NaN)."""
        if self.kind == "servo":
            return _servo_summary(self)
        q = dict(self.quantities)
        m = self.margins()
        out = {
            "kind": self.kind,
            "steady": self.steady,
            "operating_point": dict(self.operating_point),
            **q,
            **m,
            "bandwidth_rad_s": self.bandwidth(),
        }
        info = self.step_info()
        out["step_rise_time_s"] = info["RiseTime"]
        out["step_settling_time_s"] = info["SettlingTime"]
        out["step_overshoot_percent"] = info["Overshoot"]
        for method in FIXED_STEP_METHODS:
            out[f"largest_stable_step_{method}_s"] = self.largest_stable_step(method)
        wn, zeta, p = self.natural_frequencies()
        order = np.argsort(wn, kind="stable")
        out["poles"] = [[float(p[i].real), float(p[i].imag)] for i in order]
        out["natural_frequencies_rad_s"] = [float(wn[i]) for i in order]
        out["damping_ratios"] = [float(zeta[i]) for i in order]
        return out


# ------------------------------------------------- component servo: report ---
def _fin(v):
    """A float, or None where undefined (no NaN in a servo's summary)."""
    if v is None:
        return None
    v = float(v) + 0.0  # no negative zero
    return v if math.isfinite(v) else None


def _servo_summary(m: LinearModel) -> dict:
    q = m.quantities
    mg = m.loop_margins() or {}
    settled = not m.unstable() and m.open_loop_reason is None
    info = m.step_info() if settled else {}
    out: dict = {
        "kind": m.kind,
        "steady": m.steady,
        "operating_point": dict(m.operating_point),
        **{k: (v if isinstance(v, bool) or v is None else _fin(v)) for k, v in q.items()},
        "gain_margin_db": _fin(mg.get("gain_margin_db")),
        "phase_margin_deg": _fin(mg.get("phase_margin_deg")),
        "phase_crossover_rad_s": _fin(mg.get("phase_crossover_rad_s")),
        "gain_crossover_rad_s": _fin(mg.get("gain_crossover_rad_s")),
        "bandwidth_rad_s": _fin(m.bandwidth()) if settled else None,
        "step_rise_time_s": _fin(info.get("RiseTime")),
        "step_settling_time_s": _fin(info.get("SettlingTime")),
        "step_overshoot_percent": _fin(info.get("Overshoot")),
        "stable": not m.unstable(),
        "loop_unstable": m.loop_unstable(),
        "loop_open": m.open_loop_reason,
        "floating_levels": list(m.floating),
        "notes": list(m.notes),
    }
    for method in FIXED_STEP_METHODS:
        out[f"largest_stable_step_{method}_s"] = _fin(m.largest_stable_step(method))
    wn, zeta, p = m.natural_frequencies()
    order = np.argsort(wn, kind="stable")
    out["poles"] = [[float(p[i].real), float(p[i].imag)] for i in order]
    out["natural_frequencies_rad_s"] = [float(wn[i]) for i in order]
    out["damping_ratios"] = [_fin(zeta[i]) if wn[i] > 0 else None for i in order]
    if m.nearest is not None:
        out["nearest_with_flow"] = _servo_summary(m.nearest)
    return out


def _point_text(m: LinearModel) -> str:
    parts = []
    for k, v in m.operating_point.items():
        if k.startswith("pressure") or k == "supply_pressure":
            parts.append(f"{k} = {v * 1e-5:.6g} bar")
        elif k in ("position", "reference") and m.rotary:
            parts.append(f"{k} = {math.degrees(v) + 0.0:.6g}°")
        elif k == "position":
            parts.append(f"{k} = {v:.6g} m")
        elif k == "spool":
            parts.append(f"{k} = {v * 1e6:.6g} µm")
        else:
            parts.append(f"{k} = {v:.6g}")
    return ", ".join(parts)


def _servo_report_lines(m: LinearModel) -> list[str]:
    """The report of a component servo's model (no NaN: an undefined quantity is a dash
    with the reason)."""
    d = _servo_summary(m)
    lines = [
        "operating point (pressures absolute): "
        + _point_text(m)
        + ("" if m.steady else " [a chosen state, not steady]")
    ]
    lines.append(
        f"valve: spool at {d['spool_m'] * 1e6:.4g} µm, K_q = {d['flow_gain_m2_s']:.4g} m²/s, K_c = "
        f"{d['flow_pressure_coefficient_m3_s_pa']:.4g} m³/(s Pa); hydraulic stiffness "
        f"{d['hydraulic_stiffness_n_m']:.4g} N/m"
    )
    w_h, z_h = d["hydraulic_natural_frequency_rad_s"], d["hydraulic_damping_ratio"]
    merritt = d["merritt_natural_frequency_rad_s"]
    if w_h is not None and z_h is not None and m.open_loop_reason is not None:
        lines.append(
            f"hydraulic mode: ω_h = {w_h:.4g} rad/s (Merritt {merritt:.4g}), ζ_h = {z_h:.3g}"
        )
    elif w_h is not None and z_h is not None:
        lines.append(
            f"hydraulic mode: ω_h = {w_h:.4g} rad/s (Merritt {merritt:.4g}), ζ_h = {z_h:.3g}"
        )
        ok = "met" if d["criterion_met"] else "NOT met"
        lines.append(
            f"velocity constant K_v = {d['velocity_constant_1_s']:.4g} 1/s; criterion K_v < "
            f"2·ζ_h·ω_h = {d['stability_criterion_1_s']:.4g} 1/s: {ok}"
        )
    else:
        lines.append(f"hydraulic mode: — (no mode of the load identifiable; Merritt {merritt:.4g})")
    if m.open_loop_reason is not None:
        lines.append(f"loop open: {m.open_loop_reason}")
    elif m.loop_unstable():
        k = lti.unstable_poles(np.linalg.eigvals(m.loop_abcd[0])).size  # type: ignore[index]
        lines.append(
            f"loop: unstable with the spool demand held ({k} pole{'s' * (k > 1)} right of "
            "the imaginary axis): gain and phase margins say nothing here"
        )
    else:

        def show(v, unit, at):
            if v is None:
                return "none (no crossing)"
            return f"{v:.4g} {unit} (at {at:.4g} rad/s)"

        lines.append(
            "loop: gain margin "
            + show(d["gain_margin_db"], "dB", d["phase_crossover_rad_s"])
            + "; phase margin "
            + show(d["phase_margin_deg"], "°", d["gain_crossover_rad_s"])
        )
    unstable = lti.unstable_poles(m.poles)
    if unstable.size:
        lines.append(
            f"closed loop: UNSTABLE here ({unstable.size} pole{'s' * (unstable.size > 1)} "
            "right of the imaginary axis; the nonlinear servo limit-cycles or runs away)"
        )
    elif m.open_loop_reason is not None:
        lines.append("closed loop: no feedback at this point (bandwidth and step: —)")
    elif d["bandwidth_rad_s"] is None:
        lines.append("closed loop: stable; bandwidth — (no finite, non-zero steady gain)")
    else:
        lines.append(
            f"closed loop: stable; bandwidth {d['bandwidth_rad_s']:.4g} rad/s; small step: "
            + (
                f"rise {d['step_rise_time_s'] * 1e3:.4g} ms, overshoot "
                f"{d['step_overshoot_percent']:.3g} %, settling (2 %) "
                f"{d['step_settling_time_s'] * 1e3:.4g} ms"
                if d["step_settling_time_s"] is not None
                else "—"
            )
        )
    lines.append("poles [1/s]: ω_n, ζ")
    for (re, im), wn, z in zip(
        d["poles"], d["natural_frequencies_rad_s"], d["damping_ratios"], strict=True
    ):
        if im >= 0:
            zt = "—" if z is None else f"{z:.3g}"
            sign = "+" if im >= 0 else "-"
            lines.append(f"  {re:11.5g} {sign} {abs(im):.5g}j   {wn:10.5g} {zt:>8}")
    for name in m.floating:
        lines.append(f"structural zero removed: floating level {name}")
    lines += [f"note: {x}" for x in m.notes]
    steps = [d[f"largest_stable_step_{k}_s"] for k in FIXED_STEP_METHODS]
    lines.append(
        "largest stable step at this state: "
        + ", ".join(
            f"{k} {v * 1e3:.4g} ms" if v is not None else f"{k} —"
            for k, v in zip(FIXED_STEP_METHODS, steps, strict=True)
        )
    )
    if m.nearest is not None:
        lines.append("nearest operating point with flow:")
        lines += ["  " + x for x in _servo_report_lines(m.nearest)]
    return lines


# ---------------------------------------------------------- the paper's joint ---
def joint_jacobian(theta, omega, p, y, J, L) -> tuple[np.ndarray, np.ndarray]:
    """Analytic (A, B) of the joint's smooth right-hand side (`derivatives`) with the
    linear valve (eq. (1)–(4), options O2, O4, O6): A = ∂(θ̇, ω̇, ṗ)/∂(θ, ω, p), B =
    ∂(θ̇, ω̇, ṗ)/∂(y, T) with T a load torque added to the gravity torque."""
    if J.valve_model != VALVE_LINEAR:
        raise HydroarmError("joint.valve_model", "the analytic Jacobian needs the linear valve")
    r, n = J.crank_radius, J.gear_ratio
    A_p = J.piston_area
    c = r * math.cos(theta / n) / n  # ẋ = c·ω
    dc = -r * math.sin(theta / n) / n**2
    if J.torque_arm == TORQUE_ARM_KINEMATIC:
        a, da = c, dc
    else:
        a, da = r / n, 0.0
    b = J.viscous_friction
    inv_i = 1.0 / L.inertia
    k = J.bulk_modulus / J.trapped_volume
    k_q = J.flow_coefficient * math.sqrt(0.5 * J.supply_pressure)
    e = y - r * math.sin(theta / n)
    e_o = J.valve_saturation
    open_band = abs(e) < e_o
    # valve opening e = clip(y − x): ∂e/∂y = 1, ∂e/∂θ = −c inside the band, else 0
    de = 1.0 if open_band else 0.0
    l0 = J.null_leakage_coefficient
    ec = min(max(e, -e_o), e_o)
    u = ec / e_o
    dq0_dp = 2.0 * l0 * (1.0 - u * u)
    dq0_de = -4.0 * l0 * p * ec / (e_o * e_o)
    dq_de = k_q - dq0_de  # ∂(valve flow − null leakage)/∂e
    grav = L.weight * L.arm * math.sin(theta - J.horizontal_angle)  # −∂(W·X·cos)/∂θ
    A = np.zeros((3, 3))
    A[0, 1] = 1.0
    A[1, 0] = (A_p * p * da + grav - b * omega * (dc * a + c * da)) * inv_i
    A[1, 1] = -b * c * a * inv_i
    A[1, 2] = A_p * a * inv_i
    A[2, 0] = k * (-dq_de * de * c - A_p * dc * omega)
    A[2, 1] = -k * A_p * c
    A[2, 2] = -k * (2.0 * J.leakage_coefficient + dq0_dp)
    B = np.zeros((3, 2))
    B[2, 0] = k * dq_de * de
    B[1, 1] = -inv_i
    return A, B


def joint_jacobian_fd(theta, omega, p, y, J, L) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) as `joint_jacobian` by central differences (any valve model): A is
    `hydroarm.integrators.stability.jacobian`, the step check's own."""
    A = jacobian(theta, omega, p, y, J, L)
    B = np.empty((3, 2))
    dy = 1e-9
    fp = np.array(derivatives(theta, omega, p, y + dy, J, L))
    fm = np.array(derivatives(theta, omega, p, y - dy, J, L))
    B[:, 0] = (fp - fm) / (2 * dy)
    dt = 1e-6 * max(1.0, abs(L.weight * L.arm))
    fp = np.array(derivatives(theta, omega, p, y, J, L._replace(torque=L.torque + dt)))
    fm = np.array(derivatives(theta, omega, p, y, J, L._replace(torque=L.torque - dt)))
    B[:, 1] = (fp - fm) / (2 * dt)
    return A, B


def _valve_coefficients(e, p, J) -> tuple[float, float]:
    """(K_q, K_c) of the joint's valve at opening e [m], load pressure p [Pa]: ∂Q/∂e and
    −∂Q/∂p (central differences of `hydroarm.core.equations.valve_flow`; exact for the
    linear valve, whose K_c is 0)."""
    if J.valve_model == VALVE_LINEAR:
        return float(J.flow_coefficient * math.sqrt(0.5 * J.supply_pressure)), 0.0
    de = 1e-9
    dp = 1.0 + 1e-7 * abs(p)
    k_q = (valve_flow(e + de, p, J) - valve_flow(e - de, p, J)) / (2 * de)
    k_c = -(valve_flow(e, p + dp, J) - valve_flow(e, p - dp, J)) / (2 * dp)
    return float(k_q), float(k_c)


def _holding_opening(theta, p, J, L) -> float:
    """Valve opening e [m] at which the joint holds still at θ₂ with pressure p (ṗ = 0)."""
    x = float(jack_position(theta, J))

    def rate(e):
        return derivatives(theta, 0.0, p, x + e, J, L)[2]

    e_o = J.valve_saturation
    lo, hi = rate(-e_o), rate(e_o)
    if not (lo <= 0.0 <= hi):
        raise HydroarmError(
            "load",
            f"the valve cannot hold the load at θ₂ = {math.degrees(theta):.4g}° "
            f"(holding pressure {p * 1e-5:.4g} bar): even fully open it cannot make up the "
            "leakage; choose a lighter load or another angle",
        )
    if lo == 0.0:
        return -e_o
    # bisection (ṗ rises with e; no scipy: keeps reproduce's linear view light)
    a, b = -e_o, e_o
    for _ in range(200):
        mid = 0.5 * (a + b)
        if mid in (a, b):
            break
        r = rate(mid)
        if r == 0.0:
            return float(mid)
        if r < 0.0:
            a = mid
        else:
            b = mid
    return float(0.5 * (a + b))


def _joint_point(scenario: Scenario, at) -> tuple[dict, bool]:
    J, L = scenario.params
    steady = True
    given: dict = {}
    if at is None:
        theta = scenario.target_angle()
    elif isinstance(at, Mapping):
        given = dict(at)
        for k in given:
            if k not in ("angle", "velocity", "pressure", "lever"):
                raise HydroarmError(
                    f"at.{k}", "is not a joint state (angle, velocity, pressure, lever)"
                )
        theta = given.get("angle", scenario.target_angle())
        steady = not ({"velocity", "pressure", "lever"} & set(given))
    else:
        theta = at
    theta = _finite("at.angle" if isinstance(at, Mapping) else "at", theta)
    if abs(theta) >= scenario.joint.max_angle:
        raise HydroarmError("at", "is beyond the crank's reach (|θ₂| < n·90°)")
    omega = _finite("at.velocity", given.get("velocity", 0.0))
    p = _finite("at.pressure", given.get("pressure", float(holding_pressure(theta, J, L))))
    if "lever" in given:
        y = _finite("at.lever", given["lever"])
    else:
        y = float(jack_position(theta, J)) + _holding_opening(theta, p, J, L)
    return {"angle": float(theta), "velocity": float(omega), "pressure": float(p), "lever": y}, (
        steady
    )


def _finite(name, v) -> float:
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise HydroarmError(name, f"must be a number, got {v!r}") from None
    if not math.isfinite(f):
        raise HydroarmError(name, "is not a finite number")
    return f


def linearize_joint(scenario: Scenario, at=None) -> LinearModel:
    """[`linearize`][hydroarm.linearize] for the paper's joint."""
    J, L = scenario.params
    op, steady = _joint_point(scenario, at)
    theta, omega, p, y = op["angle"], op["velocity"], op["pressure"], op["lever"]
    if J.valve_model == VALVE_LINEAR:
        A, B = joint_jacobian(theta, omega, p, y, J, L)
    else:
        A, B = joint_jacobian_fd(theta, omega, p, y, J, L)
    r, n = J.crank_radius, J.gear_ratio
    c = r * math.cos(theta / n) / n  # ∂x/∂θ
    C = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [c, 0.0, 0.0]])
    D = np.zeros((3, 2))
    # the loop broken at the valve opening: e drives the joint, x is fed back (e = y − x)
    A_open = A.copy()
    A_open[:, 0] += B[:, 0] * c
    loop = (A_open, B[:, [0]], C[[2], :], 0.0)
    # closed-form quantities (Merritt 1967, Ch. 6, in hydroarm's lumped form: docs/linear.md)
    x = float(jack_position(theta, J))
    e = y - x
    k_q, k_c = _valve_coefficients(min(max(e, -J.valve_saturation), J.valve_saturation), p, J)
    u = min(max(e / J.valve_saturation, -1.0), 1.0)
    k_ce = k_c + 2.0 * J.leakage_coefficient + 2.0 * J.null_leakage_coefficient * (1 - u * u)
    a = c if J.torque_arm == TORQUE_ARM_KINEMATIC else r / n
    A_p, beta, V, I, b = (
        J.piston_area,
        J.bulk_modulus,
        J.trapped_volume,
        L.inertia,
        J.viscous_friction,
    )
    k_h_jack = beta * A_p**2 / V
    k_h_joint = k_h_jack * a * c
    w_h = math.sqrt(beta * a * c * (A_p**2 + b * k_ce) / (V * I))
    z_h = (beta / V * k_ce * I + b * a * c) / (2.0 * I * w_h)
    k_v = k_q * A_p / (A_p**2 + b * k_ce)
    hyd_w, hyd_z = _hydraulic_mode(A_open)
    quantities = {
        "flow_gain_m2_s": k_q,
        "flow_pressure_coefficient_m3_s_pa": k_c,
        "total_flow_pressure_coefficient_m3_s_pa": k_ce,
        "hydraulic_stiffness_n_m": k_h_jack,
        "hydraulic_stiffness_nm_rad": k_h_joint,
        "load_stiffness_nm_rad": -float(A[1, 0]) * I,
        "hydraulic_natural_frequency_rad_s": hyd_w,
        "hydraulic_damping_ratio": hyd_z,
        "merritt_natural_frequency_rad_s": w_h,
        "merritt_damping_ratio": z_h,
        "velocity_constant_1_s": k_v,
        "stability_criterion_1_s": 2.0 * hyd_z * hyd_w,
        "criterion_met": bool(k_v < 2.0 * hyd_z * hyd_w),
        "time_constant_s": 1.0 / k_v,
        "valve_opening_m": e,
    }
    return LinearModel(
        kind="joint",
        states=("angle", "velocity", "pressure"),
        inputs=("lever", "load_torque"),
        outputs=("angle", "pressure", "jack_position"),
        A=A,
        B=B,
        C=C,
        D=D,
        loop_abcd=loop,
        reference_output="jack_position",
        operating_point=op,
        quantities=quantities,
        step_jacobian=jacobian(theta, omega, p, y, J, L),
        euler_order=PAPER_EULER_ORDER,
        steady=steady,
    )


def _hydraulic_mode(A_open: np.ndarray, states=None) -> tuple[float, float]:
    """(ω_h, ζ_h) of the hydraulic mode: the poles of the actuator and load with the valve
    opening held (``A_open``, restricted to ``states``): the complex pair of largest
    magnitude, or, with no complex pair, the two poles of largest magnitude, as the roots of
    s² + 2ζω s + ω²."""
    M = A_open if states is None else A_open[np.ix_(states, states)]
    lam = np.linalg.eigvals(M)
    cplx = lam[lam.imag > 1e-9 * np.abs(lam)]
    if cplx.size:
        pole = cplx[np.argmax(np.abs(cplx))]
        w = float(abs(pole))
        return w, float(-pole.real / w) if w > 0 else math.nan
    lam = np.sort_complex(lam[np.argsort(np.abs(lam))][-2:])
    prod = float((lam[0] * lam[1]).real)
    if prod <= 0:
        return math.nan, math.nan
    w = math.sqrt(prod)
    return w, float(-(lam[0] + lam[1]).real / (2 * w))


# ------------------------------------------------------------- component servo ---
#: the servo's state names (`hydroarm.core.servo.STATES`): the names of a servo's model
STATE_NAMES = [name for name, _, _ in STATES]
LAPS = (P_LAP_PA, P_LAP_AT, P_LAP_PB, P_LAP_BT)
LAP_NAMES = ("lap_pa", "lap_at", "lap_pb", "lap_bt")


def _servo_layout(compiled, P, s: np.ndarray) -> np.ndarray:
    """The servo kernel's state vector (`hydroarm.core.servo.STATES`) of a circuit state
    (the closed-form quantities read it)."""
    index = {stem: j for j, (stem, _) in enumerate(compiled.state_names)}
    out = np.zeros(N_STATES)
    out[S_PA] = out[S_PB] = out[S_PS] = P[P_P_TANK]
    for i, stem in circuit_stems(P).items():
        if stem in index:
            out[i] = s[index[stem]]
    return out


def _state_names(compiled, P) -> list[str]:
    """Each circuit state's name in the servo's model: the servo's state it stands for, else
    the circuit's own (a PID's derivative filter, an accumulator's gas)."""
    servo = {stem: STATE_NAMES[i] for i, stem in circuit_stems(P).items()}
    return [servo.get(stem, stem) for stem, _ in compiled.state_names]


def overlapped(P) -> bool:
    """Whether the servo's spool valve has an overlapped edge."""
    return P[P_VALVE] == VALVE_SPOOL and any(P[k] > 0.0 for k in LAPS)


def in_overlap(x_v: float, P) -> bool:
    """Whether a spool valve's spool at x_v [m] sits inside its overlap: every edge closed
    (no flow through any), with at least one edge overlapped."""
    if not overlapped(P):
        return False
    openings = (x_v - P[P_LAP_PA], -x_v - P[P_LAP_AT], -x_v - P[P_LAP_PB], x_v - P[P_LAP_BT])
    return all(o <= 0.0 for o in openings)


def _actuator_node(compiled) -> str:
    """The mechanical node the servo's actuator drives (`scenario_circuit`'s ``actuator``: a
    cylinder's rod, a rotary actuator's shaft)."""
    ci = component_index(compiled, "actuator")
    c = compiled.circuit.components[ci]
    return next(c.ports[p.name] for p in compiled.decls[ci].ports if p.drives)


def _check_position(compiled, P, node: str, position: float, field_name: str) -> None:
    """Refuse a position of the load's ``node`` outside the load's end stops or one that puts
    the actuator outside its stroke (where the circuit's linkage puts the actuator's node:
    `hydroarm.model.circuit_steady.node_positions`) (one line)."""
    lo, hi = P[P_Q_MIN], P[P_Q_MAX]
    if not lo <= position <= hi:
        raise HydroarmError(
            field_name, f"{position:g} is outside the load's end stops ({lo:g} … {hi:g})"
        )
    s = compiled.s0.astype(float).copy()
    s[len(compiled.hydraulic) + compiled.mechanical[node]] = position
    x = node_positions(compiled, 0.0, s, compiled.P)[_actuator_node(compiled)]
    if not P[P_STROKE_MIN] - 1e-12 <= x <= P[P_STROKE_MAX] + 1e-12:
        raise HydroarmError(
            field_name,
            f"{position:g} puts the actuator at {x:g}, outside its stroke "
            f"({P[P_STROKE_MIN]:g} … {P[P_STROKE_MAX]:g})",
        )


def _held_reference(sc: ServoScenario) -> ServoScenario:
    """The scenario with its reference held at its final value (what the operating point
    freezes anyway; a sine on top of a table then has a circuit form too)."""
    final = float(sc.reference.positions[-1])
    ref = LeverInput(np.array([0.0]), np.array([final]), description="constant")
    return sc.replace(reference=ref)


def _servo_point(sc: ServoScenario, compiled, P, at) -> tuple[SteadyState, bool]:
    """(the operating point on the servo's circuit, whether steady): the steady state at a
    position (`hydroarm.model.circuit_steady.steady_state`, the load's node pinned there and
    the reference freed to hold it) or a chosen state."""
    t = 0.0
    final = float(sc.reference.positions[-1])
    node = "rod" if int(P[P_LOAD]) == LOAD_MASS else "joint"
    if at is None or not isinstance(at, Mapping):
        if at is None:
            # the position the final reference asks for
            pos = final
            if P[P_FEEDBACK] != FEEDBACK_MECHANICAL:
                pos = final / P[P_SENSOR_GAIN]
            elif int(P[P_LOAD]) == LOAD_CRANK:
                pos = float(crank_angle(final, P[P_CRANK_R], P[P_CRANK_N], 0.999))
        else:
            pos = _finite("at", at)
        _check_position(compiled, P, node, pos, "at")
        pin = {node: pos}
        if not overlapped(P):
            return _settled(compiled, pin), True
        # an overlapped valve: zero-lap first (a zero-lap valve meters at every spool
        # position, so the solve is not stranded inside a dead band), then the servo's own
        # overlaps from there and, if that leaves no static state, from there with the spool
        # displaced by its overlap (just outside it the valve meters as the zero-lap one did)
        zero = {k: min(float(P[i]), 0.0) for k, i in zip(LAP_NAMES, LAPS, strict=True)}
        zero_lap = build(_held_reference(sc.replace(**zero)).circuit)
        first = _settled(zero_lap, pin)
        try:
            point = steady_state(
                compiled, t, pin, ["reference"], guess=first.state, settle=False, field_name="at"
            )
        except HydroarmError:
            spool = [stem for stem, _ in compiled.state_names].index("valve.spool")
            x = float(first.state[spool])
            if x == 0.0:
                raise
            lap = max(P[P_LAP_PA], P[P_LAP_BT]) if x > 0 else max(P[P_LAP_PB], P[P_LAP_AT])
            shifted = first.state.copy()
            shifted[spool] += math.copysign(lap, x)
            point = steady_state(
                compiled, t, pin, ["reference"], guess=shifted, settle=False, field_name="at"
            )
        return point, True
    P0 = frozen_parameters(compiled, t)
    k_ref = source_offset_index(compiled, "reference")
    P0[k_ref] = final
    s = compiled.s0.astype(float).copy()
    index = {stem: j for j, (stem, _) in enumerate(compiled.state_names)}
    stems = circuit_stems(P)
    for k, v in dict(at).items():
        if k == "reference":
            P0[k_ref] = _finite("at.reference", v)
        elif k in STATE_NAMES:
            stem = stems.get(STATE_NAMES.index(k))
            if stem not in index:
                raise HydroarmError(f"at.{k}", "is not a state of this servo's configuration")
            s[index[stem]] = _finite(f"at.{k}", v)
        elif k in index:  # a state of the circuit with no servo counterpart, by its name
            s[index[k]] = _finite(f"at.{k}", v)
        else:
            raise HydroarmError(f"at.{k}", "is not a servo state or 'reference'")
    s = project(compiled, t, s, P0)
    held = held_states(compiled, t, s, P0, state_scales(compiled, P0))
    levels = circuit_floating_levels(compiled, t, s, P0, np.nonzero(~held)[0])
    return SteadyState(s, P0, t, {"reference": float(P0[k_ref])}, held, levels), False


def _settled(compiled, pin: dict[str, float]) -> SteadyState:
    """The circuit's steady state with ``pin`` held and the reference freed, from the end of
    a settling run (`hydroarm.model.circuit_steady.steady_state`), or where the solve from
    there finds none, from the circuit's initial state (a settling run can end where the
    least squares strands)."""
    try:
        return steady_state(compiled, 0.0, pin, ["reference"], field_name="at")
    except HydroarmError:
        return steady_state(compiled, 0.0, pin, ["reference"], settle=False, field_name="at")


def linearize_servo(sc: ServoScenario, at=None, _nearest: bool = True) -> LinearModel:
    """[`linearize`][hydroarm.linearize] for a component servo (docs/linear.md "Component
    servos"), on its circuit (`hydroarm.model.servo_circuit.scenario_circuit`) and the
    system kernel: the operating point by `hydroarm.model.circuit_steady.steady_state`, the
    Jacobians by central differences of the kernel's right-hand side (steps ε^(1/3) × each
    state's scale), floating levels removed, the loop broken at the spool demand
    (`hydroarm.analysis.circuit_linear.break_loop`), the overlap rule of the circuit
    linearizer; the states, inputs and outputs named as the servo's."""
    P = sc.vector()
    compiled = build(_held_reference(sc).circuit)
    point, steady = _servo_point(sc, compiled, P, at)
    t, s, Pc = point.t, point.state, point.P
    names = _state_names(compiled, P)
    index = {stem: j for j, (stem, _) in enumerate(compiled.state_names)}
    stems = circuit_stems(P)
    # the states the kernel moves, in the servo's order (`hydroarm.core.servo.STATES`), then
    # the circuit's own
    servo_order = {index[stem]: i for i, stem in stems.items() if stem in index}
    dyn = np.array(
        sorted(np.nonzero(~point.held)[0], key=lambda i: servo_order.get(int(i), N_STATES + i)),
        np.int64,
    )
    scale = state_scales(compiled, Pc)

    def f(x, PP=Pc):
        return circuit_rhs(compiled, t, x, PP)

    J = circuit_jacobian(lambda x: f(x)[dyn], s, scale, dyn)
    # the PID's derivative filter: no derivative reads it (at K_d = 0 its rate is multiplied
    # by K_d; with a derivative the pid takes the sensor's rate, scenario_circuit), so its
    # mode is seen by nothing: left out, exactly
    alive = [j for j, i in enumerate(dyn) if names[i] != "controller.measurement_filtered"]
    dyn, J = dyn[alive], J[np.ix_(alive, alive)]
    k_ref = source_offset_index(compiled, "reference")
    r = float(Pc[k_ref])
    gain = P[P_SENSOR_GAIN] if P[P_FEEDBACK] != FEEDBACK_MECHANICAL else 1.0
    hr = FD_STEP * max(abs(r), scale[index[stems[S_Q]]] * gain)
    df = FD_STEP * max(1.0, abs(P[P_FORCE]), P[P_MASS])
    load_par = "load.force" if int(P[P_LOAD]) == LOAD_MASS else "load.torque"
    dyn_list = [int(i) for i in dyn]
    n = dyn.size
    B = np.empty((n, 2))
    for col, (k, h, sign) in enumerate(
        ((k_ref, hr, 1.0), (compiled.parameter_index[load_par], df, -1.0))
    ):  # the circuit's load force is minus the servo's external force
        Pp, Pm = Pc.copy(), Pc.copy()
        Pp[k] += h
        Pm[k] -= h
        B[:, col] = sign * (f(s, Pp) - f(s, Pm))[dyn] / (2 * h)
    C = np.zeros((3, n))
    for row, i in enumerate((S_Q, S_PA, S_PB)):
        C[row, dyn_list.index(index[stems[i]])] = 1.0
    D = np.zeros((3, 2))
    levels = circuit_floating_levels(compiled, t, s, Pc, dyn)
    vectors = [_last_pivot(v, dyn) for _, v in levels]
    A_r, B_r, C_r, rest, _ = lti.reduce_levels(J, B, C, dyn, vectors)
    # the loop broken at the spool demand (the controller's output), reduced as the model
    controller = Loop("controller", ("valve",), "demand")  # scenario_circuit's names
    broken = break_loop(compiled, point, controller, t, s, scale, dyn, [])
    assert broken.abcd is not None
    A_o, b_o, c_o, _ = broken.abcd
    A_l, b_l, c_l, rest_l, _ = lti.reduce_levels(A_o, b_o, c_o, dyn, vectors)
    velocity = [j for j, k in enumerate(rest_l) if dyn_list[k] == index[stems[S_V]]]
    ss = _servo_layout(compiled, P, s)
    x_v = float(ss[S_XV])
    reason = None
    nearest = None
    loop: tuple | None = (A_l, b_l, c_l, 0.0)
    if in_overlap(x_v, P):
        lap = max(P[P_LAP_PA], P[P_LAP_BT]) if x_v >= 0 else max(P[P_LAP_PB], P[P_LAP_AT])
        reason = (
            f"the spool at {x_v * 1e6:.3g} µm sits inside its ±{lap * 1e6:.3g} µm overlap: no "
            "flow gain, so no feedback acts here"
        )
        loop = None
        if _nearest:
            zero = {name: 0.0 for name in ("lap_pa", "lap_at", "lap_pb", "lap_bt")}
            nearest = linearize_servo(sc.replace(**zero), at=float(ss[S_Q]), _nearest=False)
            side = 1.0 if x_v >= 0 else -1.0
            nearest.operating_point["spool"] = nearest.operating_point.get("spool", 0.0) + (
                side * lap
            )
            # the valve line's spool is the displaced one too, as the operating point's
            nearest.quantities["spool_m"] = nearest.quantities["spool_m"] + side * lap
            nearest.notes.append(
                f"the spool displaced by its overlap ({side * lap * 1e3:+.4g} mm): there the "
                "valve meters as a zero-lap valve, linearised as one"
            )
    spool_max = P[P_SPOOL_MAX] if math.isfinite(P[P_SPOOL_MAX]) and P[P_SPOOL_MAX] > 0 else 1e-3
    steps = (FD_STEP * spool_max, FD_STEP * float(scale[index[stems[S_PA]]]))
    quantities = _servo_quantities(
        _stiffness(compiled, point, P),
        P,
        x_v,
        A_l,
        velocity,
        _load_flow(compiled, point, controller),
        steps,
    )
    op = {names[i]: float(s[i]) for i in dyn_list}
    op["reference"] = r
    nh, nm = len(compiled.hydraulic), len(compiled.mechanical)
    pressure = np.array([unit == "Pa" for _, unit in compiled.state_names])
    return LinearModel(
        kind="servo",
        states=tuple(names[dyn_list[k]] for k in rest),
        inputs=("reference", "load_force"),
        outputs=("position", "pressure_a", "pressure_b"),
        A=A_r,
        B=B_r,
        C=C_r,
        D=D,
        loop_abcd=loop,
        reference_output="position",
        operating_point=op,
        quantities=quantities,
        step_jacobian=stability_jacobian(t, s, Pc, compiled.net, pressure),
        euler_order=circuit_euler_order(s.size, nh, nm),
        steady=steady,
        floating=[_level_label(v, names) for v in vectors],
        open_loop_reason=reason,
        nearest=nearest,
        rotary=int(P[P_LOAD]) != LOAD_MASS,
    )


def _load_flow(compiled, point: SteadyState, loop: Loop):
    """Q_L(Δx_v, Δp_L) = (Q_A − Q_B)/2 [m³/s], the valve's flows into chamber A and out of
    chamber B (its port flows ``valve_A_flow_lpm``, ``valve_B_flow_lpm`` on the system
    kernel) at the operating point with p_A − p_B moved by Δp_L (split evenly) and the spool
    by Δx_v: its state, and its command (the loop broken there,
    `hydroarm.analysis.circuit_linear.broken_circuit`) for a spool with no dynamics."""
    broken, P, k_inj, _ = broken_circuit(compiled, point, loop)
    index = {stem: j for j, (stem, _) in enumerate(compiled.state_names)}
    spool, p_a, p_b = index["valve.spool"], index["A.pressure"], index["B.pressure"]

    def q_load(dx: float, dp: float) -> float:
        S = point.state.copy()
        S[spool] += dx
        S[p_a] += 0.5 * dp
        S[p_b] -= 0.5 * dp
        PP = P.copy()
        PP[k_inj] += dx
        res = CircuitResult(broken, np.array([point.t]), S[None, :], -1, PP)
        q_a = float(res.output("valve_A_flow_lpm")[0])
        q_b = float(res.output("valve_B_flow_lpm")[0])
        return -0.5 * (q_a - q_b) / 6.0e4  # the port flows leave the chambers: into the valve

    return q_load


def _last_pivot(v: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """A floating level whose largest entries tie (a chamber pair's common level, (1, 1) on
    p_A, p_B) with the others among them shrunk by 1e-12 (far below the differences'
    1e-10), so that `lti.reduce_levels` drops the last of them (p_B, as the servo kernel's
    model did) whatever the order of the sort."""
    out = v.copy()
    big = np.abs(out[keep])
    tied = keep[big >= (1.0 - 1e-9) * np.max(big)]
    out[tied[:-1]] *= 1.0 - 1e-12
    return out


def _level_label(v: np.ndarray, names: list[str]) -> str:
    """A floating level's label: the names of the states it moves, joined by " + "."""
    return " + ".join(names[i] for i in np.nonzero(np.abs(v) > 1e-3)[0])


def _stiffness(compiled, point: SteadyState, P) -> tuple[float, float]:
    """(K_h, λ) at the operating point: the actuator's hydraulic stiffness K_h = A_A²/C_A +
    A_B²/C_B [N/m; rotary: N m/rad] (the two oil columns in parallel, Merritt 1967 §6.2), C
    the compliance V/β_e its law gives each chamber (`hydroarm.model.circuit_steady.compliances`),
    and the lever λ from the actuator's force to the load's (the crank linkage's force lever,
    `hydroarm.model.circuit_steady.linkage_levers`; 1 without a linkage)."""
    ci = component_index(compiled, "actuator")
    cap = compliances(compiled, point.t, point.state, point.P)
    c_a, c_b = (cap[ci, compiled.decls[ci].port_names.index(k)] for k in ("a", "b"))
    k_h = P[P_AREA_A] ** 2 / c_a + P[P_AREA_B] ** 2 / c_b
    levers = linkage_levers(compiled, point.t, point.state, point.P)
    return float(k_h), levers.get(_actuator_node(compiled), 1.0)


def _servo_quantities(stiffness, P, x_v, A_loop, velocity, q_load, steps) -> dict:
    """K_q, K_c (central differences of the valve's load flow ``q_load(Δx_v, Δp_L)`` [m³/s]
    about the spool's position, steps ``steps`` = (Δx_v [m], Δp_L [Pa])), the hydraulic
    stiffness (``stiffness``: (K_h, λ), `_stiffness`) at the actuator and at the load
    (K_h·λ²), ω_h and ζ_h (the loop's mode in which the load's velocity takes the largest
    part: `lti.participation_mode`), Merritt's ω_h, K_v and the criterion; None where
    undefined."""
    k_h, lever = stiffness
    a_a = P[P_AREA_A]
    dx, dp = steps
    k_q = (q_load(dx, 0.0) - q_load(-dx, 0.0)) / (2 * dx)
    k_c = -(q_load(0.0, dp) - q_load(0.0, -dp)) / (2 * dp)
    if in_overlap(x_v, P):
        k_q = k_c = 0.0  # no edge open: no flow, whatever the step of the differences
    k_h_load = k_h * lever**2
    w_merritt = math.sqrt(k_h_load / P[P_MASS])
    w_h, z_h = lti.participation_mode(A_loop, velocity)
    fb = P[P_FB_GAIN] if P[P_FEEDBACK] == FEEDBACK_MECHANICAL else P[P_KP] * P[P_SENSOR_GAIN]
    k_v = fb * k_q / a_a
    crit = None if w_h is None or z_h is None else 2.0 * z_h * w_h
    return {
        "flow_gain_m2_s": float(k_q),
        "flow_pressure_coefficient_m3_s_pa": float(k_c),
        "hydraulic_stiffness_n_m": float(k_h),
        "hydraulic_stiffness_load": float(k_h_load),
        "hydraulic_natural_frequency_rad_s": w_h,
        "hydraulic_damping_ratio": z_h,
        "merritt_natural_frequency_rad_s": w_merritt,
        "velocity_constant_1_s": float(k_v),
        "stability_criterion_1_s": crit,
        "criterion_met": None if crit is None else bool(k_v < crit),
        "spool_m": float(x_v),
    }


# ------------------------------------------------------------------- entry ---
def linearize(scenario, at=None) -> LinearModel:
    """Linearise a servo about an operating point (docs/linear.md).

    Parameters
    ----------
    scenario : Scenario or ServoScenario
        A [`Scenario`][hydroarm.Scenario] (the paper's joint, any physics option) or a
        [`ServoScenario`][hydroarm.ServoScenario] (a component servo).
    at : float or mapping, optional
        None: at rest at the scenario's target (the final lever or reference). A number: at
        rest at this angle [rad] or position [m or rad], the steady state with the load held
        and the valve at its holding opening. A mapping: a state, linearised as given (joint:
        ``angle``, ``velocity``, ``pressure``, ``lever``; servo: state names of
        `hydroarm.core.servo.STATES` or of its circuit, and ``reference``).

    Returns
    -------
    LinearModel
        The closed loop's state-space model at the operating point and its quantities.
    """
    if isinstance(scenario, Scenario):
        return linearize_joint(scenario, at)
    if isinstance(scenario, ServoScenario):
        return linearize_servo(scenario, at)
    raise HydroarmError("scenario", "must be a Scenario or a ServoScenario")


# --------------------------------------------------------- load and angle ---
VARIATION_COLUMNS = (
    "hydraulic_natural_frequency_rad_s",
    "hydraulic_damping_ratio",
    "velocity_constant_1_s",
    "gain_margin_db",
    "phase_margin_deg",
    "bandwidth_rad_s",
    "step_overshoot_percent",
)


def linear_variation(joint, loads, angles):
    """The paper's joint linearised at rest at each (load, angle).

    ω_h, ζ_h, K_v, the gain and phase margins, the bandwidth and the small-step overshoot: a
    loop over [`linearize`][hydroarm.linearize] (about 5 ms a point once warm; docs/linear.md).

    Parameters
    ----------
    joint : ServoJoint or str
        A [`ServoJoint`][hydroarm.ServoJoint] or a parameter-set name.
    loads : sequence of int or Load
        Load numbers 1–10 of Appendix I, or [`Load`][hydroarm.Load] objects.
    angles : sequence of float
        Joint angles θ₂ [rad].

    Returns
    -------
    pandas.DataFrame
        One row per pair (loads outer, angles inner), columns ``load, inertia_kg_m2,
        angle_deg, angle_rad, held`` and `VARIATION_COLUMNS`; a pair the valve cannot hold
        (beyond its stall) has ``held`` false and NaN quantities.
    """
    import pandas as pd

    if isinstance(joint, str):
        joint = parameter_set(joint)
    angles = np.atleast_1d(np.asarray(angles, float))
    rows = []
    for load in loads:
        ld = paper_load(load) if not hasattr(load, "inertia") else load
        name = load if not hasattr(load, "inertia") else ld.name
        sc = saturation_test(joint, ld, "raise")
        for theta in angles:
            row = {
                "load": name,
                "inertia_kg_m2": float(ld.inertia),
                "angle_deg": math.degrees(float(theta)),
                "angle_rad": float(theta),
            }
            try:
                m = linearize(sc, at=float(theta))
            except HydroarmError as exc:
                if exc.field != "load":
                    raise
                row.update({"held": False, **{k: math.nan for k in VARIATION_COLUMNS}})
            else:
                q = m.quantities
                row["held"] = True
                row["hydraulic_natural_frequency_rad_s"] = q["hydraulic_natural_frequency_rad_s"]
                row["hydraulic_damping_ratio"] = q["hydraulic_damping_ratio"]
                row["velocity_constant_1_s"] = q["velocity_constant_1_s"]
                mg = m.margins()
                row["gain_margin_db"] = mg["gain_margin_db"]
                row["phase_margin_deg"] = mg["phase_margin_deg"]
                row["bandwidth_rad_s"] = m.bandwidth()
                row["step_overshoot_percent"] = m.step_info()["Overshoot"]
            rows.append(row)
    cols = ["load", "inertia_kg_m2", "angle_deg", "angle_rad", "held", *VARIATION_COLUMNS]
    return pd.DataFrame(rows, columns=cols)


def linear_variation_figure(frame, *, title=None):
    """ω_h, ζ_h and the margins against angle, one line per load
    (`hydroarm.plotting.linear.variation_figure` of
    [`linear_variation`][hydroarm.linear_variation])."""
    return variation_figure(frame, title=title)
