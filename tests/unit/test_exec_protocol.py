"""The planner protocol's messages: shipped schemas, encoders that match them, fleet updates."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
from pathlib import Path

import jsonschema
import pytest
from hypothesis import given
from hypothesis import strategies as st

import fleetsim.sim.loop as loop
from fleetsim import load_scenario, load_suite
from fleetsim.enums import Disturbed, Progress
from fleetsim.exec import SubprocessPlanner
from fleetsim.exec.client import ProtocolError, _Session
from fleetsim.exec.protocol import (
    FleetEncoder,
    LegBook,
    decode_plan,
    decode_response,
    dumps,
    encode_fleet,
    encode_init,
    encode_plan,
    encode_task,
    loads,
)
from fleetsim.exec.rounds import RoundAnswerError, nothing_changed, read_round_answer
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.controller import ROUND_CALLS, FleetController
from fleetsim.planning.plans import FleetPlan, RouteError
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.guard import PlannerFault, PlannerGuard
from fleetsim.sim.loop import run_scenario

ROOT = Path(__file__).resolve().parents[2]
NAMES = ("init", "ready", "request", "response", "round-answer", "dispatch-answer")


def schema(name: str) -> dict:
    return json.loads((ROOT / "schemas" / f"planner-{name}.schema.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", NAMES)
def test_the_shipped_schema_is_the_packaged_one_and_valid(name: str) -> None:
    packaged = ROOT / "fleetsim" / "schemas" / f"planner-{name}.schema.json"
    assert json.loads(packaged.read_text(encoding="utf-8")) == schema(name)
    jsonschema.Draft202012Validator.check_schema(schema(name))


def crossing():  # type: ignore[no-untyped-def]
    suite = load_suite(ROOT / "scenario_suites" / "examples.fleetsim.yaml")
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == "crossing"), suite)


def test_init_and_requests_match_their_schemas_and_updates_carry_only_changes() -> None:
    scenario = crossing()
    controller = FleetController(scenario)
    first = controller.snapshot(0.0)
    jsonschema.validate(encode_init(scenario.layout, first), schema("init"))
    full = encode_fleet(first)
    task = scenario.tasks[0]
    jsonschema.validate(
        {"type": "plan_routes", "id": 1, "vehicle": task.vehicle_id, "task": encode_task(task), "fleet": full},
        schema("request"),
    )
    assert [v["id"] for v in full["vehicles"]] == sorted(v.id for v in scenario.vehicles)

    moved = controller.states[task.vehicle_id]._replace(x=123.0)
    controller.set_state(moved)
    second = controller.snapshot(0.1)
    update = encode_fleet(second, first)
    jsonschema.validate(
        {"type": "fix_legs", "id": 2, "vehicle": task.vehicle_id, "task": encode_task(task), "fleet": update},
        schema("request"),
    )
    assert [v["id"] for v in update["vehicles"]] == [task.vehicle_id]
    assert update["plans"] == [] and update["tasks"] == [] and update["time"] == 0.1


# What inspect adds around the layout: about the map file, and its station sets (which a scenario's
# orders draw from, and which reach a dispatcher as its orders' stops, not through the planner's layout).
MAP_FILE_KEYS = {"map", "format", "part", "meters_per_pixel", "lint", "warnings", "stations"}


@pytest.mark.parametrize(
    ("suite", "name", "map_options"),
    [
        ("examples.fleetsim.yaml", "crossing", []),
        ("sites.fleetsim.yaml", "packing-hall-lif", ["--layout", "hall-ground", "--robot-type", "Acme.Tug"]),
        ("sites.fleetsim.yaml", "clinic-rmf", ["--level", "L1", "--graph", "0"]),
    ],
)
def test_the_init_layout_is_exactly_the_layout_fleetsim_inspect_json_prints(
    suite: str, name: str, map_options: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    from fleetsim.cli import main

    loaded = load_suite(ROOT / "scenario_suites" / suite)
    spec = next(spec for spec in loaded.scenarios if spec.name == name)
    scenario = load_scenario(spec, loaded)
    layout = scenario.layout
    settings = [
        "--radius", repr(layout.vehicle_radius), "--safety-margin", repr(layout.safety_margin),
        "--conflict-model", layout.conflict_model.value, "--connection-tolerance", repr(layout.connection_tolerance),
        "--joint-angle-tolerance", repr(layout.joint_angle_tolerance),
    ]  # fmt: skip
    assert main(["inspect", str(spec.map_path), "--json", *settings, *map_options]) == 0
    inspected = json.loads(capsys.readouterr().out)
    init = json.loads(dumps(encode_init(layout, FleetController(scenario).snapshot(0.0))))

    assert set(inspected) - set(init["layout"]) == MAP_FILE_KEYS
    assert init["layout"] == {key: value for key, value in inspected.items() if key not in MAP_FILE_KEYS}
    assert all("names" in segment for segment in init["layout"]["segments"])
    if name != "crossing":  # a LIF edge's id, an RMF lane's waypoints: sites name their segments
        assert any(segment["names"] for segment in init["layout"]["segments"])


def test_a_served_planner_gets_the_segments_names_and_a_1_2_init_without_them_still_loads() -> None:
    loaded = load_suite(ROOT / "scenario_suites" / "sites.fleetsim.yaml")
    scenario = load_scenario(next(s for s in loaded.scenarios if s.name == "packing-hall-lif"), loaded)
    init = json.loads(dumps(encode_init(scenario.layout, FleetController(scenario).snapshot(0.0))))
    assert _Session(init).layout.segments == scenario.layout.segments  # names included
    for segment in init["layout"]["segments"]:
        del segment["names"]
    older = _Session({**init, "protocol": "fleetsim-planner/1.2"})
    assert [s.names for s in older.layout.segments.values()] == [() for _ in scenario.layout.segments]


def test_an_update_names_the_vehicles_that_changed_whatever_order_the_fleets_list_them_in() -> None:
    # Two snapshots of a run list the vehicles in the same order (compared value by value); fleets put
    # together otherwise are compared vehicle by vehicle, with the same result. A value replaced by an
    # equal one is no change.
    controller = FleetController(crossing())
    first = controller.snapshot(0.0)
    plan = controller.plans[2]
    controller.set_state(controller.states[1]._replace(x=-4.5))
    controller.set_plan(type(plan)(2, plan.legs + plan.legs[-1:]))
    controller.set_plan(type(plan)(1, controller.plans[1].legs))  # an equal plan, another object
    second = controller.snapshot(0.1)
    in_order = encode_fleet(second, first)
    reordered = dataclasses.replace(
        first,
        vehicles=dict(reversed(first.vehicles.items())),
        plans=dict(reversed(first.plans.items())),
    )
    assert list(reordered.plans) != list(second.plans)
    assert encode_fleet(second, reordered) == in_order
    assert [v["id"] for v in in_order["vehicles"]] == [1]
    assert [p["vehicle_id"] for p in in_order["plans"]] == [2]


def test_the_routed_set_is_encoded_again_only_when_it_is_another() -> None:
    controller = FleetController(crossing())
    encoder = FleetEncoder()
    first = controller.snapshot(0.0)
    assert loads(encoder.encode(first))["routed"] == []
    task = controller.tasks.head(1)
    assert task is not None
    routing = type(controller.plans[1])(
        1, tuple(dataclasses.replace(leg, goal_for_task=task.id) for leg in controller.plans[1].legs[:1])
    )
    controller.tasks.mark_routed(routing)
    second = controller.snapshot(0.1)
    assert second.routed is not first.routed
    assert loads(encoder.encode(second, first))["routed"] == [task.id]
    assert loads(encoder.encode(controller.snapshot(0.2), second))["routed"] == [task.id]


def test_the_python_client_keeps_the_fleet_by_vehicle_id_across_updates() -> None:
    scenario = crossing()
    controller = FleetController(scenario)
    first = controller.snapshot(0.0)
    session = _Session(json.loads(json.dumps(encode_init(scenario.layout, first))))
    rebuilt = session.snapshot(json.loads(json.dumps(encode_fleet(first))))
    assert dict(rebuilt.vehicles) == dict(first.vehicles) and dict(rebuilt.plans) == dict(first.plans)
    kept_plans = dict(rebuilt.plans)
    moved = controller.states[1]._replace(x=-4.5, speed=1.25)
    controller.set_state(moved)
    second = controller.snapshot(0.1)
    updated = session.snapshot(json.loads(json.dumps(encode_fleet(second, first))))
    assert dict(updated.vehicles) == dict(second.vehicles)
    assert all(updated.plans[vid] is kept_plans[vid] for vid in kept_plans), "unchanged plans stay the same objects"
    assert session.layout.connections == scenario.layout.connections


def test_an_answer_decodes_to_plans_then_route_errors_and_a_request_error_is_raised() -> None:
    plan = {
        "vehicle_id": 1,
        "legs": [{"segment": 1, "traverse": "forward", "progress": "reverse", "fixed": True, "goal_for_task": None}],
    }
    items = decode_response({"id": 1, "plans": [plan], "route_errors": [{"vehicle_id": 2, "message": "blocked"}]})
    assert isinstance(items[0], FleetPlan) and items[0].legs[0].progress.value == "reverse"
    assert items[1] == RouteError(2, "blocked")
    with pytest.raises(RouteError, match="no way through"):
        decode_response({"id": 1, "route_error": "no way through"})


def test_a_served_planner_answers_like_the_planner_itself() -> None:
    scenario = crossing()
    controller = FleetController(scenario)
    fleet = controller.snapshot(0.0)
    session = _Session(json.loads(json.dumps(encode_init(scenario.layout, fleet))))
    task = scenario.tasks[0]
    request = {
        "type": "plan_routes",
        "id": 1,
        "vehicle": task.vehicle_id,
        "task": encode_task(task),
        "fleet": encode_fleet(fleet),
    }
    answer = session.answer(ReservingPlanner(), json.loads(json.dumps(request)))
    jsonschema.validate(answer, schema("response"))
    assert decode_response(answer) == list(ReservingPlanner().plan_routes(task, fleet, scenario.layout))


def test_the_disturbed_field_travels_only_while_set_and_protocol_1_0_clients_are_still_greeted() -> None:
    scenario = crossing()
    controller = FleetController(scenario)
    first = controller.snapshot(0.0)
    init = json.loads(json.dumps(encode_init(scenario.layout, first)))
    assert init["protocol"] == "fleetsim-planner/1.5"
    assert all("disturbed" not in v for v in encode_fleet(first)["vehicles"])  # as in 1.0 when undisturbed
    session = _Session(init)
    session.snapshot(json.loads(json.dumps(encode_fleet(first))))
    controller.set_state(controller.states[1]._replace(disturbed=Disturbed.STOPPED))
    second = controller.snapshot(0.1)
    update = json.loads(json.dumps(encode_fleet(second, first)))
    assert update["vehicles"][0]["disturbed"] == "stopped"
    jsonschema.validate(
        {"type": "fix_legs", "id": 2, "vehicle": 1, "task": encode_task(scenario.tasks[0]), "fleet": update},
        schema("request"),
    )
    assert session.snapshot(update).vehicles[1].disturbed is Disturbed.STOPPED
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({**update["vehicles"][0], "disturbed": "late"}, schema("request")["$defs"]["vehicle_state"])
    _Session({**init, "protocol": "fleetsim-planner/1"})  # the same major version
    with pytest.raises(ProtocolError):
        _Session({**init, "protocol": "fleetsim-planner/2.0"})


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_floats_travel_exactly_whoever_writes_them(value: float) -> None:
    # fleetsim writes with orjson; other clients write what their JSON library gives (Python's json
    # module: repr). Either way the same float arrives, so served planners decide as in process.
    assert loads(dumps(value)) == value and loads(json.dumps(value)) == value
    assert json.loads(dumps(value)) == value


def test_the_fleet_encoder_writes_the_same_document_and_keeps_each_plans_json() -> None:
    scenario = crossing()
    controller = FleetController(scenario)
    first = controller.snapshot(0.0)
    encoder = FleetEncoder()
    assert loads(encoder.encode(first)) == encode_fleet(first)
    assert {vid: (plan, dumps(encode_plan(plan))) for vid, plan in first.plans.items()} == encoder.plans
    controller.set_state(controller.states[1]._replace(x=-4.5))
    plan = first.plans[2]
    controller.set_plan(type(plan)(2, plan.legs + plan.legs[-1:]))
    second = controller.snapshot(0.1)
    assert loads(encoder.encode(second, first)) == encode_fleet(second, first)
    assert encoder.plans[2] == (second.plans[2], dumps(encode_plan(second.plans[2])))
    nothing = loads(encoder.encode(second, second))
    assert (nothing["vehicles"], nothing["plans"], nothing["tasks"]) == ([], [], [])


class _HandBack:
    """Answers every call with the vehicle's plan in force, or with one more leg on it (``grow``)."""

    def __init__(self, grow: bool = False) -> None:
        self.grow = grow

    def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        plan = fleet.plans[task.vehicle_id]
        return [type(plan)(plan.vehicle_id, plan.legs + plan.legs[-1:]) if self.grow else plan]

    fix_legs = plan_routes


