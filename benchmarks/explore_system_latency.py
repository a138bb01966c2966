"""Slider-to-curve and visit latency of ``hydroarm explore --config`` on system files,
measured in headless Chromium against the bare run of the same system in the same run
(issue 29; docs/explore.md "Any system file").

Workloads (the files as they are): examples/circuit_position_servo.toml (10 components, RK4
at 10 µs for 3 s: 0.3 M steps a run) and tests/data/mechanism/boom.toml (a boom on a
revolute joint, 6 components, RK4 at 20 µs for 1.5 s: 75 k steps a run).

Prints, per file:
  * the reference: the bare run, ``SystemModel.run`` with the slider's value set (build the
    circuit, ``hydroarm.model.circuit.simulate``, the output columns), in this process,
    best and median of ``--repeat``;
  * slider to curve: a click on the slider's track in the browser until the page shows the
    run's table and curves (the status line "run N done in …", polled at each animation
    frame), clicks alternating between two points of the track; best and median, and the
    median's ratio to the reference's median; and the run's own time on the server's thread
    (the status line's), the rest being the page's round trip and drawing;
  * a visit: the page loaded until the chart (SVG) is shown (best and median);
  * the load average (1, 5, 15 min) before and after, and the time (UTC).

Run: python benchmarks/explore_system_latency.py [--repeat 5]
Needs the explore extra and a Chromium (``/usr/bin/chromium``).
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path
from urllib.request import urlopen

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.explore.system import load_system_model  # noqa: E402

BOOM = ROOT / "tests" / "data" / "mechanism" / "boom.toml"
CASES = {  # file, slider, the two points of its track clicked in turn
    "circuit": (ROOT / "examples" / "circuit_position_servo.toml", "payload.mass", (0.9, 0.3)),
    "mechanism": (BOOM, "supply.pressure", (0.1, 0.4)),
}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _serve(config: Path) -> tuple[subprocess.Popen, int]:
    port = _free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "hydroarm.cli", "explore", "--config", str(config),
         "--port", str(port), "--no-browser"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env,
        start_new_session=True,
    )  # fmt: skip
    assert proc.stdout is not None
    for line in proc.stdout:  # the URL line: the file read and run, the server starting
        if f"127.0.0.1:{port}" in line:
            break
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        try:
            with urlopen(f"http://127.0.0.1:{port}/", timeout=2):
                return proc, port
        except OSError:
            time.sleep(0.05)
    raise SystemExit("the server did not answer")


def _stats(xs: list[float]) -> str:
    return f"best {min(xs):6.3f} s, median {statistics.median(xs):6.3f} s"


def _reference(config: Path, slider: str, fractions, repeat: int) -> list[float]:
    model = load_system_model(config)
    s = model.slider(slider)
    out = []
    for k in range(repeat):
        v = s.low + fractions[k % 2] * (s.high - s.low)
        t0 = time.perf_counter()
        model.run({slider: v})
        out.append(time.perf_counter() - t0)
    return out


def _browser(port: int, slider: str, fractions, repeat: int, chromium: str):
    from playwright.sync_api import sync_playwright

    visits: list[float] = []
    updates: list[float] = []
    runs: list[float] = []  # the server's own time of each run [s]
    with sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=chromium, args=["--no-sandbox", "--disable-gpu"], headless=True
        )
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        for _ in range(repeat):
            t0 = time.perf_counter()
            page.goto(f"http://127.0.0.1:{port}/")
            page.get_by_test_id("chart").locator("svg").first.wait_for(state="visible")
            visits.append(time.perf_counter() - t0)
        box = page.get_by_test_id(f"slider-{slider}").bounding_box()
        assert box is not None
        for k in range(repeat):
            x = box["x"] + fractions[k % 2] * box["width"]
            t0 = time.perf_counter()
            page.mouse.click(x, box["y"] + 0.5 * box["height"])
            page.wait_for_function(
                "n => document.querySelector('[data-testid=status]')?.textContent"
                ".startsWith(`run ${n} done`)",
                arg=k + 1,
                polling="raf",
            )
            updates.append(time.perf_counter() - t0)
            text = page.get_by_test_id("status").inner_text()  # "run N done in 0.61 s"
            runs.append(float(text.split(" in ")[1].split()[0]))
        browser.close()
    return visits, updates, runs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args(argv)
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        raise SystemExit("needs Chromium (apt-get install chromium)")
    load0 = os.getloadavg()
    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime())} UTC, {os.cpu_count()} cores, "
          f"load average {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}")  # fmt: skip
    for kind, (config, slider, fractions) in CASES.items():
        ref = _reference(config, slider, fractions, a.repeat)
        proc, port = _serve(config)
        try:
            visits, updates, runs = _browser(port, slider, fractions, a.repeat, chromium)
        finally:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        ratio = statistics.median(updates) / statistics.median(ref)
        print(f"{kind} ({config.name}, slider {slider}):")
        print(f"  bare run (reference)   {_stats(ref)}")
        print(f"  slider to curve        {_stats(updates)}   median ×{ratio:.2f} the bare run")
        print(f"  of which the run       {_stats(runs)}   (the server's thread)")
        print(f"  visit to chart         {_stats(visits)}")
    load1 = os.getloadavg()
    print(f"# load average after: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
