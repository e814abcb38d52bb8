"""Export is the inverse of import: the VDA 5050 orders ``fleetsim orders RUN`` writes for a recorded run,
decoded and read as a vehicle reads them (messages.decode_order, orders.read_order and join_order), give
back exactly the plans the run accepted; they pass the official validators of both versions, use the
map's node and edge ids (a LIF site's own), and the same run always exports the same bytes."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import official
import pytest

from fleetsim.cli.main import main
from fleetsim.cli.orders import ORDERS_FOLDER, add_orders_arguments, orders
from fleetsim.cli.recorded import RecordedRun, read_recorded_run
from fleetsim.cli.run import UsageError
from fleetsim.enums import Progress, Traverse
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import initial_plan, initial_state
from fleetsim.recording.replay import replay
from fleetsim.vda5050.export import ExportedOrder, ExportError, export_orders, order_document, order_line
from fleetsim.vda5050.messages import decode_order
from fleetsim.vda5050.model import VERSIONS, Order
from fleetsim.vda5050.orders import Join, OrderStatus, join_order, read_order
from fleetsim.vda5050.places import site_graph

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
EXAMPLES = ["crossing", "loop-one-way", "corridor-passing-bay", "mixed-shapes"]
LIF = "packing-hall-lif"
SCENARIOS = [*EXAMPLES, LIF]
PLANNER = "fleetsim.planners:ReservingPlanner"
TRAVERSE = {"f": Traverse.FORWARD, "b": Traverse.BACKWARD}
PROGRESS = {"f": Progress.FORWARD, "r": Progress.REVERSE}


# Runs of other kinds, for the round trip: a planner whose run fails (the greedy one deadlocks in the
# corridor), and an Open-RMF site with random stops.
GREEDY = "greedy-corridor"
CLINIC = "random-stops-in-the-clinic"
ROUND_TRIPS = [*SCENARIOS, GREEDY, CLINIC]


def _record(root: Path, planner: str, *suites: str) -> None:
    assert main(["run", *suites, "--planner", planner, "--record", str(root)]) in (0, 1)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Run folders recorded by ``fleetsim run --record``: the example scenarios and the LIF site with the
    reserving planner, and the other runs above."""
    root = tmp_path_factory.mktemp("runs")
    _record(root, PLANNER, str(SUITES / "examples.fleetsim.yaml"), f"{SUITES / 'sites.fleetsim.yaml'}::{LIF}")
    _record(
        root / "greedy", "fleetsim.planners:GreedyPlanner", f"{SUITES / 'examples.fleetsim.yaml'}::corridor-passing-bay"
    )
    _record(root, PLANNER, f"{SUITES / 'disturbances.fleetsim.yaml'}::{CLINIC}")
    folders = {name: root / "examples" / name for name in EXAMPLES} | {
        LIF: root / "sites" / LIF,
        GREEDY: root / "greedy" / "examples" / "corridor-passing-bay",
        CLINIC: root / "disturbances" / CLINIC,
    }
    assert all((folder / "trace.jsonl").is_file() for folder in folders.values())
    assert json.loads((folders[GREEDY] / "result.json").read_text())["status"] == "failed"
    return folders


def _run(folder: Path) -> RecordedRun:
    return read_recorded_run(folder, None)


def _drive(legs: tuple[FleetLeg, ...]) -> list[tuple[Any, ...]]:
    return [(leg.segment, leg.traverse, leg.progress, leg.fixed) for leg in legs]


def _accepted(run: RecordedRun) -> Iterator[tuple[int, FleetPlan, FleetPlan]]:
    """From the trace itself: each accepted plan with its step and the plan the vehicle had before it."""
    scenario = run.scenario
    plans = {v.id: initial_plan(v) for v in scenario.vehicles}
    for line, frame in zip(run.lines[1:], replay(scenario, run.lines), strict=True):
        step, _, accepted, _ = json.loads(line)
        for vehicle_id, legs in accepted:
            drives = tuple(FleetLeg(s, TRAVERSE[t], PROGRESS[p], bool(f)) for s, t, p, f, _ in legs)
            yield step, FleetPlan(vehicle_id, drives), plans[vehicle_id]
        plans = dict(frame.plans)


