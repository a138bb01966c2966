"""The single-joint view's state: settings with units, the paper's saturation tests run on
each change, the metrics beside Tables I and III, the linear view.

Plain Python (no web framework): the page (`hydroarm.explore.app`) only reads and sets
it. Every run is [`hydroarm.model.scenario.simulate`][hydroarm.simulate] of
[`saturation_test`][hydroarm.saturation_test] (one physics); the load is the paper's arm
alone (Appendix I load 1) with a mass added in the hand at the stall test's 460 mm, as
``hydroarm reproduce`` builds its load sweep. Values are SI floats [kg, Pa, m²/s/√Pa,
m³/s/Pa, m³, -]; the sliders' display units are in `SLIDERS`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..analysis import lti
from ..analysis.linear import linearize
from ..batch import saturation
from ..errors import HydroarmError
from ..io.catalog import DEFAULT_SET, parameter_set_names
from ..io.schema import parameter_set
from ..model.joint import TORQUE_ARMS, VALVE_MODELS, Load, ServoJoint
from ..model.scenario import saturation_test, simulate
from ..paper.data import table1, table3
from ..paper.reproduce import HAND_DISTANCE
from .charts import rounded, time_panels

DIRECTIONS = ("raise", "lower")
# keep every 20th step for the plots (0.2 ms at the paper's 10 µs: 20 points per 63 % time
# constant of ~25 ms); the metrics are observed at every step (SimulationResult.metrics)
RECORD_EVERY = 20
MAX_POINTS = 400  # points of a curve sent to the browser (evenly thinned: 4 ms apart)
# the chart's panels: (trace, axis name with its unit) and their spacing [px]
PANELS = (
    ("theta", "θ₂ [deg]"),
    ("x", "jack x [mm]"),
    ("p", "load p [bar]"),
    ("xdot", "jack ẋ [mm/s]"),
)
PANEL_STEP = 160
CHART_TOP = 64  # [px] above the first panel: the title, then the first axis's name
BODE_POINTS = 200  # frequencies of the Bode plot sent to the browser
BODE_HEIGHT = 520  # [px]
CHART_HEIGHT = CHART_TOP + len(PANELS) * PANEL_STEP + 10  # [px]


_r = rounded


@dataclass(frozen=True)
class Slider:
    """A slider of the single-joint view: its field, label, display unit, the display value's
    factor to SI (SI = display × ``scale``), range and step in display units."""

    field: str
    label: str
    unit: str
    scale: float
    low: float
    high: float
    step: float


# the sliders; K, L and V are shown relative to the chosen parameter set's values (×), the
# others in their units; ranges cover the paper's loads (0 to past the 0.45 kg stall mass),
# pressures (the pump's 31 bar and the 45 bar what-if) and the sets' gearbox losses
# (ucl-arm-measured: 0.965 at stall)
SLIDERS = (
    Slider("hand_mass", "load mass in the hand", "kg", 1.0, 0.0, 0.6, 0.01),
    Slider("supply_pressure", "supply pressure p_s", "bar", 1e5, 10.0, 60.0, 0.5),
    Slider("flow_gain", "valve flow coefficient K", "× set", 1.0, 0.25, 4.0, 0.05),
    Slider("leakage_gain", "leakage coefficient L", "× set", 1.0, 0.1, 4.0, 0.05),
    Slider("volume_gain", "trapped volume V", "× set", 1.0, 0.25, 4.0, 0.05),
    Slider("gearbox_loss_at_stall", "gearbox loss at stall", "-", 1.0, 0.0, 0.99, 0.01),
)
SLIDER_BY_FIELD = {s.field: s for s in SLIDERS}
METHODS = ("euler", "rk4")


@dataclass(frozen=True)
class JointSettings:
    """What the single-joint view's controls set (SI; the gains are factors on the set's
    K, L and V). ``None`` for supply pressure and gearbox loss: the parameter set's."""

    parameter_set: str = DEFAULT_SET
    hand_mass: float = 0.0
    supply_pressure: float | None = None
    flow_gain: float = 1.0
    leakage_gain: float = 1.0
    volume_gain: float = 1.0
    gearbox_loss_at_stall: float | None = None
    valve_model: str | None = None
    torque_arm: str | None = None
    method: str = "euler"

    def __post_init__(self):
        names = parameter_set_names()
        if self.parameter_set not in names:
            raise HydroarmError(
                "parameter_set", f"must be one of {', '.join(names)}, got {self.parameter_set!r}"
            )
        for s in SLIDERS:
            v = getattr(self, s.field)
            if v is None:
                continue
            d = v / s.scale
            if not (isinstance(v, (int, float)) and math.isfinite(v) and s.low <= d <= s.high):
                raise HydroarmError(
                    s.field, f"must be between {s.low:g} and {s.high:g} {s.unit}, got {d!r}"
                )
        for f, allowed in (
            ("valve_model", VALVE_MODELS),
            ("torque_arm", tuple(TORQUE_ARMS)),
            ("method", METHODS),
        ):
            v = getattr(self, f)
            if v is not None and v not in allowed:
                raise HydroarmError(f, f"must be one of {', '.join(allowed)}, got {v!r}")