def test_the_python_client_answers_a_plan_handed_back_unchanged_as_nothing_to_change() -> None:
    scenario = crossing()
    fleet = FleetController(scenario).snapshot(0.0)
    session = _Session(loads(dumps(encode_init(scenario.layout, fleet))))
    task = scenario.tasks[0]
    request = {"type": "fix_legs", "id": 7, "vehicle": task.vehicle_id, "task": encode_task(task)}
    unchanged = session.answer(_HandBack(), loads(dumps({**request, "fleet": encode_fleet(fleet)})))
    assert unchanged == {"id": 7, "plans": [], "route_errors": []}
    grown = session.answer(_HandBack(grow=True), request)
    [plan] = decode_response(grown)
    assert isinstance(plan, FleetPlan) and len(plan.legs) == len(fleet.plans[task.vehicle_id].legs) + 1


# -- planning rounds in one message (1.2) ---------------------------------------------------------------


def _round_message(calls, fleet=None):  # type: ignore[no-untyped-def]
    message = {
        "type": "round",
        "calls": [
            {"type": method, "id": number, "vehicle": task.vehicle_id, "task": encode_task(task)}
            for number, (method, task) in enumerate(calls, start=1)
        ],
    }
    if fleet is not None:
        message["fleet"] = encode_fleet(fleet)
    return loads(dumps(message))


