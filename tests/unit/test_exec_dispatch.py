"""The dispatcher's messages of the planner protocol (1.5): boards, assignments, tasks made from orders."""

from __future__ import annotations

import io
import json
from collections.abc import Sequence
from pathlib import Path
from types import MappingProxyType
from typing import Any

import jsonschema
import pytest
from dispatch_support import ORDERS, FirstIdle, Scripted, scenario, with_period

from fleetsim.dispatch.protocol import Assignment, OpenOrder, OrderBoard
from fleetsim.enums import Progress
from fleetsim.exec.client import _Session, serve
from fleetsim.exec.dispatching import (
    BoardEncoder,
    BoardReader,
    decode_assignments,
    encode_assignments,
    encode_board,
)
from fleetsim.exec.protocol import FleetEncoder, dumps, encode_fleet, encode_init, encode_task, loads
from fleetsim.orders import Order, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.controller import FleetController
from fleetsim.scenario import Task
from fleetsim.sim.loop import run_scenario

ROOT = Path(__file__).resolve().parents[2]


def schema(name: str) -> dict[str, Any]:
    return json.loads((ROOT / "schemas" / f"planner-{name}.schema.json").read_text(encoding="utf-8"))


# Every field of a board away from its default: a started order with a stop served, vehicle types, a
# priority, a deadline, a stop's required progress and dwell; an order held and one waiting.
HELD = Order("h1", (Stop(7, Progress.REVERSE, 12.5), Stop(2)), 3.0, 250.0, ("agv", "tugger"), 2)
WAITING = Order("w2", (Stop(4, None, 0.0),), 0.0)
BOARD = OrderBoard(
    time=41.3,
    why=("release", "period"),
    orders=MappingProxyType({
        "h1": OpenOrder(HELD, 1, True, 1, 3.0),
        "w2": OpenOrder(WAITING, None, False, 0, 40.0),
    }),
    sequences=MappingProxyType({1: ("h1",), 2: ()}),
    idle=(2,),
)  # fmt: skip


def _request(number: int, board: OrderBoard, fleet: dict[str, Any] | None = None) -> dict[str, Any]:
    request: dict[str, Any] = {"type": "dispatch", "id": number, "board": loads(BoardEncoder().encode(board))}
    if fleet is not None:
        request["fleet"] = fleet
    return request


def test_a_board_travels_as_the_same_order_board_and_matches_the_request_schema() -> None:
    encoded = BoardEncoder().encode(BOARD)
    assert loads(encoded) == encode_board(BOARD)
    jsonschema.validate(_request(7, BOARD), schema("request"))
    assert BoardReader().board(json.loads(encoded)) == BOARD
    held = loads(encoded)["orders"][0]
    assert held["stops"][0] == {"segment": 7, "progress": "reverse", "dwell": 12.5}
    assert (held["vehicle_types"], held["priority"], held["deadline"]) == (["agv", "tugger"], 2, 250.0)
    with pytest.raises(jsonschema.ValidationError):  # narrowly not: a reason the dispatcher is never asked for
        jsonschema.validate(
            {**_request(7, BOARD), "board": {**encode_board(BOARD), "why": ["bored"]}}, schema("request")
        )


def test_every_board_of_a_run_arrives_equal_and_an_open_order_stays_the_same_object() -> None:
    shown = Scripted(lambda board: FirstIdle().dispatch(board, None, None))
    run_scenario(with_period(ORDERS, 5.0), ReservingPlanner(), dispatcher=shown)
    assert len(shown.boards) >= 5
    encoder, reader = BoardEncoder(), BoardReader()
    read = [reader.board(loads(encoder.encode(board))) for board in shown.boards]
    assert read == shown.boards
    first, second = read[0], read[1]
    kept = set(first.orders) & set(second.orders)
    assert kept and all(first.orders[oid].order is second.orders[oid].order for oid in kept)


def test_assignments_travel_in_their_order_and_the_answer_schema_holds_them() -> None:
    assignments = [Assignment(2, ("w2", "h1")), Assignment(1, ())]
    answer = encode_assignments(9, assignments)
    jsonschema.validate(answer, schema("dispatch-answer"))
    assert decode_assignments(json.loads(json.dumps(answer))) == assignments
    for garbage in (
        {"id": 9, "assignments": [{"vehicle_id": "2", "orders": ["w2"]}]},
        {"id": 9, "assignments": [{"vehicle_id": 2, "orders": "w2"}]},
        {"id": 9, "assignments": [{"vehicle_id": 2}]},
        {"id": 9},
    ):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(garbage, schema("dispatch-answer"))


def test_tasks_made_from_orders_carry_their_order_and_are_sent_once_as_new_tasks() -> None:
    loop = scenario()
    controller = FleetController(loop)
    first = controller.snapshot(0.0)
    encoder = FleetEncoder(loop.tasks)
    session = _Session(json.loads(dumps(encode_init(loop.layout, first))))
    session.snapshot(loads(encoder.encode(first)))
    pick = Task(1, 1, 7, Progress.FORWARD, "a", 0, 90.0)
    drop = Task(2, 1, 2, None, "a", 1, 90.0)
    controller.requeue(1, (), (pick, drop))
    second = controller.snapshot(0.1)
    update = loads(encoder.encode(second, first))
    assert update == encode_fleet(second, first, {task.id: task for task in loop.tasks})
    assert update["new_tasks"] == [encode_task(pick), encode_task(drop)]
    assert encode_task(pick) == {
        "id": 1, "vehicle_id": 1, "goal_segment": 7, "goal_progress": "forward",
        "order_id": "a", "stop": 0, "deadline": 90.0,
    }  # fmt: skip
    jsonschema.validate({"type": "plan_routes", "id": 1, "vehicle": 1, "task": encode_task(pick)}, schema("request"))
    jsonschema.validate(_request(1, BOARD, update), schema("request"))
    assert session.snapshot(update).tasks[1] == (pick, drop)
    controller.requeue(1, (2,), ())  # the queue changes again, with no task the process lacks
    third = controller.snapshot(0.2)
    later = loads(encoder.encode(third, second))
    assert later["tasks"] == [[1, [1]]] and "new_tasks" not in later
    assert "order_id" not in encode_task(Task(3, 1, 2))  # a task of tasks.csv: as before 1.5


