"""Vehicle colours never take a colour the pictures give a meaning to; a type's own colour still wins."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.recording import colours
from fleetsim.recording.colours import (
    ALERT,
    CYCLE,
    MIN_DIFFERENCE,
    RESERVED,
    colour_difference,
    hex_colour,
    palette_colour,
    vehicle_colours,
)
from fleetsim.scenario import Scenario

ROOT = Path(__file__).resolve().parents[2]


def example(name: str) -> Scenario:
    suite = load_suite(ROOT / "scenario_suites" / "examples.fleetsim.yaml")
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


def test_every_palette_colour_is_perceptibly_distinct_from_every_reserved_colour() -> None:
    # The fixed list and the first 300 generated ones: a fleet of 308 draws none in a reserved colour.
    too_near = []
    for position in range(308):
        colour = palette_colour(position)
        for name, reserved in RESERVED.items():
            difference = colour_difference(colour, reserved)
            if difference < MIN_DIFFERENCE:
                too_near.append((position + 1, hex_colour(colour), name, round(difference, 1)))
    assert too_near == []


def test_the_third_vehicle_is_no_longer_the_red_of_cycles_and_root_causes() -> None:
    # The case: Tableau's red (#d62728) was vehicle 3, 3.3 CIEDE2000 units from the cycle red.
    assert colour_difference((0.839, 0.153, 0.157, 1.0), CYCLE) < 5
    assert colour_difference(palette_colour(2), CYCLE) >= MIN_DIFFERENCE
    assert hex_colour(palette_colour(2)) != "#d62728"


def test_the_first_two_vehicles_keep_their_colours() -> None:
    # A two-vehicle picture reads as it did: Tableau blue and green.
    assert [hex_colour(palette_colour(p)) for p in (0, 1)] == ["#1f77b4", "#2ca02c"]


def test_the_drawn_reserved_colours_come_from_the_one_definition() -> None:
    # picture.py and scene.py spell no colour of their own for what RESERVED names.
    for module in ("picture.py", "scene.py"):
        source = (ROOT / "fleetsim" / "recording" / module).read_text(encoding="utf-8")
        for rgba in RESERVED.values():
            assert hex_colour(rgba) not in source, (module, hex_colour(rgba))
        assert not re.search(r"\(\s*0\.\d+,\s*0\.\d+,\s*0\.\d+,\s*[01]\.\d+\)", source), module


def test_colour_difference_matches_published_ciede2000_pairs() -> None:
    # Sharma, Wu and Dalal (2005), table 1: pairs 1, 4, 7, 17, 25 and 33.
    pairs = [
        ((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
        ((50.0, -1.3802, -84.2814), (50.0, 0.0, -82.7485), 1.0000),
        ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
        ((50.0, 2.5, 0.0), (73.0, 25.0, -18.0), 27.1492),
        ((60.2574, -34.0099, 36.2677), (60.4626, -34.1751, 39.4387), 1.2644),
        ((2.0776, 0.0795, -1.1350), (0.9033, -0.0636, -0.5514), 0.9082),
    ]
    for first, second, expected in pairs:
        assert colours._ciede2000(first, second) == pytest.approx(expected, abs=1e-4)
        assert colours._ciede2000(second, first) == pytest.approx(expected, abs=1e-4)
    assert colours._lab((1.0, 0.0, 0.0, 1.0)) == pytest.approx((53.24, 80.09, 67.20), abs=0.02)
    assert colour_difference((0.0, 0.0, 0.0, 1.0), (1.0, 1.0, 1.0, 1.0)) == pytest.approx(100.0, abs=0.01)


def test_a_vehicle_types_own_color_wins_even_a_reserved_one() -> None:
    # The narrow negative: the suite's `color` is the user's choice, kept as written.
    crossing = example("crossing")
    painted = replace(
        crossing,
        vehicles=tuple(replace(v, type=replace(v.type, color=ALERT)) if v.id == 2 else v for v in crossing.vehicles),
    )
    assert vehicle_colours(painted) == {1: palette_colour(0), 2: ALERT}