def _wire(exported: ExportedOrder, version: str) -> Order:
    """The order as a vehicle receives it: the exported line's message, decoded."""
    message = json.loads(order_line(exported))["message"]
    return decode_order(json.dumps(message).encode("utf-8"), version)


def _read_back(
    run: RecordedRun, version: str, exported: list[ExportedOrder]
) -> list[tuple[Join, FleetPlan | None, tuple[Any, ...]]]:
    """Every exported order joined, in turn, by the vehicle it is for, as :func:`join_order` does it."""
    scenario = run.scenario
    graph = site_graph(scenario.layout, map_id=scenario.name)
    vehicles = {v.id: v for v in scenario.vehicles}
    status = {v: OrderStatus() for v in vehicles}
    joined = []
    for (_, _, before), item in zip(_accepted(run), exported, strict=True):
        order = _wire(item, version)
        vehicle = vehicles[item.vehicle_id]
        reading = read_order(order, graph, scenario.layout, vehicle.type, vehicle.progress)
        join, plan, errors = join_order(order, reading, status[vehicle.id], before, graph)
        joined.append((join, plan, errors + reading.problems))
        stitch = max((node for node in order.nodes if node.released), key=lambda node: node.sequence_id)
        status[vehicle.id] = OrderStatus(order.order_id, order.order_update_id, stitch.node_id, stitch.sequence_id)
    return joined


# -- the round trip ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ROUND_TRIPS)
@pytest.mark.parametrize("version", ["2.0", "2.1"])
def test_every_exported_order_reads_back_as_the_plan_fleetsim_accepted(
    recorded: dict[str, Path], name: str, version: str
) -> None:
    run = _run(recorded[name])
    exported = export_orders(run.scenario, run.lines, version=version)
    accepted = list(_accepted(run))
    assert len(exported) == len(accepted) > len(run.scenario.vehicles)  # some updates, not only first orders
    firsts: set[int] = set()
    for (join, plan, problems), (step, wanted, _), item in zip(
        _read_back(run, version, exported), accepted, exported, strict=True
    ):
        assert (item.step, item.vehicle_id) == (step, wanted.vehicle_id)
        assert _wire(item, version) == item.order  # the document says all the model does
        assert problems == ()
        assert join is (Join.UPDATE if item.vehicle_id in firsts else Join.NEW)
        firsts.add(item.vehicle_id)
        assert plan is not None and _drive(plan.legs) == _drive(wanted.legs), (
            f"step {step}, vehicle {wanted.vehicle_id}"
        )


def test_the_reversing_tugger_is_sent_backing_edges(recorded: dict[str, Path]) -> None:
    run = _run(recorded["mixed-shapes"])
    exported = export_orders(run.scenario, run.lines)
    backing = [
        (edge.orientation, leg.progress)
        for item in exported
        for edge, leg in zip(
            item.order.edges, item.plan.legs[len(item.plan.legs) - len(item.order.edges) :], strict=True
        )
    ]
    assert (math.pi, Progress.REVERSE) in backing
    assert all((orientation == math.pi) is (progress is Progress.REVERSE) for orientation, progress in backing)


def test_a_goal_leg_ends_at_a_node_that_names_the_task(recorded: dict[str, Path]) -> None:
    run = _run(recorded["loop-one-way"])
    exported = export_orders(run.scenario, run.lines)
    described = {
        (item.vehicle_id, item.order.order_update_id, node.sequence_id): node.node_description
        for item in exported
        for node in item.order.nodes[1:]
    }
    goals = [
        ((item.vehicle_id, item.order.order_update_id, edge.sequence_id + 1), f"goal of task {leg.goal_for_task}")
        for item in exported
        for edge, leg in zip(
            item.order.edges, item.plan.legs[len(item.plan.legs) - len(item.order.edges) :], strict=True
        )
        if leg.goal_for_task is not None
    ]
    assert goals and all(described[key] == text for key, text in goals)
    assert sum(text is not None for text in described.values()) == len(goals)  # no other node is described


