"""``hydroarm explore --config`` on system files (issue 29) in a real headless browser
(Chromium from the system's packages, driven by Playwright), as tests/test_explore_browser.py
does for the arm: each server runs as the command in a subprocess on a free 127.0.0.1 port,
and the test waits for its own readiness (the URL line it prints when its file has been read
and run, then the page answering; no time budget: tests/explore_server.py).

Checked, at desktop (1280 px) and phone (390 px) width, on a circuit file
(examples/circuit_position_servo.toml with an ``[explore]`` section) and a mechanism file
(tests/data/mechanism/boom.toml, as it is: the page's defaults): the curves are drawn in the
browser (ECharts, as SVG; no picture comes from the server), no request leaves 127.0.0.1,
a click on a slider changes its number field's value and the curves (the chart's pixels and
the table of final values), a lower supply lowers the boom. On the circuit at desktop width:
a value the run cannot take shows the run's one-line message and keeps the curves, the page
stays usable (the slider back, the curves again); a value typed into a number field runs
on Enter, one outside the slider's range is refused with its message; an output removed
from the plotted ones leaves the chart and the table. Screenshots go to
``tests/artifacts/explore_system/`` (ignored by git; the path is printed with ``-s``).
"""

from __future__ import annotations

import math
import os
import re
import shutil
import time
from pathlib import Path
from urllib.parse import urlparse

import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
IN_CI = os.environ.get("CI", "").lower() == "true"
ROOT = Path(__file__).parents[1]
ARTIFACTS = Path(__file__).parent / "artifacts" / "explore_system"
# a slider's click to the new curves: the run (0.3-0.7 s for the servo's 3 s on the
# shared 2-core machine) and the page's round trip; 30 s leaves room for a loaded CI machine
UPDATE_TIMEOUT_MS = 30000
WIDTHS = {"desktop": 1280, "phone": 390}

if CHROMIUM is None and not IN_CI:
    pytest.skip(
        "no Chromium binary (apt-get install chromium); CI=true makes this fail",
        allow_module_level=True,
    )

from explore_server import ExploreServer, excavator_copy, press  # noqa: E402  (tests/explore_server.py)
from playwright.sync_api import expect, sync_playwright  # noqa: E402


def Server(config: Path) -> ExploreServer:
    """``hydroarm explore --config FILE`` in a subprocess; its ``wait()`` follows the server's
    own readiness (tests/explore_server.py)."""
    return ExploreServer("--config", str(config))


# the example circuit with an [explore] section: its sliders' ranges, a natural frequency of
# the valve that the run cannot take at the file's step (1e6 rad/s at 10 µs RK4: the run
# leaves finite numbers), the outputs plotted first
EXPLORE = """
[explore]
outputs = ["load_position_m", "A_pressure_bar", "B_pressure_bar", "valve_spool_m"]

[explore.parameters]
"payload.mass" = ["20 kg", "400 kg"]
"valve.natural_frequency" = ["100 rad/s", "1e6 rad/s"]
"""


@pytest.fixture(scope="module")
def servers(tmp_path_factory):
    """The servers, started together (their starts overlap): the example circuit with
    :data:`EXPLORE`, the boom mechanism as it is (the page's defaults), the excavator with
    its block task."""
    circuit = tmp_path_factory.mktemp("explore") / "circuit_position_servo.toml"
    circuit.write_text((ROOT / "examples" / "circuit_position_servo.toml").read_text() + EXPLORE)
    files = {
        "circuit": circuit,
        "mechanism": ROOT / "tests" / "data" / "mechanism" / "boom.toml",
        # the excavator with its block task, its page's runs 0.5 s (test_explore_live_system)
        "excavator": excavator_copy(tmp_path_factory.mktemp("excavator")),
    }
    running = {k: Server(f) for k, f in files.items()}
    try:
        for s in running.values():
            s.wait()
        yield running
    finally:
        for s in running.values():
            s.stop()


@pytest.fixture(scope="module")
def browser():
    with sync_playwright() as p:
        b = p.chromium.launch(
            executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"], headless=True
        )
        try:
            yield b
        finally:
            b.close()


def _final(page, output: str) -> float:
    """The value at the end of ``output`` in the page's table."""
    row = page.get_by_test_id("summary").locator("tr", has_text=output).first
    return float(row.locator("td").nth(1).inner_text())


