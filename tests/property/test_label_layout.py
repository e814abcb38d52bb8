"""Labels placed again as their list changes (``LabelLayout``, a recording's alert labels step after step)
take exactly the places that placing each list from scratch gives them (``LabelSpace``, the last spot
when every spot is taken)."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.layout.segment import Point
from fleetsim.recording.labels import Box, Label, LabelLayout, LabelSpace, box_around

LETTER = 0.5
# Eight ways out from a label's anchor, and how far each spot is: labels crowd a small square, so that
# most of them are pushed out and a change moves the labels around it.
WAYS = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (0.7, 0.7), (-0.7, 0.7), (-0.7, -0.7), (0.7, -0.7)]


def spots(anchor: tuple[int, int], way: int, count: int) -> list[Point]:
    """Left and right of ``anchor`` along a way, further out each time (as ``spots_beside`` lays them)."""
    dx, dy = WAYS[way]
    x, y = 0.25 * anchor[0], 0.25 * anchor[1]
    found: list[Point] = []
    for step in range(1, count + 1):
        found += [(x + 0.3 * step * dx, y + 0.3 * step * dy), (x - 0.3 * step * dx, y - 0.3 * step * dy)]
    return found


@st.composite
def label_pools(draw: st.DrawFn) -> dict[int, Label]:
    """Labels by key (a key always stands for the same spots and text)."""
    pool = {}
    for key in range(draw(st.integers(1, 30))):
        anchor = (draw(st.integers(0, 12)), draw(st.integers(0, 12)))
        spot_list = spots(anchor, draw(st.integers(0, 7)), draw(st.integers(1, 5)))
        pool[key] = Label(key, spot_list, "x" * draw(st.integers(1, 12)))
    return pool


def from_scratch(labels: list[Label]) -> list[tuple[int, Box]]:
    space = LabelSpace(4.0 * LETTER)
    places = []
    for label in labels:
        placed = space.place(label.spots, label.text, LETTER)
        if placed is None:
            placed = len(label.spots) - 1, box_around(label.spots[-1], label.text, LETTER)
            space.add(placed[1])
        places.append(placed)
    return places


@settings(max_examples=300, deadline=None)
@given(label_pools(), st.data())
def test_labels_placed_again_take_the_places_from_scratch(pool: dict[int, Label], data: st.DataObject) -> None:
    layout = LabelLayout(8.0 * LETTER, LETTER)
    keys = sorted(pool)
    shown: list[int] = []
    for _ in range(data.draw(st.integers(1, 12))):
        # Mostly a few labels come and go in key order (as alerts do); now and then a shuffle.
        if data.draw(st.integers(0, 5)) == 0:
            shown = data.draw(st.permutations(keys)).copy()[: data.draw(st.integers(0, len(keys)))]
        else:
            for key in data.draw(st.lists(st.sampled_from(keys), max_size=4)):
                shown = sorted(set(shown) ^ {key})
        labels = [pool[key] for key in shown]
        assert [(p.spot, p.box) for p in layout.place(labels)] == from_scratch(labels)


def test_a_label_whose_neighbour_goes_moves_back_beside_its_segment() -> None:
    first = Label("a", [(0.0, 0.0), (0.0, 5.0)], "aaaa")
    second = Label("b", [(0.0, 0.0), (0.0, 5.0)], "bbbb")
    layout = LabelLayout(4.0, 1.0)
    assert [p.spot for p in layout.place([first, second])] == [0, 1]
    assert [p.spot for p in layout.place([second])] == [0]
    assert [p.spot for p in layout.place([first, second])] == [0, 1]
    assert [p.spot for p in layout.place([second, first])] == [0, 1]


def test_a_label_with_every_spot_taken_takes_its_last() -> None:
    crowd = [Label(key, [(0.0, 0.0), (0.0, 0.1)], "label") for key in range(3)]
    places = LabelLayout(4.0, 1.0).place(crowd)
    assert [p.spot for p in places] == [0, 1, 1]
    assert places[2].box == box_around((0.0, 0.1), "label", 1.0)