def hand_load(mass: float) -> Load:
    """The paper's arm alone (load 1) with ``mass`` [kg] in the hand at 460 mm (the load of
    ``hydroarm reproduce``'s load sweep): W = W₁ + m·g, W·X = W₁X₁ + m·g·d, I = I₁ + m·d²
    (`hydroarm.batch.saturation.hand_load`)."""
    return saturation.hand_load(mass, distance=HAND_DISTANCE)


def build_joint(s: JointSettings) -> ServoJoint:
    """The chosen parameter set with the settings applied."""
    j = parameter_set(s.parameter_set)
    changes: dict = {
        "flow_coefficient": j.flow_coefficient * s.flow_gain,
        "leakage_coefficient": j.leakage_coefficient * s.leakage_gain,
        "trapped_volume": j.trapped_volume * s.volume_gain,
    }
    for f in ("supply_pressure", "gearbox_loss_at_stall", "valve_model", "torque_arm"):
        v = getattr(s, f)
        if v is not None:
            changes[f] = v
    return j.replace(**changes)


def _paper_rows() -> list[dict]:
    """Tables I (measured) and III (Model 2): {table, load, hand mass [kg], raise, lower [m/s]}."""
    out = []
    for name, cells in (("Table I (measured)", table1()), ("Table III (Model 2)", table3())):
        loads = sorted({k for k, _ in cells})
        for k in loads:
            out.append(
                {
                    "source": name,
                    "load": int(k),
                    "raise": cells[(k, "raise")] * 1e-3,
                    "lower": cells[(k, "lower")] * 1e-3,
                }
            )
    return out


@dataclass
class JointRun:
    """The two saturation tests of one setting: results by direction, metrics, the error text
    of a setting that cannot run (then no results)."""

    settings: JointSettings
    results: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)
    error: str = ""


