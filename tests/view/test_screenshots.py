"""The viewer's pictures in docs/watching.md, taken here in headless Chromium from real runs.

    FLEETSIM_UPDATE_DOCS=1 python -m pytest tests/view/test_screenshots.py

takes them anew into docs/images/; otherwise the test takes them and checks that the pages show what the
pictures are of and that the committed pictures are there, with the same size.
"""

from __future__ import annotations

import importlib.util
import os
import struct
import threading
import time
from pathlib import Path
from typing import Any

import pytest
from viewer import EXAMPLES, REPO, ready, short_suite, state

from fleetsim.cli.main import main
from fleetsim.load.suites.scenario import load_scenario, load_scenario_dir
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import GreedyPlanner, ReservingPlanner
from fleetsim.recording.artifacts import write_run_artifacts
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.loop import run_scenario
from fleetsim.view import write_view_file
from fleetsim.view.session import LiveSession

IMAGES = REPO / "docs" / "images"
SIZE = {"width": 1200, "height": 700}


def _keep(page: Any, name: str, tmp_path: Path) -> None:
    """Take the picture: into docs/images with FLEETSIM_UPDATE_DOCS=1, else beside the test's files,
    compared in size with the committed one."""
    target = IMAGES / name
    if os.environ.get("FLEETSIM_UPDATE_DOCS") == "1":
        page.screenshot(path=str(target))
        return
    taken = tmp_path / name
    page.screenshot(path=str(taken))
    assert target.is_file(), f"{target} is missing: FLEETSIM_UPDATE_DOCS=1 python -m pytest {__file__}"
    assert _png_size(taken) == _png_size(target) == (SIZE["width"], SIZE["height"])


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", data[16:24])
    return width, height


def test_a_failed_run_at_its_failure_with_a_vehicle_hovered(browser: Any, tmp_path: Path) -> None:
    main(["run", f"{EXAMPLES}::loop-one-way", "--planner", "fleetsim.planners:BFSPlanner", "--record", str(tmp_path)])
    page = browser.new_page(viewport=SIZE)
    page.goto((tmp_path / "examples" / "loop-one-way" / "view.html").as_uri())
    ready(page)  # a failed run's page opens at its failure
    x, y = page.evaluate("fleetsimView.screenOf(2)")
    box = page.locator("#canvas").bounding_box()
    page.mouse.move(box["x"] + x, box["y"] + y)
    page.locator("#tooltip").wait_for(state="visible")
    assert state(page)["shown"].startswith("t = 5.10 s")
    _keep(page, "view-failure.png", tmp_path)
    page.close()


def test_a_stuck_fleet_at_its_end_shows_who_waits_for_whom(browser: Any, tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("lattice", REPO / "benchmarks" / "lattice.py")
    assert spec is not None and spec.loader is not None
    lattice = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(lattice)
    folder = lattice.write_lattice_scenario(tmp_path / "lattice", 21, 30, seed=1)
    scenario = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=600.0))
    result = run_scenario(scenario, GreedyPlanner())
    paths = write_run_artifacts(tmp_path / "run", result, scenario=scenario, more=write_view_file)
    page = browser.new_page(viewport=SIZE)
    page.goto(Path(paths["view"]).as_uri())
    ready(page)
    page.evaluate(f"fleetsimView.seek({result.steps - 1})")
    banner = page.locator("#banner")
    banner.wait_for(state="visible")
    assert "(at the end: who waits for whom)" in banner.inner_text()
    _keep(page, "view-stuck.png", tmp_path)
    page.close()


def test_a_live_run_paused_on_the_page(browser: Any, tmp_path: Path) -> None:
    suite = load_suite(short_suite(tmp_path, 30))
    scenario = load_scenario(suite.scenarios[0], suite)
    with LiveSession(2.0, open_browser=False, say=lambda _: None) as session:
        watch = session.begin(scenario, {"planner": "fleetsim.planners:ReservingPlanner"})
        thread = threading.Thread(target=run_scenario, args=(scenario, ReservingPlanner()), kwargs={"watch": watch})
        thread.daemon = True
        thread.start()
        page = browser.new_page(viewport=SIZE)
        page.goto(session.url)
        ready(page)
        page.wait_for_function("() => fleetsimView.state().time >= 6")
        page.click("#play")
        page.wait_for_function("() => fleetsimView.state().live.paused")
        time.sleep(0.3)
        assert "live, paused" in state(page)["shown"]
        _keep(page, "view-live.png", tmp_path)
        page.select_option("#speed", "max")
        page.click("#play")
        thread.join(timeout=30)
        page.close()


def test_a_shift_with_orders_waiting_carried_and_a_vehicle_hovered(browser: Any, tmp_path: Path) -> None:
    from orders_support import warehouse_run

    from fleetsim.recording.orders import frame_and_orders_at

    scenario, result = warehouse_run()
    assert result.trace is not None
    paths = write_run_artifacts(tmp_path / "run", result, scenario=scenario, more=write_view_file)
    step = 4200  # 7 minutes in: two orders waiting at a pick station, two vehicles loaded, one dwelling
    _, orders = frame_and_orders_at(scenario, result.trace.lines, step)
    assert orders is not None and orders.waiting and any(c.loaded for c in orders.carry.values())
    page = browser.new_page(viewport=SIZE)
    page.goto(Path(paths["view"]).as_uri())
    ready(page)
    page.evaluate(f"fleetsimView.seek({step})")
    page.wait_for_function(f"() => fleetsimView.drawnOrders && fleetsimView.drawnOrders.step === {step}")
    hovered = next(v for v, c in orders.carry.items() if c.loaded)
    x, y = page.evaluate(f"fleetsimView.screenOf({hovered})")
    box = page.locator("#canvas").bounding_box()
    page.mouse.move(box["x"] + x, box["y"] + y)
    page.locator("#tooltip").wait_for(state="visible")
    assert f"order {orders.carry[hovered].orders[0]}, stop" in page.inner_text("#tooltip")
    _keep(page, "view-orders.png", tmp_path)
    page.close()


@pytest.mark.parametrize("name", ["view-failure.png", "view-stuck.png", "view-live.png", "view-orders.png"])
def test_the_watching_page_shows_each_picture(name: str) -> None:
    assert f"images/{name}" in (REPO / "docs" / "watching.md").read_text(encoding="utf-8")
