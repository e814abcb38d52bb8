"""The shipped Open-RMF building map, mutated: every broken value is a located MapError, never a TypeError.

Each mutation edits one value of ``scenario_suites/sites/clinic/map.building.yaml`` as a user (or a
careless script) might: a list replaced by a number, an index out of range, a string where a lane should
be. The loader must name the file, the YAML line of the value and its key path, and nothing else may
escape it. The exhaustive sweep at the end replaces every value of the file, one at a time, with values of
the wrong type and range.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from fleetsim.errors import FleetsimError, LoadError, LoadErrors, MapError
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map

CLINIC = Path(__file__).resolve().parents[2] / "scenario_suites" / "sites" / "clinic" / "map.building.yaml"
TEXT = CLINIC.read_text(encoding="utf-8")
FIRST_LANE = (
    '      - [0, 1, {bidirectional: [4, true], graph_idx: [2, 0], orientation: [1, ""], speed_limit: [3, 0]}]\n'
)


def mutated(old: str, new: str, *, count: int = 1) -> str:
    assert TEXT.count(old) >= count, f"the clinic map no longer holds {old!r}"
    return TEXT.replace(old, new, count)


def line_of(text: str, marker: str) -> int:
    """The 1-based line of the first occurrence of ``marker`` in ``text``."""
    return text[: text.index(marker)].count("\n") + 1


# id, the mutated text, a marker on the line the error must point at, the key path, words of the problem
CASES = [
    (
        "lanes-a-number",
        mutated("    lanes:\n", "    lanes: 0.5\n    old_lanes:\n"),
        "lanes: 0.5",
        "levels.L1.lanes",
        "lanes is 0.5; it must be a list",
    ),
    (
        "lifts-a-number",
        mutated("lifts:\n  lift_1:\n", "lifts: -1.0e+9\nold_lifts:\n  lift_1:\n"),
        "lifts: -1.0e+9",
        "lifts",
        "lifts is -1000000000.0; it must be a mapping",
    ),
    (
        "lifts-a-text",  # YAML 1.1 reads -1e9 (no dot) as a string
        mutated("lifts:\n  lift_1:\n", "lifts: -1e9\nold_lifts:\n  lift_1:\n"),
        "lifts: -1e9",
        "lifts",
        "lifts is '-1e9'; it must be a mapping",
    ),
    (
        "lane-vertex-out-of-range",
        mutated("      - [1, 2, {", "      - [1, 99, {"),
        "[1, 99, {",
        "levels.L1.lanes[1][1]",
        "lane vertex 99 is not a vertex index (0 to 9)",
    ),
    (
        "lane-vertex-negative",
        mutated("      - [1, 2, {", "      - [-1, 2, {"),
        "[-1, 2, {",
        "levels.L1.lanes[1][0]",
        "lane vertex -1 is not a vertex index (0 to 9)",
    ),
    (
        "measurement-vertex-out-of-range",
        mutated("      - [8, 9, {distance", "      - [8, 10, {distance"),
        "[8, 10, {distance",
        "levels.L1.measurements[0][1]",
        "measurement vertex 10 is not a vertex index (0 to 9)",
    ),
    (
        "graph-negative",
        mutated(FIRST_LANE, FIRST_LANE.replace("graph_idx: [2, 0]", "graph_idx: [2, -1]")),
        "graph_idx: [2, -1]",
        "levels.L1.lanes[0][2].graph_idx",
        "graph_idx is -1; it must be a whole number >= 0",
    ),
    (
        "graph-a-fraction",
        mutated(FIRST_LANE, FIRST_LANE.replace("graph_idx: [2, 0]", "graph_idx: [2, 0.5]")),
        "graph_idx: [2, 0.5]",
        "levels.L1.lanes[0][2].graph_idx",
        "graph_idx is 0.5; it must be a whole number >= 0",
    ),
    (
        "distance-infinite",
        mutated("{distance: [3, 20]}", "{distance: [3, .inf]}"),
        "{distance: [3, .inf]}",
        "levels.L1.measurements[0][2].distance",
        "measurement distance is inf; it must be a finite number",
    ),
    (
        "scale-infinite",  # each number finite, their ratio not
        mutated("{distance: [3, 20]}", "{distance: [3, 1.0e+308]}").replace(
            '[500, 100, 0, ""]', '[100.000001, 100, 0, ""]'
        ),
        "[8, 9, {distance",
        "levels.L1.measurements[0]",
        "both must be positive (and give a finite scale)",
    ),
    (
        "vertex-at-infinity",
        mutated("[700, 500, 0, pharmacy", "[1.0e+308, 500, 0, pharmacy").replace("[3, 20]}", "[3, 20000]}"),
        "[1.0e+308, 500",
        "levels.L1.vertices[3]",
        "vertex 3 lies at infinity once scaled by 50 m/px",
    ),
    (
        "lane-a-string",
        mutated(FIRST_LANE, '      - "lobby--v1"\n'),
        '"lobby--v1"',
        "levels.L1.lanes[0]",
        "lane 'lobby--v1' must be a list [start vertex, end vertex, {params}]",
    ),
    (
        "lane-too-short",
        mutated(FIRST_LANE, "      - [0, 1]\n"),
        "[0, 1]\n",
        "levels.L1.lanes[0]",
        "lane [0, 1] must be a list [start vertex, end vertex, {params}]",
    ),
    (
        "lane-parameters-a-list",
        mutated(FIRST_LANE, "      - [0, 1, [4, true]]\n"),
        "[0, 1, [4, true]]",
        "levels.L1.lanes[0][2]",
        "lane parameters is [4, True]; it must be a mapping",
    ),
    (
        "lane-parameter-not-a-pair",
        mutated(FIRST_LANE, "      - [0, 1, {bidirectional: true}]\n"),
        "bidirectional: true}",
        "levels.L1.lanes[0][2].bidirectional",
        "parameter 'bidirectional' is True; it must be [type, value]",
    ),
    (
        "bidirectional-a-number",
        mutated(FIRST_LANE, FIRST_LANE.replace("[4, true]", "[4, 1]")),
        "bidirectional: [4, 1]",
        "levels.L1.lanes[0][2].bidirectional",
        "bidirectional is 1; it must be true or false",
    ),
    (
        "vertices-a-string",
        mutated("    vertices:\n", "    vertices: many\n    old_vertices:\n"),
        "vertices: many",
        "levels.L1.vertices",
        "vertices is 'many'; it must be a list of [x, y, z, name, {params}]",
    ),
    (
        "vertex-a-number",
        mutated('      - [300, 500, 0, ""]\n', "      - 7\n"),
        "      - 7\n",
        "levels.L1.vertices[1]",
        "vertex 1 is 7; it must be a list [x, y, z, name, {params}]",
    ),
    (
        "vertex-x-a-string",
        mutated("[100, 500, 0, lobby]", "[west, 500, 0, lobby]"),
        "[west, 500",
        "levels.L1.vertices[0][0]",
        "vertex 0 x is 'west'; it must be a finite number",
    ),
    (
        "vertex-y-not-a-number",
        mutated("[100, 500, 0, lobby]", "[100, .nan, 0, lobby]"),
        "[100, .nan",
        "levels.L1.vertices[0][1]",
        "vertex 0 y is nan; it must be a finite number",
    ),
    (
        "vertex-name-a-number",
        mutated("[500, 300, 0, ward_b]", "[500, 300, 0, 12]"),
        "[500, 300, 0, 12]",
        "levels.L1.vertices[5][3]",
        "vertex 5 name is 12; it must be a string",
    ),
    (
        "vertex-parameters-a-list",
        mutated("{is_charger: [4, true]}", "[is_charger]"),
        "pharmacy, [is_charger]",
        "levels.L1.vertices[3][4]",
        "vertex 3 parameters is ['is_charger']; it must be a mapping",
    ),
    (
        "measurements-a-number",
        mutated("    measurements:\n", "    measurements: 3\n    old_measurements:\n"),
        "measurements: 3",
        "levels.L1.measurements",
        "measurements is 3; it must be a list",
    ),
    (
        "doors-a-number",
        mutated("    doors:\n", "    doors: 5\n    old_doors:\n"),
        "doors: 5",
        "levels.L1.doors",
        "doors is 5; it must be a list",
    ),
    (
        "level-a-list",
        mutated("  L2:\n    elevation: 4\n", "  L2: [1, 2]\n  old_L2:\n    elevation: 4\n"),
        "L2: [1, 2]",
        "levels.L2",
        "level 'L2' is [1, 2]; it must be a mapping",
    ),
    (
        "levels-a-list",
        "levels: [L1, L2]\n" + mutated("levels:\n", "old_levels:\n"),
        "levels: [L1, L2]",
        "levels",
        "levels is ['L1', 'L2']; it must be a mapping",
    ),
    (
        "coordinate-system-a-number",
        mutated("coordinate_system: reference_image", "coordinate_system: 3"),
        "coordinate_system: 3",
        "coordinate_system",
        "coordinate_system 3 is not supported",
    ),
]
OPTIONS = {"level-a-list": MapOptions(level="L2")}


@pytest.mark.parametrize(("text", "marker", "key", "words"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_a_mutated_clinic_map_gives_a_located_map_error_with_its_key_path(
    tmp_path: Path, request: pytest.FixtureRequest, text: str, marker: str, key: str, words: str
) -> None:
    path = tmp_path / "map.building.yaml"
    path.write_text(text, encoding="utf-8")
    case = request.node.callspec.id
    with pytest.raises(MapError) as caught:
        load_site_map(path, OPTIONS.get(case))
    error = caught.value
    line = line_of(text, marker)
    assert error.location is not None and error.location.line == line, str(error)
    assert error.location.field == key, str(error)
    assert str(error).startswith(f"{path}:{line}:"), str(error)
    assert f"field {key!r}" in str(error) and words in error.problem, str(error)


def test_the_shipped_clinic_map_loads_unmutated(tmp_path: Path) -> None:
    # The narrow negative: the same file, copied as the mutations are, loads with its 9 graph-0 lanes.
    path = tmp_path / "map.building.yaml"
    path.write_text(TEXT, encoding="utf-8")
    site = load_site_map(path)
    assert len(site.segments) == 9 and site.segments[0].names == ("lobby--v1", "v1--lobby")
    assert site.meters_per_pixel == pytest.approx(20 / 400)


def test_a_level_with_an_empty_vertex_list_says_so_at_each_lane(tmp_path: Path) -> None:
    path = tmp_path / "map.building.yaml"
    path.write_text(mutated("    vertices:\n", "    vertices: []\n    old_vertices:\n"), encoding="utf-8")
    with pytest.raises(LoadErrors) as caught:
        load_site_map(path)
    problems = [error.problem for error in caught.value.errors]
    assert len(problems) == 11  # the measurement and the ten lanes
    assert problems[0] == "measurement vertex 8 is not a vertex index (the level has no vertices)"
    assert problems[1] == "lane vertex 0 is not a vertex index (the level has no vertices)"


def test_lifts_written_inside_a_level_are_noted_not_refused(tmp_path: Path) -> None:
    # A near miss of "lifts: -1e9": inside a level, ``lifts`` is a key fleetsim does not model (noted).
    path = tmp_path / "map.building.yaml"
    path.write_text(mutated("    doors:\n", "    lifts: -1e9\n    doors:\n"), encoding="utf-8")
    site = load_site_map(path)
    assert len(site.segments) == 9
    assert any("not-modelled: level key 'lifts'" in warning for warning in site.warnings), site.warnings


# -- every value, replaced --------------------------------------------------------------------------

BAD_VALUES: list[Any] = [None, "x", -1, -1e9, 0.5, math.nan, math.inf, True, [], [1, "a"], {}, {"k": [1]}]


def _places(value: Any, where: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every key path of ``value`` (a parsed YAML document), parents before their children."""
    yield where
    if isinstance(value, dict):
        for key, child in value.items():
            yield from _places(child, (*where, key))
    elif isinstance(value, list):
        for index, child in enumerate(value):
            yield from _places(child, (*where, index))