class JointExplorer:
    """State of the single-joint view: the settings, the last runs, the shown direction."""

    def __init__(self, settings: JointSettings | None = None, start: JointRun | None = None):
        self.settings = settings or JointSettings()
        self.direction = "raise"
        self.paper = _paper_rows()
        self._joint: tuple[JointSettings | None, ServoJoint | None] = (None, None)
        self._cache: dict[JointSettings, JointRun] = {}
        if start is not None and start.settings == self.settings:
            self._cache[self.settings] = start  # a shared run: read, never written to
        self.run = self._run(self.settings)

    # controls --------------------------------------------------------------------------
    def set(self, name: str, value, shown_only: bool = False) -> JointRun:
        """Set one control (a slider's field in its display unit, or ``parameter_set``,
        ``valve_model``, ``torque_arm``, ``method``) and run the tests again (``shown_only``:
        the shown test only, the page's first answer; `complete` runs the other)."""
        if name in SLIDER_BY_FIELD:
            s = SLIDER_BY_FIELD[name]
            try:
                value = float(value) * s.scale
            except (TypeError, ValueError):
                raise HydroarmError(name, f"must be a number, got {value!r}") from None
        elif name not in ("parameter_set", "valve_model", "torque_arm", "method"):
            raise HydroarmError(name, "is not a control of the single-joint view")
        self.settings = replace(self.settings, **{name: value})
        self.run = self._run(self.settings, (self.direction,) if shown_only else DIRECTIONS)
        _ = self.joint  # built here (a thread on the page), not when the page redraws
        return self.run

    @property
    def joint(self) -> ServoJoint:
        """The joint of the current settings (`build_joint`, remembered: a redraw reads
        it a dozen times, 10+ ms each to build)."""
        settings, joint = self._joint
        if joint is None or settings != self.settings:
            joint = build_joint(self.settings)
            self._joint = (self.settings, joint)
        return joint

    def display_value(self, name: str) -> float:
        """A slider's current value in its display unit (the set's value when not set)."""
        s = SLIDER_BY_FIELD[name]
        v = getattr(self.settings, name)
        if v is None:
            v = getattr(self.joint, name)
        return v / s.scale

    def option(self, name: str):
        """A choice's current value (``parameter_set``, ``valve_model``, ``torque_arm``,
        ``method``): the set's own when not chosen."""
        v = getattr(self.settings, name)
        return getattr(self.joint, name) if v is None else v

    def test(self, direction: str) -> JointRun:
        """Show the paper's raise or lower test (the raise and lower buttons)."""
        if direction not in DIRECTIONS:
            raise HydroarmError("direction", f"must be raise or lower, got {direction!r}")
        self.direction = direction
        return self.run

    @property
    def complete(self) -> bool:
        """Whether both tests of the current setting have run (or it cannot run)."""
        return bool(self.run.error) or all(d in self.run.results for d in DIRECTIONS)

    def run_rest(self) -> JointRun:
        """Run the test `set` left out (``shown_only``) for the current setting."""
        return self._run(self.settings)

    def _run(self, s: JointSettings, directions=DIRECTIONS) -> JointRun:
        out = self._cache.get(s)
        if out is not None and (out.error or all(d in out.results for d in directions)):
            return out
        out = out or JointRun(s)
        try:
            joint = build_joint(s)
            load = hand_load(s.hand_mass)
            for d in directions:
                if d in out.results:
                    continue
                res = simulate(
                    saturation_test(joint, load, d, method=s.method, record_every=RECORD_EVERY)
                )
                out.results[d] = res
                out.metrics[d] = res.metric_values()
        except HydroarmError as exc:
            out.results.clear()
            out.metrics.clear()
            out.error = str(exc)
        if len(self._cache) > 64 and s not in self._cache:  # a slider dragged back and forth
            self._cache.clear()
        self._cache[s] = out
        return out

    # what the page shows ---------------------------------------------------------------
    @property
    def result(self):
        """The shown direction's [`SimulationResult`][hydroarm.SimulationResult] (None when
        the setting cannot run)."""
        return self.run.results.get(self.direction)

    def saturation_velocity(self, direction: str | None = None) -> float:
        """The saturation velocity [m/s] of a test (nan when it cannot run)."""
        m = self.run.metrics.get(direction or self.direction)
        return math.nan if m is None else float(m["saturation_velocity"])

    def metric_rows(self) -> list[dict]:
        """Rows {quantity, unit, raise, lower}: this setting's metrics (display units)."""
        rows = []
        for q, key, unit, scale in (
            ("saturation velocity", "saturation_velocity", "mm/s", 1e3),
            ("63 % time constant T'", "time_constant_start", "ms", 1e3),
            ("peak load pressure", "peak_pressure", "bar", 1e-5),
        ):
            r: dict = {"quantity": q, "unit": unit}
            for d in DIRECTIONS:
                m = self.run.metrics.get(d)
                r[d] = math.nan if m is None else float(m[key]) * scale
            rows.append(r)
        r = {"quantity": "stalled", "unit": ""}
        for d in DIRECTIONS:
            m = self.run.metrics.get(d)
            r[d] = "" if m is None else ("yes" if m["stalled"] else "no")
        rows.append(r)
        return rows

    def paper_rows(self) -> list[dict]:
        """Tables I and III beside the model: {source, load, hand, raise, lower} [mm/s]; the
        model's row first (its hand mass), the loads' hand masses from Appendix I."""
        rows = [
            {
                "source": "model (this setting)",
                "load": f"{self.settings.hand_mass:.2f} kg in the hand",
                "raise": self.saturation_velocity("raise") * 1e3,
                "lower": self.saturation_velocity("lower") * 1e3,
            }
        ]
        for r in self.paper:
            rows.append(
                {
                    "source": r["source"],
                    "load": f"load {r['load']}",
                    "raise": r["raise"] * 1e3,
                    "lower": r["lower"] * 1e3,
                }
            )
        return rows

    def linear(self) -> dict:
        """The linear view at the shown test's target: the model
        ([`LinearModel`][hydroarm.LinearModel]), its margins and bandwidth [rad/s];
        ``error`` when it cannot be linearised."""
        res = self.result
        if res is None:
            return {"error": self.run.error or "no run"}
        try:
            model = linearize(res.scenario)
            return {
                "model": model,
                "margins": model.margins(),
                "bandwidth": float(model.bandwidth()),
                "error": "",
            }
        except HydroarmError as exc:
            return {"error": str(exc)}

    def chart(self) -> dict:
        """ECharts options of the shown test (the page draws them in the browser: data, no
        picture): θ₂, jack position, load pressure and jack velocity against time, one panel
        each, at most `MAX_POINTS` points a curve; its title the saturation velocity."""
        tr = self.traces()
        v = self.saturation_velocity() * 1e3
        title = f"{self.direction} test: saturation velocity {v:.2f} mm/s"
        if not tr:
            return {"title": {"text": self.run.error or "no run", "textStyle": {"fontSize": 12}}}
        panels = [(name, [(name, tr[key])]) for key, name in PANELS]
        curves = time_panels(
            tr["t"],
            panels,
            top=CHART_TOP,
            height=120,
            step=PANEL_STEP,
            time_name="time [s]",
            max_points=MAX_POINTS,
        )
        return {
            "animation": False,
            "title": {"text": title, "left": "center", "top": 4, "textStyle": {"fontSize": 13}},
            "tooltip": {"trigger": "axis"},
            **curves,
        }

    def bode(self, lin: dict | None = None) -> dict:
        """ECharts options of the linear view's Bode plot (magnitude [dB] and phase [deg]
        against frequency [rad/s], log axis): the open loop broken at the valve opening and
        the closed loop lever → jack, from `linear` (``lin``: its answer, if made); at
        the nearest operating point with flow where the loop is open (as ``bode_figure``)."""
        lin = self.linear() if lin is None else lin
        if lin["error"]:
            return {"title": {"text": lin["error"], "textStyle": {"fontSize": 12}}}
        model = lin["model"]
        if model.loop_abcd is None and model.nearest is not None:
            model = model.nearest
        if model.loop_abcd is None:
            return {"title": {"text": f"the loop is open here: {model.open_loop_reason}"}}
        w = model.frequency_grid(BODE_POINTS)
        a, b, c, d = model.loop_abcd
        at, bt, ct, dt = model.tracking_abcd
        curves = (
            ("open loop (broken at the valve opening)", lti.freqresp(a, b, c, d, w)),
            ("closed loop, lever → jack", lti.freqresp(at, bt, ct, dt, w)),
        )
        m = lin["margins"]
        title = (
            f"gain margin {m['gain_margin_db']:.3g} dB, phase margin "
            f"{m['phase_margin_deg']:.3g}°, bandwidth {lin['bandwidth']:.4g} rad/s"
        )
        axes = []
        for i, name in enumerate(("magnitude [dB]", "phase [deg]")):
            axes.append(
                (
                    {
                        "type": "log",
                        "gridIndex": i,
                        "min": _r(w[0]),
                        "max": _r(w[-1]),
                        "name": "frequency [rad/s]" if i else "",
                        "nameLocation": "middle",
                        "nameGap": 24,
                        # the grid's ends are not round: only the decades are labelled
                        "axisLabel": {
                            "show": bool(i),
                            "showMinLabel": False,
                            "showMaxLabel": False,
                        },
                    },
                    {"type": "value", "gridIndex": i, "name": name, "scale": True},
                )
            )
        series = []
        for label, h in curves:
            h = np.asarray(h)
            mag = 20 * np.log10(np.maximum(np.abs(h), 1e-300))
            phase = np.degrees(np.unwrap(np.angle(h)))
            for i, v in enumerate((mag, phase)):
                series.append(
                    {
                        "name": label,
                        "type": "line",
                        "showSymbol": False,
                        "xAxisIndex": i,
                        "yAxisIndex": i,
                        "data": [[_r(a), _r(b)] for a, b in zip(w, v, strict=True)],
                    }
                )
        return {
            "animation": False,
            "title": {"text": title, "left": "center", "top": 4, "textStyle": {"fontSize": 12}},
            "legend": {"top": 28, "type": "scroll"},
            "tooltip": {"trigger": "axis"},
            "axisPointer": {"link": [{"xAxisIndex": "all"}]},
            "grid": [
                {"left": 64, "right": 16, "top": 80, "height": 170},
                {"left": 64, "right": 16, "top": 300, "height": 170},
            ],
            "xAxis": [a[0] for a in axes],
            "yAxis": [a[1] for a in axes],
            "series": series,
        }

    def traces(self) -> dict:
        """The shown test's traces in display units: t [s], θ₂ [deg], x [mm], p [bar],
        ẋ [mm/s] (empty when the setting cannot run)."""
        res = self.result
        if res is None:
            return {}
        return {
            "t": res.t,
            "theta": np.degrees(res.theta),
            "x": res.x * 1e3,
            "p": res.p * 1e-5,
            "xdot": res.xdot * 1e3,
        }
