"""The viewer's document (what the page draws, from the trace), its page, and the live run's pacer."""

from __future__ import annotations

import json
import math
import threading
import time
from pathlib import Path

import pytest

from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import BFSPlanner
from fleetsim.recording.replay import replay
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import Failure
from fleetsim.view import Pacer, StepRecords, outcome_part, recorded_page, view_document
from fleetsim.view.live import parse_speed

EXAMPLES = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"


def _run(name: str):  # type: ignore[no-untyped-def]
    suite = load_suite(EXAMPLES)
    scenario = load_scenario(next(s for s in suite.scenarios if s.name == name), suite)
    result = run_scenario(scenario, BFSPlanner())
    assert result.trace is not None
    return scenario, result


def test_step_records_hold_everyone_first_then_only_what_changed() -> None:
    scenario, result = _run("loop-one-way")
    assert result.trace is not None
    encoder = StepRecords()
    lines = result.trace.lines
    frames = list(replay(scenario, lines))
    first, second = encoder.record(frames[0], lines[1]), encoder.record(frames[1], lines[2])
    assert first[0] == 0 and [r[0] for r in first[1]] == sorted(v.id for v in scenario.vehicles)
    assert [plan[0] for plan in first[2]] == sorted(v.id for v in scenario.vehicles)
    assert first[3] == [] and first[5] == {}  # no alert, no disturbance yet: said once
    assert first[6] is None and second[6] is None  # a run without transport orders says nothing of them
    assert second[3] is None and second[5] is None  # unchanged: not said again
    assert [r[0] for r in second[1]] == list(frames[1].moved)
    pose = frames[1].poses[second[1][0][0]]
    assert second[1][0][1:] == [pose.segment, "f", "f", round(pose.x * 1000), round(pose.y * 1000),
                                round(pose.heading * 18000 / math.pi), round(pose.speed * 1000)]  # fmt: skip
    last = [encoder.record(frame, lines[frame.step + 1]) for frame in frames[2:]][-1]
    assert [alert[0] for alert in last[3]] == [9, 10]  # the alerts the run failed on, when they came
    assert ["alert", 9, [2], [1]] in last[4]


def test_the_outcome_names_the_failure_step_and_who_waits_for_whom() -> None:
    stuck = Failure(
        "deadlock",
        12.0,
        "no progress",
        {
            "vehicles": [
                {"vehicle": 1, "blocked_by": [2], "contested": [5]},
                {"vehicle": 2, "blocked_by": [1], "planned_near": [3]},
            ],
            "cycles": [[1, 2]],
            "roots": [{"kind": "cycle", "vehicles": [1, 2]}],
        },
    )
    outcome = outcome_part({"status": "failed", "ended": "deadlock"}, [stuck], 0.1, 200)
    assert outcome["failure"]["step"] == 119  # the step that ended at 12.0 s
    assert outcome["stuck"]["relations"] == [
        [1, 2, "wait-for", True],
        [2, 1, "wait-for", True],
        [2, 3, "planned-near", False],
    ]
    assert outcome["stuck"]["roots"] == [1, 2] and outcome["stuck"]["contested"] == [5]
    assert outcome_part({}, [], 0.1, 10) == {
        "status": None, "ended": None, "trace_hash": None, "failure_count": 0, "failure": None, "contacts": [], "stuck": None,
        "stalls": [],
    }  # fmt: skip


def test_a_contact_read_back_from_result_json_keeps_its_place_on_the_page() -> None:
    details = {"time": 15.603448, "until": 16.7, "vehicles": [1, 2], "x": -5.7612, "y": -1.9659, "depth": 0.6392}
    touched = Failure("contact", 15.6034481, "vehicles 1 and 2 touched", details)
    # as result.json holds it and `fleetsim view` reads it: the failure's time and the contact's are one key
    saved = touched.to_dict()
    read_back = Failure("contact", saved["time"], saved["message"], {k: saved[k] for k in details if k != "time"})
    expected = [{"time": 15.603448, "x": -5.7612, "y": -1.9659, "vehicles": [1, 2]}]
    assert outcome_part({}, [touched], 0.1, 200)["contacts"] == expected
    assert outcome_part({}, [read_back], 0.1, 200)["contacts"] == expected


def test_the_page_keeps_a_script_in_a_name_inert() -> None:
    scenario, result = _run("crossing")
    assert result.trace is not None
    name = "</script><script>alert(1)</script>"
    document = view_document(scenario, result.trace.lines, {"planner": name}, {})
    html = recorded_page(document)
    assert "</script><script>alert(1)" not in html
    embedded = html.split('data-encoding="json">', 1)[1].split("</script>", 1)[0]
    assert json.loads(embedded)["planner"] == name


def test_a_paused_pacer_holds_until_resumed_or_stepped() -> None:
    pacer = Pacer(None)
    pacer.start()
    pacer.pause()
    let_through: list[int] = []

    def loop() -> None:
        for step in range(3):
            pacer.wait_for_moment((step + 1) * 0.1)
            pacer.hold_while_paused()
            let_through.append(step)

    thread = threading.Thread(target=loop, daemon=True)
    thread.start()
    time.sleep(0.3)
    assert let_through == []  # held after its first step
    pacer.step()
    time.sleep(0.3)
    assert let_through == [0]  # one step, then held again
    pacer.resume()
    thread.join(timeout=5)
    assert let_through == [0, 1, 2]


def test_a_pacer_keeps_the_speed_and_lets_a_stop_through() -> None:
    pacer = Pacer(10.0)
    pacer.start()
    started = time.monotonic()
    pacer.wait_for_moment(1.0)  # one simulated second at 10x
    assert time.monotonic() - started == pytest.approx(0.1, abs=0.05)
    stop = threading.Event()
    pacer.stopped = stop.is_set
    pacer.pause()
    threading.Timer(0.2, stop.set).start()
    started = time.monotonic()
    pacer.hold_while_paused()  # a stop asked for lets a paused run end
    assert time.monotonic() - started < 1.0


@pytest.mark.parametrize(("text", "speed"), [("1", 1.0), ("0.25", 0.25), ("max", None), ("1000", 1000.0)])
def test_speeds_parse(text: str, speed: float | None) -> None:
    assert parse_speed(text) == speed


@pytest.mark.parametrize("text", ["0", "-1", "1001", "fast", "nan", "inf"])
def test_bad_speeds_are_refused(text: str) -> None:
    with pytest.raises(ValueError, match=r"must be a multiple of real time from 0.01 to 1000, or 'max'"):
        parse_speed(text)
