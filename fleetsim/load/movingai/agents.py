"""A ``.scen`` file's first N agents as fleetsim vehicles, each with one task.

fleetsim's vehicles stand on segments, not on cells, so a cell becomes a segment at that cell:

- **Start.** Agent ``i`` (1-based, file order) is vehicle ``i``, at rest on its start cell's centre, on
  the segment from that cell to one of its free neighbours, facing it (``progress forward``). The
  neighbour is the first, in this order, that is not a cell of an earlier agent's start segment (so
  vehicles do not start on conflicting segments when they can help it), then the one nearest the goal
  (by Manhattan distance), then right, below, left, above.
- **Goal.** Its task (id ``i``) is the segment between the goal cell and the goal cell's free neighbour
  nearest the start (Manhattan; ties as above). A planner that arrives over that neighbour enters the
  goal segment there and comes to rest on the goal cell, its last leg's end; fleetsim counts the task done
  when the vehicle enters its goal segment, one cell before the goal cell. An agent whose start is its
  goal starts on its goal segment, so its task is done at once.

The vehicle type, unless the scenario's ``vehicle_type`` names one, is :func:`movingai_vehicle_type`: one
cell per second at cruise, so that a route of ``k`` cells takes about ``k`` seconds, as ``k`` timesteps
of a MAPF plan.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from fleetsim.enums import Progress, Traverse, TurnCapability
from fleetsim.errors import Location, ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.movingai.grid import Grid
from fleetsim.load.movingai.scen import ScenAgent
from fleetsim.scenario import Task, Vehicle, VehicleType

__all__ = ["MOVINGAI_TYPE_NAME", "agent_vehicles", "movingai_vehicle_type"]

MOVINGAI_TYPE_NAME = "movingai"
Cell = tuple[int, int]
_CELL_NAME = re.compile(r"r([0-9]+)c([0-9]+)")


def movingai_vehicle_type(cell_size: float) -> VehicleType:
    """The vehicle of a MAPF agent on cells of ``cell_size`` metres: half a cell long and wide (so only
    segments that share a cell conflict), one cell per second at cruise, accelerating at four cells per
    second squared (a start or a stop costs an eighth of a cell, a quarter of a second), turning in place
    at 90° per second (a quarter turn takes one second, as a rotation takes one timestep in the League of
    Robot Runners)."""
    return VehicleType(
        name=MOVINGAI_TYPE_NAME,
        length=0.5 * cell_size,
        width=0.5 * cell_size,
        height=0.5 * cell_size,
        max_speed=cell_size,
        acceleration=4.0 * cell_size,
        turn_capability=TurnCapability.IN_PLACE,
        turn_rate=90.0,
    )


class _Cells:
    """Which segment joins two neighbouring cells, from the segments' end names (``r3c4``)."""

    def __init__(self, grid: Grid, segments: Sequence[Segment]) -> None:
        self.grid = grid
        self.between: dict[tuple[Cell, Cell], int] = {}
        for segment in segments:
            if segment.ends is not None:
                first, second = (_cell(name) for name in segment.ends)
                self.between[(first, second)] = segment.id

    def leaving(self, cell: Cell, neighbour: Cell) -> tuple[int, Traverse]:
        if (cell, neighbour) in self.between:
            return self.between[(cell, neighbour)], Traverse.FORWARD
        return self.between[(neighbour, cell)], Traverse.BACKWARD

    def neighbours(self, cell: Cell) -> tuple[Cell, ...]:
        row, column = cell
        around = ((row, column + 1), (row + 1, column), (row, column - 1), (row - 1, column))
        return tuple(other for other in around if self.grid.free(*other))


def _cell(name: str) -> Cell:
    found = _CELL_NAME.fullmatch(name)
    assert found is not None  # the reader names every end so
    return int(found.group(1)), int(found.group(2))


def _distance(a: Cell, b: Cell) -> int:
    return abs(a[0] - b[0]) + abs(a[1] - b[1])


def agent_vehicles(
    agents: Sequence[ScenAgent], grid: Grid, segments: Sequence[Segment], vehicle_type: VehicleType, path: Path
) -> tuple[tuple[tuple[Vehicle, int], ...], tuple[tuple[Task, int], ...]]:
    """The agents' vehicles and tasks (see the module docstring), each with its line in ``path``.

    An agent on a cell without a free neighbour has no segment to stand on: a located error."""
    cells = _Cells(grid, segments)
    taken: set[Cell] = set()
    vehicles, tasks = [], []
    for number, agent in enumerate(agents, start=1):
        goal_next = _around(cells, agent.goal, agent.start, taken=None, path=path, line=agent.line, what="goal")
        goal_segment, _ = cells.leaving(agent.goal, goal_next)
        if agent.start == agent.goal:
            start_next = goal_next
        else:
            start_next = _around(cells, agent.start, agent.goal, taken, path, agent.line, "start")
        segment, traverse = cells.leaving(agent.start, start_next)
        taken.update((agent.start, start_next))
        vehicles.append((Vehicle(number, segment, traverse, Progress.FORWARD, vehicle_type), agent.line))
        tasks.append((Task(number, number, goal_segment), agent.line))
    return tuple(vehicles), tuple(tasks)


def _around(cells: _Cells, cell: Cell, toward: Cell, taken: set[Cell] | None, path: Path, line: int, what: str) -> Cell:
    """The neighbour of ``cell`` its segment leads to: not ``taken`` if possible, then nearest ``toward``."""
    options = cells.neighbours(cell)
    if not options:
        row, column = cell
        msg = (
            f"the {what} (x={column}, y={row}) is a free cell without a free neighbour: "
            "no segment reaches it, so no vehicle can stand or arrive there"
        )
        raise ScenarioFileError(msg, Location(path, line=line, field=f"{what}_x"))
    blocked = taken or set()
    ranked = sorted(enumerate(options), key=lambda item: (item[1] in blocked, _distance(item[1], toward), item[0]))
    return ranked[0][1]