def test_the_python_client_answers_a_round_up_to_its_first_change_and_asks_for_rounds_from_1_2_on() -> None:
    scenario = crossing()
    fleet = FleetController(scenario).snapshot(0.0)
    init = loads(dumps(encode_init(scenario.layout, fleet)))
    session = _Session(init)
    assert session.speaks_rounds
    assert not _Session({**init, "protocol": "fleetsim-planner/1.1"}).speaks_rounds
    assert not _Session({**init, "protocol": "fleetsim-planner/1"}).speaks_rounds
    first, second = scenario.tasks[0], scenario.tasks[1]
    calls = [("fix_legs", first), ("fix_legs", second), ("fix_legs", first)]
    message = _round_message(calls, fleet)
    jsonschema.validate(message, schema("request"))
    nothing = session.answer_round(_HandBack(), message)  # every plan handed back: nothing to change
    jsonschema.validate(nothing, schema("round-answer"))
    assert nothing["answers"] == [{"id": n, "plans": [], "route_errors": []} for n in (1, 2, 3)]
    assert len(nothing["durations"]) == 3 and all(seconds >= 0 for seconds in nothing["durations"])
    changed = session.answer_round(_HandBack(grow=True), {"type": "round", "calls": message["calls"]})  # same fleet
    assert len(changed["answers"]) == len(changed["durations"]) == 1, "it stops after the first change"
    [plan] = decode_response(changed["answers"][0])
    assert isinstance(plan, FleetPlan) and plan.vehicle_id == first.vehicle_id
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({**message, "calls": []}, schema("request"))


