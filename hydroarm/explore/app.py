"""The web page of ``hydroarm explore`` (NiceGUI; docs/explore.md).

NiceGUI (the optional ``explore`` extra) is imported by the functions that build the page,
when the server starts: the rest of hydroarm, the command line included, loads without it.

Three tabs: the single joint (`JointExplorer`), its linear
view, and the live arm with the block-stacking task (`LiveArm`).
The page only draws the state and passes the controls on; every browser tab gets its own
state. NiceGUI serves its own JavaScript, CSS and fonts: nothing is loaded from elsewhere.
"""

from __future__ import annotations

import asyncio
import math
import time
from pathlib import Path

from ..arm import JOINT_NAMES, ArmScenario
from ..errors import HydroarmError
from ..files import atomic_write_text
from ..io.catalog import parameter_set_names
from ..model.joint import TORQUE_ARMS, VALVE_MODELS
from .blocks import BLOCK_SIZE, PAD, PAD_RADIUS, TABLE_TOP, TABLE_X, TABLE_Y
from .joint import BODE_HEIGHT, CHART_HEIGHT, METHODS, SLIDERS, JointExplorer, JointRun
from .live import GRASP_KEY, KEYS, SPEEDS, LiveArm
from .pages import client_number, refused, run_latest, serve_page
from .scene import Shown, link_frame, place_link


def _nicegui():
    """NiceGUI's ``ui`` and ``run`` (imported on first use: an optional dependency)."""
    from nicegui import run, ui

    return ui, run


TICK_S = 1.0 / 30.0  # the live arm's timer [s]: 30 frames per second
SCENE_WIDTH, SCENE_MIN = 760, 280  # the 3-D scene's width [px]: at most, at least (a phone)
SCENE_ASPECT = 560 / 760  # its height per width
JOINT_LABELS = {
    "shoulder_elevation": "shoulder elevation",
    "humeral_rotation": "humeral rotation",
    "elbow_reach": "elbow reach",
    "wrist_rotation": "wrist rotation",
}
# the sliders that are factors on the set's value: (the joint's field, unit, SI → unit)
ABSOLUTE = {
    "flow_gain": ("flow_coefficient", "m²/(s·√Pa)", 1.0),
    "leakage_gain": ("leakage_coefficient", "mm³/(s·bar)", 1e14),
    "volume_gain": ("trapped_volume", "cm³", 1e6),
}
BLOCK_COLOURS = ("#c0392b", "#2471a3", "#d4ac0d", "#7d3c98", "#1e8449")


