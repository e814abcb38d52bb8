"""Legal continuations: what ``Layout.continuations`` offers a planner is exactly what the plan checks accept.

The progress rules are written once (``fleetsim.layout.continuations.progresses_after``); the check
``illegal-progress-change``, the reference planners' searches and the planner-facing helper all use
them. These tests hold the helper against the check over every leg of every shipped map, for both turn
capabilities, and run the getting-started planner (which routes with the helper) on every shipped
scenario.
"""

from __future__ import annotations

import importlib.util
import sys
from dataclasses import replace
from pathlib import Path
from types import ModuleType

import pytest

from fleetsim import load_scenario, load_suite, run_scenario
from fleetsim.enums import JointKind, Progress, Traverse, TurnCapability
from fleetsim.layout import Continuation, Layout
from fleetsim.layout.reachability import moves, next_steps
from fleetsim.planning.checks import CheckContext, RejectionCode, check_plan
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario
from tests.docs.examples import REPO, blocks

CURVE = replace(DEFAULT_VEHICLE_TYPE, name="tugger", turn_capability=TurnCapability.CURVE)
IN_PLACE = replace(DEFAULT_VEHICLE_TYPE, name="agv", turn_capability=TurnCapability.IN_PLACE)
SUITES = sorted((REPO / "scenario_suites").glob("*.fleetsim.yaml"))


def shipped_scenarios() -> list[Scenario]:
    found = []
    for path in SUITES:
        suite = load_suite(path)
        found += [load_scenario(spec, suite) for spec in suite.scenarios if spec.generate is None]
    return found


SCENARIOS = shipped_scenarios()
MAPS = {str(scenario.layout.source): scenario.layout for scenario in SCENARIOS}


def legs_of(layout: Layout) -> list[tuple[int, Traverse, Progress]]:
    return [
        (sid, traverse, progress)
        for sid, segment in sorted(layout.segments.items())
        for traverse in Traverse
        if segment.allows(traverse)
        for progress in Progress
    ]


def accepted(layout: Layout, vehicle_type: object, before: FleetLeg, after: FleetLeg) -> bool:
    """Whether the plan checks accept ``after`` driven right after ``before`` (a fixed leg)."""
    assert vehicle_type in (CURVE, IN_PLACE)
    ctx = CheckContext(
        layout=layout,
        vehicle_types={1: vehicle_type},  # type: ignore[dict-item]
        plans={1: FleetPlan(1, (before,))},
        queues={1: ()},
    )
    return check_plan(FleetPlan(1, (before, after)), ctx) is None


@pytest.mark.parametrize("source", sorted(MAPS), ids=lambda source: Path(source).parent.name)
@pytest.mark.parametrize("vehicle_type", [CURVE, IN_PLACE], ids=["curve", "in_place"])
def test_every_continuation_offered_is_accepted_and_every_other_next_leg_rejected(
    source: str, vehicle_type: object
) -> None:
    layout = MAPS[source]
    for segment, traverse, progress in legs_of(layout):
        before = FleetLeg(segment, traverse, progress, fixed=True)
        offered = layout.continuations(vehicle_type, segment, traverse, progress)  # type: ignore[arg-type]
        assert len(set(offered)) == len(offered)
        for next_segment, next_traverse, joint in layout.successors(segment, traverse):
            for next_progress in Progress:
                after = FleetLeg(next_segment, next_traverse, next_progress, fixed=True)
                legal = Continuation(next_segment, next_traverse, next_progress, joint) in offered
                assert legal == accepted(layout, vehicle_type, before, after), (before, after, joint)


