"""Trace lines are exactly what ``json.dumps(..., separators=(",", ":"))`` writes, whoever encodes them.

Lines are encoded by orjson where it writes the same bytes, and by json otherwise (text beyond ASCII,
integers beyond 64 bits); the hash is over the lines, so recorded hashes must not notice which.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any
from unittest.mock import patch

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.enums import Progress, Traverse
from fleetsim.motion.fleet_cruise import StateColumns
from fleetsim.planning.snapshot import VehicleState
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE
from fleetsim.sim import trace as trace_module
from fleetsim.sim.trace import Trace, cruised_records, vehicle_records

value = st.one_of(st.none(), st.integers(), st.text(), st.booleans())
event = st.lists(value, min_size=1, max_size=4)


def _json(line: list[Any]) -> str:
    return json.dumps(line, separators=(",", ":"))


@settings(max_examples=300, deadline=None)
@given(events=st.lists(event, max_size=4), plans=st.lists(st.lists(value, max_size=3), max_size=3))
def test_a_step_line_is_what_json_writes(events: list[list[Any]], plans: list[list[Any]]) -> None:
    trace = Trace()
    trace.begin({"vehicles": [1]})
    trace.record(0, (), plans, events)
    assert trace.lines[-1] == _json([0, [], plans, events])
    expected = hashlib.sha256("".join(f"{line}\n" for line in trace.lines).encode("ascii"))
    assert trace.digest == expected.hexdigest()


def test_lines_beyond_ascii_and_64_bit_integers_are_escaped_as_json_escapes_them() -> None:
    trace = Trace()
    trace.record(0, (), [], [["route-error", 3, "kein Weg über Gang 4 → Rampe\x7f"]])
    trace.record(1, (), [[2**70, []]], [])
    assert trace.lines == [
        '[0,[],[],[["route-error",3,"kein Weg \\u00fcber Gang 4 \\u2192 Rampe\\u007f"]]]',
        f"[1,[],[[{2**70},[]]],[]]",
    ]


def test_a_trace_without_kept_lines_has_the_same_hash() -> None:
    kept, streamed = Trace(), Trace(keep_lines=False)
    for trace in (kept, streamed):
        trace.begin({"vehicles": [1, 2]})
        trace.record(0, (), [[1, [[5, "f", "f", 1, None]]]], [["complete", 7], ["route-error", 2, "ü"]])
    assert streamed.lines == []
    assert streamed.digest == kept.digest


# -- vehicle records rounded in arrays (many vehicles) ----------------------------------------------------

_HALVES = st.integers(-(10**9), 10**9).map(lambda k: k / 2000.0)  # x * 1000 lands on .5: ties to even
_COORDINATE = st.one_of(
    st.floats(-1e6, 1e6, allow_nan=False),
    _HALVES,
    st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 0.0005, -0.0005, 0.0015, 2.5e-3]),
)


def _one_by_one(state: VehicleState) -> tuple[Any, ...]:
    traverse = {Traverse.FORWARD: "f", Traverse.BACKWARD: "b"}[state.traverse]
    progress = {Progress.FORWARD: "f", Progress.REVERSE: "r"}[state.progress]
    heading = round(state.heading * (180.0 / 3.141592653589793) * 100.0)
    return (
        state.id,
        state.segment,
        traverse,
        progress,
        round(state.x * 1000.0),
        round(state.y * 1000.0),
        heading,
        round(state.speed * 1000.0),
    )


@st.composite
def _states(draw: st.DrawFn) -> list[VehicleState]:
    count = draw(st.integers(64, 90))
    return [
        VehicleState(
            vid,
            draw(st.integers(1, 10**6)),
            draw(st.sampled_from(list(Traverse))),
            draw(st.sampled_from(list(Progress))),
            0.0,
            draw(st.one_of(_COORDINATE.map(abs), st.just(0.0))),
            draw(_COORDINATE),
            draw(_COORDINATE),
            draw(st.floats(-4.0, 4.0, allow_nan=False)),
            DEFAULT_VEHICLE_TYPE,
            None,
        )
        for vid in range(1, count + 1)
    ]


@settings(max_examples=100, deadline=None)
@given(_states())
def test_records_rounded_in_arrays_are_those_rounded_one_by_one(states: list[VehicleState]) -> None:
    records = vehicle_records(states)
    assert records == [_one_by_one(state) for state in states]
    assert all(type(value) is int for record in records for value in record[4:])


def test_a_value_too_large_for_int64_is_rounded_one_by_one() -> None:
    states = [
        VehicleState(
            vid,
            1,
            Traverse.FORWARD,
            Progress.FORWARD,
            0.0,
            0.0,
            1e300 if vid == 7 else 1.5,
            0.0,
            0.0,
            DEFAULT_VEHICLE_TYPE,
            None,
        )
        for vid in range(1, 65)
    ]
    records = vehicle_records(states)
    assert records[6][4] == round(1e300 * 1000.0) and records[0][4] == 1500


# -- the records of cruising vehicles, read from their columns ----------------------------------------------


def _columns(states: list[VehicleState]) -> StateColumns:
    """``states`` as the arrays hand them over: the objects and the columns they were made of."""
    return StateColumns(
        [state.id for state in states],
        states,
        [state.segment for state in states],
        [state.traverse for state in states],
        [state.progress for state in states],
        np.array([[state.speed, state.x, state.y, state.heading] for state in states]).reshape(-1, 4).T,
        np.arange(len(states), dtype=np.intp),
    )


@settings(max_examples=100, deadline=None)
@given(_states())
def test_records_read_from_columns_are_those_of_the_states(states: list[VehicleState]) -> None:
    records = cruised_records(_columns(states))
    assert records == [_one_by_one(state) for state in states]
    assert all(type(value) is int for record in records for value in record[4:])


def test_a_value_too_large_for_int64_in_the_columns_is_rounded_one_by_one() -> None:
    states = [_state(vid, x=1e300 if vid == 7 else 1.5) for vid in range(1, 65)]
    records = cruised_records(_columns(states))
    assert records[6][4] == round(1e300 * 1000.0) and records[0][4] == 1500


@settings(max_examples=100, deadline=None)
@given(_states(), st.lists(st.booleans(), min_size=120, max_size=120), st.integers(1, 100))
def test_a_step_of_some_vehicles_one_by_one_and_some_in_columns_is_the_line_of_all_in_order(
    states: list[VehicleState], in_columns: list[bool], piece: int
) -> None:
    """However the vehicles are split, and however many records a piece of the line holds."""
    alone = [state for state, columns in zip(states, in_columns, strict=False) if not columns]
    cruised = [state for state, columns in zip(states, in_columns, strict=False) if columns]
    split, whole = Trace(), Trace()
    for trace in (split, whole):
        trace.begin({"vehicles": [state.id for state in states]})
    # Pieces of any size, and the arrays however few cruise (their records are those one by one: above).
    with patch.object(trace_module, "_PIECE", piece), patch.object(trace_module, "_IN_ARRAYS_FROM", 1):
        split.record(0, alone, [[1, []]], [["complete", 2]], _columns(cruised))
        moved = [state._replace(x=state.x + 1.0) for state in states[::3]]  # a later step: some changed
        split.record(
            1, [state for state in moved if state.id % 2], [], [], _columns([s for s in moved if not s.id % 2])
        )
    whole.record(0, states, [[1, []]], [["complete", 2]])
    whole.record(1, moved, [], [])
    assert split.lines == whole.lines and split.digest == whole.digest
    assert json.loads(split.lines[1])[1] == [list(_one_by_one(state)) for state in states]


def _state(vid: int, *, x: float) -> VehicleState:
    return VehicleState(vid, 1, Traverse.FORWARD, Progress.FORWARD, 0.0, 0.0, x, 0.0, 0.0, DEFAULT_VEHICLE_TYPE, None)
