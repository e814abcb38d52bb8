"""fleetsim: test fleet route planners against declarative scenarios, headless."""

from fleetsim.enums import ConflictModel, Direction, JointKind, Progress, Shape, Traverse, TurnCapability
from fleetsim.errors import (
    FleetsimError,
    LayoutError,
    LoadError,
    Location,
    MapError,
    ScenarioFileError,
    SuiteError,
)
from fleetsim.layout.segment import Segment

__version__ = "0.1.0"

__all__ = [
    "ConflictModel",
    "Direction",
    "FleetsimError",
    "JointKind",
    "LayoutError",
    "LoadError",
    "Location",
    "MapError",
    "Progress",
    "ScenarioFileError",
    "Segment",
    "Shape",
    "SuiteError",
    "Traverse",
    "TurnCapability",
    "__version__",
]
