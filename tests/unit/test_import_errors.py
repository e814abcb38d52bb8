"""Malformed LIF and RMF files: one located error each (JSON pointer or YAML line, the bad value), never a
traceback, and nothing half loaded (a scenario on such a map does not load at all)."""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from site_documents import edge, layout, lif_v1, node, quarter, save_json, save_yaml, to_v2

from fleetsim.errors import LoadError, LoadErrors, MapError
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.suites.scenario import load_scenario_dir

BASE = lif_v1(
    layout(
        "hall",
        [node("A", 0, 0), node("B", 5, 0), node("C", 5, 5)],
        [
            edge("A-B", "A", "B"),
            edge("B-C", "B", "C", trajectory=quarter((5, 0), (5, 5), (5, 5))),
        ],
    )
)
Mutation = Callable[[Any], object]


def _set(path: str, value: object) -> Mutation:
    def mutate(document: Any) -> None:
        *parents, last = [int(k) if k.isdigit() else k for k in path.strip("/").split("/")]
        target = document
        for key in parents:
            target = target[key]
        if value is _DELETE:
            del target[last]
        else:
            target[last] = value

    return mutate


_DELETE = object()
TRAJECTORY = "/layouts/0/edges/1/vehicleTypeEdgeProperties/0/trajectory"

LIF_CASES: list[tuple[str, Mutation, dict[str, Any], str, str]] = [
    # (id, mutation, options, pointer, words in the message)
    ("meta-not-object", _set("/metaInformation", "x"), {}, "/metaInformation", "'x' must be an object, not a string"),
    ("layouts-and-origins", _set("/origins", []), {}, "/", "has both 'layouts' (LIF 1.0) and 'origins' (LIF 2.0)"),
    ("layouts-empty", _set("/layouts", []), {}, "/layouts", "must not be empty"),
    ("layouts-not-list", _set("/layouts", {"a": 1}), {}, "/layouts", "{'a': 1} must be a list, not an object"),
    (
        "layout-id-missing",
        _set("/layouts/0/layoutId", _DELETE),
        {},
        "/layouts/0",
        "required member 'layoutId' is missing",
    ),
    ("layout-id-number", _set("/layouts/0/layoutId", 5), {}, "/layouts/0/layoutId", "5 must be a string, not a number"),
    ("nodes-missing", _set("/layouts/0/nodes", _DELETE), {}, "/layouts/0", "required member 'nodes' is missing"),
    (
        "node-id-twice",
        _set("/layouts/0/nodes/1/nodeId", "A"),
        {},
        "/layouts/0/nodes/1/nodeId",
        "nodeId 'A' is used twice",
    ),
    ("node-id-empty", _set("/layouts/0/nodes/1/nodeId", " "), {}, "/layouts/0/nodes/1/nodeId", "' ' must not be empty"),
    (
        "x-string",
        _set("/layouts/0/nodes/0/nodePosition/x", "1.0"),
        {},
        "/layouts/0/nodes/0/nodePosition/x",
        "'1.0' must be a number, not a string",
    ),
    (
        "y-missing",
        _set("/layouts/0/nodes/2/nodePosition/y", _DELETE),
        {},
        "/layouts/0/nodes/2/nodePosition",
        "required member 'y' is missing",
    ),
    (
        "x-boolean",
        _set("/layouts/0/nodes/0/nodePosition/x", True),
        {},
        "/layouts/0/nodes/0/nodePosition/x",
        "True must be a number, not a boolean",
    ),
    (
        "unknown-start-node",
        _set("/layouts/0/edges/0/startNodeId", "Q"),
        {},
        "/layouts/0/edges/0",
        "edge 'A-B': startNodeId 'Q' is not a node of any layout of this file",
    ),
    (
        "end-node-number",
        _set("/layouts/0/edges/0/endNodeId", 7),
        {},
        "/layouts/0/edges/0/endNodeId",
        "7 must be a string, not a number",
    ),
    (
        "properties-not-list",
        _set("/layouts/0/edges/0/vehicleTypeEdgeProperties", "T"),
        {},
        "/layouts/0/edges/0/vehicleTypeEdgeProperties",
        "'T' must be a list",
    ),
    (
        "type-id-missing",
        _set("/layouts/0/edges/0/vehicleTypeEdgeProperties/0/vehicleTypeId", _DELETE),
        {},
        "/layouts/0/edges/0/vehicleTypeEdgeProperties/0",
        "required member 'vehicleTypeId' is missing",
    ),
    (
        "knots-too-few",
        _set(f"{TRAJECTORY}/knotVector", [0, 0, 1, 1]),
        {},
        TRAJECTORY,
        "the knot vector has 4 values; 3 control points of degree 2 need 6",
    ),
    (
        "knot-above-one",
        _set(f"{TRAJECTORY}/knotVector", [0, 0, 0, 1, 1, 2]),
        {},
        f"{TRAJECTORY}/knotVector/5",
        "knot 2.0 is outside [0, 1]",
    ),
    (
        "weight-zero",
        _set(f"{TRAJECTORY}/controlPoints/1/weight", 0),
        {},
        TRAJECTORY,
        "weights=[1.0, 0.0, 1.0] must be finite and > 0",
    ),
    ("degree-fraction", _set(f"{TRAJECTORY}/degree", 1.5), {}, f"{TRAJECTORY}/degree", "1.5 must be a whole number"),
    (
        "control-x-null",
        _set(f"{TRAJECTORY}/controlPoints/0/x", None),
        {},
        f"{TRAJECTORY}/controlPoints/0/x",
        "None must be a number, not null",
    ),
    (
        "trajectory-off-its-node",
        _set(f"{TRAJECTORY}/controlPoints/0/x", 6.0),
        {},
        TRAJECTORY,
        "the trajectory starts at (6, 0), 1 m from its node 'B' at (5, 0)",
    ),
    (
        "edge-to-itself",
        _set("/layouts/0/edges/0/endNodeId", "A"),
        {},
        "/layouts/0/edges/0",
        "edge 'A-B' joins node 'A' to itself without a trajectory",
    ),
    (
        "type-twice",
        lambda d: d["layouts"][0]["edges"][0]["vehicleTypeEdgeProperties"].append(
            {"vehicleTypeId": "T", "rotationAllowed": True}
        ),
        {},
        "/layouts/0/edges/0/vehicleTypeEdgeProperties/1",
        "robot type 'T' has two property objects on this edge",
    ),
    ("no-edges", _set("/layouts/0/edges", []), {}, "/layouts/0", "layout 'hall' has no edges"),
    (
        "unknown-layout",
        lambda d: None,
        {"layout": "hal"},
        "",
        "map_options.layout='hal' is not a layout of this file ('hall'); did you mean 'hall'?",
    ),
    (
        "unknown-robot-type",
        lambda d: None,
        {"robot_type": "U"},
        "",
        "map_options.robot_type='U' has no edges in layout 'hall' (robot types there: 'T')",
    ),
    (
        "duplicate-layout-id",
        lambda d: d["layouts"].append(copy.deepcopy(d["layouts"][0])),
        {},
        "/layouts/1/layoutId",
        "layoutId 'hall' is used twice",
    ),
]