def test_an_update_that_does_not_start_at_the_stitching_node_does_not_read_back(recorded: dict[str, Path]) -> None:
    """Narrow negative of the round trip: the same orders with the updates' sequence ids shifted are refused."""
    run = _run(recorded["crossing"])
    exported = export_orders(run.scenario, run.lines)
    update = next(item for item in exported if item.order.order_update_id > 0)
    order = update.order
    shifted = Order(
        order.header,
        order.order_id,
        order.order_update_id,
        tuple(type(n)(n.node_id, n.sequence_id + 2, n.released, n.actions, n.node_position) for n in order.nodes),
        tuple(
            type(e)(e.edge_id, e.sequence_id + 2, e.released, e.start_node_id, e.end_node_id, orientation=e.orientation)
            for e in order.edges
        ),
    )
    broken = [
        ExportedOrder(i.vehicle_id, i.step, i.at, shifted if i is update else i.order, i.plan, i.before)
        for i in exported
    ]
    joined = _read_back(run, "2.0", broken)
    _, _, errors = joined[exported.index(update)]
    assert [error.error_type for error in errors] == ["orderUpdateError"]


def test_a_vehicle_already_driving_its_start_gets_its_first_order_from_its_last_node(recorded: dict[str, Path]) -> None:
    """Vehicle 2 of the crossing, its first plan left out: it drives its start leg (fixed from the start)
    to the end, and its first order, later, begins at that leg's entry node (the vehicle's last node) and
    still reads back as its plan."""
    run = _run(recorded["crossing"])
    lines = [run.lines[0]]
    for line in run.lines[1:]:
        step, vehicles, plans, events = json.loads(line)
        if step == 0:
            plans = [plan for plan in plans if plan[0] != 2]
        lines.append(json.dumps([step, vehicles, plans, events], separators=(",", ":")))
    edited = RecordedRun(run.trace_path, run.scenario, lines, run.document, [], False)
    exported = export_orders(run.scenario, lines)
    [first, *_] = [item for item in exported if item.vehicle_id == 2]
    [start] = [v for v in run.scenario.vehicles if v.id == 2]
    [frame] = [f for f in replay(run.scenario, lines) if f.step == first.step - 1]
    pose, origin = frame.poses[2], initial_state(start, run.scenario.layout)
    assert first.step > 0 and pose.segment == start.start_segment
    assert math.dist((pose.x, pose.y), (origin.x, origin.y)) > 1.0  # it has driven off its start
    graph = site_graph(run.scenario.layout, map_id=run.scenario.name)
    assert first.order.nodes[0].node_id == graph.entry_node(start.start_segment, start.traverse)
    assert first.order.edges[0].edge_id == graph.edge_id(start.start_segment, start.traverse)
    for (_, plan, problems), item in zip(_read_back(edited, "2.0", exported), exported, strict=True):
        assert problems == () and plan is not None and _drive(plan.legs) == _drive(item.plan.legs)


def test_a_plan_that_drops_the_fixed_legs_is_an_export_error_naming_step_and_vehicle(recorded: dict[str, Path]) -> None:
    run = _run(recorded["crossing"])
    lines = list(run.lines)
    step, vehicles, plans, events = json.loads(lines[51])
    assert step == 50 and plans[0][0] == 1
    plans = [[1, [[4, "f", "f", 1, None]]]]  # vehicle 1, on segment 2 with 2 and 3 fixed, sent to 4
    lines[51] = json.dumps([step, vehicles, plans, events])
    with pytest.raises(
        ExportError, match=r"step 50: vehicle 1's accepted plan \[4f\] does not begin with its fixed legs \[2f, 3f"
    ):
        export_orders(run.scenario, lines)
    assert export_orders(run.scenario, run.lines)  # narrow: the run as it was exports


