"""``hydroarm explore`` end to end in a real headless browser (Chromium from the system's
packages, driven by Playwright): the server runs as the command in a subprocess on a free
127.0.0.1 port and is stopped at the end.

Checked: the page loads with no request leaving 127.0.0.1 (every request is recorded by
Playwright's route interception); moving the load slider changes the plotted saturation
velocity the right way; a held lever key moves the drawn arm; a scripted key sequence grasps
a block and stacks it on the pad; a saved attempt replays through the arm file reader;
Ctrl-C stops the server with one line. Screenshots of each view are saved under
``tests/artifacts/explore/`` (ignored by git; the path is printed).

Skipped only when no Chromium binary exists and CI is not set (in CI, CI=true, they run).
"""

from __future__ import annotations

import math
import os
import re
import shutil
import signal
import time
from pathlib import Path
from urllib.parse import urlparse

import pytest

from hydroarm.arm import load_arm_text
from hydroarm.explore.live import LEVER_RATE

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
IN_CI = os.environ.get("CI", "").lower() == "true"
ARTIFACTS = Path(__file__).parent / "artifacts" / "explore"

if CHROMIUM is None and not IN_CI:
    pytest.skip(
        "no Chromium binary (apt-get install chromium); CI=true makes this fail",
        allow_module_level=True,
    )

from explore_server import ExploreServer, press  # noqa: E402  (tests/explore_server.py)
from playwright.sync_api import expect, sync_playwright  # noqa: E402


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("explore")
    srv = ExploreServer("--out", str(tmp / "attempts"))
    try:
        srv.wait()  # the server's own readiness, no time budget (tests/explore_server.py)
        yield {"port": srv.port, "tmp": tmp, "proc": srv.proc}
    finally:
        srv.stop()


def _velocity(page) -> float:
    """The saturation velocity [mm/s] the plot's title shows (the SVG keeps text as text)."""
    title = page.get_by_test_id("joint-plot").locator("svg text", has_text="saturation velocity")
    m = re.search(r"saturation velocity ([-\d.]+) mm/s", title.first.text_content() or "")
    assert m, "no velocity in the plot's title"
    return float(m.group(1))


def _angles(page) -> dict[str, float]:
    text = page.get_by_test_id("angles").text_content() or ""
    return {k: float(v) for k, v in re.findall(r"(\w+)=([-\d.]+)", text)}


def _hold(page, plan: dict[str, float]) -> None:
    """Hold each key for its time [s], all pressed together, released in turn."""
    for k in plan:
        page.keyboard.down(k)
    t0 = time.monotonic()
    for k, dur in sorted(plan.items(), key=lambda kv: kv[1]):
        time.sleep(max(t0 + dur - time.monotonic(), 0.0))
        page.keyboard.up(k)


# the lever box's keys: (raise, lower) of each joint (docs/explore.md)
KEYS = {
    "shoulder_elevation": ("q", "a"),
    "humeral_rotation": ("w", "s"),
    "elbow_reach": ("e", "d"),
    "wrist_rotation": ("r", "f"),
}


def _correct(page, target: dict[str, float], tol: float = 1.0) -> dict[str, float]:
    """Tap the keys until every drawn angle is within ``tol`` [deg] of ``target``: the open
    loop holds above land within a few degrees only (key timing through the page on a busy
    machine), as a person at the lever box corrects by eye; a few rounds at most. Each tap
    is 0.7 of the error's time: on a loaded CI machine a release arrives late, and full taps
    overshot back and forth for ten rounds, missing the place pose (2026-11-26); a damped
    tap converges from either side (twenty rounds at most)."""
    rate = math.degrees(LEVER_RATE)
    now = _settle(page)
    for _ in range(20):
        err = {k: target[k] - now[k] for k in target}
        if all(abs(e) < tol for e in err.values()):
            break
        _hold(
            page,
            {
                KEYS[k][0 if e > 0 else 1]: 0.7 * abs(e) / rate
                for k, e in err.items()
                if abs(e) >= tol / 2
            },
        )
        now = _settle(page)
    return now