def _off(value, v: float, tol: float) -> bool:
    """Whether a control's ``value`` (what the page last sent: any JSON) is not the number
    ``v`` to ``tol`` (then the page is sent ``v``)."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    return not ok or abs(value - v) > tol


def _fmt(v, digits: int = 3) -> str:
    if isinstance(v, str):
        return v
    if v is None or not math.isfinite(v):
        return "–"
    return f"{v:.{digits}g}"


# ------------------------------------------------------------------ single joint ---
def _joint_view(state: JointExplorer, linear_holder: dict):
    """The single joint's controls, chart and tables; returns its draw function and the
    linear view's (drawn into ``linear_holder``'s elements, on a thread, when its tab shows)."""
    ui, run = _nicegui()
    lock = asyncio.Lock()

    with ui.row().classes("w-full items-start gap-6"):
        with ui.column().classes("w-full sm:w-80 gap-1"):
            ui.label("Joint and load").classes("text-lg font-medium")
            selects = {}
            for name, label, options in (
                ("parameter_set", "parameter set", parameter_set_names()),
                ("valve_model", "valve model", list(VALVE_MODELS)),
                ("torque_arm", "torque arm", list(TORQUE_ARMS)),
                ("method", "integrator", list(METHODS)),
            ):
                value = state.option(name)
                selects[name] = ui.select(options, value=value, label=label).classes("w-full")
                selects[name].mark(f"select-{name}")
            sliders = {}
            for s in SLIDERS:
                lab = ui.label().classes("text-sm mt-2")
                sl = ui.slider(
                    min=s.low, max=s.high, step=s.step, value=state.display_value(s.field)
                )
                sl.props(f'data-testid="slider-{s.field}"').mark(f"slider-{s.field}")
                sliders[s.field] = (sl, lab)
            with ui.row():
                raise_btn = ui.button("raise test")
                lower_btn = ui.button("lower test").props("outline")
            status = ui.label().classes("text-red-700 text-sm")
        with ui.column().classes("grow min-w-[300px] max-w-full"):
            plot = ui.echart(state.chart(), renderer="svg").classes("w-full")
            plot.style(f"height: {CHART_HEIGHT}px").props('data-testid="joint-plot"')
            plot.mark("joint-chart")
        with ui.column().classes("w-full md:w-[30rem] max-w-full gap-2 overflow-x-auto"):
            ui.label("Metrics of this setting").classes("text-lg font-medium")
            metrics = ui.table(
                columns=[
                    {"name": "quantity", "label": "quantity", "field": "quantity", "align": "left"},
                    {"name": "raise", "label": "raise", "field": "raise"},
                    {"name": "lower", "label": "lower", "field": "lower"},
                    {"name": "unit", "label": "unit", "field": "unit", "align": "left"},
                ],
                rows=[],
                row_key="quantity",
            ).props('dense flat bordered data-testid="metrics"')
            metrics.mark("metrics")
            ui.label("Saturation velocity beside the paper [mm/s]").classes(
                "text-lg font-medium mt-2"
            )
            paper = ui.table(
                columns=[
                    {"name": "source", "label": "source", "field": "source", "align": "left"},
                    {"name": "load", "label": "load", "field": "load", "align": "left"},
                    {"name": "raise", "label": "raise", "field": "raise"},
                    {"name": "lower", "label": "lower", "field": "lower"},
                ],
                rows=[],
                row_key="id",
            ).props('dense flat bordered data-testid="paper"')
            ui.label(
                "Load: the arm alone (Appendix I load 1) plus the mass in the hand at 460 mm; "
                "Table I loads 1 and 5 carry 0 and 0.45 kg, Table III's loads 6 and 10 are "
                "Model 2's re-rated loads."
            ).classes("text-xs text-gray-600")

    guard = {"on": False}  # controls set from the state: not a user's change

    def draw() -> None:
        guard["on"] = True
        for s in SLIDERS:
            sl, lab = sliders[s.field]
            v = state.display_value(s.field)
            lab.text = f"{s.label}: {v:.3g} {s.unit}"
            if s.field in ABSOLUTE:  # a factor on the set's value: the value itself too
                name, unit, factor = ABSOLUTE[s.field]
                value = getattr(state.joint, name) * factor
                lab.text += f" = {value:.3g} {unit}"
            if _off(sl.value, v, 0.5 * s.step):
                sl.value = v  # the parameter set's value after a change of set
        for name in ("valve_model", "torque_arm"):
            selects[name].value = state.option(name)
        guard["on"] = False
        run_ = state.run
        status.text = run_.error
        plot.options.clear()
        plot.options.update(state.chart())
        plot.update()
        metrics.rows = [
            {**r, "raise": _fmt(r["raise"]), "lower": _fmt(r["lower"])} for r in state.metric_rows()
        ]
        paper.rows = [
            {**r, "id": i, "raise": _fmt(r["raise"]), "lower": _fmt(r["lower"])}
            for i, r in enumerate(state.paper_rows())
        ]
        shown, other = (
            (raise_btn, lower_btn) if state.direction == "raise" else (lower_btn, raise_btn)
        )
        shown.props(remove="outline")
        other.props("outline")
        linear_holder["stale"] = True
        if linear_holder.get("visible"):
            asyncio.ensure_future(linear_draw())

    pending: dict = {}

    async def change(name: str, value) -> None:
        """Run the tests with the new value on a thread (the numba kernels release the
        GIL); values arriving meanwhile (a slider dragged) are coalesced: the latest of each
        control is run next, the ones in between are skipped."""
        if guard["on"]:
            return
        if name not in selects:
            try:
                value = client_number(name, value)
            except HydroarmError as exc:
                refused(name, exc.problem)
                draw()  # the slider back to the setting
                return
        pending[name] = value
        while True:
            why = await run_latest(pending, lock, run.io_bound, set_shown)
            if why is None:  # the call holding the lock runs it
                return
            draw()  # the shown test's curves first
            if why:
                status.text = why
            if state.complete:
                return
            async with lock:  # then the other test, for the tables
                await run.io_bound(state.run_rest)
            if not pending:  # else the values that came meanwhile run next
                draw()
                return

    def set_shown(name: str, value) -> None:
        state.set(name, value, shown_only=True)

    for name, sel in selects.items():
        sel.on_value_change(lambda e, n=name: change(n, e.value))
    for field, (sl, _) in sliders.items():
        sl.on_value_change(lambda e, f=field: change(f, e.value))

    async def show(direction: str) -> None:
        state.test(direction)
        if not state.complete:
            async with lock:
                await run.io_bound(state.run_rest)
        draw()

    raise_btn.on_click(lambda: show("raise"))
    lower_btn.on_click(lambda: show("lower"))

    # the linear view (its own tab): computed on a thread when the tab shows -----------
    linear_lock = asyncio.Lock()

    def linear_compute() -> tuple[dict, dict]:
        lin = state.linear()
        return lin, state.bode(lin)

    async def linear_draw() -> None:
        if "plot" not in linear_holder or not linear_holder.get("stale", True):
            return
        if linear_lock.locked():  # the running computation draws the latest state next
            return
        async with linear_lock:
            while linear_holder.get("stale", True):
                linear_holder["stale"] = False
                linear_holder["error"].text = "computing the linear view…"
                lin, bode = await run.io_bound(linear_compute)
                linear_show(lin, bode)

    def linear_show(lin: dict, bode: dict) -> None:
        lp, lt, le = linear_holder["plot"], linear_holder["table"], linear_holder["error"]
        le.text = lin["error"]
        lp.options.clear()
        lp.options.update(bode)
        lp.update()
        if lin["error"]:
            lt.rows = []
            return
        m = lin["margins"]
        lt.rows = [
            {"quantity": "gain margin", "value": _fmt(m["gain_margin_db"]), "unit": "dB"},
            {"quantity": "phase margin", "value": _fmt(m["phase_margin_deg"]), "unit": "deg"},
            {
                "quantity": "gain crossover",
                "value": _fmt(m["gain_crossover_rad_s"]),
                "unit": "rad/s",
            },
            {
                "quantity": "phase crossover",
                "value": _fmt(m["phase_crossover_rad_s"]),
                "unit": "rad/s",
            },
            {"quantity": "closed-loop bandwidth", "value": _fmt(lin["bandwidth"]), "unit": "rad/s"},
        ]

    return draw, linear_draw


def _linear_view(state: JointExplorer, holder: dict) -> None:
    ui, run = _nicegui()
    with ui.row().classes("w-full items-start gap-6"):
        holder["plot"] = ui.echart({}, renderer="svg").classes("w-full md:w-[46rem]")
        holder["plot"].style(f"height: {BODE_HEIGHT}px").props('data-testid="bode"')
        with ui.column().classes("w-full sm:w-96"):
            ui.label("Margins at the shown test's target").classes("text-lg font-medium")
            holder["table"] = ui.table(
                columns=[
                    {"name": "quantity", "label": "quantity", "field": "quantity", "align": "left"},
                    {"name": "value", "label": "value", "field": "value"},
                    {"name": "unit", "label": "unit", "field": "unit", "align": "left"},
                ],
                rows=[],
                row_key="quantity",
            ).props('dense flat bordered data-testid="margins"')
            holder["error"] = ui.label().classes("text-red-700 text-sm")
            ui.label(
                "The joint linearised at rest at the test's final angle, the load held "
                "(hydroarm.analysis.linear, docs/linear.md): the loop broken at the valve "
                "opening, and the closed loop from lever to jack."
            ).classes("text-xs text-gray-600")


# ------------------------------------------------------------------ live arm ---
def _live_view(live: LiveArm, out_dir: Path, width: int = SCENE_WIDTH):
    """The live arm's scene (``width`` [px] wide), levers, gauges and task; returns its
    timer's switch (on only while the tab shows: a hidden tab does not step)."""
    ui, run = _nicegui()
    with ui.row().classes("w-full items-start gap-4"):
        with ui.column().classes(f"gap-1 w-[{width}px] max-w-full overflow-hidden"):
            scene = ui.scene(
                width=width,
                height=round(width * SCENE_ASPECT),
                grid=False,
                background_color="#f4f6f8",
                camera=ui.scene.perspective_camera(fov=32, near=0.01, far=20.0),
            )
            scene.props('data-testid="scene"')
            ui.label(
                "Keys (hold, several at once): "
                + ", ".join(
                    f"{k.upper()}/{k2.upper()} {JOINT_LABELS[n]}"
                    for (k, (n, _)), (k2, _) in zip(
                        list(KEYS.items())[::2], list(KEYS.items())[1::2], strict=True
                    )
                )
                + f"; {GRASP_KEY.upper()} or space: grasp / release"
            ).classes("text-sm text-gray-700")
        with ui.column().classes("w-full sm:w-96 gap-1"):
            # the lever box on screen: hold a button (touch, pen or mouse: pointer events)
            # as a key is held; several at once with several fingers
            with ui.grid(columns=4).classes("w-full gap-1").props('data-testid="lever-box"'):
                for k, (n, sign) in KEYS.items():
                    arrow = "▲" if sign > 0 else "▼"
                    b = ui.button(f"{k.upper()} {arrow}").props(
                        f'dense no-caps data-testid="hold-{k}" title="{JOINT_LABELS[n]}"'
                    )
                    b.style("touch-action: none; user-select: none")
                    b.on("pointerdown", lambda _, k=k: hold(k, True))
                    for ev in ("pointerup", "pointercancel", "pointerleave"):
                        b.on(ev, lambda _, k=k: hold(k, False))
            ui.label(
                "columns: shoulder elevation, humeral rotation, elbow reach, wrist rotation"
            ).classes("text-xs text-gray-600")
            with ui.row().classes("items-center"):
                pause_btn = ui.button("pause").props('data-testid="pause"')
                reset_btn = ui.button("reset").props('outline data-testid="reset"')
                speed = ui.toggle({s: f"×{s:g}" for s in SPEEDS}, value=live.speed)
                speed.props('data-testid="speed"')
            clock = ui.label().props('data-testid="clock"').classes("text-sm")
            stopped = ui.label().props('data-testid="stopped"').classes("text-sm text-red-700")
            ui.label("Levers [deg]").classes("text-lg font-medium")
            sliders = {}
            for n in JOINT_NAMES:
                lo, hi = live.ranges[n]
                lab = ui.label().classes("text-sm")
                sl = ui.slider(
                    min=round(math.degrees(lo), 1),
                    max=round(math.degrees(hi), 1),
                    step=1.0,
                    value=math.degrees(live.levers[n]),
                ).props(f'data-testid="lever-{n}"')
                sliders[n] = (sl, lab)
            angles = ui.label().props('data-testid="angles"').classes("text-sm font-mono")
            angles.mark("angles")
            ui.label("Power pack").classes("text-lg font-medium")
            gauges = {}
            for key in (
                "supply_pressure",
                "pump_flow",
                *JOINT_NAMES,
            ):
                lab = ui.label().classes("text-xs")
                bar = ui.linear_progress(value=0.0, show_value=False, size="10px")
                with ui.row().classes("w-full justify-between text-[10px] text-gray-500 -mt-1"):
                    scale = [ui.label() for _ in range(3)]  # the scale: low, middle, high
                gauges[key] = (bar, lab, scale)
            ui.label("Block stacking").classes("text-lg font-medium")
            score = ui.label().props('data-testid="score"').classes("text-sm").mark("score")
            with ui.row():
                grasp_btn = ui.button("grasp / release").props('data-testid="grasp"').mark("grasp")
                save_btn = ui.button("save attempt").props('outline data-testid="save"')
            saved = ui.label().props('data-testid="saved"').classes("text-xs break-all")
            events = ui.label().classes("text-xs text-gray-600")

    # the scene: a table with its pad and blocks, a torso, the arm ----------------
    with scene:
        (x0, x1), (y0, y1) = TABLE_X, TABLE_Y  # the floor's extent (blocks.py)
        ui.scene.box(x1 - x0, y1 - y0, 0.02).move(
            (x0 + x1) / 2, (y0 + y1) / 2, TABLE_TOP - 0.01
        ).material("#b08d57")
        ui.scene.cylinder(PAD_RADIUS, PAD_RADIUS, 0.002, 24).move(
            PAD[0], PAD[1], TABLE_TOP + 0.001
        ).rotate(math.pi / 2, 0, 0).material("#27ae60")
        # the torso: on the arm's left (+y), a right arm
        ui.scene.box(0.14, 0.30, 0.6).move(-0.06, 0.19, -0.22).material("#d5d8dc", opacity=0.5)
        ui.scene.sphere(0.035).move(0, 0, 0).material("#566573")
        upper = ui.scene.cylinder(0.028, 0.025, 1.0, 16).material("#5d6d7e")
        fore = ui.scene.cylinder(0.024, 0.02, 1.0, 16).material("#85929e")
        elbow = ui.scene.sphere(0.028).material("#566573")
        wrist = ui.scene.sphere(0.021).material("#566573")
        hand = ui.scene.box(0.05, 0.05, 0.015).material("#e59866")
        blocks = [
            ui.scene.box(BLOCK_SIZE, BLOCK_SIZE, BLOCK_SIZE).material(
                BLOCK_COLOURS[i % len(BLOCK_COLOURS)]
            )
            for i in range(len(live.task.blocks))
        ]
    scene.move_camera(
        x=0.5, y=-1.1, z=0.2, look_at_x=0.12, look_at_y=0.08, look_at_z=-0.3, duration=0.0
    )

    guard = {"on": False, "last": time.perf_counter()}

    changed = Shown(4).changed  # rounded to 0.1 mm / 0.0001: only changes go to the browser

    def draw() -> None:
        P = live.points()
        for name, obj, a, b in (("upper", upper, P[0], P[1]), ("fore", fore, P[1], P[2])):
            if changed(name, (*a, *b)):
                place_link(obj, a, b)
        if changed("elbow", P[1]):
            elbow.move(*P[1].tolist())
        if changed("wrist", P[2]):
            wrist.move(*P[2].tolist())
        ang = live.angles()
        if changed("hand", (*P[2], *P[3], ang["wrist_rotation"])):
            hand.move(*P[3].tolist()).rotate_R(link_frame(P[3] - P[2], roll=ang["wrist_rotation"]))
        held = live.task.held
        for i, (box, b) in enumerate(zip(blocks, live.task.blocks, strict=True)):
            if changed(("block", i), b.centre):
                box.move(*b.centre.tolist())
            if changed(("held", i), (i == held,)):
                colour = BLOCK_COLOURS[i % len(BLOCK_COLOURS)]
                box.material(colour, opacity=0.7 if i == held else 1.0)
        guard["on"] = True
        for n, (sl, lab) in sliders.items():
            v = math.degrees(live.levers[n])
            if _off(sl.value, v, 0.5):
                sl.value = round(v, 1)
            lab.text = f"{JOINT_LABELS[n]}: lever {v:.1f}°, arm {math.degrees(ang[n]):.1f}°"
        guard["on"] = False
        angles.text = "angles [deg]: " + ", ".join(
            f"{n}={math.degrees(ang[n]):.2f}" for n in JOINT_NAMES
        )
        g = live.gauges()
        relief = g["relief_pressure"]
        ps_max = 1.5 * relief
        for key, (bar, lab, scale) in gauges.items():
            if key == "supply_pressure":  # 0 to 1.5 × relief: the relief is marked
                v = g[key]
                lab.text = f"supply pressure {v * 1e-5:.1f} bar (relief {relief * 1e-5:.0f} bar)"
                bar.value = max(min(v / ps_max, 1.0), 0.0)
                ticks = ("0 bar", f"{0.75 * relief * 1e-5:.0f}", f"{ps_max * 1e-5:.0f} bar")
            elif key == "pump_flow":
                v, cap = g["valve_flow"], g["pump_capacity"]
                top = cap if math.isfinite(cap) else 1e-5
                lab.text = f"valves draw {v * 6e4:.3f} l/min" + (
                    f" of the pump's {cap * 6e4:.2f} l/min" if math.isfinite(cap) else ""
                )
                bar.value = max(min(v / top, 1.0), 0.0)
                ticks = ("0 l/min", f"{top * 3e4:.2g}", f"{top * 6e4:.2g} l/min")
            else:
                v = g["pressures"][key]
                lab.text = f"{JOINT_LABELS[key]} load pressure {v * 1e-5:+.1f} bar"
                bar.value = max(min(0.5 + 0.5 * v / ps_max, 1.0), 0.0)
                ticks = (f"−{ps_max * 1e-5:.0f} bar", "0", f"+{ps_max * 1e-5:.0f} bar")
            for lbl, text in zip(scale, ticks, strict=True):
                if lbl.text != text:
                    lbl.text = text
        s = live.score()
        err = s["placement_error"]
        score.text = (
            f"stacked {s['stacked']} of {s['blocks']}; placement error "
            f"{'–' if not math.isfinite(err) else f'{err * 1e3:.1f} mm'}; time {s['time']:.1f} s"
            + (" — done" if s["done"] else "")
        )
        state = live.state  # the button, the clock and the message from one state
        pause_btn.text = {"running": "pause", "paused": "resume", "stopped": "reset"}[state]
        clock.text = f"t = {live.t:.2f} s (×{live.speed:g})" + (
            "" if state == "running" else f" {state}"
        )
        stopped.text = live.stopped
        events.text = " · ".join(live.task.events[-4:])

    def tick() -> None:
        now = time.perf_counter()
        dt, guard["last"] = now - guard["last"], now
        try:
            live.tick(dt)
        except HydroarmError:
            pass  # the live arm is stopped: draw() shows it (button, clock, message)
        draw()

    def on_key(e) -> None:
        if e.action.repeat:
            return
        try:
            what = live.key(e.key.name, bool(e.action.keydown))
        except HydroarmError as exc:
            refused(exc.field, exc.problem)
            return
        if what:
            draw()

    def toggle_pause() -> None:
        if live.state == "stopped":
            reset()
            return
        live.toggle_pause()
        guard["last"] = time.perf_counter()
        draw()

    def reset() -> None:
        live.reset()
        guard["last"] = time.perf_counter()
        saved.text = ""
        draw()

    def save() -> None:
        out_dir.mkdir(parents=True, exist_ok=True)
        stamp = time.strftime("%Y%m%d-%H%M%S")
        path = out_dir / f"attempt-{stamp}.csv"
        k = 1
        while path.exists():
            k += 1
            path = out_dir / f"attempt-{stamp}-{k}.csv"
        atomic_write_text(path, live.recording_csv())
        saved.text = f"saved {path}"

    def hold(k: str, down: bool) -> None:
        """An on-screen lever button pressed or released (as its key)."""
        live.key(k, down)

    def lever_changed(n: str, value) -> None:
        if guard["on"]:
            return
        try:
            live.set_lever(n, math.radians(client_number(f"lever.{n}", value)))
        except HydroarmError as exc:  # one line; the slider is put back by the next draw
            refused(exc.field, exc.problem)
            draw()

    def speed_changed(value) -> None:
        try:
            live.set_speed(client_number("speed", value))
        except HydroarmError as exc:
            refused(exc.field, exc.problem)
            speed.value = live.speed

    speed.on_value_change(lambda e: speed_changed(e.value))

    for n, (sl, _) in sliders.items():
        sl.on_value_change(lambda e, n=n: lever_changed(n, e.value))
    pause_btn.on_click(toggle_pause)
    reset_btn.on_click(reset)

    def grasp() -> None:
        live.grasp()
        draw()

    grasp_btn.on_click(grasp)
    save_btn.on_click(save)
    ui.keyboard(on_key=on_key, ignore=["input", "textarea", "select"])
    draw()
    timer = ui.timer(TICK_S, tick, active=False)

    def showing(on: bool) -> None:
        """The tab shown or hidden: only a shown arm steps (the clock resumes from now)."""
        guard["last"] = time.perf_counter()
        if not on:
            live.release_keys()
        timer.active = on

    return showing