@pytest.mark.parametrize(
    ("mutate", "options", "pointer", "words"), [c[1:] for c in LIF_CASES], ids=[c[0] for c in LIF_CASES]
)
def test_a_malformed_lif_file_gives_one_located_error(
    tmp_path: Path, mutate: Mutation, options: dict[str, Any], pointer: str, words: str
) -> None:
    document = copy.deepcopy(BASE)
    mutate(document)
    path = save_json(tmp_path, document)
    with pytest.raises(LoadError) as caught:  # several errors (LoadErrors): this one is the first
        load_site_map(path, MapOptions(**options))
    location = caught.value.location
    assert location is not None and Path(location.path) == path
    assert (location.field or "") == pointer
    assert words in caught.value.problem, caught.value.problem


V2_CASES = [
    (
        "robot-types-empty",
        ("/origins/0/layouts/0/edges/0/mobileRobotTypeEdgeProperties/0/mobileRobotTypes", []),
        "must not be empty",
    ),
    (
        "manufacturer-missing",
        ("/origins/0/layouts/0/edges/0/mobileRobotTypeEdgeProperties/0/mobileRobotTypes/0/manufacturer", _DELETE),
        "required member 'manufacturer' is missing",
    ),
    ("origin-id-missing", ("/origins/0/originId", _DELETE), "required member 'originId' is missing"),
]


@pytest.mark.parametrize(("change", "words"), [c[1:] for c in V2_CASES], ids=[c[0] for c in V2_CASES])
def test_a_malformed_lif_2_file_gives_one_located_error(tmp_path: Path, change: tuple[str, object], words: str) -> None:
    document = to_v2(BASE)
    _set(*change)(document)
    with pytest.raises(MapError) as caught:
        load_site_map(save_json(tmp_path, document))
    assert words in caught.value.problem
    assert caught.value.location is not None and caught.value.location.field is not None


def test_a_lif_file_that_is_not_json_is_located_at_its_line(tmp_path: Path) -> None:
    path = tmp_path / "site.lif.json"
    path.write_text('{"metaInformation": {},\n "layouts": [,]}')
    with pytest.raises(MapError) as caught:
        load_site_map(path)
    assert caught.value.location is not None and caught.value.location.line == 2
    assert "not valid JSON" in caught.value.problem


