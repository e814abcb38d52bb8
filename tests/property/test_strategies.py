"""The Hypothesis strategies of fleetsim.strategies: valid layouts, valid scenarios, exact saving, and the
reference planners on what they generate (ReservingPlanner stays safe; BFSPlanner's collision is found)."""

from __future__ import annotations

import contextlib
import io
import math
import tempfile
from dataclasses import replace
from pathlib import Path

import networkx as nx
import yaml
from hypothesis import HealthCheck, find, given, settings
from hypothesis import strategies as st

from fleetsim.cli import main
from fleetsim.enums import ConflictModel, Progress, TurnCapability
from fleetsim.layout import build_layout
from fleetsim.layout.segment import Segment
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planners.routing import State, next_states, shortest_route
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, ScenarioSettings, VehicleType
from fleetsim.sim.loop import run_scenario
from fleetsim.strategies import LAYOUT_KINDS, GenerationSpec, geometry, layouts, load_saved, save_scenario, scenarios

AGV = replace(DEFAULT_VEHICLE_TYPE, name="agv")
TUGGER = VehicleType("tugger", 1.4, 0.7, 0.5, 1.2, 0.4, TurnCapability.CURVE)
MIXED = GenerationSpec(vehicles=(1, 4), vehicle_types=(AGV, TUGGER))
SPECS = (
    GenerationSpec(),
    MIXED,
    GenerationSpec(layout="loop", one_way=True, vehicle_types=(TUGGER,)),
    GenerationSpec(
        layout="corridor",
        vehicles=(1, 2),  # a corridor of up to three straights between its ends has room for two tuggers
        vehicle_types=(DEFAULT_VEHICLE_TYPE, TUGGER),
        settings=ScenarioSettings(conflict_model=ConflictModel.BBOX, safety_margin=0.2, time_limit=120.0),
    ),
)
spec_and_scenario = st.sampled_from(SPECS).flatmap(lambda spec: st.tuples(st.just(spec), scenarios(spec)))


# -- layouts --------------------------------------------------------------------------------------


