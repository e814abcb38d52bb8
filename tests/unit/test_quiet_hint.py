"""The planner's quiet hint (fleetsim.planning.quiet): a resting vehicle is not asked until something it
watches changes, and the reference planner's promise is exact (the same runs with the hint honoured or
ignored)."""

from __future__ import annotations

import copy
import importlib.util
import math
from collections.abc import Hashable, Iterator
from dataclasses import replace
from pathlib import Path

import pytest
from loop_switches import run_switched, same_run

from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.layout import Layout, Segment, build_layout
from fleetsim.load.suites.scenario import load_scenario, load_scenario_dir
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.planning import FleetController, FleetLeg, FleetPlan, FleetSnapshot, Response
from fleetsim.planning.quiet import Quiet, Resting
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, ScenarioSettings, Task, Vehicle

ROOT = Path(__file__).resolve().parents[2]
SUITES = sorted((ROOT / "scenario_suites").glob("*.fleetsim.yaml"))


def _straight(sid: int, start: tuple[float, float], end: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (start, end))


# Lane 1 → 2 → 3, a lane 11 → 12 → 13 crossing segment 2 (so 12 and 2 conflict), and a far segment 21.
LAYOUT = build_layout(
    [
        *(_straight(sid, (4.0 * k, 0.0), (4.0 * k + 4.0, 0.0)) for k, sid in enumerate((1, 2, 3))),
        _straight(11, (6.0, -8.0), (6.0, -4.0)),
        _straight(12, (6.0, -4.0), (6.0, 4.0)),
        _straight(13, (6.0, 4.0), (6.0, 8.0)),
        _straight(21, (0.0, 20.0), (4.0, 20.0)),
    ],
    vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius,
)
START = {1: 1, 2: 11, 3: 21}


def _leg(segment: int, fixed: bool = False, goal: int | None = None) -> FleetLeg:
    return FleetLeg(segment, Traverse.FORWARD, Progress.FORWARD, fixed, goal_for_task=goal)


def _controller(*tasks: Task, quiet: bool = True) -> FleetController:
    vehicles = tuple(
        Vehicle(vid, segment, Traverse.FORWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE)
        for vid, segment in START.items()
    )
    types = {DEFAULT_VEHICLE_TYPE.name: DEFAULT_VEHICLE_TYPE}
    return FleetController(Scenario("quiet", LAYOUT, types, vehicles, tasks), quiet=quiet)


class Promising:
    """Answers nothing and promises quiet for the vehicles in ``calm``, watching ``watch``; records calls."""

    def __init__(self, calm: set[int], watch: frozenset[int] = frozenset(), until: float = math.inf) -> None:
        self.calm, self.watch, self.until = calm, watch, until
        self.until_standing = False
        self.vehicles: frozenset[int] = frozenset()
        self.marks: frozenset[Hashable] = frozenset()
        self.writes: frozenset[Hashable] = frozenset()
        self.changed: list[Hashable] = []  # what changed_marks() answers next
        self.changes: dict[int, list[Hashable]] = {}  # vehicle -> the marks its next call changes
        self.calls: list[int] = []
        self.answers: dict[int, list[FleetPlan]] = {}  # vehicle -> what its next call answers
        self.quiet_epoch = 0

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return self.fix_legs(task, fleet, layout)

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self.calls.append(task.vehicle_id)
        self.changed += self.changes.pop(task.vehicle_id, [])
        return self.answers.pop(task.vehicle_id, [])

    def quiet(self, vehicle_id: int, fleet: FleetSnapshot) -> Quiet | None:
        if vehicle_id not in self.calm:
            return None
        return Quiet(
            self.watch, self.until, self.until_standing, vehicles=self.vehicles, marks=self.marks, writes=self.writes
        )

    def changed_marks(self) -> list[Hashable]:
        changed, self.changed = self.changed, []
        return changed


def _round(controller: FleetController, planner: Promising, time: float) -> list[int]:
    before = len(planner.calls)
    controller.bookkeeping()
    list(controller.consult_all(planner, time))
    return planner.calls[before:]


TASKS = (Task(1, 1, 3), Task(2, 2, 13))


def test_a_vehicle_promised_quiet_is_not_asked_again_until_something_changes() -> None:
    controller = _controller(*TASKS)
    planner = Promising({1})
    assert _round(controller, planner, 0.0) == [1, 2]
    assert _round(controller, planner, 0.1) == [2]
    assert _round(controller, planner, 0.2) == [2]


