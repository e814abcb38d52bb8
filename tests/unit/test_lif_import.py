"""LIF files (1.0 and 2.0 structures) as driving maps: layouts, robot types, NURBS edges, merging."""

from __future__ import annotations

import math
from itertools import pairwise
from pathlib import Path

import pytest
from site_documents import edge, layout, lif_v1, load, node, nurbs, quarter, save_json, to_v2

from fleetsim.enums import Direction, Shape
from fleetsim.errors import LoadErrors, MapError
from fleetsim.layout.nurbs import CHORD_TOLERANCE
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map

SQUARE_NODES = [node("A", 0, 0), node("B", 10, 0), node("C", 10, 10)]
STRAIGHTS = lif_v1(
    layout(
        "hall",
        SQUARE_NODES,
        [
            edge("A-B", "A", "B"),
            edge("B-C", "B", "C"),
            edge("B-A", "B", "A"),
        ],
    )
)


@pytest.mark.parametrize("structure", ["1.0", "2.0"])
def test_edges_become_segments_in_file_order_and_opposite_edges_one_two_way_segment(
    tmp_path: Path, structure: str
) -> None:
    document = STRAIGHTS if structure == "1.0" else to_v2(STRAIGHTS)
    site = load(tmp_path, document)
    assert site.format == "lif" and site.part == (
        "layout 'hall', robot type 'T'" if structure == "1.0" else "layout 'hall', robot type 'T/T'"
    )
    assert [(s.id, s.shape, s.direction, s.names, s.waypoints) for s in site.segments] == [
        (1, Shape.STRAIGHT, Direction.BOTH, ("A-B", "B-A"), ((0.0, 0.0), (10.0, 0.0))),
        (2, Shape.STRAIGHT, Direction.FORWARD, ("B-C",), ((10.0, 0.0), (10.0, 10.0))),
    ]
    assert site.warnings == ()


def test_a_json_file_is_lif_by_its_content_whatever_its_name(tmp_path: Path) -> None:
    assert load(tmp_path, STRAIGHTS, name="exported.json").format == "lif"


def test_a_lif_json_file_without_lif_content_is_refused(tmp_path: Path) -> None:
    with pytest.raises(MapError, match=r"this \.lif\.json file is not LIF: its top level needs 'metaInformation'"):
        load(tmp_path, {"metaInformation": {}, "nodes": []})


# -- several layouts ------------------------------------------------------------------------------

TWO_LAYOUTS = lif_v1(
    layout("ground", [node("A", 0, 0), node("B", 5, 0)], [edge("g1", "A", "B")]),
    layout("upper", [node("C", 0, 0), node("D", 0, 7)], [edge("u1", "C", "D"), edge("u2", "D", "C")]),
)


@pytest.mark.parametrize("structure", ["1.0", "2.0"])
def test_a_layout_is_chosen_by_its_id_and_the_others_are_noted(tmp_path: Path, structure: str) -> None:
    document = TWO_LAYOUTS if structure == "1.0" else to_v2(TWO_LAYOUTS)
    site = load(tmp_path, document, layout="upper")
    assert [(s.names, s.direction) for s in site.segments] == [(("u1", "u2"), Direction.BOTH)]
    pointer = "/layouts/0" if structure == "1.0" else "/origins/0/layouts/0"
    assert site.warnings == (
        f"{tmp_path / 'site.lif.json'}: warning not-modelled: another layout (another level or "
        f"area) (once, first at {pointer} ('ground')); fleetsim does not model it and ignores it",
    )


def test_several_layouts_need_the_layout_option(tmp_path: Path) -> None:
    with pytest.raises(
        MapError, match=r"holds 2 layouts \('ground', 'upper'\); choose one with map_options: \{layout: ID\}"
    ):
        load(tmp_path, TWO_LAYOUTS)