BUILDING = """\
levels:
  L1:
    vertices:
      - [0, 0, 0, a]
      - [200, 0, 0, b]
      - [200, 200, 0, ""]
    measurements:
      - [0, 1, {distance: [3, 10]}]
    lanes:
      - [0, 1, {bidirectional: [4, true], graph_idx: [2, 0]}]
      - [1, 2, {bidirectional: [4, false], graph_idx: [2, 0]}]
"""

RMF_CASES = [
    ("yaml-syntax", BUILDING.replace("[0, 1, {bidirectional", "[0, 1, {bidirectional: ["), {}, 10, "invalid YAML"),
    ("no-levels", "name: x\n", {}, 1, "levels is None; it must be a mapping"),
    (
        "web-mercator",
        "coordinate_system: web_mercator\n" + BUILDING,
        {},
        1,
        "coordinate_system 'web_mercator' is not supported",
    ),
    (
        "vertex-x-text",
        BUILDING.replace("[200, 0, 0, b]", "[wide, 0, 0, b]"),
        {},
        5,
        "vertex 1 x is 'wide'; it must be a finite number",
    ),
    (
        "lane-vertex-out-of-range",
        BUILDING.replace("[1, 2, {", "[1, 9, {"),
        {},
        11,
        "lane vertex 9 is not a vertex index (0 to 2)",
    ),
    (
        "lane-params-list",
        BUILDING.replace("[0, 1, {bidirectional: [4, true], graph_idx: [2, 0]}]", "[0, 1, [4, true]]"),
        {},
        10,
        "lane parameters is [4, True]; it must be a mapping",
    ),
    (
        "bidirectional-text",
        BUILDING.replace("[4, true]", "[4, 'yes']"),
        {},
        10,
        "bidirectional is 'yes'; it must be true or false",
    ),
    (
        "graph-fraction",
        BUILDING.replace("graph_idx: [2, 0]}]\n      - [1", "graph_idx: [2, 1.5]}]\n      - [1"),
        {},
        10,
        "graph_idx is 1.5; it must be a whole number",
    ),
    ("distance-zero", BUILDING.replace("[3, 10]", "[3, 0]"), {}, 8, "both must be positive"),
    ("unknown-level", BUILDING, {"level": "L2"}, 2, "map_options.level='L2' is not a level of this building ('L1')"),
    ("empty-graph", BUILDING, {"graph": 3}, 3, "level 'L1' has no lanes in graph 3 (graphs with lanes: 0)"),
    (
        "lane-of-no-length",
        BUILDING.replace('[200, 200, 0, ""]', '[200, 0, 0, ""]'),
        {},
        11,
        "lane 1 joins vertices 1 and 2, which are at the same place",
    ),
    (
        "duplicate-key",
        BUILDING.replace("    lanes:", "    measurements: []\n    lanes:"),
        {},
        9,
        "duplicate key 'measurements'",
    ),
    ("python-tag", "levels: !!python/object:os.system {}\n", {}, 1, "could not determine a constructor"),
    (
        "param-not-pair",
        BUILDING.replace("{distance: [3, 10]}", "{distance: 10}"),
        {},
        8,
        "parameter 'distance' is 10; it must be [type, value]",
    ),
    # Mutated files whose structure the loader used to trust (a TypeError or KeyError leaked from them).
    (
        "lanes-a-number",
        BUILDING.replace("    lanes:\n", "    lanes: 0.5\n    old_lanes:\n"),
        {},
        9,
        "lanes is 0.5; it must be a list",
    ),
    ("lifts-a-number", BUILDING + "lifts: -1.0e+9\n", {}, 12, "lifts is -1000000000.0; it must be a mapping"),
    (
        "measurements-a-number",
        BUILDING.replace("    measurements:\n", "    measurements: 3\n    m:\n"),
        {},
        7,
        "measurements is 3; it must be a list",
    ),
    (
        "vertices-a-string",
        "levels:\n  L1:\n    vertices: many\n",
        {},
        3,
        "vertices is 'many'; it must be a list of [x, y",
    ),
    ("doors-a-number", BUILDING + "    doors: 5\n", {}, 12, "doors is 5; it must be a list"),
    ("vertex-a-number", BUILDING.replace("[200, 0, 0, b]", "7"), {}, 5, "vertex 1 is 7; it must be a list [x, y"),
    (
        "vertex-name-a-number",
        BUILDING.replace("[200, 0, 0, b]", "[200, 0, 0, 5]"),
        {},
        5,
        "vertex 1 name is 5; it must be a string",
    ),
    (
        "distance-nan",
        BUILDING.replace("[3, 10]", "[3, .nan]"),
        {},
        8,
        "measurement distance is nan; it must be a finite number",
    ),
    ("distance-negative", BUILDING.replace("[3, 10]", "[3, -10]"), {}, 8, "both must be positive"),
    (
        "distance-text",
        BUILDING.replace("[3, 10]", "[3, far]"),
        {},
        8,
        "measurement distance is 'far'; it must be a finite number",
    ),
    (
        "graph-negative",
        BUILDING.replace("graph_idx: [2, 0]}]\n      - [1", "graph_idx: [2, -1]}]\n      - [1"),
        {},
        10,
        "graph_idx is -1; it must be a whole number >= 0",
    ),
    ("level-a-list", "levels:\n  L1: [1, 2]\n", {}, 2, "level 'L1' is [1, 2]; it must be a mapping"),
    (
        "lane-end-a-string",
        BUILDING.replace("[1, 2, {", "[1, two, {"),
        {},
        11,
        "lane vertex 'two' is not a vertex index (0 to 2)",
    ),
    (
        "scale-overflow",
        BUILDING.replace("[3, 10]", "[3, 1.0e+308]").replace("[200, 0, 0, b]", "[1.0e-10, 0, 0, b]"),
        {},
        8,
        "give a finite scale",
    ),
    (
        "coordinates-overflow",
        BUILDING.replace("[200, 200, 0", "[1.0e+308, 200, 0").replace("[3, 10]", "[3, 1000]"),
        {},
        6,
        "vertex 2 lies at infinity",
    ),
]