class _Recorded(SubprocessPlanner):
    """A planner process that is not started: what it is sent is kept, and every call answered with nothing."""

    def __init__(self) -> None:
        super().__init__(["unused"])
        self.sent: list[bytes] = []
        self._process = object()  # type: ignore[assignment]
        self.rounds = True

    def _send(self, message: bytes) -> None:
        self.sent.append(message)

    def _read_line(self, timeout: float | None) -> bytes:
        first = self.requests + 1
        calls = len(loads(self.sent[-1])["calls"])
        nothing = [{"id": n, "plans": [], "route_errors": []} for n in range(first, first + calls)]
        return dumps({"answers": nothing, "durations": [0.0] * calls})


def test_a_rounds_calls_are_written_as_each_call_on_its_own_would_be() -> None:
    scenario = crossing()
    fleet = FleetController(scenario).snapshot(0.0)
    task = scenario.tasks[0]
    zero = dataclasses.replace(task, id=0, goal_progress=Progress.REVERSE)  # "id":0 twice in its call
    again = dataclasses.replace(task)  # the same id, another task: encoded anew
    calls = [
        ("fix_legs", task.vehicle_id, task),
        ("plan_routes", task.vehicle_id, task),
        ("fix_legs", zero.vehicle_id, zero),
        ("plan_routes", task.vehicle_id + 1, task),  # a vehicle asked about another's task
        ("fix_legs", again.vehicle_id, dataclasses.replace(again, goal_segment=again.goal_segment + 1)),
    ]
    process = _Recorded()
    for _ in range(2):  # the second round uses what the first kept
        process.plan_round(calls, fleet, scenario.layout)
    for round_number, message in enumerate(process.sent):
        first = 1 + round_number * len(calls)
        expected = [
            {"type": method, "id": first + index, "vehicle": vehicle, "task": encode_task(asked)}
            for index, (method, vehicle, asked) in enumerate(calls)
        ]
        assert loads(message)["calls"] == expected
        assert message.startswith(b'{"type":"round","calls":[' + b",".join(dumps(call) for call in expected) + b"]")


