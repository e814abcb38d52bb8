"""What an imported map needs to be told, and what every loaded map is (whatever its format)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from fleetsim.layout.segment import Segment
from fleetsim.load.common.stations import NO_STATIONS, StationSets

__all__ = ["MapOptions", "SiteMap"]


@dataclass(frozen=True, slots=True)
class MapOptions:
    """A suite's ``map_options``: which part of a LIF or RMF file forms the driving map, and how big a
    MovingAI map's cells are.

    ``layout`` (LIF ``layoutId``) and ``robot_type`` (LIF ``manufacturer/seriesName``, or a LIF 1.0
    ``vehicleTypeId``) choose a LIF layout and whose edges form the map; ``level`` (a level name) and
    ``graph`` (a lane's ``graph_idx``) choose an RMF level and navigation graph. ``None``: the default.
    """

    layout: str | None = None
    robot_type: str | None = None
    level: str | None = None
    graph: int | None = None
    cell_size: float | None = None

    def given(self) -> dict[str, str | int | float]:
        """The options that are set, by name (in declaration order)."""
        values = {
            "layout": self.layout,
            "robot_type": self.robot_type,
            "level": self.level,
            "graph": self.graph,
            "cell_size": self.cell_size,
        }
        return {name: value for name, value in values.items() if value is not None}


@dataclass(frozen=True, slots=True)
class SiteMap:
    """A loaded driving map: segments sorted by id, and what loading it had to say.

    ``format`` is ``tiled``, ``lif``, ``rmf`` or ``movingai``; ``meters_per_pixel`` is known for Tiled and RMF maps
    drawn on an image. ``part`` names what was read of a LIF or RMF file (layout and robot type, level and
    graph, a MovingAI map's size). ``stations`` are the station sets the map names (:mod:`fleetsim.load.common.stations`): set
    name → its stations, each set's segments ascending, each once.
    """

    path: Path
    format: str
    segments: tuple[Segment, ...]
    warnings: tuple[str, ...] = ()
    meters_per_pixel: float | None = None
    part: str = ""
    stations: StationSets = field(default_factory=lambda: NO_STATIONS)
