"""Slider-to-curve and visit latency of ``hydroarm explore`` (the arm page) and its live arm's
real-time factor, measured in headless Chromium (issue 32; targets: a slider's new curves in
≤ 0.5 s, a visit in ≤ 1 s, warm kernels, on the 2-core machine).

Prints:
  * the reference: the bare runs a slider change makes (``JointExplorer.set``: the paper's
    raise and lower saturation tests, the single joint's physics), in this process, best and
    median of ``--repeat``;
  * slider to curve: a click on the load slider's track until the chart's title shows the new
    saturation velocity (polled at each animation frame), each click at a new point (a value
    seen before would come from the page's cache); best and median, and the median's ratio
    to the bare runs' median;
  * a visit: the page loaded until the single joint's chart (SVG) is shown (best, median);
    and 20 visits arriving together (plain HTTP GETs of the page at once): the slowest;
  * the live arm's real-time factor: simulated seconds per wall second on the live tab at
    ×1 (the page's clock read twice, ``--live`` seconds apart; 1.0 is real time);
  * the load average before and after, and the time (UTC).
With ``--system`` it then runs benchmarks/explore_system_latency.py (the system page).

Run: python benchmarks/explore_latency.py [--repeat 5] [--live 10] [--system]
Needs the explore extra and a Chromium (``/usr/bin/chromium``).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from urllib.request import urlopen

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from explore_server import ExploreServer  # noqa: E402  (tests/explore_server.py)

from hydroarm.explore import JointExplorer  # noqa: E402

SLIDER = "hand_mass"


def fraction(k: int) -> float:
    """The k-th point of the load slider's track clicked: each a new value (0.15-0.85 of the
    track, never twice the same: the page keeps the runs of values seen before)."""
    return 0.15 + 0.7 * ((0.618034 * k) % 1.0)


VISITORS = 20


def _stats(xs: list[float]) -> str:
    return f"best {min(xs):6.3f} s, median {statistics.median(xs):6.3f} s"


def _reference(repeat: int) -> list[float]:
    out = []
    for k in range(repeat):
        e = JointExplorer()  # a fresh cache: each change runs
        t0 = time.perf_counter()
        e.set(SLIDER, round(0.6 * fraction(k), 2))
        out.append(time.perf_counter() - t0)
    return out


def _title(page) -> str:
    return page.evaluate(
        "() => [...document.querySelectorAll('[data-testid=joint-plot] svg text')]"
        ".map(t => t.textContent).find(t => t.includes('saturation velocity')) || ''"
    )


def _browser(port: int, repeat: int, live_s: float, chromium: str):
    from playwright.sync_api import sync_playwright

    visits: list[float] = []
    updates: list[float] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=chromium, args=["--no-sandbox", "--disable-gpu"], headless=True
        )
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        for _ in range(repeat):
            t0 = time.perf_counter()
            page.goto(f"http://127.0.0.1:{port}/")
            page.get_by_test_id("joint-plot").locator("svg").first.wait_for(state="visible")
            visits.append(time.perf_counter() - t0)
        box = page.get_by_test_id(f"slider-{SLIDER}").bounding_box()
        assert box is not None
        for k in range(repeat + 1):
            before = _title(page)
            x = box["x"] + fraction(k) * box["width"]
            t0 = time.perf_counter()
            page.mouse.click(x, box["y"] + 0.5 * box["height"])
            page.wait_for_function(
                "old => { const t = [...document.querySelectorAll("
                "'[data-testid=joint-plot] svg text')].map(t => t.textContent)"
                ".find(t => t.includes('saturation velocity')); return t && t !== old; }",
                arg=before,
                polling="raf",
                timeout=120000,
            )
            if k:  # the first click: the track's first value (a cold thread pool)
                updates.append(time.perf_counter() - t0)
        page.get_by_test_id("tab-live").click()
        page.get_by_test_id("clock").wait_for(state="visible")
        time.sleep(1.0)

        def clock() -> tuple[float, float]:
            text = page.get_by_test_id("clock").inner_text()
            return time.perf_counter(), float(re.search(r"t = ([\d.]+) s", text).group(1))

        w0, s0 = clock()
        time.sleep(live_s)
        w1, s1 = clock()
        browser.close()
    return visits, updates, (s1 - s0) / (w1 - w0)


def _together(port: int) -> float:
    def get(_):
        t0 = time.perf_counter()
        with urlopen(f"http://127.0.0.1:{port}/", timeout=300) as r:
            r.read()
        return time.perf_counter() - t0

    with ThreadPoolExecutor(VISITORS) as pool:
        return max(pool.map(get, range(VISITORS)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--live", type=float, default=10.0, help="seconds of the live arm timed")
    ap.add_argument("--system", action="store_true", help="the system page's numbers too")
    a = ap.parse_args(argv)
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        raise SystemExit("needs Chromium (apt-get install chromium)")
    load0 = os.getloadavg()
    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime())} UTC, {os.cpu_count()} cores, "
          f"load average {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}")  # fmt: skip
    ref = _reference(a.repeat)
    srv = ExploreServer("--out", str(Path(tempfile.mkdtemp()) / "attempts"))
    try:
        srv.wait()
        visits, updates, rtf = _browser(srv.port, a.repeat, a.live, chromium)
        together = _together(srv.port)
    finally:
        srv.stop()
    ratio = statistics.median(updates) / statistics.median(ref)
    print("arm page (hydroarm explore):")
    print(f"  bare runs (reference)  {_stats(ref)}")
    print(f"  slider to curve        {_stats(updates)}   median ×{ratio:.2f} the bare runs"
          "   (target ≤ 0.5 s)")  # fmt: skip
    print(f"  visit to chart         {_stats(visits)}   (target ≤ 1 s)")
    print(f"  {VISITORS} visits at once     slowest {together:6.3f} s (the page's HTML)")
    print(f"  live real-time factor  {rtf:6.3f} simulated s per wall s at ×1 (1.0: real time)")
    load1 = os.getloadavg()
    print(f"# load average after: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}")
    if a.system:
        import explore_system_latency

        explore_system_latency.main(["--repeat", str(a.repeat)])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
