"""A Tiled map with one mistake gives exactly one MapError naming the file, the object and the bad value."""

from __future__ import annotations

import copy
import json
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from fleetsim.errors import LoadErrors, MapError
from fleetsim.load.tiled.reader import load_map

HEADER = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<map version="1.8" orientation="orthogonal" '
    'width="10" height="10" tilewidth="32" tileheight="32" infinite="0">\n'
)


def tmx(tmp_path: Path, body: str, header: str = HEADER, name: str = "bad.tmx") -> Path:
    path = tmp_path / name
    path.write_text(header + body + "\n</map>\n", encoding="utf-8")
    return path


def objects(*xml_objects: str) -> str:
    return '<objectgroup id="1" name="segments">\n' + "\n".join(xml_objects) + "\n</objectgroup>"


def straight(object_id: int = 7, points: str = "0,0 32,0", extra: str = "", body: str = "") -> str:
    return f'<object id="{object_id}" type="straight" x="10" y="10"{extra}>{body}<polyline points="{points}"/></object>'


def direction(value: str, kind: str = "") -> str:
    type_attr = f' type="{kind}"' if kind else ""
    return f'<properties><property name="direction"{type_attr} value="{value}"/></properties>'


def map_error(path: Path) -> MapError:
    with pytest.raises(MapError) as info:
        load_map(path)
    assert str(path) in str(info.value)
    return info.value


# --- the file as a whole -------------------------------------------------------------------------


def test_unsupported_suffix_is_named(tmp_path: Path) -> None:
    path = tmp_path / "map.txt"
    path.write_text("{}")
    assert "'.txt'" in str(map_error(path))


def test_missing_map_file_is_a_map_error(tmp_path: Path) -> None:
    assert str(map_error(tmp_path / "nowhere.tmx")).endswith("nowhere.tmx: file not found")


def test_malformed_json_reports_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "bad.json"
    path.write_text('{\n  "width": 10,\n  "height": }\n')
    error = map_error(path)
    assert error.location is not None and (error.location.line, error.location.column) == (3, 13)
    assert f"{path}:3:13" in str(error)


def test_malformed_xml_reports_line_and_column(tmp_path: Path) -> None:
    error = map_error(tmx(tmp_path, "<objectgroup>\n<object id='1'>\n</objectgroup>"))
    assert error.location is not None and error.location.line == 5 and error.location.column == 3


def test_non_orthogonal_map_names_the_orientation(tmp_path: Path) -> None:
    header = HEADER.replace('"orthogonal"', '"isometric"')
    assert "the map's orientation is 'isometric'; fleetsim reads orthogonal maps only" in str(
        map_error(tmx(tmp_path, objects(straight()), header))
    )


def test_infinite_map_is_rejected(tmp_path: Path) -> None:
    header = HEADER.replace('infinite="0"', 'infinite="1"')
    assert "the map is infinite (infinite = '1')" in str(map_error(tmx(tmp_path, objects(straight()), header)))


def test_infinite_json_map_is_rejected(tmp_path: Path) -> None:
    path = tmp_path / "inf.json"
    path.write_text(
        json.dumps(
            {
                "orientation": "orthogonal",
                "infinite": True,
                "width": 1,
                "height": 1,
                "tilewidth": 32,
                "tileheight": 32,
                "layers": [],
            }
        )
    )
    assert "the map is infinite (infinite = True); fleetsim reads fixed-size maps only" in str(map_error(path))


def test_map_without_segments_is_rejected(tmp_path: Path) -> None:
    body = objects('<object id="1" x="0" y="0"><polyline points="0,0 1,1"/></object>')  # no class: ignored
    assert "no segments" in str(map_error(tmx(tmp_path, body)))


@pytest.mark.parametrize(("value", "shown"), [("-1", "'-1'"), ("0", "'0'"), ("fast", "'fast'")])
def test_bad_meters_per_pixel_is_rejected(tmp_path: Path, value: str, shown: str) -> None:
    props = f'<properties><property name="meters_per_pixel" value="{value}"/></properties>'
    error = map_error(tmx(tmp_path, props + objects(straight())))
    assert f"meters_per_pixel is {shown}; it must be a " in str(error)