def test_a_round_answered_with_nothing_to_change_is_recognised_by_its_bytes_as_the_clients_spell_it() -> None:
    scenario = crossing()
    fleet = FleetController(scenario).snapshot(0.0)
    init = loads(dumps(encode_init(scenario.layout, fleet)))
    calls = [("fix_legs", task) for task in scenario.tasks[:2]]
    # The Python client's spelling (orjson, compact) and JSON.stringify's (the Node.js example) are the same.
    answer = _Session(init).answer_round(_HandBack(), _round_message(calls, fleet))
    line = dumps(answer)
    compact = json.dumps(answer, separators=(",", ":")).encode()  # JSON.stringify's spelling, floats aside
    assert line.partition(b'"durations"')[0] == compact.partition(b'"durations"')[0]
    assert nothing_changed(compact, 1, 2) == answer["durations"]
    assert nothing_changed(line, 1, 2) == answer["durations"]
    nothing = [{"id": n, "plans": [], "route_errors": []} for n in (1, 2)]
    refused = {
        "another round's ids": (dumps({"answers": nothing, "durations": [0.5, 0.25]}), 2, 2),
        "fewer answers than calls": (dumps({"answers": nothing, "durations": [0.5, 0.25]}), 1, 3),
        "more durations": (dumps({"answers": nothing, "durations": [0.5, 0.25, 0.1]}), 1, 2),
        "fewer durations": (dumps({"answers": nothing, "durations": [0.5]}), 1, 2),
        "a whole-number duration": (dumps({"answers": nothing, "durations": [0.5, 0]}), 1, 2),
        "a negative duration": (dumps({"answers": nothing, "durations": [0.5, -0.25]}), 1, 2),
        "another key after them": (dumps({"answers": nothing, "durations": [0.5, 0.25], "x": 1}), 1, 2),
        "spaces": (json.dumps({"answers": nothing, "durations": [0.5, 0.25]}).encode(), 1, 2),
        "a plan": (dumps({"answers": [nothing[0], {**nothing[1], "plans": [encode_plan(fleet.plans[1])]}],
                          "durations": [0.5, 0.25]}), 1, 2),
        "cut short": (dumps({"answers": nothing, "durations": [0.5, 0.25]})[:-2], 1, 2),
        "not JSON after all": (dumps({"answers": nothing, "durations": [0.5, 0.25]})[:-1] + b"]", 1, 2),
    }  # fmt: skip
    for case, (other, first, count) in refused.items():
        assert nothing_changed(other, first, count) is None, case
    assert nothing_changed(dumps({"answers": nothing, "durations": [0.5, 0.25]}), 1, 2) == [0.5, 0.25]


