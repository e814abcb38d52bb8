"""The commonest step of a large fleet, taken for all its cruising vehicles at once in arrays.

Most vehicles on most steps simply go on along their speed profile without reaching the end of their leg
(:meth:`Driver.cruise`). Done vehicle by vehicle, that step reads a dozen small objects per vehicle (the
driver, its profile, its track, the floats in them), and once a fleet no longer fits in the processor's
cache each of those reads waits for memory: the per-vehicle cost doubled from 100 to 1,000 vehicles.

:class:`FleetCruise` keeps what that step needs, for every vehicle that may cruise (*armed*), in one
array per quantity, and steps them all with the same floating-point operations in the same order as
:meth:`Driver.cruise` and :meth:`SpeedProfile.running_at`, so every position, speed and hash is the
same to the last bit. A vehicle the arrays cannot step this time (its profile or its leg ends, it moves
onto another piece of a curve, its plan changed) is handed back: its driver is brought up to date and the
loop steps it as before, then arms it again. While armed, a driver's own kinematic fields are stale;
:meth:`release` brings them up to date before anyone else reads them.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from functools import partial
from itertools import chain
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

from fleetsim.enums import Progress, Traverse
from fleetsim.motion.driver import EPS, Driver
from fleetsim.motion.profile import SpeedProfile
from fleetsim.planning.plans import FleetPlan
from fleetsim.planning.snapshot import VehicleState

__all__ = ["CruiseStep", "FleetCruise", "StateColumns"]

_make_state = partial(tuple.__new__, VehicleState)
_REVERSE = Progress.REVERSE

# Rows of the float table. The first eight are the driver's kinematics (Driver.kinematics), the last
# five of them in the order of a state's fields; handed back on release.
(ELAPSED, TRAVELLED, ODOMETER, DISTANCE, SPEED, X, Y, HEADING) = range(8)
# The speed profile's terms (SpeedProfile.running_terms).
(STOP, ACCELERATE_UNTIL, BRAKE_FROM, V0, ACCELERATION, HALF_ACCELERATION, PEAK, DECELERATION) = range(8, 16)
(PROFILE_DISTANCE, ACCELERATED, CRUISED) = range(16, 19)
# The leg's track and where on it the vehicle is: coordinates [LOW, HIGH) locate it on the piece that
# starts at START (Track.pieces); NOSE is its heading there.
(LENGTH, BACKWARD, LOW, HIGH, START, AX, AY, DX, DY, PIECE, NOSE) = range(19, 30)
_ROWS = 30
# Rows of the object table: a state's other fields.
_OBJECTS = 6  # id, segment, traverse, progress, type, disturbed

FloatRows = npt.NDArray[np.float64]


class StateColumns(NamedTuple):
    """The new states of a step's cruising vehicles, ascending id, as objects and as the columns they were
    made from: what the trace records of them is read from the columns, without taking each state apart
    again."""

    ids: list[int]
    states: list[VehicleState]
    segments: list[int]
    traverses: list[Traverse]
    progresses: list[Progress]
    motion: FloatRows  # rows: speed, x, y, heading (the states' fields)
    positions: npt.NDArray[np.intp]  # each vehicle's index in the drivers (the loop's order)


class CruiseStep(NamedTuple):
    """One step of the arrays: the vehicles stepped, and the indices (ascending) of all the others, which
    their drivers step one by one."""

    cruised: StateColumns
    others: list[int]


_NOBODY = StateColumns([], [], [], [], [], np.zeros((4, 0)), np.zeros(0, dtype=np.intp))


class FleetCruise:
    """The armed vehicles' cruise terms, by index in ``drivers`` (the loop's order, ascending id)."""

    # The smallest fleet the arrays pay for: their fixed cost per step (some sixty array operations) is
    # what stepping about 200 vehicles one by one costs (measured: 100 vehicles 8.7 µs per vehicle-step
    # one by one and 9.2 in arrays, 200 about even, 400 10.2 and 9.5).
    SMALLEST = 256
    # Steps a vehicle must be able to cruise on before it is armed: arming and handing back a vehicle
    # (some 7 µs at 10,000 vehicles) costs more than stepping it one by one twice (harness µs per
    # vehicle-step at 1,000 vehicles, medians of 3 paired runs: 6.29 arming every vehicle that may
    # cruise, 6.19 looking one step ahead, 6.08 two, 6.12 three; at 10,000, 9.12-9.14 either way).
    AHEAD = 2

    def __init__(self, drivers: Sequence[Driver], *, batched: bool = True) -> None:
        n = len(drivers)
        self._drivers = list(drivers)
        self.batched = batched  # False: nothing is ever armed; every vehicle is stepped by its driver
        self._everyone = list(range(n))
        self.released = _Released(self)  # the drivers by id, each handed back up to date first
        self.index = {driver.id: i for i, driver in enumerate(drivers)}
        self._table: FloatRows = np.zeros((_ROWS, n))
        self._armed = np.zeros(n, dtype=bool)
        self._plans: list[FleetPlan | None] = [None] * n  # the plan each armed vehicle was armed on
        self._recalled: list[int] = []  # armed vehicles to hand back at the next step (their plan changed)
        # A state's other fields, by index: the same objects a driver would put in its state.
        self._objects = np.full((_OBJECTS, n), None, dtype=object)
        self._objects[0] = [driver.id for driver in drivers]
        self._pending: list[int] = []  # arms taken into the tables at the next step
        self._pending_rows: list[tuple[float, ...]] = []
        self._pending_objects: list[tuple[Any, ...]] = []
        self._last_dt = 0.0  # the last step's length (0 before the first: every vehicle that may is armed)

    # -- arming and releasing --------------------------------------------------------------------------

    def arm(self, i: int, plan: FleetPlan) -> None:
        """Arm vehicle ``i`` if its driver will cruise on ``plan`` (its plan after the step just taken);
        taken into the tables at the next :meth:`step`."""
        if not self.batched:
            return
        driver = self._drivers[i]
        terms = driver.cruise_terms(plan)
        if terms is None:
            return
        profile, track = terms
        if type(profile) is not SpeedProfile:
            return  # slowing down for a disturbance: the driver steps it itself
        kinematics = driver.kinematics()
        elapsed, distance, speed = kinematics[ELAPSED], kinematics[DISTANCE], kinematics[SPEED]
        coordinate = track.length - distance if track.backward else distance
        along = track.along
        found = bisect_right(along, coordinate)
        low = along[found - 1] if found > 0 else -math.inf  # the coordinates that find the same piece
        high = along[found] if found < len(along) else math.inf
        # Not armed when the next AHEAD steps (each as long as the last) end its profile or, at the speed
        # it has now, reach the end of its leg or of its piece (on a curve's short pieces, almost every
        # step): the arrays would most likely hand it back before arming it paid. Its driver steps it
        # as the arrays would have (the same arithmetic), so only the work of arming it is saved.
        ahead = self.AHEAD * self._last_dt
        room = min(track.length - EPS - distance, coordinate - low if track.backward else high - coordinate)
        if elapsed + ahead >= profile.stop_time or room <= speed * ahead:
            return
        start, ax, ay, dx, dy, piece, _, forward, reverse = track.pieces[track.piece_of[found]]
        where = (track.length, 1.0 if track.backward else 0.0, low, high, start, ax, ay, dx, dy, piece)
        leg = plan.legs[0]
        nose = reverse if leg.progress is _REVERSE else forward
        self._plans[i] = plan
        self._pending.append(i)
        self._pending_rows.append(kinematics + profile.running_terms() + where + (nose,))
        self._pending_objects.append(
            (driver.id, leg.segment, leg.traverse, driver.progress, driver.type, driver.disturbed)
        )

    def release(self, i: int) -> None:
        """Hand vehicle ``i`` back to its driver: its fields brought up to date, no longer armed."""
        if self._pending:
            self._take_pending()
        if self._armed[i]:
            self._release(np.array([i], dtype=np.intp))

    def release_all(self) -> None:
        self._release(self._armed.nonzero()[0])

    def forget(self, vehicles: Iterable[int], plan_of: Callable[[int], FleetPlan]) -> None:
        """Hand back at the next step the armed vehicles among ``vehicles`` whose plan is now another
        than the one they were armed on."""
        index = self.index
        plans = self._plans
        for vehicle in vehicles:
            i = index[vehicle]
            if plans[i] is not None and plan_of(vehicle) is not plans[i]:
                self._recalled.append(i)

    def _release(self, indices: npt.NDArray[np.intp]) -> None:
        if self._pending:
            self._take_pending()
        listed = indices.tolist()
        drivers = self._drivers
        plans = self._plans
        for i, kinematics in zip(listed, self._table[: HEADING + 1, indices].T.tolist(), strict=True):
            drivers[i].take_kinematics(*kinematics)
            plans[i] = None
        self._armed[indices] = False

    def _take_pending(self) -> None:
        indices = self._pending
        # One flat pass over the rows' floats: np.array of the tuples first looks for their shape (156 rows
        # of 30: 75 µs against 107).
        flat = np.fromiter(chain.from_iterable(self._pending_rows), np.float64, count=len(indices) * _ROWS)
        self._table[:, indices] = flat.reshape(len(indices), _ROWS).T
        # Every field is a scalar to numpy (ints, str enums, a dataclass, None): one object per cell.
        self._objects[:, indices] = np.array(self._pending_objects, dtype=object).T
        self._armed[indices] = True
        self._pending = []
        self._pending_rows = []
        self._pending_objects = []

    # -- the step ------------------------------------------------------------------------------------

    def step(self, dt: float) -> CruiseStep:
        """Step every armed vehicle that cruises all step long, as :meth:`Driver.cruise` would.

        Returns the vehicles stepped (ascending id) and the indices of all the others (ascending),
        released to their drivers, which the loop steps one by one.
        """
        if self._pending:
            self._take_pending()
        if not self.batched:
            return CruiseStep(_NOBODY, self._everyone)
        self._last_dt = dt
        table = self._table
        armed = self._armed
        with np.errstate(all="ignore"):  # the columns of vehicles not armed hold anything
            t1 = table[ELAPSED] + dt
            stop = table[STOP]
            accelerating = t1 <= table[ACCELERATE_UNTIL]
            holding = t1 <= table[BRAKE_FROM]
            peak = table[PEAK]
            accelerated = table[ACCELERATED]
            cruised = table[CRUISED]
            v0 = table[V0]
            # SpeedProfile.running_at, phase by phase; min(a, b) is a unless b < a, max(a, b) a unless b > a.
            gone = t1 * (v0 + table[HALF_ACCELERATION] * t1)
            gone_accelerating = np.where(gone < accelerated, gone, accelerated)
            fast = v0 + table[ACCELERATION] * t1
            speed_accelerating = np.where(fast < peak, fast, peak)
            gone = accelerated + peak * (t1 - table[ACCELERATE_UNTIL])
            gone_holding = np.where(gone < cruised, gone, cruised)
            left = stop - t1
            fast = table[DECELERATION] * left
            speed_braking = np.where(fast < peak, fast, peak)
            gone = table[PROFILE_DISTANCE] - 0.5 * speed_braking * left
            gone_braking = np.where(gone > cruised, gone, cruised)
            travelled = np.where(accelerating, gone_accelerating, np.where(holding, gone_holding, gone_braking))
            speed = np.where(accelerating, speed_accelerating, np.where(holding, peak, speed_braking))
            # Driver.cruise
            distance = travelled - table[TRAVELLED]
            along = table[DISTANCE] + distance
            length = table[LENGTH]
            coordinate = np.where(table[BACKWARD] > 0.0, length - along, along)
            ok = armed & (t1 < stop) & (distance > 0.0) & ~(along >= length - EPS)
            ok &= (coordinate >= table[LOW]) & (coordinate < table[HIGH])
            piece = table[PIECE]
            fraction = np.where(piece > 0.0, (coordinate - table[START]) / piece, 0.0)
            x = table[AX] + fraction * table[DX]
            y = table[AY] + fraction * table[DY]
            odometer = table[ODOMETER] + distance
        if self._recalled:
            ok[self._recalled] = False
            self._recalled = []
        stepped_now = np.stack((t1, travelled, odometer, along, speed, x, y, table[NOSE]))
        np.copyto(table[: HEADING + 1], stepped_now, where=ok)
        handed_back = (armed & ~ok).nonzero()[0]
        if len(handed_back):
            self._release(handed_back)
        stepped = ok.nonzero()[0]
        ids, segments, traverses, progresses, types, disturbed = self._objects[:, stepped].tolist()
        moved = table[DISTANCE : HEADING + 1, stepped]
        distances, speeds, xs, ys, headings = moved.tolist()
        fields = zip(
            ids, segments, traverses, progresses, distances, speeds, xs, ys, headings, types, disturbed, strict=True
        )
        states = list(map(_make_state, fields))
        cruised = StateColumns(ids, states, segments, traverses, progresses, moved[SPEED - DISTANCE :], stepped)
        return CruiseStep(cruised, (~ok).nonzero()[0].tolist())


class _Released(Mapping[int, Driver]):
    """The drivers by vehicle id, each released from the arrays (up to date) before it is handed out:
    for whoever changes a driver between steps (the disturbances)."""

    def __init__(self, cruise: FleetCruise) -> None:
        self._cruise = cruise

    def __getitem__(self, vehicle: int) -> Driver:
        cruise = self._cruise
        i = cruise.index[vehicle]
        cruise.release(i)
        return cruise._drivers[i]

    def __iter__(self) -> Iterator[int]:
        return iter(self._cruise.index)

    def __len__(self) -> int:
        return len(self._cruise.index)