def test_hints_ignored_every_vehicle_is_asked_every_round() -> None:
    controller = _controller(*TASKS, quiet=False)
    planner = Promising({1, 2})
    assert [_round(controller, planner, t / 10) for t in range(3)] == [[1, 2]] * 3


def test_a_planner_without_quiet_is_asked_as_before() -> None:
    class Plain:
        def __init__(self) -> None:
            self.calls: list[int] = []

        def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
            self.calls.append(task.vehicle_id)
            return []

        fix_legs = plan_routes

    controller = _controller(*TASKS)
    planner = Plain()
    for t in range(3):
        list(controller.consult_all(planner, t / 10))
    assert planner.calls == [1, 2] * 3


def test_its_own_new_plan_wakes_a_resting_vehicle() -> None:
    controller = _controller(*TASKS)
    planner = Promising({1})
    _round(controller, planner, 0.0)
    controller.set_plan(FleetPlan(1, (_leg(1, fixed=True), _leg(2), _leg(3, goal=1))))
    assert _round(controller, planner, 0.1) == [1, 2]


def test_another_vehicle_fixing_a_leg_near_a_watched_segment_wakes_it_and_a_far_one_does_not() -> None:
    controller = _controller(*TASKS)
    planner = Promising({1}, watch=frozenset({2}))
    _round(controller, planner, 0.0)
    # Vehicle 2 fixes 11 (far from 2): vehicle 1 rests on; then 12, which crosses segment 2: it wakes.
    planner.answers[2] = [FleetPlan(2, (_leg(11, fixed=True), _leg(12), _leg(13, goal=2)))]
    assert _round(controller, planner, 0.1) == [2]
    assert _round(controller, planner, 0.2) == [2]
    planner.answers[2] = [FleetPlan(2, (_leg(11, fixed=True), _leg(12, fixed=True), _leg(13, goal=2)))]
    assert _round(controller, planner, 0.3) == [2]  # vehicle 1 was asked before vehicle 2's answer
    assert _round(controller, planner, 0.4) == [1, 2]


def test_a_changed_queue_of_a_vehicle_holding_legs_near_a_watched_segment_wakes_it() -> None:
    controller = _controller(*TASKS)
    planner = Promising({1}, watch=frozenset({1}))
    _round(controller, planner, 0.0)
    controller.requeue(3, (), (Task(9, 3, 21),))  # vehicle 3 stands on 21, far from segment 1
    assert _round(controller, planner, 0.1) == [2, 3]
    controller.requeue(2, (), (Task(8, 2, 13),))  # vehicle 2 stands on 11, far too
    assert _round(controller, planner, 0.2) == [2, 3]
    controller.requeue(1, (), (Task(7, 1, 3),))  # its own queue
    assert _round(controller, planner, 0.3) == [1, 2, 3]


def test_the_time_a_vehicle_rests_until_wakes_it() -> None:
    controller = _controller(*TASKS)
    planner = Promising({1}, until=0.25)
    assert [_round(controller, planner, t / 10) for t in range(4)] == [[1, 2], [2], [2], [1, 2]]


def test_a_vehicle_resting_until_it_stands_is_asked_at_the_first_round_that_finds_it_at_rest() -> None:
    controller = _controller(*TASKS)
    planner = Promising({1})
    planner.until_standing = True
    moving = controller.states[1]._replace(speed=0.5)
    controller.set_state(moving)
    assert _round(controller, planner, 0.0) == [1, 2]
    assert _round(controller, planner, 0.1) == [2]
    controller.set_state(moving._replace(speed=3e-15))  # braked to a stop, a rounding error left
    assert _round(controller, planner, 0.2) == [1, 2]


def _both_resting(planner: Promising) -> FleetController:
    """A controller whose two busy vehicles have each been asked once and rest on ``planner``'s hints."""
    controller = _controller(*TASKS)
    _round(controller, planner, 0.0)
    assert _round(controller, planner, 0.1) == []
    return controller


def test_a_new_quiet_epoch_wakes_every_resting_vehicle() -> None:
    planner = Promising({1, 2})
    controller = _both_resting(planner)
    planner.quiet_epoch += 1
    assert _round(controller, planner, 0.2) == [1, 2]
    assert _round(controller, planner, 0.3) == []


