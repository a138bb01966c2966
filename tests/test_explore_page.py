"""``hydroarm explore``'s page and its callbacks in NiceGUI's own simulated browser (its
``user_simulation``, the engine of its pytest ``user`` fixture, run here without
pytest-asyncio): controls change the state, the state is drawn. Fast; no real browser (that
is tests/test_explore_browser.py)."""

from __future__ import annotations

import asyncio

import pytest

from hydroarm.explore import default_arm

nicegui = pytest.importorskip("nicegui")  # the explore extra (in the test extra)
from nicegui import ui  # noqa: E402
from nicegui.testing.user_simulation import user_simulation  # noqa: E402

from hydroarm.explore import app  # noqa: E402


def _velocity(user) -> float:
    (table,) = user.find(marker="metrics").elements
    return float(table.rows[0]["raise"])


def test_page_callbacks(tmp_path):
    arm = default_arm()

    async def story():
        async with user_simulation(lambda: app.page(arm, tmp_path)) as user:
            await user.open("/")
            await user.should_see("load mass in the hand: 0 kg")
            await user.should_see("Saturation velocity beside the paper [mm/s]")
            v0 = _velocity(user)
            (slider,) = user.find(marker="slider-hand_mass").elements
            slider.value = 0.45  # the callback runs the tests on a thread
            await user.should_see("load mass in the hand: 0.45 kg", retries=100)
            for _ in range(100):  # the table follows the label in the same redraw
                if _velocity(user) != v0:
                    break
                await asyncio.sleep(0.02)
            # Table I: 0.45 kg in the hand raises slower (20.8 against 24.4 mm/s)
            assert _velocity(user) < v0
            # another parameter set: its own valve model and gearbox loss are shown
            (sets,) = user.find(marker="select-parameter_set").elements
            sets.value = "ucl-arm-measured"
            await user.should_see("gearbox loss at stall: 0.965 -", retries=100)
            (valve,) = user.find(marker="select-valve_model").elements
            assert valve.value == "orifice"
            user.find("lower test").click()
            (chart,) = user.find(marker="joint-chart").elements  # the curves (ECharts)
            for _ in range(100):
                if chart.options["title"]["text"].startswith("lower test: saturation velocity"):
                    break
                await asyncio.sleep(0.02)
            assert chart.options["title"]["text"].startswith("lower test: saturation velocity")
            assert len(chart.options["series"]) == 4  # θ₂, x, p, ẋ: data, not a picture
            # the live arm: the grasp button with the hand far from the blocks
            user.find("Live arm and blocks").click()
            await user.should_see("Block stacking", retries=200)  # built when first opened
            user.find(marker="grasp").click()
            await user.should_see("nothing in reach")
            (score,) = user.find(marker="score").elements
            assert score.text.startswith("stacked 0 of 3")
            # a lever key pressed, then released, through the page's keyboard handler
            key = {"key": "q", "code": "KeyQ", "location": 0, "repeat": False}
            key |= {"altKey": False, "ctrlKey": False, "metaKey": False, "shiftKey": False}
            keyboard = user.find(ui.keyboard)
            keyboard.trigger("key", {**key, "action": "keydown"})
            await asyncio.sleep(0.5)
            keyboard.trigger("key", {**key, "action": "keyup"})
            (angles,) = user.find(marker="angles").elements
            shoulder = float(angles.text.split("shoulder_elevation=")[1].split(",")[0])
            assert shoulder > 1.0  # degrees: the lever moved at 45°/s for about 0.5 s

    asyncio.run(story())
