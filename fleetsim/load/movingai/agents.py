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

from collections.abc import Sequence
from pathlib import Path

from fleetsim.enums import Progress, TurnCapability
from fleetsim.errors import Location
from fleetsim.layout.segment import Segment
from fleetsim.load.movingai.cells import Cell, GridCells, neighbour_toward
from fleetsim.load.movingai.grid import Grid
from fleetsim.load.movingai.scen import ScenAgent
from fleetsim.scenario import Task, Vehicle, VehicleType

__all__ = ["MOVINGAI_TYPE_NAME", "agent_vehicles", "movingai_vehicle_type"]

MOVINGAI_TYPE_NAME = "movingai"


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


def agent_vehicles(
    agents: Sequence[ScenAgent], grid: Grid, segments: Sequence[Segment], vehicle_type: VehicleType, path: Path
) -> tuple[tuple[tuple[Vehicle, int], ...], tuple[tuple[Task, int], ...]]:
    """The agents' vehicles and tasks (see the module docstring), each with its line in ``path``.

    An agent on a cell without a free neighbour has no segment to stand on: a located error."""
    cells = GridCells(grid, segments)
    taken: set[Cell] = set()
    vehicles, tasks = [], []
    for number, agent in enumerate(agents, start=1):
        goal_next = _around(cells, agent.goal, agent.start, None, path, agent.line, "goal")
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


def _around(
    cells: GridCells, cell: Cell, toward: Cell, taken: set[Cell] | None, path: Path, line: int, what: str
) -> Cell:
    """The neighbour of ``cell`` its segment leads to (:func:`neighbour_toward`), errors at the agent's row."""
    row, column = cell
    where = Location(path, line=line, field=f"{what}_x")
    return neighbour_toward(cells, cell, toward, taken, f"the {what} (x={column}, y={row})", where)