def test_layouts_of_several_origins_are_all_offered(tmp_path: Path) -> None:
    document = to_v2(TWO_LAYOUTS)
    document["origins"].append({"originId": "O2", "layouts": [document["origins"][0]["layouts"].pop()]})
    assert [s.names for s in load(tmp_path, document, layout="upper").segments] == [("u1", "u2")]


# -- robot types ----------------------------------------------------------------------------------

TYPED = lif_v1(
    layout(
        "hall",
        [
            node("A", 0, 0, "Acme.Tug", "Acme.Lift"),
            node("B", 4, 0, "Acme.Tug", "Acme.Lift"),
            node("C", 4, 4, "Acme.Tug"),
        ],
        [
            edge("A-B", "A", "B", "Acme.Tug", "Acme.Lift"),
            edge("B-C", "B", "C", "Acme.Tug"),
            edge("C-A", "C", "A", "Acme.Tug", trajectory=quarter((4, 4), (0, 4), (0, 0))),
        ],
    )
)


@pytest.mark.parametrize(
    ("structure", "tug", "lift"), [("1.0", "Acme.Tug", "Acme.Lift"), ("2.0", "Acme/Tug", "Acme/Lift")]
)
def test_the_robot_type_option_chooses_whose_edges_form_the_map(
    tmp_path: Path, structure: str, tug: str, lift: str
) -> None:
    document = TYPED if structure == "1.0" else to_v2(TYPED)
    assert [s.names for s in load(tmp_path, document, robot_type=tug).segments] == [("A-B",), ("B-C",), ("C-A",)]
    lifted = load(tmp_path, document, robot_type=lift)
    assert [s.names for s in lifted.segments] == [("A-B",)]
    assert "warning skipped-edge: an edge not usable by" in lifted.warnings[0] and "(2 times" in lifted.warnings[0]


def test_a_robot_type_that_may_use_every_edge_skips_none(tmp_path: Path) -> None:
    assert load(tmp_path, TYPED, robot_type="Acme.Tug").warnings == ()


def test_an_edge_to_a_node_of_its_own_layout_is_kept_without_a_warning(tmp_path: Path) -> None:
    document = lif_v1(
        layout(
            "hall", [node("A", 0, 0), node("B", 5, 0), node("Z", 5, 5)], [edge("e1", "A", "B"), edge("lift", "B", "Z")]
        )
    )
    site = load(tmp_path, document)
    assert [s.names for s in site.segments] == [("e1",), ("lift",)] and site.warnings == ()


def test_edges_that_differ_per_robot_type_need_the_option(tmp_path: Path) -> None:
    with pytest.raises(MapError) as caught:
        load(tmp_path, to_v2(TYPED))
    assert caught.value.location is not None and caught.value.location.field == "/origins/0/layouts/0/edges/1"
    assert "edges differ per robot type ('Acme/Lift', 'Acme/Tug'; this edge first)" in caught.value.problem


def test_edges_shared_alike_by_every_robot_type_need_no_option(tmp_path: Path) -> None:
    shared = lif_v1(
        layout(
            "hall",
            [node("A", 0, 0, "X.1", "X.2"), node("B", 4, 0, "X.1", "X.2")],
            [edge("A-B", "A", "B", "X.1", "X.2")],
        )
    )
    site = load(tmp_path, shared)
    assert site.part == "layout 'hall', robot type 'X.1'" and len(site.segments) == 1


def test_one_property_object_may_serve_several_mobile_robot_types(tmp_path: Path) -> None:
    document = to_v2(lif_v1(layout("hall", [node("A", 0, 0), node("B", 4, 0)], [edge("A-B", "A", "B")])))
    prop = document["origins"][0]["layouts"][0]["edges"][0]["mobileRobotTypeEdgeProperties"][0]
    prop["mobileRobotTypes"].append({"manufacturer": "Other", "seriesName": "S"})
    assert [s.names for s in load(tmp_path, document, robot_type="Other/S").segments] == [("A-B",)]


# -- NURBS trajectories ---------------------------------------------------------------------------