def test_missing_map_width_is_named(tmp_path: Path) -> None:
    assert "'width' is missing" in str(map_error(tmx(tmp_path, objects(straight()), HEADER.replace('width="10" ', ""))))


# --- objects -------------------------------------------------------------------------------------


def test_duplicate_ids_name_both_objects(tmp_path: Path) -> None:
    body = objects(straight(7)) + '<objectgroup id="2" name="more">' + straight(7) + "</objectgroup>"
    message = str(map_error(tmx(tmp_path, body)))
    assert "object 7" in message and "'segments'" in message and "'more'" in message


@pytest.mark.parametrize("object_id", [0, -3, 2**31, 10**300])
def test_an_id_outside_tileds_range_is_refused(tmp_path: Path, object_id: int) -> None:
    message = str(map_error(tmx(tmp_path, objects(straight(object_id)))))
    assert f"the object's id is {object_id}; Tiled ids are positive integers up to 2147483647" in message


def test_the_largest_tiled_id_loads(tmp_path: Path) -> None:
    (segment,) = load_map(tmx(tmp_path, objects(straight(2**31 - 1)))).segments
    assert segment.id == 2**31 - 1


def test_unknown_direction_names_object_and_value(tmp_path: Path) -> None:
    message = str(map_error(tmx(tmp_path, objects(straight(body=direction("sideways"))))))
    assert "object 7" in message
    assert "unknown direction 'sideways' (expected both, forward or backward)" in message


def test_direction_enum_index_out_of_range_is_rejected(tmp_path: Path) -> None:
    message = str(map_error(tmx(tmp_path, objects(straight(body=direction("5", "int"))))))
    assert "object 7" in message and "the direction property is 5" in message


def test_direction_int_property_that_is_not_a_number_is_rejected(tmp_path: Path) -> None:
    message = str(map_error(tmx(tmp_path, objects(straight(body=direction("one", "int"))))))
    assert "object 7" in message and "'one'" in message


def test_non_numeric_coordinate_names_object_and_value(tmp_path: Path) -> None:
    body = objects('<object id="4" type="straight" x="abc" y="0"><polyline points="0,0 1,1"/></object>')
    assert "object 4: x is 'abc'; it must be a number" in str(map_error(tmx(tmp_path, body)))


def test_non_numeric_polyline_point_names_object_and_value(tmp_path: Path) -> None:
    message = str(map_error(tmx(tmp_path, objects(straight(points="0,0 1,y")))))
    assert "object 7" in message and "'y'" in message


def test_malformed_polyline_points_text_is_rejected(tmp_path: Path) -> None:
    message = str(map_error(tmx(tmp_path, objects(straight(points="0,0 1;1")))))
    assert "object 7" in message and "the points are '0,0 1;1'" in message


def test_json_string_coordinate_that_is_not_a_number_is_rejected(tmp_path: Path) -> None:
    document = json_map()
    document["layers"][0]["layers"][0]["objects"][0]["polyline"][1]["y"] = "north"
    assert "object 7: point y is 'north'; it must be a number" in str(map_error(save_json(tmp_path, document)))


def test_polyline_with_one_point_is_rejected(tmp_path: Path) -> None:
    message = str(map_error(tmx(tmp_path, objects(straight(points="5,5")))))
    assert "object 7" in message and "at least 2" in message


def test_zero_length_polyline_is_rejected(tmp_path: Path) -> None:
    message = str(map_error(tmx(tmp_path, objects(straight(points="5,5 5,5 5,5")))))
    assert "object 7" in message and "zero length" in message


def test_missing_template_names_object_and_template_path(tmp_path: Path) -> None:
    body = objects('<object id="12" template="templates/nope.tx" x="1" y="1"/>')
    message = str(map_error(tmx(tmp_path, body)))
    assert "object 12" in message and "'templates/nope.tx'" in message