def test_a_changed_mark_wakes_the_vehicles_resting_on_it_and_no_other() -> None:
    planner = Promising({1, 2})
    planner.marks = frozenset({("haven", 7)})
    controller = _both_resting(planner)
    planner.marks = frozenset({("haven", 8)})
    planner.changed = [("haven", 9)]  # a mark nobody watches: nobody wakes
    assert _round(controller, planner, 0.2) == []
    planner.changed = [("haven", 7)]
    assert _round(controller, planner, 0.3) == [1, 2]  # now resting on ("haven", 8)
    planner.changed = [("haven", 8)]
    assert _round(controller, planner, 0.4) == [1, 2]
    assert _round(controller, planner, 0.5) == []


class Writing(Promising):
    """Promising, with write_again (recorded among the calls, as minus the vehicle), and each vehicle's hint
    watching a mark of its own, ("own", vehicle)."""

    def __init__(self, calm: set[int]) -> None:
        super().__init__(calm)
        self.written: list[int] = []

    def quiet(self, vehicle_id: int, fleet: FleetSnapshot) -> Quiet | None:
        quiet = super().quiet(vehicle_id, fleet)
        return None if quiet is None else replace(quiet, marks=frozenset({("own", vehicle_id)}))

    def write_again(self, vehicle_id: int) -> None:
        self.written.append(vehicle_id)
        self.calls.append(-vehicle_id)


def test_a_changed_write_is_written_again_at_the_writers_turn_without_asking_it() -> None:
    planner = Writing({1, 2})
    planner.writes = frozenset({("haven", 3)})
    controller = _both_resting(planner)
    planner.changed = [("haven", 9)]  # a mark nobody writes: nothing to do
    assert _round(controller, planner, 0.2) == []
    planner.changed = [("haven", 3)]  # both rest on: each writes again at its turn, once
    assert _round(controller, planner, 0.3) == [-1, -2]
    assert _round(controller, planner, 0.4) == []
    # Vehicle 2 is asked, and its call changes the mark both write: vehicle 1's turn is past, so it writes
    # again at its turn in the next round.
    planner.changed = [("own", 2)]
    planner.changes[2] = [("haven", 3)]
    assert _round(controller, planner, 0.5) == [2]
    assert _round(controller, planner, 0.6) == [-1]
    # Vehicle 1's call changes it: vehicle 2's turn comes after, in the same round.
    planner.changed = [("own", 1)]
    planner.changes[1] = [("haven", 3)]
    assert _round(controller, planner, 0.7) == [1, -2]
    assert _round(controller, planner, 0.8) == []


def test_a_woken_writer_is_asked_rather_than_writing_again() -> None:
    planner = Writing({1, 2})
    planner.writes = frozenset({("haven", 3)})
    controller = _both_resting(planner)
    planner.changed = [("haven", 3), ("own", 1)]  # vehicle 1 is asked (which writes anyway), once
    assert _round(controller, planner, 0.2) == [1, -2]
    assert planner.written == [2]
    planner.changed = [("haven", 3)]
    planner.quiet_epoch += 1  # every resting vehicle is asked
    assert _round(controller, planner, 0.3) == [1, 2]
    assert planner.written == [2]  # (the round before)


def test_without_write_again_a_changed_write_wakes_the_writer() -> None:
    planner = Promising({1, 2})
    planner.writes = frozenset({("haven", 3)})
    controller = _both_resting(planner)
    planner.changed = [("haven", 3)]
    assert _round(controller, planner, 0.2) == [1, 2]
    assert _round(controller, planner, 0.3) == []


def test_a_rejected_plan_wakes_every_resting_vehicle() -> None:
    controller = _controller(*TASKS)
    planner = Promising({1})
    _round(controller, planner, 0.0)
    # Vehicle 2 answers a plan that does not start on the segment it stands on: rejected.
    planner.answers[2] = [FleetPlan(2, (_leg(12, fixed=True), _leg(13, goal=2)))]
    assert _round(controller, planner, 0.1) == [2]
    assert _round(controller, planner, 0.2) == [1, 2]


def test_resting_wakes_by_the_conflict_sets_of_the_legs_that_changed() -> None:
    resting = Resting(LAYOUT.conflicts)
    resting.rest(1, Quiet(frozenset({2})))
    resting.rest(3, Quiet(frozenset({21})))
    far = FleetPlan(2, (_leg(11, fixed=True),))
    resting.plan_changed(None, far)
    assert set(resting.resting) == {1, 3}
    # Only the planned legs changed: nobody's reservations did.
    resting.plan_changed(far, FleetPlan(2, (_leg(11, fixed=True), _leg(12))))
    assert set(resting.resting) == {1, 3}
    resting.plan_changed(far, FleetPlan(2, (_leg(11, fixed=True), _leg(12, fixed=True))))
    assert set(resting.resting) == {3}
    resting.plan_changed(None, FleetPlan(3, (_leg(21, fixed=True),)))  # its own plan
    assert resting.resting == {}