def arc_edges(*trajectories: tuple[str, str, str, dict[str, object]]) -> dict[str, object]:
    return lif_v1(
        layout(
            "hall",
            [node("A", 5, 0), node("B", 0, 5), node("C", 15, 0)],
            [edge(eid, s, e, trajectory=t) for eid, s, e, t in trajectories],
        )
    )


def test_a_rational_quadratic_trajectory_becomes_a_circular_path_within_the_chord_tolerance(tmp_path: Path) -> None:
    site = load(tmp_path, arc_edges(("A-B", "A", "B", quarter((5, 0), (5, 5), (0, 5)))))
    (segment,) = site.segments
    assert segment.shape is Shape.PATH and segment.first == (5.0, 0.0) and segment.last == (0.0, 5.0)
    assert all(abs(math.hypot(x, y) - 5.0) < 1e-9 for x, y in segment.waypoints)  # every sample on the circle
    # The farthest a chord strays from the circle is at its middle: r − distance of the chord's midpoint.
    sagitta = max(5.0 - math.hypot((a[0] + b[0]) / 2, (a[1] + b[1]) / 2) for a, b in pairwise(segment.waypoints))
    assert sagitta <= CHORD_TOLERANCE
    assert segment.length == pytest.approx(5.0 * math.pi / 2, abs=0.01)


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_trajectories_of_degree_one_to_three_with_weights_run_from_node_to_node(tmp_path: Path, degree: int) -> None:
    points = [(5.0, 0.0), (6.0, 3.0), (3.0, 6.0), (1.0, 6.0), (0.0, 5.0)]
    knots = (
        [0.0] * (degree + 1)
        + [i / (len(points) - degree) for i in range(1, len(points) - degree)]
        + [1.0] * (degree + 1)
    )
    trajectory = nurbs(degree, knots, points, [1.0, 2.0, 0.5, 3.0, 1.0])
    (segment,) = load(tmp_path, arc_edges(("A-B", "A", "B", trajectory))).segments
    assert segment.first == (5.0, 0.0) and segment.last == (0.0, 5.0)
    if degree == 1:
        assert segment.waypoints == tuple(points)
    else:
        assert len(segment.waypoints) > len(points)


def test_a_trajectory_end_within_five_centimetres_of_its_node_is_snapped_onto_it(tmp_path: Path) -> None:
    trajectory = nurbs(1, [0, 0, 0.5, 1, 1], [(5.03, 0.0), (3.0, 3.0), (0.0, 4.96)])
    (segment,) = load(tmp_path, arc_edges(("A-B", "A", "B", trajectory))).segments
    assert segment.waypoints == ((5.0, 0.0), (3.0, 3.0), (0.0, 5.0))


def test_opposite_curved_edges_along_the_same_arc_make_one_two_way_segment(tmp_path: Path) -> None:
    there = quarter((5, 0), (5, 5), (0, 5))
    back = quarter((0, 5), (5, 5), (5, 0))
    site = load(tmp_path, arc_edges(("out", "A", "B", there), ("back", "B", "A", back)))
    assert [(s.names, s.direction) for s in site.segments] == [(("out", "back"), Direction.BOTH)]


def test_opposite_edges_along_different_paths_stay_two_one_way_segments(tmp_path: Path) -> None:
    there = quarter((5, 0), (5, 5), (0, 5))
    back = quarter((0, 5), (0, 0), (5, 0))  # bulges the other way
    site = load(tmp_path, arc_edges(("out", "A", "B", there), ("back", "B", "A", back)))
    assert [(s.id, s.names, s.direction) for s in site.segments] == [
        (1, ("out",), Direction.FORWARD),
        (2, ("back",), Direction.FORWARD),
    ]


def test_parallel_edges_in_one_direction_are_separate_segments_and_pair_up_in_order(tmp_path: Path) -> None:
    document = lif_v1(
        layout(
            "hall",
            [node("A", 0, 0), node("B", 5, 0)],
            [
                edge("e1", "A", "B"),
                edge("e2", "A", "B"),
                edge("e3", "B", "A"),
            ],
        )
    )
    assert [(s.names, s.direction) for s in load(tmp_path, document).segments] == [
        (("e1", "e3"), Direction.BOTH),
        (("e2",), Direction.FORWARD),
    ]