def _replaced(document: Any, where: tuple[Any, ...], value: Any) -> Any:
    changed = copy.deepcopy(document)
    if not where:
        return value
    parent = changed
    for step in where[:-1]:
        parent = parent[step]
    parent[where[-1]] = value
    return changed


def test_every_value_of_the_clinic_map_replaced_gives_success_or_a_located_error(tmp_path: Path) -> None:
    document = yaml.safe_load(TEXT)
    path = tmp_path / "map.building.yaml"
    places = list(_places(document))
    assert len(places) > 200  # the sweep covers the whole file
    unlocated = []
    for number, where in enumerate(places):
        # One bad value per place, in turn: each kind of value reaches each kind of place (a load is ~30 ms
        # of YAML parsing, so every value at every place would take a minute and a half).
        for value in (BAD_VALUES[number % len(BAD_VALUES)],):
            text = yaml.dump(_replaced(document, where, value), Dumper=yaml.CSafeDumper, sort_keys=False)
            path.write_text(text, encoding="utf-8")
            try:
                load_site_map(path)
            except LoadError as error:  # one error, or several (LoadErrors) each located
                errors = getattr(error, "errors", [error])
                if any(e.location is None or e.location.line is None for e in errors):
                    unlocated.append((where, value, str(error)))
            except FleetsimError as error:
                unlocated.append((where, value, f"not a load error: {error!r}"))
    assert unlocated == []
