"""Transport orders on the viewer page, in headless Chromium: what it draws at a step is what the trace
says then (waiting stations, each vehicle's order, loaded, dwelling, stalled, the counts), the backlog chart
is the result's, and a stall is an event that names the orders held up."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from orders_support import stall_run, warehouse_run
from viewer import ready, state

from fleetsim.recording.artifacts import write_run_artifacts
from fleetsim.recording.orders import followed
from fleetsim.view import write_view_file


@pytest.fixture(scope="module")
def pages(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("orders")
    made = {}
    for name, (scenario, result) in (("warehouse", warehouse_run()), ("stall", stall_run("end"))):
        paths = write_run_artifacts(root / name, result, scenario=scenario, more=write_view_file)
        made[name] = Path(paths["view"])
    return made


def _shown_at(page: Any, step: int) -> dict[str, Any]:
    page.evaluate(f"fleetsimView.seek({step})")
    page.wait_for_function(f"() => fleetsimView.drawnOrders && fleetsimView.drawnOrders.step === {step}")
    shown: dict[str, Any] = page.evaluate("fleetsimView.drawnOrders")
    return shown


def test_the_page_draws_the_orders_the_trace_has_at_each_step_and_the_results_backlog(
    page: Any, pages: dict[str, Path]
) -> None:
    scenario, result = warehouse_run()
    assert result.trace is not None and result.measures is not None
    # steps to look at: one with orders waiting, one with a vehicle loaded, one dwelling, and the last
    wanted: dict[str, int] = {}
    states = {}
    for frame, tracker, _ in followed(scenario, result.trace.lines):
        now = tracker.state()
        for key, holds in (
            ("waiting", bool(now.waiting)),
            ("loaded", any(c.loaded for c in now.carry.values())),
            ("dwelling", any(c.dwell is not None for c in now.carry.values())),
            ("two waiting", any(len(w) > 1 for w in now.waiting.values())),
        ):
            if holds and key not in wanted and frame.step > 2000:
                wanted[key] = frame.step
                states[frame.step] = now
        states.setdefault(frame.step, now) if frame.step == result.steps - 1 else None
    assert len(wanted) == 4, wanted
    page.goto(pages["warehouse"].as_uri())
    ready(page)
    for step in [*wanted.values(), result.steps - 1]:
        now = states[step]
        shown = _shown_at(page, step)
        assert shown["waiting"] == {str(s): len(w) for s, w in now.waiting.items()}, step
        assert shown["badges"] == {
            str(v): c.orders[0] + (f" +{len(c.orders) - 1}" if len(c.orders) > 1 else "")
            for v, c in now.carry.items()
            if c.orders
        }, step
        assert shown["loaded"] == [v for v, c in now.carry.items() if c.loaded]
        assert shown["dwelling"] == [v for v, c in now.carry.items() if c.dwell is not None]
        assert shown["stalled"] == []
        assert page.inner_text("#orders") == f"orders: {now.done} completed \u00b7 {now.open} open"
        backlog = page.evaluate("fleetsimView.drawnBacklog")
        assert backlog["sample"] == [n for t, n in result.measures.backlog if t <= step * 0.1 + 1e-9][-1]
    chart = page.evaluate("fleetsimView.backlog()")
    assert chart == [[t, n] for t, n in result.measures.backlog]
    assert chart[-1] == list(result.measures.backlog[-1])  # the chart's last point is the result's last sample
    assert page.locator("#backlog").is_visible()


def test_a_stall_is_the_next_event_names_the_orders_held_up_and_hover_says_the_order_and_stop(
    page: Any, pages: dict[str, Path]
) -> None:
    page.goto(pages["stall"].as_uri())
    ready(page)
    assert state(page)["step"] == 160  # a failed run opens at its failure: the stall
    page.evaluate("fleetsimView.seek(0)")
    page.keyboard.press("n")  # releases and assignments are routine: the next event is the stall
    page.wait_for_function("() => fleetsimView.state().step === 160")
    shown = _shown_at(page, 160)
    assert shown["stalled"] == [2] and shown["badges"] == {"1": "a", "2": "b"}
    row = page.locator('#events li[data-kind="stall"]')
    assert row.count() == 1
    assert " ".join(row.inner_text().split()).startswith(
        "16.10 s vehicle 2 stalled; orders held up: b (vehicle 2 (task 3"
    )
    x, y = page.evaluate("fleetsimView.screenOf(2)")
    box = page.locator("#canvas").bounding_box()
    page.mouse.move(box["x"] + x, box["y"] + y)
    tooltip = page.locator("#tooltip")
    tooltip.wait_for(state="visible")
    text = tooltip.inner_text()
    assert "order b, stop 1 of 2" in text
    assert "stalled at 16.1 s; orders held up: b" in text
    assert page.inner_text("#orders") == "orders: 0 completed \u00b7 3 open"


def test_a_run_without_orders_shows_no_order_parts(page: Any, tmp_path: Path) -> None:
    from fleetsim import load_scenario, load_suite
    from fleetsim.planners import ReservingPlanner
    from fleetsim.sim.loop import run_scenario

    suite = load_suite("scenario_suites/examples.fleetsim.yaml")
    scenario = load_scenario(next(s for s in suite.scenarios if s.name == "crossing"), suite)
    result = run_scenario(scenario, ReservingPlanner())
    paths = write_run_artifacts(tmp_path / "run", result, scenario=scenario, more=write_view_file)
    page.goto(Path(paths["view"]).as_uri())
    ready(page)
    page.evaluate("fleetsimView.seek(10)")
    page.wait_for_function("() => fleetsimView.drawnPoses().step === 10")
    assert page.evaluate("fleetsimView.drawnOrders") is None
    assert page.inner_text("#orders") == "" and not page.locator("#backlog").is_visible()