# -- what is written ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ROUND_TRIPS)
@pytest.mark.parametrize("version", ["2.0", "2.1"])
def test_every_exported_message_passes_the_official_validators(
    recorded: dict[str, Path], name: str, version: str
) -> None:
    run = _run(recorded[name])
    exported = export_orders(run.scenario, run.lines, version=version)
    for item in exported:
        document = order_document(item.order)
        assert document["version"] == VERSIONS[version]
        assert official.validate(version, "order", document) == [], (
            f"order {item.order.order_update_id} of vehicle {item.vehicle_id}"
        )
    wrong = {**order_document(exported[0].order)}
    wrong["edges"] = [{k: v for k, v in wrong["edges"][0].items() if k != "endNodeId"}, *wrong["edges"][1:]]
    assert official.validate(version, "order", wrong) != [], "the validators must see an edge without its end node"


def test_lif_orders_name_the_sites_own_nodes_and_edges(recorded: dict[str, Path]) -> None:
    lif = json.loads((SUITES / "sites" / "packing-hall" / "map.lif.json").read_text(encoding="utf-8"))
    [layout] = [layout for layout in lif["layouts"] if layout["layoutId"] == "hall-ground"]
    edges = {edge["edgeId"]: (edge["startNodeId"], edge["endNodeId"]) for edge in layout["edges"]}
    nodes = {node["nodeId"] for node in layout["nodes"]}
    run = _run(recorded[LIF])
    exported = export_orders(run.scenario, run.lines)
    sent = [edge for item in exported for edge in item.order.edges]
    assert sent and all(edges[edge.edge_id] == (edge.start_node_id, edge.end_node_id) for edge in sent)
    assert {node.node_id for item in exported for node in item.order.nodes} <= nodes
    tiled = export_orders(_run(recorded["crossing"]).scenario, _run(recorded["crossing"]).lines)
    assert all(
        edge.edge_id.startswith("e") and edge.edge_id not in edges for item in tiled for edge in item.order.edges
    )


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="fleetsim orders")
    add_orders_arguments(parser)
    return parser


def _orders(*words: str) -> int:
    return orders(_parser().parse_args(list(words)))


