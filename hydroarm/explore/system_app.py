"""The system page of ``hydroarm explore --config FILE`` for any system file (NiceGUI,
imported when the page is built; docs/explore.md "Any system file").

Sliders for the chosen parameters, each with a number field (absolute values in their
units; a typed value runs on Enter or when the field is left), the outputs to plot,
the curves drawn in the browser by ECharts (``ui.echart``: the page sends data, not
pictures), a table of each plotted output's value at the end, least and greatest (the
unit is the name's ending: ``_bar``, ``_deg``, ``_lpm``) and, for a mechanism, its stick
figure and a live view of it in 3-D (``ui.scene``). A slider's change runs the system on a thread
(`update`: the event loop keeps serving);
changes arriving meanwhile are coalesced (the latest of each slider runs next). The state
each visitor starts from (`SystemModel`: the file's own run)
is built once before the server starts and shared read-only, so a visit costs no run.
"""

from __future__ import annotations

import asyncio
import math
import time

from ..errors import HydroarmError
from .live_system import LiveSystem
from .pages import client_number, refused, run_latest, serve_page
from .scene import Shown, link_frame, place_link
from .system import SystemExplorer, SystemModel

LIVE_TICK_S = 0.1  # the live mechanism's timer [s]: 10 frames per second
SCENE_WIDTH, SCENE_MIN = 480, 280  # the live mechanism's 3-D scene's width [px]: at most, least
SCENE_MARGIN = 64  # the page's and the panel's padding round the scene [px]
SCENE_ASPECT = 0.75  # its height per width


def _nicegui():
    """NiceGUI's ``ui`` and ``run`` (imported on first use: an optional dependency)."""
    from nicegui import run, ui

    return ui, run


def _chart(state: SystemExplorer, box):
    """The outputs' chart (ECharts, drawn as SVG: its legend and axes are text the page's
    tests can read) in ``box``."""
    ui, run = _nicegui()
    with box:
        chart = ui.echart(state.chart(), renderer="svg").classes("w-full")
    chart.style(f"height: {state.chart_height()}px").props('data-testid="chart"')
    return chart.mark("chart")


