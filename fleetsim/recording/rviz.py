"""The RViz view of a scenario: the shipped layout with its top-down view framed on the scenario's map.

The map's bounding box (with a margin) sets the view's centre and scale, so a map far from the origin or
much larger than the default view is shown whole; text markers are sized to the vehicles and never
smaller than what reads at that scale.
"""

from __future__ import annotations

from dataclasses import dataclass

from fleetsim.scenario import Scenario

__all__ = ["FramedView", "framed_view", "rviz_config"]


@dataclass(frozen=True, slots=True)
class FramedView:
    """Where to look at a scenario's map: its bounding box, the RViz view that frames it, a text height."""

    min_x: float
    min_y: float
    max_x: float
    max_y: float
    scale: float  # RViz TopDownOrtho pixels per metre
    letter: float  # text marker height, metres

    @property
    def centre(self) -> tuple[float, float]:
        return (self.min_x + self.max_x) / 2, (self.min_y + self.max_y) / 2


# The render area of the shipped RViz layout's window (1400 x 900 less the panels), pixels.
_VIEW_PIXELS = (1050.0, 800.0)
_LETTER_PIXELS = 14.0  # the smallest text height that reads at the framed view


def framed_view(scenario: Scenario) -> FramedView:
    """The map's bounding box (with a margin), the RViz scale that shows all of it, and a text height
    that follows the vehicles' size and stays legible at that scale."""
    segments = scenario.layout.segments.values()
    xs = [x for segment in segments for x, _ in segment.waypoints]
    ys = [y for segment in segments for _, y in segment.waypoints]
    margin = 2.0
    width, height = max(xs) - min(xs) + 2 * margin, max(ys) - min(ys) + 2 * margin
    scale = min(_VIEW_PIXELS[0] / width, _VIEW_PIXELS[1] / height)
    size = max(max(v.type.length, v.type.width) for v in scenario.vehicles) if scenario.vehicles else 1.0
    letter = max(0.35 * size, _LETTER_PIXELS / scale)
    return FramedView(min(xs) - margin, min(ys) - margin, max(xs) + margin, max(ys) + margin, scale, letter)


def rviz_config(scenario: Scenario, template: str) -> str:
    """The shipped RViz layout with its view framing ``scenario``'s map."""
    view = framed_view(scenario)
    cx, cy = view.centre
    framed = template.replace(
        "      Scale: 20\n      X: 0\n      Y: 0\n",
        f"      Scale: {view.scale:.3f}\n      X: {cx:.3f}\n      Y: {cy:.3f}\n",
    )
    if framed == template:
        msg = "the RViz layout template has no 'Scale: 20 / X: 0 / Y: 0' view to frame"
        raise ValueError(msg)
    return f"# Framed on scenario {scenario.name!r}: centre ({cx:.2f}, {cy:.2f}) m, {view.scale:.1f} px/m.\n{framed}"