def test_a_round_answer_is_checked_against_its_round() -> None:
    scenario = crossing()
    fleet = FleetController(scenario).snapshot(0.0)
    calls = [("fix_legs", task.vehicle_id, task) for task in scenario.tasks[:2]]
    nothing = [{"id": n, "plans": [], "route_errors": []} for n in (5, 6)]
    assert read_round_answer({"answers": nothing, "durations": [0.5, 1]}, 5, calls, fleet) == [([], 0.5), ([], 1)]
    plan = encode_plan(fleet.plans[1])
    handed_back = [{"id": 5, "plans": [plan], "route_errors": []}, nothing[1]]
    assert [
        answer for answer, _ in read_round_answer({"answers": handed_back, "durations": [0.0, 0.0]}, 5, calls, fleet)
    ] == [[fleet.plans[1]], []]
    [(error, _)] = read_round_answer(
        {"answers": [{"id": 5, "route_error": "no way"}], "durations": [0.0]}, 5, calls, fleet
    )
    assert error == RouteError(None, "no way")
    wrong = {
        "durations[1]: 'late' is not of type 'number'": {"answers": nothing, "durations": [0.0, "late"]},
        "2 answers and 1 durations": {"answers": nothing, "durations": [0.0]},
        "3 answers to a round of 2 calls": {"answers": [*nothing, nothing[0]], "durations": [0.0] * 3},
        "the answer to request 6 in place of request 5's (answers[0])": {
            "answers": nothing[::-1],
            "durations": [0.0] * 2,
        },
        "answers[0] (request 5) changing something": {
            "answers": [{"id": 5, "route_error": "no way"}, nothing[1]],
            "durations": [0.0] * 2,
        },
        "[] should be non-empty": {"answers": [], "durations": []},
        "answers[1].plans[0]": {
            "answers": [nothing[0], {**nothing[1], "plans": [{"legs": []}]}],
            "durations": [0.0] * 2,
        },
    }
    for message, answer in wrong.items():
        with pytest.raises(RoundAnswerError) as raised:
            read_round_answer(answer, 5, calls, fleet)
        assert message in str(raised.value), (message, str(raised.value))


class _InProcessRounds:
    """A planner answering rounds in process, as the Python client does: in order, up to the first change."""

    rounds = True

    def __init__(self, planner: ReservingPlanner) -> None:
        self.planner = planner
        self.plan_routes, self.fix_legs = planner.plan_routes, planner.fix_legs
        self.asked: list[int] = []

    def plan_round(self, calls, fleet, layout):  # type: ignore[no-untyped-def]
        self.asked.append(len(calls))
        answers = []
        for method, _vehicle, task in calls:
            try:
                response = list(getattr(self.planner, method)(task, fleet, layout))
            except RouteError as error:
                answers.append((error, 0.0))
                break
            answers.append((response, 0.0))
            if response and not (len(response) == 1 and response[0] == fleet.plans.get(response[0].vehicle_id)):
                break
        return answers


@pytest.mark.parametrize("name", ["crossing", "loop-one-way", "mixed-shapes"])
def test_a_planner_asked_in_rounds_makes_the_same_run_as_one_call_at_a_time(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    suite = load_suite(ROOT / "scenario_suites" / "examples.fleetsim.yaml")
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)
    monkeypatch.setattr(loop._Run, "quiet", False)  # (rounds ask every vehicle: the same calls, one by one)
    direct = run_scenario(scenario, ReservingPlanner())
    rounds = _InProcessRounds(ReservingPlanner())
    asked = run_scenario(scenario, rounds)  # type: ignore[arg-type]
    assert (asked.status, asked.trace_hash) == (direct.status, direct.trace_hash)
    assert asked.metrics.planner_calls == direct.metrics.planner_calls
    assert len(rounds.asked) < direct.metrics.planner_calls, "some rounds answered several calls"


