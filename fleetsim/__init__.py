"""fleetsim: test fleet route planners against declarative scenarios, headless.

The public API is exactly what this module exports (``__all__``); everything else may change.

Importing :mod:`fleetsim` is cheap: each public name is imported from its module when it is first used,
so that the command line and the pytest plugin (loaded in every pytest session of an environment where
fleetsim is installed) pay only for what they use.

The library holds no tests, so pytest does not rewrite its asserts (PYTEST_DONT_REWRITE; the plugin
unmarks its other modules, see ``pytest_fleetsim.plugin``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fleetsim.dispatch import Assignment, Dispatcher, OpenOrder, OrderBoard
    from fleetsim.enums import ConflictModel, Direction, Disturbed, JointKind, Progress, Shape, Traverse, TurnCapability
    from fleetsim.errors import (
        FleetsimError,
        LayoutError,
        LoadError,
        LoadErrors,
        Location,
        MapError,
        PlannerError,
        ScenarioError,
        ScenarioFileError,
        SuiteError,
        UnreachableTaskError,
    )
    from fleetsim.exec.spec import load_planner_factory
    from fleetsim.layout import Connection, Continuation, Layout, LintFinding, Segment, build_layout
    from fleetsim.load import (
        ScenarioSpec,
        Suite,
        TiledMap,
        discover_suites,
        load_map,
        load_scenario,
        load_scenario_dir,
        load_suite,
        write_map,
    )
    from fleetsim.orders import Order, Shift, Stop
    from fleetsim.planning import (
        CollisionAlert,
        FleetLeg,
        FleetPlan,
        FleetSnapshot,
        Planner,
        Quiet,
        Rejection,
        RejectionCode,
        RouteError,
        VehicleState,
    )
    from fleetsim.scenario import (
        DEFAULT_VEHICLE_TYPE,
        Expectations,
        Scenario,
        ScenarioSettings,
        Task,
        Vehicle,
        VehicleType,
    )
    from fleetsim.sim import Divergence, Failure, RunResult, first_divergence, run_scenario
    from fleetsim.specs.python import PlannerSpecError

from fleetsim.version import __version__

__all__ = [
    "DEFAULT_VEHICLE_TYPE",
    "Assignment",
    "CollisionAlert",
    "ConflictModel",
    "Connection",
    "Continuation",
    "Direction",
    "Dispatcher",
    "Disturbed",
    "Divergence",
    "Expectations",
    "Failure",
    "FleetLeg",
    "FleetPlan",
    "FleetSnapshot",
    "FleetsimError",
    "JointKind",
    "Layout",
    "LayoutError",
    "LintFinding",
    "LoadError",
    "LoadErrors",
    "Location",
    "MapError",
    "OpenOrder",
    "Order",
    "OrderBoard",
    "Planner",
    "PlannerError",
    "PlannerSpecError",
    "Progress",
    "Quiet",
    "Rejection",
    "RejectionCode",
    "RouteError",
    "RunResult",
    "Scenario",
    "ScenarioError",
    "ScenarioFileError",
    "ScenarioSettings",
    "ScenarioSpec",
    "Segment",
    "Shape",
    "Shift",
    "Stop",
    "Suite",
    "SuiteError",
    "Task",
    "TiledMap",
    "Traverse",
    "TurnCapability",
    "UnreachableTaskError",
    "Vehicle",
    "VehicleState",
    "VehicleType",
    "__version__",
    "build_layout",
    "discover_suites",
    "first_divergence",
    "load_map",
    "load_planner_factory",
    "load_scenario",
    "load_scenario_dir",
    "load_suite",
    "run_scenario",
    "write_map",
]

_HOMES: dict[str, str] = {
    "Assignment": "fleetsim.dispatch",
    "CollisionAlert": "fleetsim.planning",
    "ConflictModel": "fleetsim.enums",
    "Connection": "fleetsim.layout",
    "Continuation": "fleetsim.layout",
    "DEFAULT_VEHICLE_TYPE": "fleetsim.scenario",
    "Direction": "fleetsim.enums",
    "Dispatcher": "fleetsim.dispatch",
    "Disturbed": "fleetsim.enums",
    "Divergence": "fleetsim.sim",
    "Expectations": "fleetsim.scenario",
    "Failure": "fleetsim.sim",
    "FleetLeg": "fleetsim.planning",
    "FleetPlan": "fleetsim.planning",
    "FleetSnapshot": "fleetsim.planning",
    "FleetsimError": "fleetsim.errors",
    "JointKind": "fleetsim.enums",
    "Layout": "fleetsim.layout",
    "LayoutError": "fleetsim.errors",
    "LintFinding": "fleetsim.layout",
    "LoadError": "fleetsim.errors",
    "LoadErrors": "fleetsim.errors",
    "Location": "fleetsim.errors",
    "MapError": "fleetsim.errors",
    "OpenOrder": "fleetsim.dispatch",
    "Order": "fleetsim.orders",
    "OrderBoard": "fleetsim.dispatch",
    "Planner": "fleetsim.planning",
    "PlannerError": "fleetsim.errors",
    "PlannerSpecError": "fleetsim.specs.python",
    "Progress": "fleetsim.enums",
    "Quiet": "fleetsim.planning",
    "Rejection": "fleetsim.planning",
    "RejectionCode": "fleetsim.planning",
    "RouteError": "fleetsim.planning",
    "RunResult": "fleetsim.sim",
    "Scenario": "fleetsim.scenario",
    "ScenarioError": "fleetsim.errors",
    "ScenarioFileError": "fleetsim.errors",
    "ScenarioSettings": "fleetsim.scenario",
    "ScenarioSpec": "fleetsim.load",
    "Segment": "fleetsim.layout",
    "Shape": "fleetsim.enums",
    "Shift": "fleetsim.orders",
    "Stop": "fleetsim.orders",
    "Suite": "fleetsim.load",
    "SuiteError": "fleetsim.errors",
    "Task": "fleetsim.scenario",
    "TiledMap": "fleetsim.load",
    "Traverse": "fleetsim.enums",
    "TurnCapability": "fleetsim.enums",
    "UnreachableTaskError": "fleetsim.errors",
    "Vehicle": "fleetsim.scenario",
    "VehicleState": "fleetsim.planning",
    "VehicleType": "fleetsim.scenario",
    "build_layout": "fleetsim.layout",
    "discover_suites": "fleetsim.load",
    "first_divergence": "fleetsim.sim",
    "load_map": "fleetsim.load",
    "load_planner_factory": "fleetsim.exec.spec",
    "load_scenario": "fleetsim.load",
    "load_scenario_dir": "fleetsim.load",
    "load_suite": "fleetsim.load",
    "run_scenario": "fleetsim.sim",
    "write_map": "fleetsim.load",
}


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'fleetsim' has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value  # looked up once
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
