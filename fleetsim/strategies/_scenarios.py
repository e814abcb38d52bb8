"""The ``scenarios`` strategy: a layout, vehicles on non-conflicting starts, and reachable tasks.

Everything is valid by construction rather than filtered afterwards, so Hypothesis rarely discards an
example: starts are drawn only among segments whose conflict sets miss every earlier start's, and goals
only among segments the vehicle can still reach with its turn capability whatever route a planner took
to the goal before. Counts are drawn first (``st.integers``), so they shrink toward the minimum. The
layout is replaced by a larger one when it has no room for the number of vehicles drawn.

Every scenario is also solvable without a possible collision, so a failing run blames the planner, not
the scenario: the vehicles could do their tasks one after another, each keeping clear of the others
standing on their starts (later vehicles) or parked on their last goals (earlier ones). Without this, a
vehicle parked for good on the only way to another's goal would fail every planner.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

from hypothesis import strategies as st
from hypothesis.strategies import SearchStrategy

from fleetsim.enums import ConflictModel, Progress, Traverse, TurnCapability
from fleetsim.layout.layout import Layout, build_layout
from fleetsim.layout.segment import Segment
from fleetsim.load.suites.scenario import default_vehicle_type
from fleetsim.planners.routing import State, next_states
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, ScenarioSettings, Task, Vehicle, VehicleType
from fleetsim.strategies._layouts import SMALLEST_FIRST, check_kind, check_range, draw_kind_layout, plainest_layout
from fleetsim.strategies._room import NoRoomError, Room, clashes, spare_starts

__all__ = ["GenerationSpec", "scenarios"]


@dataclass(frozen=True, slots=True)
class GenerationSpec:
    """What :func:`scenarios` may generate; ranges are inclusive ``(low, high)``.

    ``size`` means junctions per side (warehouse), straights per side (loop) or straights between the
    two end straights (corridor). ``one_way`` applies to loops (``None``: either). Each vehicle's type is
    drawn from ``vehicle_types`` (``()``: the default type); ``settings`` go into every scenario.
    """

    layout: str = "any"
    size: tuple[int, int] = (1, 3)
    vehicles: tuple[int, int] = (1, 3)
    tasks: tuple[int, int] = (1, 2)  # per vehicle
    one_way: bool | None = None
    vehicle_types: tuple[VehicleType, ...] = ()
    settings: ScenarioSettings = field(default_factory=ScenarioSettings)

    def __post_init__(self) -> None:
        check_kind(self.layout)
        check_range("size", self.size, 1)
        check_range("vehicles", self.vehicles, 0)
        check_range("tasks", self.tasks, 0)
        names = [t.name.casefold() for t in self.types]
        if len(set(names)) != len(names):
            msg = f"vehicle_types={[t.name for t in self.types]!r} must have distinct names (case-insensitive)"
            raise ValueError(msg)

    @property
    def types(self) -> tuple[VehicleType, ...]:
        """The types vehicles are drawn from."""
        return self.vehicle_types or (DEFAULT_VEHICLE_TYPE,)

    @property
    def type_map(self) -> Mapping[str, VehicleType]:
        """The types by name, as the scenario (and the loader) hold them."""
        return MappingProxyType({t.name: t for t in self.types})


def _layout(segments: Sequence[Segment], settings: ScenarioSettings, radius: float) -> Layout:
    return build_layout(
        segments,
        vehicle_radius=radius,
        connection_tolerance=settings.connection_tolerance,
        joint_angle_tolerance=settings.joint_angle_tolerance,
        safety_margin=settings.safety_margin,
        conflict_model=settings.conflict_model,
    )


def _radius(used: Sequence[VehicleType], types: Mapping[str, VehicleType], settings: ScenarioSettings) -> float:
    """The conflict radius the loader will use for these vehicles (the same rule, or the round trip breaks)."""
    if not used:
        default = default_vehicle_type(types, settings)
        used = [default] if default is not None else list(types.values())
    if settings.conflict_model is ConflictModel.BBOX:
        return max(t.bbox_radius for t in used)
    return max(t.swept_radius for t in used)


def _state_key(state: State) -> tuple[int, bool, bool]:
    return state[0], state[1] is Traverse.BACKWARD, state[2] is Progress.REVERSE


class _Reach:
    """The states a vehicle of one turn capability reaches from a state in one or more legs (memoised).

    With ``usable``, only over those segments: the part of the map the vehicle may drive while every
    other vehicle stands still (see :func:`_draw_tasks`).
    """

    def __init__(self, layout: Layout, capability: TurnCapability, usable: frozenset[int] | None = None) -> None:
        self.layout = layout
        self.capability = capability
        self.usable = usable
        self._after: dict[State, frozenset[State]] = {}

    def after(self, state: State) -> frozenset[State]:
        if state not in self._after:
            # The state itself stays out, as in the route searches: a route never comes back to where it
            # starts (a goal on the vehicle's own leg is met there, without a route).
            seen = {state}
            frontier = [state]
            while frontier:
                for following in next_states(self.layout, self.capability, frontier.pop()):
                    if following not in seen and (self.usable is None or following[0] in self.usable):
                        seen.add(following)
                        frontier.append(following)
            self._after[state] = frozenset(seen - {state})
        return self._after[state]

    def matches(self, state: State, progress: Progress | None) -> bool:
        # A vehicle turning in place can arrive with either progress (it turns on the goal leg).
        return progress is None or self.capability is TurnCapability.IN_PLACE or state[2] is progress

    def goals(self, here: frozenset[State], progress: Progress | None, *, every: bool) -> set[int]:
        """Segments reachable in one or more legs, arriving with ``progress``, from every state in
        ``here`` (``every``) or from at least one."""
        found: set[int] | None = None
        for state in sorted(here, key=_state_key):
            reached = {s[0] for s in self.after(state) if self.matches(s, progress)}
            found = reached if found is None else (found & reached if every else found | reached)
        return found or set()

    def arrivals(self, here: frozenset[State], goal: int, progress: Progress | None) -> frozenset[State]:
        """Every state a vehicle in ``here`` may be in once it has reached ``goal``, whatever its route."""
        found = {s for state in here for s in (state, *self.after(state)) if s[0] == goal and self.matches(s, progress)}
        if progress is not None and self.capability is TurnCapability.IN_PLACE:
            found = {(segment, traverse, progress) for segment, traverse, _ in found}
        return frozenset(found)


class _Whereabouts:
    """Where a vehicle may be after its tasks so far: ``anywhere`` whatever routes a planner takes (every
    next goal must be reachable from all of these), ``alone`` along routes that keep clear of the
    vehicles standing still (the next goal must be reachable from one of these)."""

    def __init__(self, anywhere: _Reach, alone: _Reach, start: State) -> None:
        self.reach = (anywhere, alone)
        self.here = (frozenset({start}), frozenset({start}))

    def goals(
        self, progress: Progress | None, here: tuple[frozenset[State], frozenset[State]] | None = None
    ) -> list[int]:
        """Goals for the next task from ``here`` (default: where the vehicle is now), sorted."""
        anywhere, alone = here or self.here
        return sorted(
            self.reach[0].goals(anywhere, progress, every=True) & self.reach[1].goals(alone, progress, every=False)
        )

    def after(self, goal: int, progress: Progress | None) -> tuple[frozenset[State], frozenset[State]]:
        """Where the vehicle may be once it has reached ``goal``."""
        return (
            self.reach[0].arrivals(self.here[0], goal, progress),
            self.reach[1].arrivals(self.here[1], goal, progress),
        )


def _starts(layout: Layout, taken: set[int], capability: TurnCapability) -> list[State]:
    """States a vehicle may start in: no conflict shared with earlier starts, and somewhere to go."""
    return [
        (sid, traverse, progress)
        for sid, segment in layout.segments.items()
        if not layout.conflicts(sid) & taken
        for traverse in Traverse
        if segment.allows(traverse)
        for progress in Progress
        if any(True for _ in next_states(layout, capability, (sid, traverse, progress)))
    ]


def _draw_tasks(draw: st.DrawFn, where: _Whereabouts, count: int) -> list[tuple[int, Progress | None]]:
    """Up to ``count`` goals, each reachable from wherever the previous one may have left the vehicle.

    Goals before the last keep a way on when possible; a vehicle that can get nowhere gets fewer tasks.
    """
    goals: list[tuple[int, Progress | None]] = []
    for number in range(count):
        progress = draw(st.sampled_from((None, Progress.FORWARD, Progress.REVERSE)))
        options = where.goals(progress)
        if not options:
            progress, options = None, where.goals(None)
        if number < count - 1:
            options = [g for g in options if where.goals(None, where.after(g, progress))] or options
        if not options:
            break
        goal = draw(st.sampled_from(options))
        goals.append((goal, progress))
        where.here = where.after(goal, progress)
    return goals


def _usable(layout: Layout, standing: Iterable[int]) -> frozenset[int]:
    """Segments a vehicle may drive without conflicting with vehicles standing on ``standing``."""
    blocked = set().union(*(layout.conflicts(sid) for sid in standing))
    return frozenset(sid for sid in layout.segments if sid not in blocked)


def _draw_starts(
    draw: st.DrawFn, layout: Layout, wanted: Sequence[VehicleType], apart: Layout, spare: frozenset[int], room: Room
) -> list[tuple[State, VehicleType]]:
    """A start per wanted vehicle, each leaving room for the rest.

    ``spare`` holds at least ``len(wanted)`` starts pairwise apart in ``apart`` (the layout with the
    largest radius of the spec, whose conflict sets contain ``layout``'s). A start is kept only if
    enough spare starts stay apart from it, or a new spare set of the segments still free is large
    enough; so some spare start is always an option for the next vehicle. A start that would leave
    too little room gives way to the next one that leaves enough: what a drawn start means then does
    not depend on how many vehicles follow, which keeps shrinking stable.
    """
    starts: list[tuple[State, VehicleType]] = []
    taken: set[int] = set()
    blocked: set[int] = set()  # segments clashing in ``apart`` with a start so far
    left = set(spare)

    def leaves(segment: int, still: int) -> set[int] | None:
        near = clashes(apart, segment)
        if len(left - near) >= still:
            return left - near
        again = spare_starts(apart, room.capabilities, among=set(apart.segments) - blocked - near)
        return set(again) if len(again) >= still else None

    for number, vehicle_type in enumerate(wanted, start=1):
        options = _starts(layout, taken, vehicle_type.turn_capability)
        first = options.index(draw(st.sampled_from(options)))
        still = len(wanted) - number
        for start in (*options[first:], *options[:first]):
            rest = leaves(start[0], still)
            if rest is not None:
                break
        assert rest is not None, "a spare start is always an option"
        starts.append((start, vehicle_type))
        taken |= layout.conflicts(start[0])
        blocked |= clashes(apart, start[0])
        left = rest
    return starts


class _Sizing:
    """Which layouts have room for how many vehicles of a spec (see :mod:`fleetsim.strategies._room`)."""

    def __init__(self, spec: GenerationSpec) -> None:
        self.spec = spec
        self.kinds = SMALLEST_FIRST if spec.layout == "any" else (spec.layout,)
        self.sizes = range(spec.size[0], spec.size[1] + 1)
        self.radius = _radius(spec.types, spec.type_map, spec.settings)  # the largest any mix of types gives
        self.room = Room(self._plainest, {t.turn_capability for t in spec.types})

    def _plainest(self, kind: str, size: int) -> Layout:
        return self.layout(plainest_layout(kind, size, self.spec.one_way))

    def layout(self, segments: Sequence[Segment]) -> Layout:
        return _layout(segments, self.spec.settings, self.radius)

    def check(self) -> None:
        """Refuse a spec none of whose layouts has room for its largest number of vehicles."""
        most = self.spec.vehicles[1]
        if not any(self.room.smallest(kind, self.sizes, most) is not None for kind in self.kinds):
            raise NoRoomError(
                self.spec.layout,
                self.spec.size,
                self.spec.vehicles,
                self.room.most(self.kinds, self.sizes),
                self.radius,
            )

    def draw(self, draw: st.DrawFn) -> tuple[str, int, list[Segment]]:
        """Kind, size and segments, drawn as :func:`fleetsim.strategies.layouts` draws them."""
        kind = draw(st.sampled_from(self.kinds))
        size = draw(st.integers(*self.spec.size))
        return kind, size, draw_kind_layout(draw, kind, size, self.spec.one_way)

    def fit(
        self, kind: str, size: int, segments: list[Segment], count: int
    ) -> tuple[list[Segment], Layout, frozenset[int]]:
        """A layout with room for ``count`` vehicles: its segments, its largest-radius layout, a spare set.

        The drawn layout when it has room; else the plainest layout of the next kind (in smallest-first
        order, starting with the drawn one) and size (from the drawn one up) that has. The layout is
        drawn before the number of vehicles, so a counterexample shrinks toward fewer vehicles and a
        smaller layout independently.
        """
        apart = self.layout(segments)
        spare = spare_starts(apart, self.room.capabilities)
        if len(spare) >= count:
            return segments, apart, spare
        first = self.kinds.index(kind)
        for other in (*self.kinds[first:], *self.kinds[:first]):
            sizes = [n for n in self.sizes if n >= size] if other == kind else self.sizes
            fitting = self.room.smallest(other, sizes, count) or self.room.smallest(other, self.sizes, count)
            if fitting is not None:
                return (
                    plainest_layout(other, fitting, self.spec.one_way),
                    self.room.layout(other, fitting),
                    self.room.spare(other, fitting),
                )
        raise AssertionError("check() found room for the most vehicles in some kind")


def _draw_scenario(draw: st.DrawFn, spec: GenerationSpec, sizing: _Sizing, name: str) -> Scenario:
    settings, types = spec.settings, spec.type_map
    kind, size, drawn = sizing.draw(draw)
    count = draw(st.integers(*spec.vehicles))
    segments, apart, spare = sizing.fit(kind, size, drawn, count)
    wanted = [draw(st.sampled_from(spec.types)) for _ in range(count)]
    radius = _radius(wanted, types, settings)
    layout = apart if radius == apart.vehicle_radius else _layout(segments, settings, radius)
    starts = _draw_starts(draw, layout, wanted, apart, spare, sizing.room)
    vehicles: list[Vehicle] = []
    tasks: list[Task] = []
    parked: list[int] = []  # where the vehicles so far end up: their last goal, else their start
    reaches: dict[TurnCapability, _Reach] = {}
    for index, (start, vehicle_type) in enumerate(starts):
        vehicles.append(Vehicle(index + 1, *start, vehicle_type))
        capability = vehicle_type.turn_capability
        anywhere = reaches.setdefault(capability, _Reach(layout, capability))
        standing = [*parked, *(other[0] for other, _ in starts[index + 1 :])]
        where = _Whereabouts(anywhere, _Reach(layout, capability, _usable(layout, standing)), start)
        goals = _draw_tasks(draw, where, draw(st.integers(*spec.tasks)))
        tasks += [Task(len(tasks) + k, index + 1, goal, arrive) for k, (goal, arrive) in enumerate(goals, start=1)]
        parked.append(goals[-1][0] if goals else start[0])
    return Scenario(
        name=name,
        layout=layout,
        vehicle_types=types,
        vehicles=tuple(vehicles),
        tasks=tuple(tasks),
        settings=settings,
    )


def scenarios(spec: GenerationSpec = GenerationSpec(), *, name: str = "generated") -> SearchStrategy[Scenario]:
    """Complete, valid scenarios as ``spec`` describes; each loads back unchanged after :func:`save_scenario`.

    Every scenario has a number of vehicles in ``spec.vehicles``: layouts are drawn large enough for
    it. A spec none of whose layouts has room for ``spec.vehicles[1]`` vehicles raises
    :class:`NoRoomError` (a ``ValueError``) here, before anything is drawn.
    """

    sizing = _Sizing(spec)
    sizing.check()

    @st.composite
    def strategy(draw: st.DrawFn) -> Scenario:
        return _draw_scenario(draw, spec, sizing, name)

    return strategy()
