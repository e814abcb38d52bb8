"""The hand-packed CDR of markers and the clock is byte for byte what the rosbags typestore serialises."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.recording import cdr
from fleetsim.recording import messages as m
from fleetsim.recording.cdr import Marker, MarkerArray, Points, Stamp

ORANGE = (1.0, 0.55, 0.0, 1.0)


def typestore_bytes(array: MarkerArray) -> bytes:
    message = m.marker_array_message(array)
    return bytes(m._store().serialize_cdr(message, "visualization_msgs/msg/MarkerArray"))


def marker(**changes: object) -> Marker:
    fields: dict[str, object] = {
        "stamp": Stamp(12, 500_000_000),
        "frame_id": "map",
        "ns": "plans",
        "id": 7,
        "type": 4,
        "action": 0,
        "position": (1.5, -2.0, 0.25),
        "scale": (0.18, 0.0, 0.0),
        "color": ORANGE,
        "frame_locked": False,
        "points": Points.of([(0.0, 0.0, 0.02), (1.0, 2.0, 0.02), (3.5, -1.25, 0.02)]),
        "text": "",
    }
    fields.update(changes)
    return Marker(**fields)  # type: ignore[arg-type]


CASES = {
    "no markers": [],
    "one line strip": [marker()],
    "no points": [marker(points=cdr.NO_POINTS)],
    "one point": [marker(points=Points.of([(1.0, 2.0, 3.0)]))],
    "delete all": [m.delete_all(Stamp(1, 0), "")],
    "delete then strip": [m.delete(Stamp(1, 0), "fixed", 3), marker()],
    "non-ascii text": [marker(type=9, text="segment 7: 1 \u27c2 2", points=cdr.NO_POINTS)],
    "frame locked": [marker(frame_locked=True, frame_id="vehicle_12")],
    # Every string length mod 4 and every point count parity, one after the other, so that each marker
    # starts at a different offset mod 8 (the points' float64s are aligned to 8).
    "every padding": [
        marker(
            frame_id="f" * (k % 5),
            ns="n" * ((k * 3) % 7),
            text="t" * (k % 6),
            points=Points.of([(float(i), -float(i), 0.5) for i in range(k % 4)]),
        )
        for k in range(24)
    ],
    "every helper": [
        m.line_list(Stamp(3, 1), "segments", 0, m.points([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)]), 0.05, ORANGE),
        m.line_strip(
            Stamp(3, 1), "disturbed", 4, m.path_points([(0.0, 0.0), (2.0, 1.0)], 0.05), 0.08, ORANGE, "vehicle_4"
        ),
        m.text_marker(Stamp(3, 1), "vehicle_4", "labels", 4, "4", (0.0, 0.0, 1.2), 0.3, ORANGE, True),
        m.arrow(Stamp(3, 1), "wait_for", 0, (0.0, 0.0, 0.6), (4.0, 1.0, 0.6), 0.12, ORANGE),
        m.disc(Stamp(3, 1), "root_cause", 0, (1.0, 2.0, 0.02), 2.5, ORANGE),
    ],
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_packed_marker_arrays_are_the_typestores_bytes(name: str) -> None:
    array = m.marker_array(CASES[name])
    assert cdr.pack_marker_array(array) == typestore_bytes(array)
    assert m.serialise(array) == typestore_bytes(array)


texts = st.text(st.characters(codec="utf-8", exclude_characters="\0"), max_size=9)
coordinates = st.floats(allow_nan=False, width=64)
points = st.lists(st.tuples(coordinates, coordinates, coordinates), max_size=4).map(Points.of)
markers = st.builds(
    Marker,
    stamp=st.builds(Stamp, st.integers(0, 2**31 - 1), st.integers(0, 999_999_999)),
    frame_id=texts,
    ns=texts,
    id=st.integers(-(2**31), 2**31 - 1),
    type=st.integers(0, 11),
    action=st.sampled_from([0, 2, 3]),
    position=st.tuples(coordinates, coordinates, coordinates),
    scale=st.tuples(coordinates, coordinates, coordinates),
    color=st.tuples(*[st.floats(0.0, 1.0, width=32)] * 4),
    frame_locked=st.booleans(),
    points=points,
    text=texts,
)


@settings(max_examples=150, deadline=None)
@given(st.lists(markers, max_size=5))
def test_any_marker_array_packs_to_the_typestores_bytes(listed: list[Marker]) -> None:
    array = MarkerArray(tuple(listed))
    assert cdr.pack_marker_array(array) == typestore_bytes(array)


@pytest.mark.parametrize("nanoseconds", [1, 999_999_999, 1_000_000_000, 61_234_567_890])
def test_the_packed_clock_is_the_typestores(nanoseconds: int) -> None:
    time = m.stamp(nanoseconds)
    assert cdr.pack_clock(time) == m.serialise(m.clock(time))
    assert len(cdr.pack_clock(time)) == cdr.CLOCK_SIZE


def test_a_marker_with_a_missing_or_misspelt_field_is_refused() -> None:
    fields = marker()._asdict()
    del fields["color"]
    with pytest.raises(TypeError):
        Marker(**fields)  # no colour: must not become an invisible alpha 0
    with pytest.raises(TypeError):
        Marker(**fields, colour=ORANGE)


def test_points_are_packed_as_triples_and_joined_in_order() -> None:
    a, b = Points.of([(1.0, 2.0, 3.0), (4.0, 5.0, 6.0)]), Points.of([(7.0, 8.0, 9.0)])
    assert Points.joined([a, b]).unpacked() == [(1.0, 2.0, 3.0), (4.0, 5.0, 6.0), (7.0, 8.0, 9.0)]
    assert a.rest().unpacked() == [(4.0, 5.0, 6.0)]
    assert cdr.NO_POINTS.rest() == cdr.NO_POINTS
    with pytest.raises(ValueError, match=r"must be \(x, y, z\)"):
        Points.of([(1.0, 2.0)])  # type: ignore[list-item]


def test_markers_sent_again_pack_as_new_ones_at_every_offset() -> None:
    # A marker's bytes after its points are kept for the next marker with the same points and text: at
    # another offset mod 8, with another stamp and id, or a position of -0.0 instead of 0.0, they must
    # still be the typestore's.
    shown = marker(type=9, text="segment 7: 1 \u27c2 2", position=(0.0, 1.0, 1.0))
    again = [shown, shown.restamped(Stamp(13, 0), 8), marker(ns="p"), shown._replace(position=(-0.0, 1.0, 1.0))]
    fillers = [marker(ns="n" * k, points=cdr.NO_POINTS) for k in range(8)]  # shifting the next one by 4s
    array = m.marker_array([marker for filler in fillers for marker in (*again, filler)])
    assert cdr.pack_marker_array(array) == typestore_bytes(array)
    assert again[1] == shown._replace(stamp=Stamp(13, 0), id=8)