def test_a_watched_vehicle_changing_its_plan_or_queue_wakes_the_resting_vehicle_wherever_it_is() -> None:
    resting = Resting(LAYOUT.conflicts)
    states = _controller(*TASKS).states
    resting.rest(1, Quiet(vehicles=frozenset({3})), states)  # vehicle 3 stands on 21, far from everything
    resting.plan_changed(None, FleetPlan(2, (_leg(11, fixed=True), _leg(12, fixed=True))))  # not watched
    resting.queue_changed([2], {})
    assert set(resting.resting) == {1}
    resting.plan_changed(None, FleetPlan(3, (_leg(21),)))  # not even a fixed leg
    assert resting.resting == {}
    resting.rest(1, Quiet(vehicles=frozenset({3})), states)
    resting.queue_changed([3], {})
    assert resting.resting == {}


def test_a_watched_vehicle_coming_to_rest_or_starting_to_move_wakes_the_resting_vehicle() -> None:
    controller = _controller(*TASKS)
    planner = Promising({1})
    planner.vehicles = frozenset({3})
    standing = controller.states[3]
    assert _round(controller, planner, 0.0) == [1, 2]
    controller.set_state(standing._replace(speed=3e-15))  # a rounding error: it still stands
    assert _round(controller, planner, 0.1) == [2]
    controller.set_state(standing._replace(speed=0.2))  # it starts to move
    assert _round(controller, planner, 0.2) == [1, 2]
    assert _round(controller, planner, 0.3) == [2]
    controller.set_state(standing._replace(speed=1e-10))  # ... and comes to rest
    assert _round(controller, planner, 0.4) == [1, 2]


def test_a_route_coming_onto_or_leaving_a_segment_near_a_watched_one_wakes_the_resting_vehicle() -> None:
    resting = Resting(LAYOUT.conflicts)
    resting.rest(1, Quiet(routes=frozenset({2})))
    across = FleetPlan(2, (_leg(11, fixed=True), _leg(12), _leg(13)))  # 12 crosses 2: planned, not fixed
    resting.plan_changed(None, FleetPlan(3, (_leg(21, fixed=True),)))
    assert set(resting.resting) == {1}
    resting.plan_changed(None, across)
    assert resting.resting == {}
    resting.rest(1, Quiet(routes=frozenset({2})))
    driven = FleetPlan(2, across.legs[1:])  # 11 driven past: the route left a segment not near 2
    resting.plan_changed(across, driven)
    resting.plan_changed(driven, FleetPlan(2, (driven.legs[0], _leg(13, fixed=True))))  # fixed: same route
    assert set(resting.resting) == {1}
    resting.plan_changed(driven, FleetPlan(2, driven.legs[1:]))  # 12 driven past: it left 2's neighbour
    assert resting.resting == {}


def _congestion(folder: Path, vehicles: int, seconds: float) -> Scenario:
    """The benchmarks' congestion site: the whole fleet queueing at a dozen stations."""
    spec = importlib.util.spec_from_file_location("warehouse", ROOT / "benchmarks" / "warehouse.py")
    assert spec is not None and spec.loader is not None
    warehouse = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(warehouse)
    site = warehouse.write_congestion_scenario(folder / "site", vehicles)
    return load_scenario_dir(site, settings=ScenarioSettings(time_limit=seconds, stop_on=()))