def _field(page, name: str):
    """The number field of a slider (Quasar passes the test id on to its <input>)."""
    return page.get_by_test_id(f"number-{name}")


def _field_value(page, name: str) -> float:
    return float(_field(page, name).input_value())


def _wait_run(page, n: int, done: str = "done") -> None:
    """Wait until the page shows its ``n``-th run ``done`` (or ``failed``: its status)."""
    status = page.get_by_test_id("status")
    expect(status).to_contain_text(f"run {n} {done} in", timeout=UPDATE_TIMEOUT_MS)


def _click_slider(page, name: str, fraction: float) -> None:
    press(page.get_by_test_id(f"slider-{name}"), fraction)


# (file, slider, where to click on its track, output, the sign of the change expected)
CASES = {
    # the payload's mass from 100 kg to about 360 kg (the track 20-400 kg): the heavier load
    # rings with a larger amplitude about the 0.7 m it settles to, so the check is only
    # that the end value moved
    "circuit": ("payload.mass", 0.9, "load_position_m", 0),
    # the supply from 100 bar to about 40 bar (the track 25-400 bar): the boom rises less
    # in the valve's 0.6 s of opening (the angle at the end is lower)
    "mechanism": ("supply.pressure", 0.05, "lift_angle_deg", -1),
}


@pytest.mark.parametrize("view", list(WIDTHS))
@pytest.mark.parametrize("kind", list(CASES))
@pytest.mark.slow
def test_a_system_page_in_a_browser(servers, browser, kind, view):
    server = servers[kind]
    name, fraction, output, sign = CASES[kind]
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    print(f"\nexplore system screenshots: {ARTIFACTS}")
    requests: list[str] = []
    page = browser.new_page(viewport={"width": WIDTHS[view], "height": 900})
    try:

        def route(r):
            requests.append(r.request.url)
            if urlparse(r.request.url).hostname == "127.0.0.1":
                r.continue_()
            else:
                r.abort()

        page.route("**/*", route)
        page.goto(f"http://127.0.0.1:{server.port}/")
        chart = page.get_by_test_id("chart")
        expect(chart.locator("svg").first).to_be_visible(timeout=30000)
        expect(chart.locator("svg text", has_text=output)).to_have_count(1)  # its legend
        expect(page.get_by_test_id("summary")).to_contain_text(output)
        if kind == "mechanism":
            expect(page.get_by_test_id("pose").locator("svg").first).to_be_visible()
        time.sleep(0.5)  # the chart's first paint
        before_png = chart.screenshot()
        value0, final0 = _field_value(page, name), _final(page, output)
        page.screenshot(path=ARTIFACTS / f"{kind}_{view}.png", full_page=True)

        t0 = time.perf_counter()
        _click_slider(page, name, fraction)
        _wait_run(page, 1)
        took = time.perf_counter() - t0
        value1, final1 = _field_value(page, name), _final(page, output)
        assert value1 != value0
        assert final1 != final0, (final0, final1)
        if sign:
            assert (final1 - final0) * sign > 0, (final0, final1)
        expect(page.get_by_test_id("error")).to_have_text("")
        time.sleep(0.5)
        assert chart.screenshot() != before_png
        page.screenshot(path=ARTIFACTS / f"{kind}_{view}_changed.png", full_page=True)
        print(
            f"{kind} at {view} width: {name} {value0:g} -> {value1:g}, {output} "
            f"{final0:g} -> {final1:g}, {took:.2f} s from the click to the table"
        )
    finally:
        page.close()
    outside = [u for u in requests if urlparse(u).hostname not in ("127.0.0.1", None)]
    assert requests and not outside, outside


