"""Transport orders read from the trace (fleetsim.recording.orders), in the failure picture and the view
document: who waits where, who carries what, dwells, stalls and the backlog, as the run's result says."""

from __future__ import annotations

import json
import re
from typing import Any

import pytest
from orders_support import stall_run, warehouse_run

from fleetsim.recording.orders import OrderTracker, followed, frame_and_orders_at
from fleetsim.recording.picture import failure_picture, render_frame_svg
from fleetsim.recording.replay import TraceError, replay
from fleetsim.view import StepRecords, outcome_part, view_document


def _lines(run: Any) -> list[str]:
    result = run[1]
    assert result.trace is not None
    return list(result.trace.lines)


def test_the_backlog_read_from_the_trace_is_the_results_and_so_are_each_orders_stops() -> None:
    scenario, result = warehouse_run()
    assert result.measures is not None and len(result.orders) >= 5
    tracker = OrderTracker.of_trace(_lines((scenario, result)))
    for frame in replay(scenario, _lines((scenario, result))):
        tracker.follow(frame)
    assert tracker.backlog == list(result.measures.backlog)
    for order in result.orders:  # a generated stream's orders drawn again from the trace header's stream
        stops = tracker.stops(order["id"])
        assert stops is not None and list(stops.segments) == order["stops"]
        assert stops.dwells == (20.0, 15.0)
    assert tracker.done == sum(1 for o in result.orders if o["completed"] is not None)
    assert tracker.open == sum(1 for o in result.orders if o["completed"] is None)


def test_waiting_carried_loaded_and_dwelling_follow_the_orders_life_in_result_json() -> None:
    scenario, result = warehouse_run()
    lives = {o["id"]: o for o in result.orders}
    dt = scenario.settings.time_step
    checked = 0
    for frame, tracker, _ in followed(scenario, _lines((scenario, result))):
        now = frame.time  # the end of the step
        state = tracker.state()
        waiting = {order for orders in state.waiting.values() for order in orders}
        for order_id, life in lives.items():
            released = life["release"] <= now - dt + 1e-6
            picked = life["served"] and life["served"][0] <= now - dt + 1e-6
            assert (order_id in waiting) == (released and not picked), (frame.step, order_id)
            if order_id in waiting:
                assert order_id in state.waiting[life["stops"][0]]
        for vehicle, carry in state.carry.items():
            life = lives[carry.orders[0]]
            assert life["vehicle"] == vehicle and life["assigned"] <= now
            assert carry.loaded == bool(life["served"] and life["served"][0] <= now - dt + 1e-6)
            if carry.dwell is not None:  # reached its stop at `since`, served when the dwell is over
                since, seconds = carry.dwell
                assert seconds == (20.0, 15.0)[carry.stop]
                assert since <= now and life["served"][carry.stop] >= since + seconds - 1e-6
                checked += 1
    assert checked > 100  # dwells were seen


def test_the_picture_of_a_stall_rings_the_vehicle_and_names_the_orders_held_up() -> None:
    scenario, result = stall_run("end")
    assert result.ended == "stall" and result.failures[0].kind == "stall"
    found = failure_picture(scenario, result)
    assert found is not None
    step, svg = found
    assert step == 160  # found at 16.1 s, the end of step 160
    assert re.search(r'<g class="stalled" data-vehicle="2" data-orders="b">', svg)
    assert "STALLED: b" in svg
    caption = " ".join(re.findall(r'class="caption-text"[^>]*>([^<]*)<', svg))
    assert "orders held up: b" in caption
    # the stations with orders waiting (none picked up yet) and each vehicle's order, from the trace
    waiting = dict(re.findall(r'<g class="waiting" data-segment="(\d+)" data-count="(\d+)"', svg))
    assert waiting == {"7": "1", "2": "1", "4": "1"}
    carried = re.findall(r'<g class="carry" data-vehicle="(\d+)" data-order="(\w+)" data-loaded="(\d)"', svg)
    assert carried == [("1", "a", "0"), ("2", "b", "0")]


def test_a_counted_stall_does_not_fail_the_run_and_a_run_without_orders_has_no_order_marks() -> None:
    scenario, result = stall_run("count")
    assert result.stalls and result.ended == "shift-end"
    assert not any(f.kind == "stall" for f in result.failures)
    picture = failure_picture(scenario, result)
    if picture is not None:  # it fails on its tasks: the picture has orders but rings no stall
        assert '<g class="orders"' in picture[1] and 'class="stalled"' not in picture[1]
    frame, orders = frame_and_orders_at(scenario, _lines((scenario, result)), 160)
    assert orders is not None and orders.carry_of(2).stalled and orders.carry_of(2).orders == ("b",)
    svg = render_frame_svg(scenario, frame, caption="plain")
    assert 'class="orders"' not in svg and 'class="stalled"' not in svg
    # the vehicle is stalled until it moves again (another vehicle's call routed it)
    moved = [
        (frame.step, tracker.carry_of(2).stalled)
        for frame, tracker, _ in followed(scenario, _lines((scenario, result)))
        if frame.step >= 160 and 2 in frame.moved
    ]
    assert moved and not moved[0][1]
    _, still = frame_and_orders_at(scenario, _lines((scenario, result)), moved[0][0] - 1)
    assert still is not None and still.carry_of(2).stalled
    last, at_end = frame_and_orders_at(scenario, _lines((scenario, result)), -1)
    assert at_end is not None and not at_end.carry_of(2).stalled and last.step == result.steps - 1
    with pytest.raises(TraceError, match="must be between 0 and"):
        frame_and_orders_at(scenario, _lines((scenario, result)), result.steps)


def test_the_view_document_carries_the_orders_step_by_step_and_the_stalls_with_their_reasons() -> None:
    scenario, result = stall_run("count")
    lines = _lines((scenario, result))
    document = view_document(scenario, lines, {}, outcome_part(result.to_dict(), result.failures, 0.1, 399))
    steps = document["steps"]
    assert steps[0][6] == {
        "carry": {"1": [["a"], 0, 0, 2, None, None, 0], "2": [["b"], 0, 0, 2, None, None, 0]},
        "waiting": {"2": ["b"], "7": ["a"]},
        "open": 2,
        "done": 0,
        "backlog": 2,  # the open orders at 0 s, after the step's releases
    }
    assert steps[50][6] == {"waiting": {"4": ["c"]}, "open": 3, "done": 0}
    assert steps[160][6] == {"carry": {"2": [["b"], 0, 0, 2, None, None, 1]}}  # stalled
    assert steps[1][6] is None  # nothing changed
    assert ["stall", 2] in steps[160][4]
    assert document["outcome"]["stalls"] == [
        {"vehicle": 2, "time": 16.1, "orders": ["b"], "reason": result.stalls[0].reason}
    ]
    assert [r[6]["backlog"] for r in steps if r[6] and "backlog" in r[6]] == [n for _, n in result.measures.backlog]  # type: ignore[union-attr]
    json.dumps(document)  # all of it JSON


def test_a_live_pages_records_learn_the_orders_from_the_header_line_when_it_comes() -> None:
    scenario, result = stall_run("end")
    lines = _lines((scenario, result))
    frames = list(replay(scenario, lines))
    unaware = StepRecords()  # a live run's converter is made before its header arrives
    assert unaware.record(frames[0], lines[1])[6] is None
    told = StepRecords()
    told.header(lines[0])
    first = told.record(frames[0], lines[1])[6]
    assert first is not None and first == StepRecords(lines[0]).record(frames[0], lines[1])[6]
