"""The planner protocol's messages: shipped schemas, encoders that match them, fleet updates."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fleetsim import load_scenario, load_suite
from fleetsim.enums import Disturbed
from fleetsim.exec.client import ProtocolError, _Session
from fleetsim.exec.protocol import (
    FleetEncoder,
    decode_response,
    dumps,
    encode_fleet,
    encode_init,
    encode_plan,
    encode_task,
    loads,
)
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.controller import FleetController
from fleetsim.planning.plans import FleetPlan, RouteError

ROOT = Path(__file__).resolve().parents[2]
NAMES = ("init", "ready", "request", "response")


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
    assert init["protocol"] == "fleetsim-planner/1.1"
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