def _settle(page, timeout: float = 8.0) -> dict[str, float]:
    """Wait until the drawn angles stop changing (the arm has reached its levers)."""
    last = _angles(page)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        time.sleep(0.4)
        now = _angles(page)
        if all(abs(now[k] - last[k]) < 0.05 for k in now):
            return now
        last = now
    return last


@pytest.mark.slow
def test_explore_in_a_browser(server):
    port = server["port"]
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    print(f"\nexplore screenshots: {ARTIFACTS}")
    requests: list[str] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"], headless=True
        )
        try:
            page = browser.new_page(viewport={"width": 1500, "height": 1000})

            def route(r):
                requests.append(r.request.url)
                host = urlparse(r.request.url).hostname
                if host in ("127.0.0.1",) or r.request.url.startswith(("data:", "blob:")):
                    r.continue_()
                else:
                    r.abort()

            page.route("**/*", route)
            page.goto(f"http://127.0.0.1:{port}/")

            # the single joint: the plot is drawn, then a heavier hand slows the raise test
            expect(page.get_by_test_id("joint-plot").locator("svg")).to_be_visible(timeout=30000)
            v0 = _velocity(page)
            page.screenshot(path=ARTIFACTS / "single_joint.png", full_page=True)
            # a click at 90 % of the track: about 0.54 kg in the hand
            press(page.get_by_test_id("slider-hand_mass"), 0.9)
            title = page.get_by_test_id("joint-plot").locator(
                "svg text", has_text="saturation velocity"
            )
            expect(title).not_to_have_text(re.compile(rf"velocity {v0:.2f} mm/s"), timeout=20000)
            expect(page.locator("body")).to_contain_text("load mass in the hand: 0.5")
            v1 = _velocity(page)
            # Table I: load 5 (0.45 kg in the hand) raises at 20.8 mm/s against load 1's 24.4
            assert v1 < v0 - 1.0, (v0, v1)
            page.screenshot(path=ARTIFACTS / "single_joint_loaded.png", full_page=True)

            # the linear view: the Bode plot and the margins
            page.get_by_test_id("tab-linear").click()
            expect(page.get_by_test_id("bode").locator("svg")).to_be_visible(timeout=20000)
            expect(page.get_by_test_id("margins")).to_contain_text("phase margin")
            time.sleep(0.5)  # the tab's slide animation
            page.screenshot(path=ARTIFACTS / "linear_view.png", full_page=True)

            # the live arm: a held lever key moves the drawn arm
            page.get_by_test_id("tab-live").click()
            scene = page.get_by_test_id("scene")
            expect(scene).to_be_visible()
            time.sleep(1.0)  # the tab's slide animation; the arm at rest
            before_png = scene.screenshot()
            a0 = _angles(page)
            _hold(page, {"q": 0.6})
            a1 = _settle(page)
            # 0.6 s at 45°/s of lever: about 27°. The key's press and release reach the arm
            # through the page and the server's event loop, and their delays differ: ±5° on
            # an idle machine, but 45° (a release 0.4 s late) was measured in CI on a loaded
            # 2-core machine (2026-11-26), so the upper bound allows a 0.7 s late release
            assert 15.0 < a1["shoulder_elevation"] - a0["shoulder_elevation"] < 60.0, (a0, a1)
            assert scene.screenshot() != before_png
            page.screenshot(path=ARTIFACTS / "live_arm.png", full_page=True)

            # block stacking: to the pick pose by keys, grasp, to the place pose, release
            page.get_by_test_id("reset").click()
            time.sleep(0.5)
            rate = math.degrees(LEVER_RATE)
            a_reset = _settle(page)
            pick = {"q": 35.0 / rate, "e": 95.0 / rate, "r": 60.0 / rate}
            _hold(page, pick)
            at_pick = {
                "shoulder_elevation": a_reset["shoulder_elevation"] + 35.0,
                "elbow_reach": a_reset["elbow_reach"] + 95.0,
                "wrist_rotation": a_reset["wrist_rotation"] + 60.0,
            }
            a_pick = _correct(page, at_pick)
            page.keyboard.press("g")
            expect(page.get_by_test_id("score")).to_contain_text("stacked 0 of 3")
            expect(page.locator("body")).to_contain_text("grasped 1")
            place = {"q": 5.0 / rate, "e": 5.0 / rate, "s": 30.0 / rate, "f": 60.0 / rate}
            _hold(page, place)
            at_place = {
                "shoulder_elevation": at_pick["shoulder_elevation"] + 5.0,
                "humeral_rotation": a_pick["humeral_rotation"] - 30.0,
                "elbow_reach": at_pick["elbow_reach"] + 5.0,
                "wrist_rotation": at_pick["wrist_rotation"] - 60.0,
            }
            _correct(page, at_place)
            page.keyboard.press("g")
            expect(page.get_by_test_id("score")).to_contain_text("stacked 1 of 3")
            page.screenshot(path=ARTIFACTS / "block_stacking.png", full_page=True)

            # the attempt saved as the lever CSV the arm command replays
            page.get_by_test_id("save").click()
            expect(page.get_by_test_id("saved")).to_contain_text("attempt-")
        finally:
            browser.close()

    assert requests, "no request recorded"
    outside = [u for u in requests if urlparse(u).hostname not in ("127.0.0.1", None)]
    assert not outside, outside
    saved = sorted((server["tmp"] / "attempts").glob("attempt-*.csv"))
    assert len(saved) == 1
    example = (Path(__file__).parents[1] / "examples" / "ucl-arm.toml").read_text()
    text = example.replace('csv = "block_stacking.csv"', f'csv = "{saved[0].name}"')
    sc = load_arm_text(text, saved[0].parent)  # the arm command's reader takes it
    assert sc.inputs["humeral_rotation"].description == f"csv:{saved[0].name}"
    rows = [ln.split(",") for ln in saved[0].read_text().splitlines() if ln[:1].isdigit()]
    # the recorded humeral rotation lever ends at the place pose's −30°: ±5° for the keys'
    # timing through the page on an idle machine; −35.4° was recorded in CI on a loaded
    # 2-core machine (2026-11-26), so ±10°: the check is that the lever is recorded
    assert -40.0 < float(rows[-1][2]) < -20.0, rows[-1]


