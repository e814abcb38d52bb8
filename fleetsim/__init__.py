"""fleetsim: test fleet route planners against declarative scenarios, headless.

The public API is exactly what this module exports (``__all__``); everything else may change.
"""

from fleetsim.enums import ConflictModel, Direction, JointKind, Progress, Shape, Traverse, TurnCapability
from fleetsim.errors import (
    FleetsimError,
    LayoutError,
    LoadError,
    Location,
    MapError,
    PlannerError,
    ScenarioFileError,
    SuiteError,
    UnreachableTaskError,
)
from fleetsim.layout import Connection, Layout, LintFinding, Segment, build_layout
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
from fleetsim.planning import (
    CollisionAlert,
    FleetLeg,
    FleetPlan,
    FleetSnapshot,
    Planner,
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
from fleetsim.sim.planner_spec import PlannerSpecError, load_planner_factory

__version__ = "0.1.0"

__all__ = [
    "CollisionAlert",
    "ConflictModel",
    "Connection",
    "DEFAULT_VEHICLE_TYPE",
    "Direction",
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
    "Location",
    "MapError",
    "Planner",
    "PlannerError",
    "PlannerSpecError",
    "Progress",
    "Rejection",
    "RejectionCode",
    "RouteError",
    "RunResult",
    "Scenario",
    "ScenarioFileError",
    "ScenarioSettings",
    "ScenarioSpec",
    "Segment",
    "Shape",
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
    "__version__",
]
