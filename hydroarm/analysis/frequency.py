"""Frequency response by simulation (issue 15; docs/linear.md, "Frequency response by
simulation").

[`frequency_response`][hydroarm.frequency_response] drives the nonlinear model with a sine of the
lever (or reference) about the operating point that [`linearize`][hydroarm.linearize] finds, one run
per (amplitude, frequency), discards the settling cycles and fits the fundamental of the output by
least squares (sine + cosine + offset on a whole number of periods, sampled uniformly: the
fit is the discrete Fourier coefficient at that frequency). The measured gain and phase sit
beside the linear model's at the same frequencies; at amplitudes near and beyond the valve's
saturation opening e_o they are the describing function of the saturated servo (the gain falls
where the jack's velocity is limited to K_q·e_o/A).

Each run starts on the linear model's periodic solution (the operating point plus the linear
steady-state response at t = 0), so that at small amplitude almost nothing is left to settle;
the settling cycles remove what the nonlinearity leaves (and, at large amplitude, the
transient onto the saturated limit cycle).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..core.equations import jack_position_trace
from ..core.servo import STATE_INDEX
from ..errors import HydroarmError
from ..integrators import registry
from ..model.lever import LeverInput
from ..model.scenario import Scenario, run_failure
from ..model.servo import ServoScenario
from ..plotting.linear import frequency_response_figure
from .linear import LinearModel, linearize

POINTS_PER_CYCLE = 200  # fixed steps per period at least (h ≤ 1/(200·f))
STEP_PER_POLE = 0.05  # and h·|λ|max ≤ 0.05 (accuracy of rk4 on the fastest pole: ~1e-8)
DEFAULT_CYCLES = 3
DEFAULT_SETTLE_CYCLES = 3
MIN_SETTLE_TIME_CONSTANTS = 3.0  # and at least 3 time constants of the slowest pole
# frequencies of one sweep: each is a simulated run of settling plus 3 periods per amplitude;
# 200 log-spaced points over the sweep's 60:1 range are 0.9 % apart, finer than any plot
# needs (10⁶ ran until killed, issue 31)
MAX_FREQUENCIES = 200


@dataclass
class FrequencyResponse:
    """Gain and phase of the nonlinear model's fundamental, beside the linear model's.

    Parameters
    ----------
    frequencies_rad_s : numpy.ndarray
        Angular frequencies [rad/s] (n_f).
    amplitudes : numpy.ndarray
        Input amplitudes (n_a) [m for the lever, or the reference's unit].
    response : numpy.ndarray
        n_a × n_f, complex: output amplitude and phase over the input's (SI).
    linear_response : numpy.ndarray
        n_f, complex: the linear model's.
    model : LinearModel
        The [`LinearModel`][hydroarm.LinearModel] at the operating point.
    input : str
        The input's name.
    output : str
        The output's name.
    step_s : numpy.ndarray
        n_a × n_f: the fixed step of each run [s].
    seconds : float
        Wall-clock time of the runs [s].
    saturation_opening : float
        The joint's full valve opening e_o [m] (NaN: a component servo).
    """

    frequencies_rad_s: np.ndarray
    amplitudes: np.ndarray
    response: np.ndarray
    linear_response: np.ndarray
    model: LinearModel
    input: str
    output: str
    step_s: np.ndarray
    seconds: float
    saturation_opening: float = math.nan  # e_o [m] of the joint (nan: a component servo)

    @property
    def gain_db(self) -> np.ndarray:
        return 20 * np.log10(np.maximum(np.abs(self.response), 1e-300))

    @property
    def linear_gain_db(self) -> np.ndarray:
        return 20 * np.log10(np.maximum(np.abs(self.linear_response), 1e-300))

    @property
    def linear_phase_deg(self) -> np.ndarray:
        """The linear phase, unwrapped continuously from low frequency (dense grid)."""
        return _unwrapped_phase(self.model, self.input, self.output, self.frequencies_rad_s)

    @property
    def phase_deg(self) -> np.ndarray:
        """The measured phase on the linear phase's branch (within ±180° of it)."""
        lin = self.linear_phase_deg
        d = np.degrees(np.angle(self.response / self.linear_response))
        return lin[None, :] + d

    def errors(self, up_to: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(max |gain − linear gain| [dB], max |phase − linear phase| [deg]) of each amplitude
        over the frequencies ≤ ``up_to`` [rad/s] (all when None)."""
        keep = np.ones(self.frequencies_rad_s.size, bool)
        if up_to is not None:
            keep = self.frequencies_rad_s <= up_to * (1 + 1e-12)
        dg = np.abs(self.gain_db - self.linear_gain_db[None, :])[:, keep]
        dp = np.abs(self.phase_deg - self.linear_phase_deg[None, :])[:, keep]
        return dg.max(axis=1), dp.max(axis=1)

    def to_pandas(self):
        """One row per (amplitude, frequency): amplitude, frequency_rad_s, frequency_hz,
        gain_db, phase_deg, linear_gain_db, linear_phase_deg, gain_error_db,
        phase_error_deg, step_s."""
        import pandas as pd

        na, nf = self.response.shape
        g, ph = self.gain_db, self.phase_deg
        lg, lp = self.linear_gain_db, self.linear_phase_deg
        w = self.frequencies_rad_s
        return pd.DataFrame(
            {
                "amplitude": np.repeat(self.amplitudes, nf),
                "frequency_rad_s": np.tile(w, na),
                "frequency_hz": np.tile(w / (2 * math.pi), na),
                "gain_db": g.ravel(),
                "phase_deg": ph.ravel(),
                "linear_gain_db": np.tile(lg, na),
                "linear_phase_deg": np.tile(lp, na),
                "gain_error_db": (g - lg[None, :]).ravel(),
                "phase_error_deg": (ph - lp[None, :]).ravel(),
                "step_s": self.step_s.ravel(),
            }
        )

    def plot(self):
        """The measured gain and phase of each amplitude (markers) on the linear Bode of the
        same transfer (line): `hydroarm.plotting.linear.frequency_response_figure`."""
        w = self.frequencies_rad_s
        lo, hi = math.log10(w.min()) - 0.5, math.log10(w.max()) + 0.3
        dense = np.logspace(lo, hi, 400)
        h = _linear(self.model, self.input, self.output, dense)
        phase = _unwrapped_phase(self.model, self.input, self.output, dense)
        e_o = self.saturation_opening
        labels = [_amplitude_label(a, e_o, self.model.kind == "joint") for a in self.amplitudes]
        q = self.model.quantities
        w_h = q.get("hydraulic_natural_frequency_rad_s", math.nan)
        title = f"{self.input} → {self.output}: simulated (markers) and linear (line)"
        return frequency_response_figure(
            dense,
            h,
            phase,
            w,
            self.gain_db,
            self.phase_deg,
            labels,
            title=title,
            marks={"ω_h": w_h, "2·ω_h": 2 * w_h} if math.isfinite(w_h) else {},
        )


def _amplitude_label(a: float, e_o: float, joint: bool) -> str:
    if joint and math.isfinite(e_o):
        return f"{a * 1e3:.3g} mm ({a / e_o:.3g}·e_o)"
    return f"amplitude {a:.3g}"


def default_amplitudes(scenario) -> tuple[float, ...]:
    """The describing-function family of the joint: e_o/40 (linear: the valve swings well
    inside its band), e_o and 10·e_o (rate-limited above ω ≈ K_v·e_o/a)."""
    if not isinstance(scenario, Scenario):
        raise HydroarmError("amplitude", "give the reference's sine amplitude for a servo")
    e_o = scenario.joint.valve_saturation
    return (e_o / 40, e_o, 10 * e_o)


def _linear(m: LinearModel, input: str, output: str, w) -> np.ndarray:
    """C[o]·(iωI − A)⁻¹·B[:, i] + D[o, i] at each ω."""
    i, o = m.inputs.index(input), m.outputs.index(output)
    n = m.A.shape[0]
    out = np.empty(len(w), complex)
    for k, wk in enumerate(np.asarray(w, float)):
        x = np.linalg.solve(1j * wk * np.eye(n) - m.A, m.B[:, i])
        out[k] = m.C[o] @ x + m.D[o, i]
    return out


def _unwrapped_phase(m: LinearModel, input: str, output: str, w) -> np.ndarray:
    """The linear phase [deg] at ``w``, unwrapped along a dense grid from 10⁻³ of the lowest
    frequency (so that it starts on the branch of the DC gain's sign)."""
    w = np.asarray(w, float)
    grid = np.unique(
        np.concatenate([np.logspace(math.log10(w.min()) - 3, math.log10(w.max()), 600), w])
    )
    ph = np.degrees(np.unwrap(np.angle(_linear(m, input, output, grid))))
    return ph[np.searchsorted(grid, w)]


def fit_fundamental(t: np.ndarray, y: np.ndarray, w: float) -> complex:
    """Least squares of y ≈ b_s·sin(ωt) + b_c·cos(ωt) + c: returns b_s + i·b_c (the complex
    amplitude of the fundamental: y's part at ω is Im((b_s + i·b_c)·e^{iωt}))."""
    M = np.column_stack([np.sin(w * t), np.cos(w * t), np.ones_like(t)])
    coef, *_ = np.linalg.lstsq(M, y, rcond=None)
    return complex(coef[0], coef[1])


def _settle_time(m: LinearModel) -> float:
    """Three time constants of the slowest decaying pole (a pole at zero to rounding, such
    as an unobservable integrator's, is left out: it does not decay and the fit's offset
    takes up what it holds)."""
    re = -m.poles.real
    re = re[re > 1e-9 * float(np.max(np.abs(m.poles)))]
    return MIN_SETTLE_TIME_CONSTANTS / float(re.min()) if re.size else 0.0


def _plan(m: LinearModel, w: float, cycles: int, settle_cycles: int, method: str):
    """(h, steps per period N, settling periods, record every K-th step): h = T/N with N a
    multiple K of POINTS_PER_CYCLE and h·|λ|max ≤ STEP_PER_POLE (a whole number of steps
    per period; POINTS_PER_CYCLE samples of each period are kept)."""
    period = 2 * math.pi / w
    lam = float(np.max(np.abs(m.poles))) if m.poles.size else 0.0
    h_max = STEP_PER_POLE / lam if lam > 0 else period
    every = max(1, math.ceil(period / h_max / POINTS_PER_CYCLE))
    n_per = POINTS_PER_CYCLE * every
    settle = max(settle_cycles, math.ceil(_settle_time(m) / period)) if settle_cycles > 0 else 0
    return period / n_per, n_per, settle, every


def _check_args(frequencies, amplitude, cycles, settle_cycles, method) -> tuple:
    w = np.atleast_1d(np.asarray(frequencies, float))
    a = np.atleast_1d(np.asarray(amplitude, float))
    if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise HydroarmError("frequencies", "must be positive finite numbers [rad/s]")
    if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise HydroarmError("amplitude", "must be positive finite numbers")
    for name, v, lo in (("cycles", cycles, 1), ("settle_cycles", settle_cycles, 0)):
        if not isinstance(v, int) or isinstance(v, bool) or v < lo:
            raise HydroarmError(name, f"must be a whole number ≥ {lo}, got {v!r}")
    if not registry.method(method).fixed_step:
        raise HydroarmError(
            "method", f"must be a fixed-step method: {', '.join(registry.fixed_step_methods())}"
        )
    return w, a


def frequency_response(
    scenario,
    frequencies: Sequence[float] | np.ndarray,
    amplitude: float | Sequence[float] | np.ndarray,
    *,
    at=None,
    cycles: int = DEFAULT_CYCLES,
    settle_cycles: int = DEFAULT_SETTLE_CYCLES,
    output: str | None = None,
    method: str = "rk4",
    start: str = "linear",
    workers: int | None = None,
) -> FrequencyResponse:
    """Frequency response of the nonlinear model by sine runs (docs/linear.md).

    Parameters
    ----------
    scenario : Scenario or ServoScenario
        A [`Scenario`][hydroarm.Scenario] (the paper's joint; the input is the lever [m]) or a
        [`ServoScenario`][hydroarm.ServoScenario] (the input is the reference).
    frequencies : sequence of float
        Angular frequencies [rad/s].
    amplitude : float or sequence of float
        One or several sine amplitudes of the input [m, or the reference's unit]: one curve
        each (the describing-function view).
    at : float or mapping, optional
        The operating point as [`linearize`][hydroarm.linearize] takes it (it must be steady).
    cycles : int
        Periods fitted [-].
    settle_cycles : int
        Periods discarded first [-] (0: none; else at least three time constants of the
        slowest closed-loop pole).
    output : str, optional
        One of the linear model's outputs (default: the angle or position).
    method : str
        A fixed-step method; the step is T/N with N ≥ 200 steps per period and
        h·|λ|max ≤ 0.05.
    start : str
        ``"linear"``: each run starts on the linear periodic solution where the joint's valve
        opening swings at most e_o/2, else at rest; ``"rest"``: at rest at the operating point.
    workers : int, optional
        Threads running the sine runs (the kernels release the GIL; default: the CPU count).

    Returns
    -------
    FrequencyResponse
        Gain and phase of each amplitude at each frequency, beside the linear model's.
    """
    w, amps = _check_args(frequencies, amplitude, cycles, settle_cycles, method)
    if start not in ("linear", "rest"):
        raise HydroarmError("start", f"must be 'linear' or 'rest', got {start!r}")
    if not isinstance(scenario, (Scenario, ServoScenario)):
        raise HydroarmError("scenario", "must be a Scenario or a ServoScenario")
    m = linearize(scenario, at=at)
    if not m.steady:
        raise HydroarmError("at", "the frequency response needs a steady operating point")
    if m.open_loop_reason is not None:
        raise HydroarmError(
            "at",
            f"the loop is open at this operating point ({m.open_loop_reason}): a small sine "
            "moves nothing there",
        )
    if (m.kind == "joint" and np.max(m.poles.real) >= 0) or (m.kind == "servo" and m.unstable()):
        raise HydroarmError("at", "the servo is not stable at this operating point")
    if isinstance(scenario, Scenario):
        reach = scenario.joint.crank_radius
        y_op = m.operating_point["lever"]
        if np.any(abs(y_op) + amps >= 0.95 * reach):
            raise HydroarmError(
                "amplitude",
                f"{amps.max() * 1e3:.4g} mm about the lever's {y_op * 1e3:.4g} mm reaches "
                f"beyond 95 % of the crank's reach ±{reach * 1e3:.4g} mm",
            )
    output = m.outputs[0] if output is None else output
    if output not in m.outputs:
        raise HydroarmError("output", f"{output!r} is not one of {', '.join(m.outputs)}")
    inp = m.inputs[0]
    h_lin = _linear(m, inp, output, w)
    jobs = [(ia, iw) for ia in range(amps.size) for iw in range(w.size)]
    resp = np.empty((amps.size, w.size), complex)
    steps = np.empty((amps.size, w.size))

    def one(job):
        ia, iw = job
        return job, _one_run(
            scenario, m, output, amps[ia], w[iw], cycles, settle_cycles, method, start
        )

    n_workers = max(1, min(len(jobs), workers or os.cpu_count() or 1))
    t0 = time.perf_counter()
    if n_workers == 1:
        done = [one(j) for j in jobs]
    else:
        with ThreadPoolExecutor(n_workers) as pool:
            done = list(pool.map(one, jobs))
    seconds = time.perf_counter() - t0
    for (ia, iw), (r, h) in done:
        resp[ia, iw] = r
        steps[ia, iw] = h
    e_o = scenario.joint.valve_saturation if isinstance(scenario, Scenario) else math.nan
    return FrequencyResponse(
        frequencies_rad_s=w,
        amplitudes=amps,
        response=resp,
        linear_response=h_lin,
        model=m,
        input=inp,
        output=output,
        step_s=steps,
        seconds=seconds,
        saturation_opening=e_o,
    )


def _linear_start(sc, m: LinearModel, phasor: np.ndarray, a: float) -> bool:
    """Whether a run starts on the linear periodic solution: the joint's valve opening
    e = y − x swings at most half its saturation e_o there (a larger swing is not linear, and
    its linear pressures can be far outside the physical ones); a component servo starts at
    rest."""
    if not isinstance(sc, Scenario):
        return False
    c = float(m.C[m.outputs.index("jack_position"), 0])
    e = abs(1.0 - c * phasor[0]) * a
    return e <= 0.5 * sc.joint.valve_saturation


def _one_run(
    sc, m: LinearModel, output: str, a: float, w: float, cycles, settle_cycles, method, start
):
    """One sine run: (complex gain of the fundamental, step)."""
    h, n_per, settle, every = _plan(m, w, cycles, settle_cycles, method)
    n_total = (settle + cycles) * n_per
    f_hz = w / (2 * math.pi)
    op = m.operating_point
    # the linear periodic solution at t = 0 for the input a·sin(ωt): Im of the phasor
    n = m.A.shape[0]
    phasor = np.linalg.solve(1j * w * np.eye(n) - m.A, m.B[:, 0])
    x0 = a * np.imag(phasor)
    if start == "rest" or not _linear_start(sc, m, phasor, a):
        x0[:] = 0.0  # at rest at the operating point: the settling cycles do the rest
    start = {name: op[name] + x0[k] for k, name in enumerate(m.states)}
    if isinstance(sc, Scenario):
        lever = LeverInput(
            np.array([0.0]), np.array([op["lever"]]), a, f_hz, 0.0, description="sine"
        )
        run = sc.replace(
            lever=lever,
            initial_angle=start["angle"],
            initial_pressure=start["pressure"],
            duration=n_total * h,
            method=method,
            step=h,
            record_every=every,
            t0=0.0,
        )
        run.check_step()
        J, L = run.params
        t, th, om, p, _, bad = registry.run(
            method,
            start["angle"],
            start["velocity"],
            start["pressure"],
            0.0,
            h,
            n_total,
            every,
            lever.times,
            lever.positions,
            lever.sine,
            J,
            L,
        )
        if bad >= 0:
            raise run_failure(run, float(t[-1]), float(th[-1]), float(om[-1]), float(p[-1]), p[0])
        y = {"angle": th, "pressure": p, "jack_position": None}[output]
        if y is None:
            y = jack_position_trace(np.ascontiguousarray(th), J)
    else:
        ref = LeverInput(
            np.array([0.0]), np.array([op["reference"]]), a, f_hz, 0.0, description="sine"
        )
        initial = dict(sc.initial)  # the whole operating point (the model's states are
        initial.update({k: v for k, v in op.items() if k in STATE_INDEX})  # fewer: levels)
        initial.update({k: v for k, v in start.items() if k in STATE_INDEX})
        run = sc.replace(
            reference=ref,
            initial=initial,
            duration=n_total * h,
            step=h,
            method=method,
            record_every=every,
        )
        res = run.run()
        t = res.t
        y = res.state(output)  # the servo's outputs are states: position, pressure_a, _b
    k0 = settle * POINTS_PER_CYCLE
    sl = slice(k0, k0 + cycles * POINTS_PER_CYCLE)  # whole periods, uniformly sampled
    b = fit_fundamental(np.asarray(t)[sl], np.asarray(y)[sl], w)
    return b / a, h