def test_a_planner_with_an_unrelated_rounds_attribute_is_called_one_call_at_a_time() -> None:
    scenario = crossing()
    planner = ReservingPlanner()
    planner.rounds = 3  # type: ignore[attr-defined]  # say, how many rounds it has seen
    assert run_scenario(scenario, planner).trace_hash == run_scenario(scenario, ReservingPlanner()).trace_hash


def test_the_guard_counts_a_rounds_calls_and_holds_each_to_the_per_call_timeout() -> None:
    scenario = crossing()
    fleet = FleetController(scenario).snapshot(0.0)
    calls = [("fix_legs", task.vehicle_id, task) for task in scenario.tasks[:2]]
    guard = PlannerGuard(timeout=5.0)
    assert guard.round(lambda *_: [([], 0.001), ([], 4.0)], calls, fleet, scenario.layout) == [[], []]
    assert guard.calls == 2
    with pytest.raises(
        PlannerFault, match=r"fix_legs\(\) for vehicle 2 did not return within the per-call timeout of 5 s"
    ):
        guard.round(lambda *_: [([], 0.001), ([], 5.5)], calls, fleet, scenario.layout)

    def failing(*_: object) -> list[object]:
        raise ValueError("bad")

    with pytest.raises(
        PlannerFault,
        match=r"a round of 2 planner calls \(the first fix_legs\(\) for vehicle 1\) raised ValueError: bad",
    ):
        guard.round(failing, calls, fleet, scenario.layout)


def test_a_round_holds_at_most_round_calls_calls_so_a_hang_is_noticed_in_bounded_time(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("warehouse", ROOT / "benchmarks" / "warehouse.py")
    assert spec is not None and spec.loader is not None
    warehouse = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(warehouse)
    folder = warehouse.write_fleet_scenario(tmp_path / "fleet", 20, seed=1)
    scenario = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=3.0, stop_on=()))
    rounds = _InProcessRounds(ReservingPlanner())
    asked = run_scenario(scenario, rounds)  # type: ignore[arg-type]
    assert max(rounds.asked) == ROUND_CALLS < 20  # 20 busy vehicles: the first rounds are cut at the cap
    assert asked.trace_hash == run_scenario(scenario, ReservingPlanner()).trace_hash


# -- legs decoded once per run (LegBook) ------------------------------------------------------------------


def _leg_json(segment: object, fixed: bool = True, goal: object = None) -> dict[str, object]:
    return {"segment": segment, "traverse": "forward", "progress": "reverse", "fixed": fixed, "goal_for_task": goal}


def test_a_leg_seen_again_is_the_same_object_and_plans_decode_equal_with_or_without_the_book() -> None:
    book = LegBook()
    data = {"vehicle_id": 3, "legs": [_leg_json(5), _leg_json(6, fixed=False, goal=2)]}
    first, again = decode_plan(data, book), decode_plan(data, book)
    assert first == again == decode_plan(data)
    assert all(a is b for a, b in zip(first.legs, again.legs, strict=True))
    assert decode_plan({"vehicle_id": 3, "legs": [_leg_json(5, fixed=False)]}, book).legs[0] is not first.legs[0]


def test_a_leg_book_starts_afresh_at_its_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(LegBook, "LIMIT", 2)
    book = LegBook()
    kept = book.leg(_leg_json(1))
    book.leg(_leg_json(2))
    assert book.leg(_leg_json(1)) is kept
    book.leg(_leg_json(3))  # the third distinct leg: the book is emptied first
    assert book.leg(_leg_json(1)) is not kept


def test_a_leg_the_book_cannot_key_exactly_is_made_and_refused_as_without_it() -> None:
    book = LegBook()
    book.leg(_leg_json(1))
    with pytest.raises(TypeError, match=r"segment=1\.0 must be an int"):
        book.leg(_leg_json(1.0))
    with pytest.raises(TypeError, match=r"goal_for_task=2\.0 must be an int"):
        book.leg(_leg_json(1, goal=2.0))