@pytest.mark.parametrize(
    ("text", "options", "line", "words"), [c[1:] for c in RMF_CASES], ids=[c[0] for c in RMF_CASES]
)
def test_a_malformed_building_map_gives_one_error_at_its_yaml_line(
    tmp_path: Path, text: str, options: dict[str, Any], line: int, words: str
) -> None:
    path = save_yaml(tmp_path, text)
    with pytest.raises(MapError) as caught:
        load_site_map(path, MapOptions(**options))
    location = caught.value.location
    assert location is not None and Path(location.path) == path and location.line == line, str(caught.value)
    assert words in caught.value.problem, caught.value.problem


def test_an_error_in_a_building_map_names_its_key_path(tmp_path: Path) -> None:
    path = save_yaml(
        tmp_path, BUILDING.replace("graph_idx: [2, 0]}]\n      - [1", "graph_idx: [2, zero]}]\n      - [1")
    )
    with pytest.raises(MapError) as caught:
        load_site_map(path)
    assert caught.value.location is not None and caught.value.location.field == "levels.L1.lanes[0][2].graph_idx"
    assert str(caught.value).startswith(f"{path}:10:")


def test_every_broken_vertex_measurement_and_lane_of_a_level_is_reported_at_once(tmp_path: Path) -> None:
    text = (
        BUILDING.replace('[200, 200, 0, ""]', '[200, "200", 0, ""]')
        .replace("[3, 10]", "[3, -1]")
        .replace("[4, false]", "[4, 0.5]")
        .replace("[0, 1, {bidirectional", "[0, 7, {bidirectional")
    )
    with pytest.raises(LoadErrors) as caught:
        load_site_map(save_yaml(tmp_path, text))
    assert [(e.location.line if e.location else None, e.problem) for e in caught.value.errors] == [
        (6, "vertex 2 y is '200'; it must be a finite number"),
        (
            8,
            "measurement 0 joins vertices 0 and 1 200 px apart at distance -1 m; both must be positive (and give a finite scale)",
        ),
        (10, "lane vertex 7 is not a vertex index (0 to 2)"),
        (11, "bidirectional is 0.5; it must be true or false"),
    ]


@pytest.mark.parametrize(
    ("change", "segments"),
    [
        (("  L1:", "  1:"), 2),  # a level named by a number
        (("levels:", "lifts:\nlevels:"), 2),  # no lifts written
        (("    lanes:", "    doors:\n    vertices_note: 1\n    lanes:"), 2),  # no doors written, an unknown key
    ],
    ids=["numbered-level", "empty-lifts", "empty-doors"],
)
def test_near_misses_of_the_mutations_still_load(tmp_path: Path, change: tuple[str, str], segments: int) -> None:
    site = load_site_map(save_yaml(tmp_path, BUILDING.replace(*change, 1)))
    assert len(site.segments) == segments


def test_a_scenario_on_a_malformed_site_does_not_load_at_all(tmp_path: Path) -> None:
    document = copy.deepcopy(BASE)
    _set(f"{TRAJECTORY}/controlPoints/0/x", 6.0)(document)
    save_json(tmp_path, document, "map.lif.json")
    (tmp_path / "vehicles.csv").write_text("vehicle_id,start_segment_id,segment_orientation\n1,A-B,forward\n")
    (tmp_path / "tasks.csv").write_text("vehicle_id,goal_segment_id\n1,B-C\n")
    with pytest.raises(MapError, match="the trajectory starts at"):
        load_scenario_dir(tmp_path)