class _Dispatching(ReservingPlanner):
    def __init__(self, answer: object = None) -> None:
        super().__init__()
        self.answer = answer
        self.boards: list[OrderBoard] = []

    def dispatch(self, board: OrderBoard, fleet: object, layout: object) -> object:
        self.boards.append(board)
        return FirstIdle().dispatch(board, fleet, layout) if self.answer is None else self.answer


def _served(planner: object, protocol: str, *messages: dict[str, Any]) -> tuple[int, list[Any], str]:
    """What ``serve`` answers to an init of ``protocol`` (a run of the loop with orders) and ``messages``:
    its exit status, its answers and what it wrote to stderr."""
    loop = scenario()
    init = {**encode_init(loop.layout, FleetController(loop).snapshot(0.0)), "protocol": protocol}
    stdin = io.BytesIO(b"".join(dumps(message) + b"\n" for message in (init, *messages)))
    stdout = io.StringIO()
    with pytest.MonkeyPatch.context() as patch:
        stderr = io.StringIO()
        patch.setattr("sys.stderr", stderr)
        status = serve(planner, stdin, stdout)  # type: ignore[arg-type]
    return status, [json.loads(line) for line in stdout.getvalue().splitlines()], stderr.getvalue()


@pytest.mark.parametrize(
    ("planner", "protocol", "says"),
    [
        (_Dispatching(), "fleetsim-planner/1.5", True),
        (_Dispatching(), "fleetsim-planner/1.4", False),  # an older fleetsim would refuse the word
        (ReservingPlanner(), "fleetsim-planner/1.5", False),  # no dispatch method
    ],
)
def test_the_python_client_says_it_dispatches_only_to_1_5_and_only_with_a_dispatch_method(
    planner: object, protocol: str, says: bool
) -> None:
    status, answers, _ = _served(planner, protocol)
    assert status == 0
    jsonschema.validate(answers[0], schema("ready"))
    assert answers[0].get("dispatches", False) is says


def test_the_python_client_answers_a_dispatch_request_as_the_dispatcher_answers_in_process() -> None:
    loop = scenario()
    fleet = FleetController(loop).snapshot(0.0)
    planner = _Dispatching()
    status, answers, _ = _served(planner, "fleetsim-planner/1.5", _request(3, BOARD, encode_fleet(fleet)))
    assert status == 0
    jsonschema.validate(answers[1], schema("dispatch-answer"))
    assert planner.boards == [BOARD]
    assert decode_assignments(answers[1]) == FirstIdle().dispatch(BOARD, fleet, loop.layout)
    assert answers[1]["id"] == 3


@pytest.mark.parametrize(
    ("answer", "said"),
    [
        ({"1": ["h1"]}, "dispatch() returned {'1': ['h1']}; it must return a list of Assignment items"),
        ([Assignment("1", ("h1",))], "dispatch() returned item 0 with vehicle_id='1'; it must be an int"),  # type: ignore[arg-type]
    ],
)
def test_a_served_dispatcher_that_returns_garbage_ends_the_process_saying_what_it_returned(
    answer: object, said: str
) -> None:
    fleet = encode_fleet(FleetController(scenario()).snapshot(0.0))
    status, answers, stderr = _served(_Dispatching(answer), "fleetsim-planner/1.5", _request(1, BOARD, fleet))
    assert status == 1 and len(answers) == 1  # the ready message, no answer
    assert said in stderr


def test_a_served_dispatcher_that_returns_assignments_the_rules_refuse_still_answers_them() -> None:
    # Narrowly not garbage: an unknown order is for the dispatcher's rules to refuse, as in process.
    fleet = encode_fleet(FleetController(scenario()).snapshot(0.0))
    wrong: Sequence[Assignment] = [Assignment(1, ("no-such-order",))]
    status, answers, _ = _served(_Dispatching(wrong), "fleetsim-planner/1.5", _request(1, BOARD, fleet))
    assert status == 0 and answers[1] == {"id": 1, "assignments": [{"vehicle_id": 1, "orders": ["no-such-order"]}]}


def test_a_dispatch_request_to_a_planner_without_dispatch_ends_the_process() -> None:
    fleet = encode_fleet(FleetController(scenario()).snapshot(0.0))
    status, _, stderr = _served(ReservingPlanner(), "fleetsim-planner/1.5", _request(1, BOARD, fleet))
    assert status == 1 and "the planner has no dispatch method" in stderr


def test_the_documented_dispatch_exchange_is_valid_protocol() -> None:
    page = (ROOT / "docs" / "other-languages.md").read_text(encoding="utf-8")
    section = page.split("## Dispatchers in other processes", 1)[1].split("\n## ", 1)[0]
    request, answer = (block.split("\n", 1)[1] for block in section.split("```json")[1:3])
    request = json.loads(request.split("\n```", 1)[0].replace(',"fleet":{...}', ""))
    answer = json.loads(answer.split("\n```", 1)[0])
    jsonschema.validate(request, schema("request"))
    jsonschema.validate(answer, schema("dispatch-answer"))
    board = BoardReader().board(request["board"])
    given = {order for assignment in decode_assignments(answer) for order in assignment.orders}
    assert given == {order.id for order in board.unassigned()}