def test_the_command_writes_a_file_per_vehicle_of_timed_messages_on_their_topics(
    recorded: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = recorded["corridor-passing-bay"]
    assert _orders(str(folder), "--out", str(tmp_path), "--manufacturer", "acme", "--interface-name", "fleet") == 0
    printed = capsys.readouterr().out.splitlines()
    run = _run(folder)
    assert len(printed) == len(run.scenario.vehicles)
    for vehicle in run.scenario.vehicles:
        lines = (tmp_path / f"{vehicle.id}.orders.jsonl").read_text(encoding="utf-8").splitlines()
        records = [json.loads(line) for line in lines]
        assert {record["topic"] for record in records} == {f"fleet/v2/acme/{vehicle.id}/order"}
        assert [record["message"]["headerId"] for record in records] == list(range(len(records)))
        assert [record["message"]["orderUpdateId"] for record in records] == list(range(len(records)))
        ats = [record["at"] for record in records]
        assert ats == sorted(ats)
        assert any(f"vehicle {vehicle.id}, {len(records)} order messages" in line for line in printed)
        first = records[0]["message"]
        assert first["timestamp"] == "2000-01-01T00:00:00.000Z" and first["manufacturer"] == "acme"
        assert first["serialNumber"] == str(vehicle.id) and first["version"] == "2.0.0"
        later = records[-1]
        seconds = int(later["at"])
        assert later["message"]["timestamp"].startswith(f"2000-01-01T00:{seconds // 60:02d}:{seconds % 60:02d}.")


def test_by_default_the_orders_go_into_the_run_folder(
    recorded: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    folder = recorded["crossing"]
    assert _orders(str(folder / "trace.jsonl"), "--vda", "2.1") == 0
    written = sorted(path.name for path in (folder / ORDERS_FOLDER).iterdir())
    assert written == ["1.orders.jsonl", "2.orders.jsonl"]
    assert (
        json.loads((folder / ORDERS_FOLDER / "1.orders.jsonl").read_text().splitlines()[0])["message"]["version"]
        == "2.1.0"
    )
    assert str(folder / ORDERS_FOLDER / "1.orders.jsonl") in capsys.readouterr().out


def test_the_same_run_exports_the_same_bytes(recorded: dict[str, Path], tmp_path: Path) -> None:
    folder = recorded["mixed-shapes"]
    for out in ("a", "b", "c"):
        assert (
            _orders(str(folder), "--out", str(tmp_path / out), *(["--manufacturer", "other"] if out == "c" else []))
            == 0
        )
    for vehicle in ("1", "2"):
        a, b, c = ((tmp_path / out / f"{vehicle}.orders.jsonl").read_bytes() for out in ("a", "b", "c"))
        assert a == b
        assert a != c  # narrow: what the options say does reach the bytes


def test_a_run_folder_without_a_trace_is_an_error_naming_the_folder(recorded: dict[str, Path], tmp_path: Path) -> None:
    (tmp_path / "result.json").write_text((recorded["crossing"] / "result.json").read_text())
    with pytest.raises(UsageError, match=rf"{tmp_path}: no trace\.jsonl in this folder"):
        _orders(str(tmp_path))
    with pytest.raises(UsageError, match=r"no such file or directory"):
        _orders(str(tmp_path / "missing"))


def test_a_run_folder_that_is_not_writable_asks_for_out(
    recorded: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = recorded["loop-one-way"]
    real = __import__("os").access
    monkeypatch.setattr(
        "fleetsim.cli.orders.os.access", lambda path, mode: False if Path(path) == folder else real(path, mode)
    )
    with pytest.raises(
        UsageError, match=rf"{folder}: the run's folder is not writable; name another folder with --out DIR"
    ):
        _orders(str(folder))
    assert _orders(str(folder), "--out", str(tmp_path)) == 0  # narrow: --out goes elsewhere
    assert not (folder / ORDERS_FOLDER).exists()


@pytest.mark.parametrize(("option", "value"), [("--manufacturer", "acme/robots"), ("--interface-name", "")])
def test_a_topic_level_that_mqtt_cannot_carry_is_a_usage_error(
    recorded: dict[str, Path], option: str, value: str
) -> None:
    with pytest.raises(UsageError, match=rf"{option}={value!r} must be a non-empty MQTT topic level"):
        _orders(str(recorded["crossing"]), option, value)


def test_an_unknown_protocol_version_is_named(recorded: dict[str, Path]) -> None:
    with pytest.raises(SystemExit):
        _parser().parse_args(["RUN", "--vda", "1.1"])
    run = _run(recorded["crossing"])
    with pytest.raises(ValueError, match=r"version='1\.1' must be one of \['2\.0', '2\.1'\]"):
        export_orders(run.scenario, run.lines, version="1.1")


def test_the_options_leave_the_command_to_run_where_fleetsims_main_keeps_it() -> None:
    parser = argparse.ArgumentParser()
    parser.set_defaults(run="fleetsim.cli.orders:orders")
    add_orders_arguments(parser)
    args = parser.parse_args(["runs/crossing"])
    assert (args.run, args.path) == ("fleetsim.cli.orders:orders", "runs/crossing")


def test_fleetsim_orders_is_a_command_of_the_command_line(recorded: dict[str, Path], tmp_path: Path) -> None:
    from fleetsim.cli.main import main

    assert main(["orders", str(recorded["crossing"]), "--out", str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["1.orders.jsonl", "2.orders.jsonl"]
    assert main(["orders", str(tmp_path / "nowhere")]) == 2  # a usage error, named


def test_fleetsim_orders_exits_2_with_a_one_line_error_for_a_folder_without_a_trace(
    recorded: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["orders", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err == f"fleetsim: error: {tmp_path}: no trace.jsonl in this folder (the run did not keep its trace)\n"
    assert main(["orders", str(recorded["crossing"]), "--out", str(tmp_path / "out")]) == 0  # narrow: a run exports
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == ["1.orders.jsonl", "2.orders.jsonl"]