@pytest.mark.slow
def test_a_failed_run_and_the_outputs_in_a_browser(servers, browser):
    page = browser.new_page(viewport={"width": WIDTHS["desktop"], "height": 900})
    try:
        page.goto(f"http://127.0.0.1:{servers['circuit'].port}/")
        chart = page.get_by_test_id("chart")
        expect(chart.locator("svg").first).to_be_visible(timeout=30000)
        time.sleep(0.5)
        before_png = chart.screenshot()
        end0 = _final(page, "load_position_m")
        # the valve at 1e6 rad/s: the run fails, its message shows, the curves stay
        _click_slider(page, "valve.natural_frequency", 0.999)
        _wait_run(page, 1, "failed")
        error = page.get_by_test_id("error")
        expect(error).to_contain_text("the run failed: system.step: the run left finite numbers")
        expect(error).to_contain_text("the curves are of the last run that worked")
        assert _final(page, "load_position_m") == end0
        page.screenshot(path=ARTIFACTS / "circuit_failed_run.png", full_page=True)
        # back to a value the run takes: the message goes, the curves are drawn again
        _click_slider(page, "valve.natural_frequency", 0.0)
        _wait_run(page, 2)
        expect(error).to_have_text("")
        assert _field_value(page, "valve.natural_frequency") == 100.0
        assert _final(page, "load_position_m") != end0  # a slower valve: another run
        # a value typed into the mass's field runs when entered; one outside the slider's
        # range is refused with its message, no run, the field back to the value set
        end1 = _final(page, "load_position_m")
        _field(page, "payload.mass").fill("250")
        _field(page, "payload.mass").press("Enter")
        _wait_run(page, 3)
        assert _final(page, "load_position_m") != end1
        _field(page, "payload.mass").fill("1000")
        _field(page, "payload.mass").press("Enter")
        expect(error).to_contain_text("payload.mass: 1000 is outside the slider's range 20 to 400")
        expect(page.get_by_test_id("status")).to_contain_text("run 3 done")
        expect(_field(page, "payload.mass")).to_have_value("250")
        # an output removed from the plotted ones leaves the table and the chart
        outputs = page.get_by_test_id("outputs")
        outputs.locator(".q-chip", has_text="valve_spool_m").locator(
            ".q-chip__icon--remove"
        ).click()
        summary = page.get_by_test_id("summary")
        expect(summary).not_to_contain_text("valve_spool_m")
        expect(summary).to_contain_text("B_pressure_bar")
        # the new chart: its legend (SVG text) names the three outputs left, one panel a unit
        chart = page.get_by_test_id("chart")
        expect(chart.locator("svg text", has_text="B_pressure_bar")).to_have_count(1)
        expect(chart.locator("svg text", has_text="valve_spool_m")).to_have_count(0)
        expect(chart.locator("svg text", has_text="t [s]")).to_have_count(1)
        time.sleep(0.5)
        assert chart.screenshot() != before_png
        page.screenshot(path=ARTIFACTS / "circuit_outputs_changed.png", full_page=True)
    finally:
        page.close()


def _lift(page) -> float:
    """The boom's angle [deg] the live view shows ("lift 12.34 deg")."""
    text = page.get_by_test_id("live-joints").inner_text()
    m = re.search(r"lift ([-\d.]+) deg", text)
    assert m, text
    return float(m.group(1))


# the 3-D scene's tip sphere (the scene's ``data-tip`` names it): its position in three.js
TIP_JS = """el => {
  const o = getElement(el).objects.get(el.dataset.tip);
  return o ? [o.mesh.position.x, o.mesh.position.y, o.mesh.position.z] : null;
}"""


def _tip(page, deadline_s: float = 10.0) -> tuple[float, list[float]]:
    """The boom's angle [deg] the page shows and its tip as the browser's scene has it, read
    when the two agree (the page's timer sends them together; the reads may straddle one)."""
    scene = page.get_by_test_id("live-scene")
    deadline = time.monotonic() + deadline_s
    while True:
        angle, tip = _lift(page), scene.evaluate(TIP_JS)
        a = math.radians(angle)
        want = [0.8 * math.cos(a), 0.0, 0.8 * math.sin(a)]
        if tip is not None and max(abs(p - q) for p, q in zip(tip, want, strict=True)) < 0.005:
            return angle, tip
        assert time.monotonic() < deadline, (angle, tip, want)
        time.sleep(0.1)


