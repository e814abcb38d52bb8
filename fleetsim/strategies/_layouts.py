"""The ``layouts`` strategy: which kind, how big, and the optional pieces, drawn so they shrink small."""

from __future__ import annotations

from hypothesis import strategies as st
from hypothesis.strategies import SearchStrategy

from fleetsim.layout.segment import Segment
from fleetsim.strategies import geometry

__all__ = [
    "LAYOUT_KINDS",
    "SMALLEST_FIRST",
    "check_kind",
    "check_range",
    "draw_kind_layout",
    "draw_layout",
    "layouts",
    "plainest_layout",
]

LAYOUT_KINDS = ("warehouse", "loop", "corridor")
# For "any", the kind whose smallest layout is smallest comes first: Hypothesis shrinks a sampled value
# toward the first choice, so a counterexample ends on the simplest layout that still fails.
SMALLEST_FIRST = ("corridor", "loop", "warehouse")


def check_kind(kind: str) -> str:
    if kind != "any" and kind not in LAYOUT_KINDS:
        msg = f"layout={kind!r} must be one of {', '.join(LAYOUT_KINDS)} or 'any'"
        raise ValueError(msg)
    return kind


def check_range(name: str, value: tuple[int, int], minimum: int) -> tuple[int, int]:
    low, high = value
    if not (isinstance(low, int) and isinstance(high, int) and minimum <= low <= high):
        msg = f"{name}={value!r} must be an inclusive range (low, high) with {minimum} <= low <= high"
        raise ValueError(msg)
    return value


def draw_layout(draw: st.DrawFn, kind: str, size: tuple[int, int], one_way: bool | None) -> list[Segment]:
    """Draw the kind first, then the size (so both shrink toward the minimum), then the options."""
    if kind == "any":
        kind = draw(st.sampled_from(SMALLEST_FIRST))
    return draw_kind_layout(draw, kind, draw(st.integers(*size)), one_way)


def draw_kind_layout(draw: st.DrawFn, kind: str, n: int, one_way: bool | None) -> list[Segment]:
    """A layout of ``kind`` and size ``n``, its options (bays, lane shift, one-way) drawn."""
    if kind == "warehouse":
        segments = geometry.warehouse(n)
    elif kind == "loop":
        segments = _loop(draw, n, one_way)
    else:
        segments = _corridor(draw, n)
    return geometry.quantized(segments)


def plainest_layout(kind: str, n: int, one_way: bool | None) -> list[Segment]:
    """The layout of ``kind`` and size ``n`` without options: no lane shift, one passing bay at the start."""
    if kind == "warehouse":
        segments = geometry.warehouse(n)
    elif kind == "loop":
        segments = geometry.loop(n, one_way=bool(one_way))
    else:
        segments = geometry.corridor(n, [(0, 1)])
    return geometry.quantized(segments)


def _loop(draw: st.DrawFn, sections: int, one_way: bool | None) -> list[Segment]:
    is_one_way = draw(st.booleans()) if one_way is None else one_way
    shift = None
    if sections >= 2:
        side = draw(st.one_of(st.none(), st.integers(0, 3)))
        if side is not None:
            first = draw(st.integers(0, sections - 2))
            shift = (side, first, draw(st.integers(first + 1, sections - 1)))
    return geometry.loop(sections, one_way=is_one_way, shift=shift)


def _corridor(draw: st.DrawFn, between: int) -> list[Segment]:
    """At least one passing bay; more may follow the first wherever three free straights remain."""
    count = between + 2
    first = draw(st.integers(0, count - 3))
    bays = [(first, draw(st.sampled_from((1, -1))))]
    start = first + 3
    while start + 3 <= count:
        if draw(st.booleans()):
            bays.append((start, draw(st.sampled_from((1, -1)))))
            start += 3
        else:
            start += 1
    return geometry.corridor(between, bays)


def layouts(
    kind: str = "any", size: tuple[int, int] = (1, 3), one_way: bool | None = None
) -> SearchStrategy[list[Segment]]:
    """Valid, connected layouts of ``kind`` (or any kind); ``size`` is an inclusive range.

    Size means junctions per side (warehouse), straights per side (loop) or straights between the two
    end straights (corridor). ``one_way`` applies to loops only: ``None`` draws either.
    """
    check_kind(kind)
    check_range("size", size, 1)

    @st.composite
    def strategy(draw: st.DrawFn) -> list[Segment]:
        return draw_layout(draw, kind, size, one_way)

    return strategy()
