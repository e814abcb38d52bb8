"""Trace lines are exactly what ``json.dumps(..., separators=(",", ":"))`` writes, whoever encodes them.

Lines are encoded by orjson where it writes the same bytes, and by json otherwise (text beyond ASCII,
integers beyond 64 bits); the hash is over the lines, so recorded hashes must not notice which.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.sim.trace import Trace

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