def test_a_tugger_keeps_its_progress_on_a_smooth_joint_flips_it_at_a_cusp_and_takes_no_corner() -> None:
    layout = next(layout for source, layout in MAPS.items() if "mixed" in source)
    for segment, traverse, progress in legs_of(layout):
        for c in layout.continuations(CURVE, segment, traverse, progress):
            assert c.joint is not JointKind.TURN_IN_PLACE
            assert (c.progress is progress) == (c.joint is JointKind.SAME)
    # An in-place turner is offered every connection, with either progress, the kept one first.
    for segment, traverse, progress in legs_of(layout):
        offered = layout.continuations(IN_PLACE.turn_capability, segment, traverse, progress)
        assert len(offered) == 2 * len(layout.successors(segment, traverse))
        assert all(offered[i].progress is progress for i in range(0, len(offered), 2))


def test_the_route_searches_step_by_the_same_rules() -> None:
    for layout in MAPS.values():
        for capability in TurnCapability:
            for state in legs_of(layout):
                offered = [(c.segment, c.traverse, c.progress) for c in layout.continuations(capability, *state)]
                assert sorted(moves(layout, capability, state)) == sorted(offered)
                # The planners' search takes per connection the first (progress kept where it may be).
                firsts = [following for following, _ in next_steps(layout, capability, state)]
                assert all(following in offered for following in firsts)
                assert len(firsts) == len({(c.segment, c.traverse) for c in layout.continuations(capability, *state)})


def test_a_string_progress_and_a_vehicle_type_are_taken_as_the_check_takes_them() -> None:
    layout = next(iter(MAPS.values()))
    segment, traverse, progress = legs_of(layout)[0]
    assert layout.continuations(CURVE, segment, traverse, progress) == layout.continuations(
        TurnCapability.CURVE,
        segment,
        traverse,
        Progress(progress.value),  # type: ignore[arg-type]
    )


def getting_started_module(name: str, folder: Path) -> ModuleType:
    """A planner module of docs/getting-started.md, written from its block as the reader would."""
    for block in blocks((REPO / "docs" / "getting-started.md").read_text(encoding="utf-8")):
        if block.title is not None and block.title.endswith(".py"):
            (folder / block.title).write_text(block.text, encoding="utf-8")
    sys.path.insert(0, str(folder))
    try:
        spec = importlib.util.spec_from_file_location(name, folder / f"{name}.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(folder))


@pytest.fixture(scope="module")
def careful(tmp_path_factory: pytest.TempPathFactory) -> type:
    folder = tmp_path_factory.mktemp("getting-started")
    getting_started_module("first_planner", folder)
    try:
        return getting_started_module("careful_planner", folder).CarefulPlanner  # type: ignore[no-any-return]
    finally:
        sys.modules.pop("first_planner", None)
        sys.modules.pop("careful_planner", None)


@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda scenario: scenario.name)
def test_the_getting_started_planner_makes_only_legal_plans_on_every_shipped_scenario(
    scenario: Scenario, careful: type
) -> None:
    result = run_scenario(scenario, careful())
    assert [event.rejection.code for event in result.rejections] == []
    assert list(result.route_errors) == []


def test_the_mixed_map_with_its_cusp_and_tugger_is_completed(careful: type) -> None:
    mixed = next(scenario for scenario in SCENARIOS if scenario.name == "mixed-shapes")
    assert {v.type.turn_capability for v in mixed.vehicles} >= {TurnCapability.CURVE}
    result = run_scenario(mixed, careful())
    assert result.ended == "completed" and result.status == "passed"


def test_a_planner_that_ignores_the_rules_is_rejected_on_the_mixed_map() -> None:
    """The narrow negative: the first planner as often written (every leg in the goal's progress)."""
    sys.path.insert(0, str(REPO / "scripts"))
    try:
        from exchange_planner import GoalProgressPlanner
    finally:
        sys.path.remove(str(REPO / "scripts"))
    mixed = next(scenario for scenario in SCENARIOS if scenario.name == "mixed-shapes")
    result = run_scenario(mixed, GoalProgressPlanner())
    assert [event.rejection.code for event in result.rejections] == [RejectionCode.ILLEGAL_PROGRESS_CHANGE]