def _touching(segments: list[Segment], a: Segment) -> set[int]:
    ends = (a.first, a.last)
    return {b.id for b in segments if any(math.dist(p, q) <= 0.05 for p in ends for q in (b.first, b.last))}


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(LAYOUT_KINDS), data=st.data())
def test_generated_layouts_are_lint_clean_connected_and_numbered_in_order(kind: str, data: st.DataObject) -> None:
    segments = data.draw(layouts(kind, size=(1, 3)))
    layout = build_layout(segments, vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
    assert [s.id for s in segments] == list(range(1, len(segments) + 1))
    findings = layout.lint()
    assert not [f for f in findings if f.severity == "error"]
    # Dead ends (lattice edges, corridor ends) at most: nothing nearly meets, fails to join or is cut off.
    assert {f.code for f in findings} <= ({"dangling-end"} if kind != "loop" else set()), findings
    assert nx.is_weakly_connected(layout.graph)
    assert nx.is_strongly_connected(layout.graph)  # every state can get back everywhere (U-turns or a ring)
    if kind != "warehouse":
        # No accidental closeness: a segment conflicts only with the segments it touches.
        for segment in segments:
            assert layout.conflicts(segment.id) == _touching(segments, segment)


@settings(max_examples=30, deadline=None)
@given(one_way=st.booleans(), data=st.data())
def test_one_way_loops_run_all_forward_around_one_cycle(one_way: bool, data: st.DataObject) -> None:
    segments = data.draw(layouts("loop", size=(1, 3), one_way=one_way))
    assert {s.direction.value for s in segments} == ({"forward"} if one_way else {"both"})
    for a, b in zip(segments, segments[1:] + segments[:1], strict=True):
        assert a.last == b.first  # exactly, so they connect whatever the tolerance


# -- scenarios ------------------------------------------------------------------------------------


def assert_same_scenario(loaded: Scenario, generated: Scenario) -> None:
    """Equal in everything but the name and file paths (a loaded scenario is named after its folder)."""
    a, b = loaded.layout, generated.layout
    assert tuple(a.segments.values()) == tuple(b.segments.values())
    assert a.connections == b.connections
    assert {sid: a.conflicts(sid) for sid in a.segments} == {sid: b.conflicts(sid) for sid in b.segments}
    assert (a.vehicle_radius, a.safety_margin, a.conflict_model) == (
        b.vehicle_radius,
        b.safety_margin,
        b.conflict_model,
    )
    assert dict(loaded.vehicle_types) == dict(generated.vehicle_types)
    assert loaded.vehicles == generated.vehicles
    assert loaded.tasks == generated.tasks
    assert loaded.settings == generated.settings
    assert loaded.expect == generated.expect


@settings(max_examples=40, deadline=None)
@given(spec_and_scenario)
def test_generated_scenario_loads_back_identically_after_saving(case: tuple[GenerationSpec, Scenario]) -> None:
    spec, scenario = case
    with tempfile.TemporaryDirectory() as tmp:
        folder = save_scenario(scenario, Path(tmp) / "generated")
        assert sorted(p.name for p in folder.iterdir()) == ["map.json", "tasks.csv", "vehicles.csv"]
        typed = spec.types != (DEFAULT_VEHICLE_TYPE,)
        assert (",type" in (folder / "vehicles.csv").read_text().splitlines()[0]) == typed
        assert_same_scenario(load_saved(folder, spec), scenario)


def _route(
    scenario: Scenario, capability: TurnCapability, state: State, goal: int, arrive: Progress | None
) -> list[State] | None:
    return shortest_route(scenario.layout, capability, state, goal, arrive, lambda segment, traverse, joint: 1.0)


def _arrival(path: list[State], capability: TurnCapability, arrive: Progress | None) -> State:
    segment, traverse, progress = path[-1]
    return (
        (segment, traverse, arrive)
        if arrive is not None and capability is TurnCapability.IN_PLACE
        else (segment, traverse, progress)
    )


@settings(max_examples=60, deadline=None)
@given(spec_and_scenario)
def test_starts_do_not_conflict_and_every_task_is_reachable(case: tuple[GenerationSpec, Scenario]) -> None:
    _, scenario = case
    layout = scenario.layout
    assert [v.id for v in scenario.vehicles] == list(range(1, len(scenario.vehicles) + 1))
    assert [t.id for t in scenario.tasks] == list(range(1, len(scenario.tasks) + 1))
    for i, vehicle in enumerate(scenario.vehicles):
        assert layout.segments[vehicle.start_segment].allows(vehicle.traverse)
        for other in scenario.vehicles[i + 1 :]:
            assert not layout.conflicts(vehicle.start_segment) & layout.conflicts(other.start_segment)
    for vehicle in scenario.vehicles:
        capability = vehicle.type.turn_capability
        state: State = (vehicle.start_segment, vehicle.traverse, vehicle.progress)
        for task in (t for t in scenario.tasks if t.vehicle_id == vehicle.id):
            path = _route(scenario, capability, state, task.goal_segment, task.goal_progress)
            assert path is not None, f"task {task} unreachable from {state}"
            state = _arrival(path, capability, task.goal_progress)


def _states_after(
    scenario: Scenario, capability: TurnCapability, here: frozenset[State], usable: frozenset[int]
) -> set[State]:
    """States reachable in one or more legs from some state in ``here``, driving on ``usable`` only."""
    graph: nx.DiGraph[State] = nx.DiGraph()
    frontier, seen = list(here), set(here)
    while frontier:
        state = frontier.pop()
        for following in next_states(scenario.layout, capability, state):
            if following[0] in usable:
                graph.add_edge(state, following)
                if following not in seen:
                    seen.add(following)
                    frontier.append(following)
    return set().union(*(nx.descendants(graph, s) for s in here if s in graph))


@settings(max_examples=60, deadline=None)
@given(spec_and_scenario)
def test_vehicles_could_do_their_tasks_one_after_another_without_conflicts(
    case: tuple[GenerationSpec, Scenario],
) -> None:
    # So every generated scenario is solvable: a failing run blames the planner, not the scenario.
    _, scenario = case
    layout = scenario.layout
    parked: dict[int, int] = {v.id: v.start_segment for v in scenario.vehicles}
    for vehicle in scenario.vehicles:
        standing = [segment for vid, segment in parked.items() if vid != vehicle.id]
        usable = frozenset(layout.segments) - frozenset().union(*(layout.conflicts(s) for s in standing))
        capability = vehicle.type.turn_capability
        assert vehicle.start_segment in usable
        here = frozenset({(vehicle.start_segment, vehicle.traverse, vehicle.progress)})
        for task in (t for t in scenario.tasks if t.vehicle_id == vehicle.id):
            arrive = task.goal_progress
            reached = _states_after(scenario, capability, here, usable)
            here = frozenset(
                _arrival([s], capability, arrive)
                for s in reached
                if s[0] == task.goal_segment
                and (arrive is None or s[2] is arrive or capability is TurnCapability.IN_PLACE)
            )
            assert here, f"vehicle {vehicle.id} cannot do task {task.id} while the others stand still"
            parked[vehicle.id] = task.goal_segment


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(spec_and_scenario)
def test_reserving_planner_never_alerts_or_is_rejected_on_generated_scenarios(
    case: tuple[GenerationSpec, Scenario],
) -> None:
    _, scenario = case
    result = run_scenario(scenario, ReservingPlanner(), keep_trace=False)
    assert not result.collisions, [c.alert.text() for c in result.collisions]
    assert not result.rejections, [str(r.rejection) for r in result.rejections]
    assert not result.route_errors, result.route_errors


def _bfs_collides(scenario: Scenario) -> bool:
    return bool(run_scenario(scenario, BFSPlanner(), keep_trace=False).collisions)


def test_bfs_planner_collision_is_found_and_shrinks_to_a_small_saved_counterexample(tmp_path: Path) -> None:
    search = settings(max_examples=200, derandomize=True, database=None, deadline=None)
    found = find(scenarios(GenerationSpec()), _bfs_collides, settings=search)
    # Small: two or three vehicles on a layout no larger than a loop with two straights per side. (Layouts
    # grow to hold the vehicles drawn, so the shrinker cannot always drop a vehicle without a new layout.)
    assert 2 <= len(found.vehicles) <= 3
    assert len(found.layout.segments) <= len(geometry.loop(2))
    assert len(found.tasks) <= 3
    # Saved as a folder, the counterexample still makes BFSPlanner collide.
    assert _bfs_collides(load_saved(save_scenario(found, tmp_path / "counterexample")))


def _suite_for(spec: GenerationSpec, folder: Path) -> Path:
    types = {
        t.name: {
            "length": t.length,
            "width": t.width,
            "height": t.height,
            "max_speed": t.max_speed,
            "acceleration": t.acceleration,
            "turn_capability": t.turn_capability.value,
            "turn_rate": t.turn_rate,
        }
        for t in spec.types
    }
    suite = {
        "fleetsim": 1,
        "name": "generated",
        "vehicle_types": types,
        "defaults": {"vehicle_type": spec.types[0].name},
        "scenarios": [{"name": "generated", "dir": f"{folder.name}/"}],
    }
    path = folder.parent / "generated.fleetsim.yaml"
    path.write_text(yaml.safe_dump(suite, sort_keys=False), encoding="utf-8")
    return path


@settings(max_examples=8, deadline=None)
@given(scenarios(MIXED))
def test_saved_scenario_folder_validates_and_loads_through_a_suite(scenario: Scenario) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = save_scenario(scenario, Path(tmp) / "generated")
        suite_path = _suite_for(MIXED, folder)
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            status = main(["validate", str(suite_path)])
        assert status == 0, out.getvalue()
        assert "1 scenario(s) valid, 0 failed" in out.getvalue()
        suite = load_suite(suite_path)
        loaded = load_scenario(suite.scenarios[0], suite)
    assert loaded.layout.vehicle_radius == scenario.layout.vehicle_radius
    assert tuple(loaded.layout.segments.values()) == tuple(scenario.layout.segments.values())
    assert loaded.vehicles == scenario.vehicles
    assert loaded.tasks == scenario.tasks


# -- the vehicle range ----------------------------------------------------------------------------

BIG = VehicleType("big", 3.0, 2.0, 1.0, 1.0, 0.5, TurnCapability.IN_PLACE)


@st.composite
def crowded_specs(draw: st.DrawFn) -> GenerationSpec:
    """Specs asking for many vehicles on small layouts, with types of every size and capability."""
    low = draw(st.integers(1, 3))
    size = (low, draw(st.integers(low, 3)))
    fewest = draw(st.integers(0, 5))
    return GenerationSpec(
        layout=draw(st.sampled_from(("any", *LAYOUT_KINDS))),
        size=size,
        vehicles=(fewest, draw(st.integers(fewest, 6))),
        tasks=(0, 1),
        one_way=draw(st.one_of(st.none(), st.booleans())),
        vehicle_types=tuple(draw(st.lists(st.sampled_from((AGV, TUGGER, BIG)), min_size=1, max_size=3, unique=True))),
    )


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(spec=crowded_specs(), data=st.data())
def test_the_number_of_vehicles_is_always_within_the_range_or_the_spec_is_refused(
    spec: GenerationSpec, data: st.DataObject
) -> None:
    try:
        strategy = scenarios(spec)
    except ValueError as error:
        assert f"vehicles={spec.vehicles!r} needs room for {spec.vehicles[1]} vehicles" in str(error)
        return
    scenario = data.draw(strategy)
    low, high = spec.vehicles
    assert low <= len(scenario.vehicles) <= high
    starts = [v.start_segment for v in scenario.vehicles]
    for i, a in enumerate(starts):
        assert not any(scenario.layout.conflicts(a) & scenario.layout.conflicts(b) for b in starts[i + 1 :])


@settings(max_examples=30, deadline=None)
@given(scenarios(GenerationSpec(layout="warehouse", size=(1, 2), vehicles=(2, 4), vehicle_types=(AGV,))))
def test_a_warehouse_of_one_junction_still_gets_two_to_four_vehicles(scenario: Scenario) -> None:
    assert 2 <= len(scenario.vehicles) <= 4


def test_a_spec_whose_layouts_cannot_hold_its_vehicles_is_refused() -> None:
    spec = GenerationSpec(layout="warehouse", size=(1, 1), vehicles=(2, 5), vehicle_types=(AGV,))
    try:
        scenarios(spec)
    except ValueError as error:
        assert str(error) == (
            "vehicles=(2, 5) needs room for 5 vehicles with non-conflicting starts, but warehouse layouts of "
            f"size=(1, 1) have room for 1 (vehicle radius {AGV.swept_radius:.2f} m); allow larger layouts or fewer vehicles"
        )
    else:
        raise AssertionError("no ValueError")
