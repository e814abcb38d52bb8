"""A League problem's robots and tasks as fleetsim vehicles and transport orders on the grid's lane graph.

- **Robots.** Agent ``i`` (from 0, the agent file's order) of the first ``teamSize`` is vehicle ``i``,
  placed as a ``.scen`` start is (:mod:`fleetsim.load.movingai.agents`): at rest on its start cell's
  centre, on the segment to a free neighbour that is not a cell of an earlier robot's start segment when
  one is left, else right, below, left, above.
- **Tasks.** Task ``k`` (from 0, the task file's order; the Start-Kit's task id) is order ``t<k>``, released
  at 0 and held back by the closed pool; each errand is a stop (dwell 0) on the segment between its cell
  and the neighbour nearest the previous errand (the first errand: the one nearest the next; a lone
  errand: right, below, left, above), as a ``.scen`` goal is placed toward the start. The stop is reached
  when the vehicle enters that segment, one cell before the errand's cell (the League counts the errand
  when the robot stands on the cell).
- **The pool.** ``max(1, floor(numTasksReveal × teamSize))`` tasks revealed at 0, one more for each
  finished, in file order (Start-Kit ``TaskManager::reveal_tasks``). The Start-Kit starts over at the
  file's first task when the file runs out; fleetsim reveals the file ``rounds`` times over (default
  once), so that every order is known before the run, as a trace header holds them.
- **Vehicle type.** The MovingAI type (one cell per second, a quarter turn per second, half a cell
  square) unless the suite declares types; ``agentSize`` scales its footprint (``agentSize × ½`` cell).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from fleetsim.enums import Progress
from fleetsim.errors import Location, ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.lorr.delays import delay_disturbances
from fleetsim.load.lorr.files import LorrItem, location_name, read_agents, read_tasks
from fleetsim.load.lorr.problem import LorrProblem
from fleetsim.load.movingai.agents import movingai_vehicle_type
from fleetsim.load.movingai.cells import Cell, GridCells, neighbour_toward
from fleetsim.load.movingai.grid import Grid
from fleetsim.orders import LorrSetup, Order, Stop
from fleetsim.scenario import RandomDisturbances, Vehicle, VehicleType

__all__ = ["LorrFleet", "lorr_fleet", "task_pool"]

_MOST_REVEALED = 2.0**31  # a pool larger than any task file (and than a float can floor into an int)
_STRATEGY_NOTE = (
    "taskAssignmentStrategy {0!r} has no counterpart: the tasks are revealed as the pool and the "
    "dispatcher assigns them (the reference dispatcher gives each to the idle robot with the least travel time)"
)


@dataclass(frozen=True, slots=True)
class LorrFleet:
    """What a problem gives a scenario: located vehicles, orders, the pool, stops and the League setup."""

    vehicles: tuple[tuple[Vehicle, int], ...]
    orders: tuple[Order, ...]
    pool: int
    vehicle_type: VehicleType
    disturbances: RandomDisturbances | None
    setup: LorrSetup


def task_pool(reveal: float, team_size: int) -> int:
    """How many tasks the League keeps revealed: ``max(1, floor(numTasksReveal × teamSize))``."""
    return max(1, math.floor(min(reveal * team_size, _MOST_REVEALED) + 1e-9))


def lorr_fleet(
    problem: LorrProblem,
    grid: Grid,
    segments: Sequence[Segment],
    cell_size: float,
    *,
    agents: int | None,
    agents_where: Location | None,
    horizon: int,
    given_type: VehicleType | None,
    rounds: int = 1,
) -> LorrFleet:
    """The fleet and orders of ``problem`` on ``grid`` (see the module docstring). ``agents``: the suite
    entry's robot count (``None``: ``teamSize``); ``given_type``: the suite's default vehicle type, if it
    declares types; ``rounds``: the task file this many times over (ids go on counting, as the
    Start-Kit's task ids do when it starts over). Every problem of the agent and task files is raised at
    its line."""
    robots = agents if agents is not None else problem.team_size
    cells = GridCells(grid, segments)
    errors = ErrorCollector()
    starts: tuple[LorrItem, ...] = ()
    tasks: tuple[LorrItem, ...] = ()
    with errors.collecting():
        starts = read_agents(problem.agent_path, grid)
    with errors.collecting():
        tasks = read_tasks(problem.task_path, grid, multi=problem.edition != "2023")
    errors.raise_if_any()
    if robots > len(starts):
        whose = "agents" if agents is not None else "teamSize"
        where = agents_where if agents is not None and agents_where is not None else problem.places.at("teamSize")
        msg = f"{whose}={robots}, but the agent file {problem.agent_path.name} has {len(starts)} agent(s)"
        raise ScenarioFileError(msg, where)
    if not tasks:
        raise ScenarioFileError("the task file has no tasks (its first line says 0)", Location(problem.task_path))
    notes: list[str] = []
    kind = given_type or movingai_vehicle_type(cell_size)
    if problem.agent_size is not None:
        if given_type is not None:
            notes.append(f"agentSize {problem.agent_size:g} is not mapped: the suite's vehicle type is used")
        elif problem.agent_size != 1.0:
            side = kind.length * problem.agent_size
            kind = replace(kind, length=side, width=side, height=side)
    vehicles = _vehicles(starts[:robots], cells, kind, problem)
    once = [_order(number, task, cells, problem) for number, task in enumerate(tasks)]
    orders = tuple(
        replace(order, id=f"t{round_ * len(once) + number}")
        for round_ in range(rounds)
        for number, order in enumerate(once)
    )
    if problem.strategy is not None:
        notes.append(_STRATEGY_NOTE.format(problem.strategy))
    if problem.agent_counter is not None:
        notes.append(f"agentCounter {problem.agent_counter} is not mapped: fleetsim has no counterpart")
    disturbances = None
    if problem.delays is not None:
        disturbances, delay_notes = delay_disturbances(problem.delays, robots, 1.0)
        notes += delay_notes
    pool = task_pool(problem.reveal, robots)
    setup = LorrSetup(problem.path.name, problem.edition, robots, pool, horizon, 1.0, tuple(notes))
    return LorrFleet(vehicles, orders, pool, kind, disturbances, setup)


def _vehicles(
    starts: Sequence[LorrItem], cells: GridCells, kind: VehicleType, problem: LorrProblem
) -> tuple[tuple[Vehicle, int], ...]:
    taken: set[Cell] = set()
    vehicles = []
    for number, start in enumerate(starts):
        cell = start.cells[0]
        what = f"agent {number}'s start, {location_name(start.locations[0], cells.grid)},"
        where = Location(problem.agent_path, line=start.line, column=1)
        neighbour = neighbour_toward(cells, cell, cell, taken, what, where)
        segment, traverse = cells.leaving(cell, neighbour)
        taken.update((cell, neighbour))
        vehicles.append((Vehicle(number, segment, traverse, Progress.FORWARD, kind), start.line))
    return tuple(vehicles)


def _order(number: int, task: LorrItem, cells: GridCells, problem: LorrProblem) -> Order:
    stops = []
    for index, cell in enumerate(task.cells):
        if index > 0:
            toward = task.cells[index - 1]
        elif len(task.cells) > 1:
            toward = task.cells[1]
        else:
            toward = cell
        what = f"errand {index + 1} of task {number}, {location_name(task.locations[index], cells.grid)},"
        where = Location(problem.task_path, line=task.line, column=1)
        neighbour = neighbour_toward(cells, cell, toward, None, what, where)
        segment, _ = cells.leaving(cell, neighbour)
        stops.append(Stop(segment))
    return Order(f"t{number}", tuple(stops), release=0.0, line=task.line)