def test_vehicles_behind_lower_ranked_blockers_that_cannot_be_moved_rest_and_run_the_same(tmp_path: Path) -> None:
    """On the congestion site, vehicles standing behind lower-ranked vehicles that cannot be moved out of
    their way rest until what their attempts read changes: hints that watch vehicles, and hints that watch
    the routes near the places that ordered the ways out found; the run is the same with them ignored."""
    scenario = _congestion(tmp_path, 60, 120.0)
    planner = ReservingPlanner()
    given: list[Quiet] = []
    others_sent: list[Hashable] = []  # marks of where other vehicles were sent to wait, named by hints
    writes_checked = 0
    hint, fix_legs = planner.quiet, planner.fix_legs
    asked: list[tuple[Task, FleetSnapshot, Layout]] = []

    def recorded_call(task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        asked[:] = [(task, fleet, layout)]
        return fix_legs(task, fleet, layout)

    def recorded(vehicle_id: int, fleet: FleetSnapshot) -> Quiet | None:
        nonlocal writes_checked
        quiet = hint(vehicle_id, fleet)
        if quiet is not None:
            given.append(quiet)
            assert quiet.marks == {("haven", vehicle_id)}  # its own place to wait: every call reads it
            others_sent.extend(quiet.writes)
            if quiet.writes and writes_checked < 3:
                writes_checked += 1
                _check_writes_again(planner, vehicle_id, quiet, *asked[0])
        return quiet

    planner.fix_legs = recorded_call  # type: ignore[method-assign]
    planner.quiet = recorded  # type: ignore[method-assign]
    honoured = run_switched(scenario, planner, quiet=True)
    ignored = run_switched(scenario, ReservingPlanner(), quiet=False)
    assert same_run(honoured) == same_run(ignored)
    assert any(quiet.vehicles for quiet in given) and any(quiet.routes for quiet in given)
    # Where the attempts sent others to wait: a change there has those that noted it note it again at their
    # turn (write_again), rather than being asked again or waking everyone.
    assert others_sent and writes_checked == 3
    assert honoured.metrics.planner_calls < 0.7 * ignored.metrics.planner_calls


def _check_writes_again(
    planner: ReservingPlanner, vehicle_id: int, quiet: Quiet, task: Task, fleet: FleetSnapshot, layout: Layout
) -> None:
    """What ``quiet.writes`` promise, right after the call that gave it: with the places it noted for others
    changed, write_again() notes them again just as asking again does, which answers nothing, changes
    nothing else and gives the same hint."""
    sent = {mark[1] for mark in quiet.writes}  # type: ignore[index]
    moved = dict.fromkeys(sent, -1)  # somewhere else
    shared = (planner._layout, planner._idle_of[0])  # (read only, and cannot be copied)
    asked, written = (copy.deepcopy(planner, {id(kept): kept for kept in shared}) for _ in range(2))
    for twin in (asked, written):
        twin._haven.update(moved)
        twin.changed_marks()
    assert ReservingPlanner.fix_legs(asked, task, fleet, layout) == []
    assert ReservingPlanner.quiet(asked, vehicle_id, fleet) == quiet
    written.write_again(vehicle_id)
    assert written._haven == asked._haven and all(written._haven[other] != -1 for other in sent)
    assert sorted(map(str, written.changed_marks())) == sorted(map(str, quiet.writes))


def _shipped() -> Iterator[tuple[str, Scenario]]:
    for path in SUITES:
        suite = load_suite(path)
        for spec in suite.scenarios:
            if spec.generate is None:
                yield f"{path.name.split('.')[0]}::{spec.name}", load_scenario(spec, suite)


def _run(scenario: Scenario, quiet: bool) -> tuple[tuple[object, ...], int]:
    result = run_switched(scenario, ReservingPlanner(), quiet=quiet)
    return (*same_run(result), result.trace_hash, result.orders), result.metrics.planner_calls


@pytest.mark.parametrize(
    ("name", "scenario"), list(_shipped()), ids=lambda value: value if isinstance(value, str) else ""
)
def test_every_shipped_scenario_runs_the_same_with_the_reference_planners_hint_honoured_or_ignored(
    name: str, scenario: Scenario
) -> None:
    honoured, calls = _run(scenario, quiet=True)
    ignored, all_calls = _run(scenario, quiet=False)
    assert honoured == ignored, name
    assert calls <= all_calls


def test_the_reference_planner_lets_cruising_vehicles_rest() -> None:
    suite = load_suite(SUITES[0].parent / "examples.fleetsim.yaml")
    honoured = ignored = 0
    for spec in suite.scenarios:
        scenario = load_scenario(spec, suite)
        honoured += _run(scenario, quiet=True)[1]
        ignored += _run(scenario, quiet=False)[1]
    assert honoured < 0.8 * ignored, (honoured, ignored)


def test_a_vehicle_standing_blocked_while_a_dance_goes_on_gets_no_hint_and_no_error() -> None:
    """Found by an 8-hour shift: no moment to wake at (pushing already, a dance going on, sent to wait
    somewhere) left nothing to take the earliest of."""
    planner = ReservingPlanner()
    planner._dance = object()  # type: ignore[assignment]  # a dance goes on
    planner._haven[7] = 3
    plan = FleetPlan(7, (_leg(1, fixed=True), _leg(2)))
    planner._calm_standing(7, plan, since=0.0, pushing=True, following=2, fleet=None)  # type: ignore[arg-type]
    assert planner._calm is not None and planner._calm[1].until == math.inf
    assert planner.quiet(7, None) is None  # type: ignore[arg-type]  # (the dance: no hint)