def test_an_edge_to_a_node_of_another_layout_is_skipped_with_a_warning(tmp_path: Path) -> None:
    document = lif_v1(
        layout("hall", [node("A", 0, 0), node("B", 5, 0)], [edge("e1", "A", "B"), edge("lift", "B", "Z")]),
        layout("roof", [node("Z", 0, 0), node("Y", 5, 0)], [edge("r1", "Z", "Y")]),
    )
    site = load(tmp_path, document, layout="hall")
    assert [s.names for s in site.segments] == [("e1",)]
    assert (
        f"{tmp_path / 'site.lif.json'}: warning skipped-edge: an edge to a node of another layout "
        "(once, first at /layouts/0/edges/1 ('lift')); no segment was made for it"
    ) in site.warnings


@pytest.mark.parametrize("key", ["endNodeId", "startNodeId"])
def test_an_edge_to_a_node_of_no_layout_is_a_located_error_naming_the_edge_and_the_node(
    tmp_path: Path, key: str
) -> None:
    lift = edge("lift", "B", "Z") if key == "endNodeId" else edge("lift", "Z", "B")
    document = lif_v1(
        layout("hall", [node("A", 0, 0), node("B", 5, 0)], [edge("e1", "A", "B"), lift]),
        layout("roof", [node("Y", 0, 0), node("X", 5, 0)], [edge("r1", "Y", "X")]),
    )
    with pytest.raises(MapError) as caught:
        load(tmp_path, document, layout="hall")
    assert caught.value.location is not None and caught.value.location.field == "/layouts/0/edges/1"
    assert caught.value.problem == f"edge 'lift': {key} 'Z' is not a node of any layout of this file"


def test_an_edge_to_a_node_of_no_layout_is_refused_even_when_its_robot_type_is_not_chosen(tmp_path: Path) -> None:
    document = lif_v1(
        layout("hall", [node("A", 0, 0), node("B", 5, 0)], [edge("e1", "A", "B"), edge("e2", "B", "Q", "U")])
    )
    with pytest.raises(MapError, match="edge 'e2': endNodeId 'Q' is not a node of any layout"):
        load(tmp_path, document, robot_type="T")


def test_a_mistyped_node_id_gets_a_did_you_mean(tmp_path: Path) -> None:
    document = lif_v1(layout("hall", [node("dock_1", 0, 0), node("dock_2", 5, 0)], [edge("e1", "dock_1", "dokc_2")]))
    with pytest.raises(
        MapError, match="endNodeId 'dokc_2' is not a node of any layout of this file; did you mean 'dock_2'"
    ):
        load(tmp_path, document)


def test_an_edge_id_used_twice_in_a_layout_is_a_located_error_naming_both_edges(tmp_path: Path) -> None:
    document = lif_v1(
        layout(
            "hall", [node("A", 0, 0), node("B", 5, 0), node("C", 5, 5)], [edge("e1", "A", "B"), edge("e1", "B", "C")]
        )
    )
    with pytest.raises(MapError) as caught:
        load(tmp_path, document)
    assert caught.value.location is not None and caught.value.location.field == "/layouts/0/edges/1"
    assert (
        caught.value.problem
        == "edgeId 'e1' is used twice in this layout: by /layouts/0/edges/0 and by /layouts/0/edges/1"
    )


def test_the_same_edge_id_in_two_layouts_is_not_a_duplicate(tmp_path: Path) -> None:
    document = lif_v1(
        layout("hall", [node("A", 0, 0), node("B", 5, 0)], [edge("e1", "A", "B")]),
        layout("roof", [node("C", 0, 0), node("D", 5, 0)], [edge("e1", "C", "D")]),
    )
    assert [s.names for s in load(tmp_path, document, layout="roof").segments] == [("e1",)]