@pytest.mark.slow
def test_a_mechanism_live_in_a_browser(servers, browser):
    """A mechanism other than the UCL arm shown in 3-D and driven (issue 32): the boom's live
    view opened, its 3-D scene (three.js: a cylinder per link, a sphere per joint and tip, a
    ground grid) fits the screen; its lever slider clicked near its top (the valve opened,
    +0.4 mm) raises the boom as it runs, and the scene's tip with it (its position read in
    the page, its pixels changed); the lever near its bottom lowers it."""
    for view, width in WIDTHS.items():
        page = browser.new_page(viewport={"width": width, "height": 900}, has_touch=view == "phone")
        try:
            page.goto(f"http://127.0.0.1:{servers['mechanism'].port}/")
            live = page.get_by_test_id("live")
            expect(live).to_be_visible(timeout=30000)
            live.get_by_text("Live: drive the mechanism").click()
            expect(page.get_by_test_id("live-clock")).to_contain_text("t = ", timeout=60000)
            scene = page.get_by_test_id("live-scene")
            expect(scene.locator("canvas")).to_be_visible()
            sbox = scene.bounding_box()
            assert sbox is not None and sbox["x"] >= 0 and sbox["x"] + sbox["width"] <= width + 1
            # the supply's gauge: the tank at 100 bar, the scale to 1.5 × it
            expect(page.get_by_test_id("live-gauge-P")).to_contain_text("100.0 bar (tank 100 bar)")
            expect(page.get_by_test_id("live-gauge-scale-P")).to_contain_text("150 bar")
            time.sleep(1.5)  # the file's waveform has run out (it ends at 0.8 s)
            slider = page.get_by_test_id("live-lever-lever.value")
            slider.scroll_into_view_if_needed()
            box = slider.bounding_box()
            assert box is not None and box["x"] + box["width"] <= width + 1
            a0, tip0 = _tip(page)
            scene.scroll_into_view_if_needed()
            before_png = scene.screenshot()
            press(slider, 0.95, touch=view == "phone")
            deadline = time.monotonic() + 60
            while _lift(page) < a0 + 5.0 and time.monotonic() < deadline:
                time.sleep(0.3)
            a1 = _lift(page)
            label = page.get_by_text("lever.value (drives spool)").inner_text()
            assert a1 > a0 + 5.0, (a0, a1, label)  # degrees: the boom rose
            a2, tip1 = _tip(page)
            assert tip1[2] > tip0[2] + 0.05, (tip0, tip1)  # metres: the drawn tip rose
            scene.scroll_into_view_if_needed()
            time.sleep(0.3)  # the scene's next frame
            assert scene.screenshot() != before_png
            page.screenshot(path=ARTIFACTS / f"mechanism_live_{view}.png", full_page=True)
            press(slider, 0.05)
            deadline = time.monotonic() + 60
            while _lift(page) > a2 - 5.0 and time.monotonic() < deadline:
                time.sleep(0.3)
            assert _lift(page) < a2 - 5.0
            expect(page.get_by_test_id("live-clock")).not_to_contain_text("stopped")
        finally:
            page.close()


def _bar(page, node: str) -> float:
    """A node's pressure [bar] in the live view's pressures line."""
    text = page.get_by_test_id("live-pressures").inner_text()
    m = re.search(rf"\b{node} ([-\d.]+)", text)
    assert m, text
    return float(m.group(1))


def _holding(page, joint: str) -> float:
    """A joint's holding torque against gravity [kN·m] (the live view's line)."""
    text = page.get_by_test_id("live-holding").inner_text()
    m = re.search(rf"\b{joint} ([-\d.]+) kN", text)
    assert m, text
    return float(m.group(1))


def _above(page) -> float:
    """How far the hand's tip is above the table [m] (the task's line)."""
    text = page.get_by_test_id("live-task").inner_text()
    m = re.search(r"the tip ([-\d.]+) m above the table", text)
    assert m, text
    return float(m.group(1))


def _set(page, name: str, low: float, high: float, value: float, touch: bool) -> None:
    """A setpoint's slider (``low`` to ``high`` in its unit) clicked (tapped) at ``value``."""
    press(page.get_by_test_id(f"live-lever-{name}"), (value - low) / (high - low), touch)


# the excavator's setpoints: (lever, low, high [deg])
EXCAVATOR = {
    "boom": ("boom_reference.value", -45.0, 50.0),
    "stick": ("stick_reference.value", -150.0, -40.0),
    "bucket": ("bucket_reference.value", -150.0, -30.0),
}