def _off(value, v: float, tol: float) -> bool:
    """Whether a control's ``value`` (what the page last sent: any JSON) is not the number
    ``v`` to ``tol``."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    return not ok or abs(value - v) > tol


def _force(v: float, torque: bool) -> str:
    """A force [N] or torque [N·m] in N or kN (from 1 kN up), four figures."""
    unit = "N·m" if torque else "N"
    return f"{v * 1e-3:.4g} k{unit}" if abs(v) >= 1e3 else f"{v:.4g} {unit}"


def page(model: SystemModel) -> None:
    """The page's content, with the visitor's own `SystemExplorer` (no run: the
    file's own, shared, is shown first)."""
    ui, run = _nicegui()
    state = SystemExplorer(model)
    lock = asyncio.Lock()
    ui.query("body").style("background: #fbfcfc")
    with ui.header().classes("items-center bg-slate-700 py-2 flex-wrap"):
        ui.label("hydroarm explore").classes("text-xl font-medium")
        ui.label(f"— {model.name}").classes("text-sm opacity-80")
    with ui.row().classes("w-full items-start gap-6 flex-wrap"):
        with ui.column().classes("w-full sm:w-80 gap-1"):
            ui.label(model.describe()).classes("text-xs text-gray-600 break-words")
            ui.label("Parameters").classes("text-lg font-medium")
            if model.defaults["parameters"]:
                ui.label(
                    "the file's own values ÷ 4 to × 4 (an [explore] section chooses others)"
                ).classes("text-xs text-gray-600")
            sliders = {}
            for s in model.sliders:
                with ui.row().classes("w-full items-center no-wrap gap-2 mt-2"):
                    ui.label(s.heading).classes("text-sm grow break-all")
                    num = ui.number(value=s.shown(s.value), format="%.4g")
                    num.props(f'dense outlined data-testid="number-{s.name}"').classes("w-28")
                    num.mark(f"number-{s.name}")
                sl = ui.slider(
                    min=s.shown(s.low), max=s.shown(s.high), step=s.shown(s.step),
                    value=s.shown(s.value),
                )  # fmt: skip
                sl.props(f'data-testid="slider-{s.name}"').mark(f"slider-{s.name}")
                sliders[s.name] = (sl, num)
            reset_btn = ui.button("the file's values").props('outline data-testid="reset"')
            status = ui.label().props('data-testid="status"').classes("text-sm text-gray-700")
            error = ui.label().props('data-testid="error"').classes("text-sm text-red-700")
            error.mark("error")
            ui.label("Outputs").classes("text-lg font-medium mt-2")
            choose = (
                ui.select(model.outputs, value=list(state.shown), multiple=True, label="plotted")
                .classes("w-full")
                .props('use-chips data-testid="outputs"')
            )
            choose.mark("outputs")
        with ui.column().classes("grow min-w-[300px] max-w-full gap-2"):
            chart_box = ui.element("div").classes("w-full")
            charts = [_chart(state, chart_box)]
            summary = (
                ui.table(
                    columns=[
                        {"name": "output", "label": "output", "field": "output", "align": "left"},
                        {"name": "final", "label": "end", "field": "final"},
                        {"name": "min", "label": "min", "field": "min"},
                        {"name": "max", "label": "max", "field": "max"},
                    ],
                    rows=state.summary_rows(),
                    row_key="output",
                )
                .props('dense flat bordered data-testid="summary"')
                .classes("max-w-full")
            )
            summary.mark("summary")
            pose_options = state.pose()
            pose = None
            if pose_options is not None:
                pose = ui.echart(pose_options, renderer="svg").classes("w-full max-w-[480px]")
                pose.style("height: 360px").props('data-testid="pose"')
            if model.mechanism is not None:
                live_panel = ui.expansion("Live: drive the mechanism from its levers")
                live_panel.classes("w-full max-w-[520px] border").props('data-testid="live"')
                with live_panel:
                    live_box = ui.column().classes("w-full gap-1")
                live_parts: dict = {}  # the live view's timer and clock, once built
                live_panel.on_value_change(
                    lambda e: _live(model, live_box, bool(e.value), live_parts)
                )

    guard = {"on": False}

    def draw(relayout: bool = False) -> None:
        guard["on"] = True
        for s in model.sliders:
            sl, num = sliders[s.name]
            v = s.shown(state.values[s.name])
            num.value = float(f"{v:.6g}")
            if _off(sl.value, v, 0.5 * s.shown(s.step)):
                sl.value = v
        guard["on"] = False
        error.text = state.error
        if relayout:  # other outputs: a new chart (ECharts merges options into the old one)
            charts[0].delete()
            charts[0] = _chart(state, chart_box)
        else:
            chart = charts[0]
            chart.options.clear()
            chart.options.update(state.chart())
            chart.update()
        summary.rows = state.summary_rows()
        if pose is not None:
            pose.options.clear()
            pose.options.update(state.pose() or {})
            pose.update()

    pending: dict = {}

    async def change(name: str, value) -> None:
        """Run with the new value on a thread; values arriving meanwhile are coalesced."""
        if guard["on"] or value is None:
            return
        try:
            value = client_number(name, value)
        except HydroarmError as exc:  # one line; the controls back to the setting
            refused(name, exc.problem)
            draw()
            return
        now = model.slider(name).shown(state.values[name])
        if name not in pending and abs(value - now) <= 1e-6 * max(abs(now), 1e-300):
            return  # the value shown (a field left unchanged, Enter then leaving it)
        pending[name] = value

        def running() -> None:
            status.text = "running…"

        why = await run_latest(pending, lock, run.io_bound, state.update, running)
        if why is None:
            return
        done = "failed" if state.error else "done"
        status.text = f"run {state.runs} {done} in {state.run_s:.2f} s"
        draw()
        if why:
            error.text = why

    def outputs_changed(e) -> None:
        try:
            if not isinstance(e.value, (list, type(None))):
                raise HydroarmError("outputs", f"must be a list of names, got {e.value!r}")
            state.choose(list(e.value or []))
        except HydroarmError as exc:
            error.text = str(exc)
            return
        draw(relayout=True)

    async def reset() -> None:
        async with lock:
            state.values = {s.name: s.value for s in model.sliders}
            state.columns, state.error = model.columns, ""
            draw()

    for name, (sl, num) in sliders.items():
        sl.on_value_change(lambda e, n=name: change(n, e.value))
        # a typed value runs when it is entered (Enter or leaving the field), not per key
        for event in ("keydown.enter", "blur"):
            num.on(event, lambda _, n=name, f=num: change(n, f.value))
    choose.on_value_change(outputs_changed)
    reset_btn.on_click(reset)


async def _live(model: SystemModel, box, shown: bool, parts: dict) -> None:
    """The live mechanism in ``box``: built (on a thread) when first opened; its timer runs
    only while it is open (``parts``: its timer and clock, kept between calls)."""
    ui, run = _nicegui()
    if "timer" in parts:
        parts["timer"].active = shown
        parts["last"][0] = time.perf_counter()
        return
    if not shown or parts.get("building"):
        return
    parts["building"] = True
    with box:
        warming = ui.label("warming up…")
    live = await run.io_bound(LiveSystem, model)
    width = SCENE_WIDTH
    try:  # the browser's width: the scene fits a phone's screen
        inner = await ui.run_javascript("window.innerWidth", timeout=5.0)
        width = int(min(SCENE_WIDTH, max(SCENE_MIN, client_number("width", inner) - SCENE_MARGIN)))
    except Exception:  # no answer, or not a number: the desktop's width (the scene clips)
        pass
    warming.delete()
    last = [time.perf_counter()]
    with box:
        scene, draw_scene = _scene(live, width)
        with ui.row().classes("items-center"):
            pause_btn = ui.button("pause").props('data-testid="live-pause"')
            reset_btn = ui.button("reset").props('outline data-testid="live-reset"')
        clock = ui.label().props('data-testid="live-clock"').classes("text-sm")
        stopped = ui.label().classes("text-sm text-red-700")
        sliders = {}
        for lv in live.levers:  # a setpoint: the joint's position in deg or mm (module doc)
            lab = ui.label().classes("text-sm")
            lo, hi = sorted((lv.shown(lv.low), lv.shown(lv.high)))
            sl = ui.slider(min=lo, max=hi, step=(hi - lo) / 200, value=lv.shown(lv.start))
            sl.props(f'data-testid="live-lever-{lv.name}"')
            sliders[lv.name] = (sl, lab)
        joints = ui.label().props('data-testid="live-joints"').classes("text-sm font-mono")
        gauges = {}
        if live.supplies:
            ui.label("Supplies").classes("text-base font-medium mt-1")
        for sup in live.supplies:
            lab = ui.label().props(f'data-testid="live-gauge-{sup.node}"').classes("text-xs")
            bar = ui.linear_progress(value=0.0, show_value=False, size="10px")
            bar.props(f'data-testid="live-gauge-bar-{sup.node}"')
            with ui.row().classes("w-full justify-between text-[10px] text-gray-500 -mt-1"):
                scale = ui.row().classes("w-full justify-between no-wrap")
                scale.props(f'data-testid="live-gauge-scale-{sup.node}"')
                with scale:  # the scale: 0, the middle, 1.5 × the setting [bar]
                    for v in (0.0, sup.top / 2, sup.top):
                        ui.label(f"{v * 1e-5:.0f}" + (" bar" if v in (0.0, sup.top) else ""))
            gauges[sup.node] = (bar, lab)
        holding = ui.label().props('data-testid="live-holding"')
        holding.classes("text-xs font-mono text-gray-700 break-words")
        pressures = ui.label().props('data-testid="live-pressures"')
        pressures.classes("text-xs font-mono text-gray-700 break-words")
        task_label = grasp_btn = None
        if live.task is not None:
            ui.label("Block task").classes("text-base font-medium mt-1")
            task_label = ui.label().props('data-testid="live-task"').classes("text-sm")
            grasp_btn = ui.button("grasp / release").props('data-testid="live-grasp"')

    guard = {"on": False}

    def draw() -> None:
        state = live.state
        pause_btn.text = {"running": "pause", "paused": "resume", "stopped": "reset"}[state]
        clock.text = f"t = {live.t:.2f} s" + ("" if state == "running" else f" {state}")
        stopped.text = live.stopped
        guard["on"] = True
        for lv in live.levers:
            sl, lab = sliders[lv.name]
            v = lv.shown(live.value(lv.name))
            if lv.joint:
                head = f"{lv.joint} setpoint ({lv.name}): {v:.4g} {lv.unit}"
            else:
                head = f"{lv.name} (drives {lv.signal}): {v:.4g} [SI]"
            lab.text = head + ("" if lv.name in live.values else " (the file's waveform)")
            span = abs(lv.shown(lv.high) - lv.shown(lv.low))
            if lv.name in live.values and _off(sl.value, v, 0.5 * span / 200):
                sl.value = v
        guard["on"] = False
        joints.text = ", ".join(f"{n} {v}" for n, v in live.joints().items())
        bars = live.pressures()
        for sup in live.supplies:
            bar, lab = gauges[sup.node]
            v = bars.get(sup.node, math.nan)
            lab.text = (
                f"{sup.node} ({', '.join(sup.sources)}): {v:.1f} bar "
                f"({sup.what} {sup.setting * 1e-5:.0f} bar)"
            )
            bar.value = max(min(v * 1e5 / sup.top, 1.0), 0.0) if math.isfinite(v) else 0.0
        kinds = dict(zip(live.joint_names, live.mechanism.joint_types, strict=True))
        holding.text = "holding against gravity: " + ", ".join(
            f"{n} {_force(v, kinds[n] != 'prismatic')}" for n, v in live.holding().items()
        )
        pressures.text = "pressures [bar]: " + ", ".join(f"{n} {v:.1f}" for n, v in bars.items())
        if task_label is not None and live.task is not None:
            above = live.task.height(live.tip()) - live.task.table
            task_label.text = (
                f"{task_said[0] or live.task.describe()}; the tip {above:.3f} m above the table"
            )
        draw_scene()

    def tick() -> None:
        now = time.perf_counter()
        dt, last[0] = now - last[0], now
        try:
            live.tick(dt)
        except HydroarmError:
            pass  # stopped: draw() shows it
        draw()

    def lever_changed(name: str, value) -> None:
        if guard["on"]:
            return
        try:
            lv = live.lever(name)
            live.set_lever(name, lv.signal_of(client_number(f"lever.{name}", value)))
        except HydroarmError as exc:
            refused(exc.field, exc.problem)
        draw()

    def pause() -> None:
        if live.state == "stopped":
            reset()
            return
        live.toggle_pause()
        last[0] = time.perf_counter()
        draw()

    def reset() -> None:
        live.reset()
        task_said[0] = ""
        last[0] = time.perf_counter()
        draw()

    task_said = [""]  # what the last grasp said, until the next tick moves the load

    def grasp() -> None:
        try:
            said = live.grasp()
        except HydroarmError as exc:
            said = str(exc)
        task_said[0] = "" if live.task is None or said == live.task.describe() else said
        draw()

    for name, (sl, _) in sliders.items():
        sl.on_value_change(lambda e, n=name: lever_changed(n, e.value))
    pause_btn.on_click(pause)
    reset_btn.on_click(reset)
    if grasp_btn is not None:
        grasp_btn.on_click(grasp)
    draw()
    with box:
        timer = ui.timer(LIVE_TICK_S, tick)
    parts.update(timer=timer, last=last)


def _scene(live: LiveSystem, width: int):
    """The live mechanism in 3-D (``ui.scene``, ``width`` [px] wide): a cylinder per link
    between its stick points, a sphere per joint, a ground grid, the camera fitted to the
    view's extent with gravity down on screen; returns the scene and its draw function, which
    moves the objects whose points changed (the scene is built once)."""
    ui, _ = _nicegui()
    view = live.view
    r = view["link"]
    scene = ui.scene(
        width=width,
        height=round(width * SCENE_ASPECT),
        grid=False,
        background_color="#f4f6f8",
        camera=ui.scene.perspective_camera(
            fov=view["fov"], near=0.01 * view["radius"], far=20.0 * view["radius"]
        ),  # fmt: skip
    )
    scene.props('data-testid="live-scene"')
    links = [(k, j) for k, j in enumerate(live.parents) if j >= 0]
    n_joints = len(live.joint_names)
    with scene:
        for a, b in view["ground"]:
            ui.scene.line(a, b).material("#c3c9cf")
        cylinders = {
            k: ui.scene.cylinder(r, r, 1.0, 16).material("#5d6d7e" if k <= n_joints else "#85929e")
            for k, _ in links
        }
        task = live.task
        load = None
        if task is not None:  # the table (a floor), the target pad and the load
            u = view["up"]
            flat = link_frame(u, u)
            floor = task.table * u + view["centre"] - (view["centre"] @ u) * u
            w = 2.4 * view["radius"]
            ui.scene.box(w, 0.004 * w, w).move(*(floor - 0.002 * w * u).tolist()).rotate_R(
                flat
            ).material("#d6c7a1", opacity=0.6)
            pad = task.target - 0.05 * task.size * u
            ui.scene.box(1.6 * task.size, 0.1 * task.size, 1.6 * task.size).move(
                *pad.tolist()
            ).rotate_R(flat).material("#58d68d", opacity=0.8)
            rise = task.height(task.target) - task.table - 0.1 * task.size
            if rise > 0:  # what holds the target up (a truck's bed, a shelf): to the table
                stand = task.target - (0.1 * task.size + rise / 2) * u
                ui.scene.box(1.4 * task.size, rise, 1.4 * task.size).move(*stand.tolist()).rotate_R(
                    flat
                ).material("#abebc6", opacity=0.35)
            load = ui.scene.box(task.size, task.size, task.size).material("#a04000")
            load.rotate_R(flat)
        # the base and each joint's origin: a sphere; each leaf's tip: a smaller one
        spheres = [
            ui.scene.sphere(1.6 * r if k <= n_joints else 1.1 * r).material(
                "#34495e" if k <= n_joints else "#e59866"
            )
            for k in range(len(live.parents))
        ]
    # the last leaf's tip, named for the page's tests (its mesh's position, read in the page)
    scene.props(f'data-tip="{spheres[-1].id}"')
    c, u = view["camera"], view["up"]
    scene.move_camera(*c.tolist(), *view["centre"].tolist(), *u.tolist(), duration=0.0)
    changed = Shown(5).changed  # only changes go to the browser

    def draw() -> None:
        P = live.points()
        for k, j in links:
            a, b = P[j], P[k]
            if changed(("link", k), (*a, *b)):
                place_link(cylinders[k], a, b, u)
        for k, sphere in enumerate(spheres):
            if changed(("point", k), P[k]):
                sphere.move(*P[k].tolist())
        if load is not None and live.task is not None:
            if changed(("load",), live.task.centre):
                load.move(*live.task.centre.tolist())

    return scene, draw


def build(model: SystemModel) -> None:
    """Register the page ``/`` (each visit gets its own state)."""
    ui, run = _nicegui()
    ui.page("/", title="hydroarm explore")(lambda: page(model))


def serve(
    model: SystemModel,
    *,
    port: int,
    show: bool,
    host: str = "127.0.0.1",
    token: str | None = None,
) -> None:
    """Build the page and serve it on ``host``:``port`` until interrupted."""
    ui, _ = _nicegui()
    build(model)
    serve_page(ui, port=port, show=show, host=host, token=token)