def _lever(page, joint: str) -> float:
    """The lever's angle [deg] its label shows ("elbow reach: lever 12.0°, arm 11.8°")."""
    label = page.get_by_text(re.compile(rf"^{joint.replace('_', ' ')}: lever"))
    m = re.search(r"lever ([-\d.]+)°", label.first.inner_text())
    assert m, joint
    return float(m.group(1))


def _hide(page, hidden: bool) -> None:
    """The browser's tab hidden or shown again, as the browser tells a page."""
    page.evaluate(
        "h => { Object.defineProperty(document, 'hidden', {value: h, configurable: true}); "
        "document.dispatchEvent(new Event('visibilitychange')); }",
        hidden,
    )


@pytest.mark.slow
def test_every_view_at_desktop_and_phone_width_and_levers_by_touch(server):
    """Screenshots of each view at 1280 and 390 px (tests/artifacts/explore/<view>_<w>.png);
    at 390 px with a touch screen: the page wraps (the controls, the tables and the 3-D scene
    within the screen), an on-screen lever button held by a touch pointer moves its lever, a
    tap on a lever's slider sets it, the gauges show their scales."""
    port = server["port"]
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"], headless=True
        )
        try:
            for width in (1280, 390):
                phone = width < 600
                page = browser.new_page(
                    viewport={"width": width, "height": 844 if phone else 900},
                    has_touch=phone,
                    is_mobile=phone,
                )
                page.goto(f"http://127.0.0.1:{port}/")
                expect(page.get_by_test_id("joint-plot").locator("svg")).to_be_visible(
                    timeout=30000
                )
                # every slider of the single joint says its value with its unit
                body = page.locator("body")
                expect(body).to_contain_text("valve flow coefficient K: 1 × set = ")
                expect(body).to_contain_text("trapped volume V: 1 × set = ")
                page.screenshot(path=ARTIFACTS / f"single_joint_{width}.png", full_page=True)
                if phone:  # the controls and the metrics fit the screen (the page wraps)
                    for testid in ("slider-hand_mass", "metrics"):
                        box = page.get_by_test_id(testid).bounding_box()
                        assert box is not None and box["x"] + box["width"] <= width + 1, testid
                page.get_by_test_id("tab-linear").click()
                expect(page.get_by_test_id("bode").locator("svg")).to_be_visible(timeout=60000)
                time.sleep(0.5)  # the tab's slide animation
                page.screenshot(path=ARTIFACTS / f"linear_view_{width}.png", full_page=True)
                page.get_by_test_id("tab-live").click()
                expect(page.get_by_test_id("scene")).to_be_visible()
                time.sleep(1.0)
                expect(body).to_contain_text("bar")  # the gauges' scales
                page.screenshot(path=ARTIFACTS / f"live_arm_{width}.png", full_page=True)
                if not phone:
                    page.close()
                    continue
                scene = page.get_by_test_id("scene").bounding_box()
                assert scene is not None and scene["x"] + scene["width"] <= width + 1
                # the lever box: E held by a touch pointer for 0.6 s raises the elbow's lever
                hold = page.get_by_test_id("hold-e")
                hold.scroll_into_view_if_needed()
                box = hold.bounding_box()
                assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= width
                e0 = _lever(page, "elbow_reach")
                touch = {"pointerType": "touch", "isPrimary": True, "pointerId": 7}
                hold.dispatch_event("pointerdown", touch)
                time.sleep(0.6)
                hold.dispatch_event("pointerup", touch)
                time.sleep(0.5)
                e1 = _lever(page, "elbow_reach")
                # 0.6 s at 45°/s: 27°; the press and release reach the server through the
                # event loop, late by up to 0.7 s on a loaded 2-core machine (as the keys)
                assert 10.0 < e1 - e0 < 60.0, (e0, e1)
                # a tap on the wrist's slider at 80 % of its track: about +54°
                slider = page.get_by_test_id("lever-wrist_rotation")
                slider.scroll_into_view_if_needed()
                sb = slider.bounding_box()
                assert sb is not None and sb["x"] + sb["width"] <= width + 1
                w0 = _lever(page, "wrist_rotation")
                press(slider, 0.8, touch=True)
                expect(
                    page.get_by_text(re.compile(r"^wrist rotation: lever (4\d|5\d|6\d)"))
                ).to_be_visible(timeout=20000)
                assert _lever(page, "wrist_rotation") > w0 + 30.0
                page.screenshot(path=ARTIFACTS / f"live_arm_{width}_touched.png", full_page=True)
                # the browser's tab hidden: the arm does not step; shown again: it does
                clock = page.get_by_test_id("clock")
                _hide(page, True)
                time.sleep(1.0)  # the event reaches the server; the last frame drawn
                t_hidden = clock.inner_text()
                time.sleep(1.5)
                assert clock.inner_text() == t_hidden
                _hide(page, False)
                expect(clock).not_to_have_text(t_hidden, timeout=20000)
                page.close()
        finally:
            browser.close()
    print(f"\nexplore screenshots: {ARTIFACTS}")


@pytest.mark.slow
def test_ctrl_c_stops_the_server(tmp_path):
    srv = ExploreServer("--out", str(tmp_path / "attempts"))
    try:
        srv.wait()
        srv.proc.send_signal(signal.SIGINT)
        srv.proc.wait(timeout=60)
        time.sleep(0.3)  # the readers take the last lines
    finally:
        srv.stop()
    err = "".join(srv.err)
    assert srv.proc.returncode in (0, 130), (srv.proc.returncode, err)
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) <= 1, err
    if srv.proc.returncode == 130:
        assert lines == ["hydroarm: interrupted"]
    assert f"http://127.0.0.1:{srv.port}" in "".join(srv.out)