async def page(
    scenario: ArmScenario, out_dir: Path, stepper_factory=None, start: JointRun | None = None
) -> None:
    """The page's content, with its own state: a single joint started from ``start`` (its
    first run, made once and shared read-only by every visitor: a visit runs nothing) and a
    live arm, built on a thread with its tab's content when that tab is first opened (a visit
    sends only the single joint's view)."""
    ui, run = _nicegui()
    ui.query("body").style("background: #fbfcfc")
    joint = JointExplorer(start=start)
    with ui.header().classes("items-center bg-slate-700 py-2 flex-wrap"):
        ui.label("hydroarm explore").classes("text-xl font-medium")
        ui.label(f"— {scenario.name}").classes("text-sm opacity-80")
    with ui.tabs().classes("w-full").props("mobile-arrows outside-arrows") as tabs:
        t_joint = ui.tab("Single joint").props('data-testid="tab-joint"')
        t_linear = ui.tab("Linear view").props('data-testid="tab-linear"')
        t_live = ui.tab("Live arm and blocks").props('data-testid="tab-live"')
    panels = ui.tab_panels(tabs, value=t_joint).classes("w-full")
    with panels:
        linear: dict = {}
        with ui.tab_panel(t_joint):
            draw_joint, draw_linear = _joint_view(joint, linear)
        with ui.tab_panel(t_linear):
            _linear_view(joint, linear)
        with ui.tab_panel(t_live):
            live_box = ui.column().classes("w-full")
    draw_joint()
    live: dict = {}  # the live view's show/hide function, once built

    async def open_live() -> None:
        if live:
            return
        live["building"] = True
        with live_box:
            warming = ui.label("warming up…").props('data-testid="warming"')
        arm = await run.io_bound(LiveArm, scenario, stepper_factory)
        width = SCENE_WIDTH
        try:  # the browser's width: the scene fits a phone's screen
            shown = await ui.run_javascript("window.innerWidth", timeout=5.0)
            width = int(min(SCENE_WIDTH, max(SCENE_MIN, client_number("width", shown) - 48)))
        except Exception:  # no answer, or not a number: the desktop's width (the scene clips)
            pass
        warming.delete()
        with live_box:
            live["showing"] = _live_view(arm, out_dir, width)

    hidden = {"page": False}  # the browser's tab hidden (another tab, a minimised window)

    def live_on() -> bool:
        now = tabs.value  # the tab shown now (another may have been chosen meanwhile)
        return (now == "Live arm and blocks" or now is t_live) and not hidden["page"]

    async def tab_changed(e) -> None:
        shown = e.value
        on_live = shown == "Live arm and blocks" or shown is t_live
        if on_live:
            await open_live()
        if "showing" in live:
            live["showing"](live_on())
        linear["visible"] = shown == "Linear view" or shown is t_linear
        if linear["visible"]:
            await draw_linear()

    tabs.on_value_change(tab_changed)

    def visibility(e) -> None:
        """The browser's tab hidden or shown again: a hidden page's arm does not step."""
        if not isinstance(e.args, bool):
            refused("visibility", f"must be true or false, got {e.args!r}")
            return
        hidden["page"] = e.args
        if "showing" in live:
            live["showing"](live_on())

    ui.on("hydroarm_hidden", visibility)
    ui.add_body_html(
        "<script>document.addEventListener('visibilitychange', "
        "() => emitEvent('hydroarm_hidden', document.hidden));</script>"
    )


def build(scenario: ArmScenario, out_dir: Path, stepper_factory=None) -> None:
    """Register the page ``/`` (each visit gets its own state; the single joint's first run
    is made once here and shared)."""
    ui, run = _nicegui()
    start = JointExplorer().run

    async def visit() -> None:
        await page(scenario, out_dir, stepper_factory, start)

    ui.page("/", title="hydroarm explore")(visit)


def serve(
    scenario: ArmScenario,
    *,
    port: int,
    show: bool,
    out_dir: Path,
    stepper_factory=None,
    host: str = "127.0.0.1",
    token: str | None = None,
) -> None:
    """Build the page and serve it on ``host``:``port`` until interrupted."""
    ui, _ = _nicegui()
    build(scenario, out_dir, stepper_factory)
    serve_page(ui, port=port, show=show, host=host, token=token)