def test_malformed_template_names_the_template_and_the_instance(tmp_path: Path) -> None:
    (tmp_path / "broken.tx").write_text("<template><object type='straight'></template>")
    body = objects('<object id="12" template="broken.tx" x="1" y="1"/>')
    with pytest.raises(MapError) as info:
        load_map(tmx(tmp_path, body))
    assert "broken.tx" in str(info.value) and "object 12" in str(info.value)


def test_json_template_that_is_not_a_template_is_rejected(tmp_path: Path) -> None:
    (tmp_path / "t.tj").write_text(json.dumps({"type": "map"}))
    body = objects('<object id="12" template="t.tj" x="1" y="1"/>')
    with pytest.raises(MapError, match="object 12"):
        load_map(tmx(tmp_path, body))


# --- no raw exception escapes for any malformed value --------------------------------------------


def load_or_map_errors(path: Path) -> None:
    """Load ``path``; the only acceptable failures are a MapError or several (LoadErrors of MapErrors)."""
    try:
        load_map(path)
    except MapError:
        return  # located: the outcome wanted
    except LoadErrors as several:
        assert all(isinstance(error, MapError) for error in several.errors)


def json_map() -> dict[str, Any]:
    return {
        "type": "map",
        "orientation": "orthogonal",
        "infinite": False,
        "width": 10,
        "height": 10,
        "tilewidth": 32,
        "tileheight": 32,
        "properties": [{"name": "meters_per_pixel", "type": "float", "value": 0.5}],
        "layers": [
            {
                "type": "group",
                "name": "g",
                "offsetx": 3,
                "offsety": 4,
                "visible": True,
                "layers": [
                    {
                        "type": "objectgroup",
                        "name": "segments",
                        "objects": [
                            {
                                "id": 7,
                                "type": "curve",
                                "x": 10,
                                "y": 20,
                                "rotation": 30,
                                "visible": True,
                                "polyline": [{"x": 0, "y": 0}, {"x": 5, "y": 6}],
                                "properties": [{"name": "direction", "type": "string", "value": "forward"}],
                            }
                        ],
                    }
                ],
            }
        ],
    }


def save_json(tmp_path: Path, document: dict[str, Any]) -> Path:
    path = tmp_path / "mutant.json"
    path.write_text(json.dumps(document))
    return path


def _leaf_paths(node: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    yield prefix
    children = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, child in children:
        yield from _leaf_paths(child, (*prefix, key))


BAD_VALUES: list[Any] = [None, "abc", "", [], {}, True, -1, 0, 1e400, [1, 2], {"x": "y"}]


def test_any_malformed_json_value_gives_a_map_error_not_a_raw_exception(tmp_path: Path) -> None:
    original = json_map()
    for path in list(_leaf_paths(original))[1:]:
        for bad in [*BAD_VALUES, "delete"]:
            document = copy.deepcopy(original)
            parent = document
            for key in path[:-1]:
                parent = parent[key]
            if bad == "delete":
                del parent[path[-1]]
            else:
                parent[path[-1]] = bad
            load_or_map_errors(save_json(tmp_path, document))


MUTANT_TMX = (
    HEADER.replace(
        'infinite="0">',
        'infinite="0"><properties><property name="meters_per_pixel" type="float" value="0.5"/></properties>',
    )
    + '<group name="g" offsetx="3" offsety="4"><objectgroup name="segments">'
    '<object id="7" type="curve" x="10" y="20" rotation="30">'
    '<properties><property name="direction" type="int" value="1"/></properties>'
    '<polyline points="0,0 5,6"/></object></objectgroup></group></map>'
)


def test_any_malformed_tmx_attribute_gives_a_map_error_not_a_raw_exception(tmp_path: Path) -> None:
    original = ET.fromstring(MUTANT_TMX)
    path = tmp_path / "mutant.tmx"
    for element_index, element in enumerate(original.iter()):
        for name in list(element.attrib):
            for bad in ["abc", "", "-1", "0", "1e999", "nan", "1,2 3", None]:
                mutant = copy.deepcopy(original)
                target = list(mutant.iter())[element_index]
                if bad is None:
                    del target.attrib[name]
                else:
                    target.set(name, bad)
                path.write_bytes(ET.tostring(mutant))
                load_or_map_errors(path)