def test_every_broken_edge_of_a_layout_is_reported_at_once(tmp_path: Path) -> None:
    document = lif_v1(
        layout(
            "hall",
            [node("A", 0, 0), node("B", 5, 0)],
            [edge("e1", "A", "B"), edge("e2", "B", "Q"), edge("e1", "B", "A"), edge("e4", "R", "A")],
        )
    )
    with pytest.raises(LoadErrors) as caught:
        load(tmp_path, document)
    assert [(e.location.field if e.location else None, e.problem) for e in caught.value.errors] == [
        ("/layouts/0/edges/1", "edge 'e2': endNodeId 'Q' is not a node of any layout of this file"),
        (
            "/layouts/0/edges/2",
            "edgeId 'e1' is used twice in this layout: by /layouts/0/edges/0 and by /layouts/0/edges/2",
        ),
        ("/layouts/0/edges/3", "edge 'e4': startNodeId 'R' is not a node of any layout of this file"),
    ]


# -- warnings: once per kind ----------------------------------------------------------------------


def test_every_attribute_fleetsim_does_not_model_is_noted_once_per_kind(tmp_path: Path) -> None:
    document = lif_v1(
        layout(
            "hall",
            [
                node("A", 0, 0, theta=0.0),
                node("B", 5, 0),
                node("C", 5, 5),
            ],
            [
                edge("A-B", "A", "B", maxSpeed=1.0, actions=[{"actionType": "beep", "blockingType": "NONE"}]),
                edge(
                    "B-C",
                    "B",
                    "C",
                    maxSpeed=0.5,
                    loadRestriction={"loaded": True, "unloaded": True},
                    rotationAllowed=False,
                ),
            ],
            stations=[{"stationId": "s", "interactionNodeIds": ["C"], "stationName": "S", "bufferSize": 2}],
        )
    )
    document["layouts"][0]["nodes"][1]["vehicleTypeNodeProperties"][0]["allowedDeviationXy"] = 0.1
    site = load(tmp_path, document, level="L1")
    codes_and_kinds = [w.split("warning ", 1)[1].split(";")[0] for w in site.warnings]
    assert codes_and_kinds == [
        "not-modelled: node attribute 'theta' (once, first at /layouts/0/nodes/0/theta)",
        "not-modelled: node property attribute 'allowedDeviationXy' (once, first at /layouts/0/nodes/1/vehicleTypeNodeProperties/0/allowedDeviationXy)",
        "not-modelled: edge property attribute 'maxSpeed' (2 times, first at /layouts/0/edges/0/vehicleTypeEdgeProperties/0/maxSpeed)",
        "not-modelled: edge property attribute 'actions' (once, first at /layouts/0/edges/0/vehicleTypeEdgeProperties/0/actions)",
        "not-modelled: edge property attribute 'rotationAllowed' (once, first at /layouts/0/edges/1/vehicleTypeEdgeProperties/0/rotationAllowed)",
        "not-modelled: edge property attribute 'loadRestriction' (once, first at /layouts/0/edges/1/vehicleTypeEdgeProperties/0/loadRestriction)",
        "option-ignored: map option 'level' (an RMF option) (once, first at map_options)",
        "not-modelled: station attribute 'bufferSize' (once, first at /layouts/0/stations/0/bufferSize)",
    ]


def test_a_file_of_modelled_attributes_only_loads_without_warnings(tmp_path: Path) -> None:
    assert load(tmp_path, to_v2(STRAIGHTS), layout="hall", robot_type="T/T").warnings == ()
    # rotationAllowed: true restricts nothing; false would be a restriction fleetsim ignores (noted above).
    assert load(tmp_path, STRAIGHTS).warnings == ()


def test_loading_twice_gives_equal_maps(tmp_path: Path) -> None:
    path = save_json(tmp_path, TYPED)
    assert load_site_map(path, MapOptions(robot_type="Acme.Tug")) == load_site_map(
        path, MapOptions(robot_type="Acme.Tug")
    )