def _pose(page, angles: dict, touch: bool) -> None:
    for joint, deg in angles.items():
        name, low, high = EXCAVATOR[joint]
        _set(page, name, low, high, deg, touch)
    for joint in angles:
        label = page.get_by_text(f"{joint} setpoint ({EXCAVATOR[joint][0]})")
        expect(label).not_to_contain_text("waveform")


@pytest.mark.slow
def test_the_excavators_block_task_in_a_browser(servers, browser):
    """Any mechanism's live view with gauges, setpoints and its block task (issue 32): the
    excavator's supply gauge (the pump's node, its scale to 1.5 × the 310 bar relief), its
    setpoint sliders in degrees; held at the dig point, the grasp puts the 1980 kg of soil
    in the bucket: the boom's holding torque rises by its weight times its reach; then (at
    1280 px) the setpoints thrown to a pose 0.65 m below the pit floor: the floor holds the
    tip on it."""
    for view, width in WIDTHS.items():
        touch = view == "phone"
        page = browser.new_page(viewport={"width": width, "height": 900}, has_touch=touch)
        try:
            page.goto(f"http://127.0.0.1:{servers['excavator'].port}/")
            live = page.get_by_test_id("live")
            expect(live).to_be_visible(timeout=30000)
            live.get_by_text("Live: drive the mechanism").click()
            expect(page.get_by_test_id("live-clock")).to_contain_text("t = ", timeout=60000)
            gauge = page.get_by_test_id("live-gauge-P")
            expect(gauge).to_contain_text("P (pump):")
            expect(gauge).to_contain_text("(relief 310 bar)")
            scale = page.get_by_test_id("live-gauge-scale-P")
            expect(scale).to_contain_text("0 bar")
            expect(scale).to_contain_text("465 bar")
            for part in (page.get_by_test_id("live-scene"), scale):
                box = part.bounding_box()
                assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= width + 1
            expect(page.get_by_text("boom setpoint (boom_reference.value)")).to_contain_text("deg")
            task = page.get_by_test_id("live-task")
            expect(task).to_contain_text("the load on the table")
            # held at the dig point (the file's start); the soil, within reach, grasped: the
            # boom's holding torque (the kernel's tree, now with the soil) rises by its
            # weight times its reach, 1980 kg x 9.81 m/s2 x some 6 m
            _pose(page, {"boom": 0.0, "stick": -80.0, "bucket": -60.0}, touch)
            time.sleep(1.0)
            page.get_by_test_id("live-scene").scroll_into_view_if_needed()
            page.screenshot(path=ARTIFACTS / f"excavator_task_{view}.png", full_page=True)
            h0, p0 = _holding(page, "boom"), _bar(page, "boom_a")
            page.get_by_test_id("live-grasp").click()
            expect(task).to_contain_text("the load (1980 kg) held on bucket")
            deadline = time.monotonic() + 30
            while _holding(page, "boom") < h0 + 100.0 and time.monotonic() < deadline:
                time.sleep(0.2)
            h1 = _holding(page, "boom")
            assert h1 > h0 + 100.0, (h0, h1)  # kN·m
            p1 = _bar(page, "boom_a")
            page.screenshot(path=ARTIFACTS / f"excavator_grasped_{view}.png", full_page=True)
            print(
                f"excavator at {view}: boom holding {h0:.1f} -> {h1:.1f} kN m; boom_a "
                f"{p0:.1f} -> {p1:.1f} bar (the front rings about its hold)"
            )
            if view == "phone":
                continue  # the floor once (at 1280 px): its contact is the server's
            # the tip driven down through the pit floor: the floor holds it
            _pose(page, {"boom": -30.0, "stick": -90.0, "bucket": -90.0}, touch)
            seen = []
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                seen.append(_above(page))
                if len(seen) > 10 and seen[-1] < 0.01:
                    break
                time.sleep(0.3)
            assert min(seen) >= 0.0 and seen[-1] < 0.01, seen
            expect(page.get_by_test_id("live-clock")).not_to_contain_text("stopped")
            page.get_by_test_id("live-scene").scroll_into_view_if_needed()
            page.screenshot(path=ARTIFACTS / f"excavator_floor_{view}.png", full_page=True)
            print(f"the tip above the pit floor: {min(seen):.3f} to {max(seen):.3f} m")
        finally:
            page.close()
