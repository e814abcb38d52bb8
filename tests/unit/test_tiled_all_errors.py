"""A Tiled map reports every broken object at once (TMX and JSON), each at its object; one stays itself."""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

from fleetsim.cli import main
from fleetsim.errors import LoadError, LoadErrors, MapError
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.tiled.reader import load_map

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
LOOP_SUITE = """\
fleetsim: 1
name: loop
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
scenarios:
  - name: loop
    dir: examples/loop/
"""
SIDEWAYS = "unknown direction 'sideways' (expected both, forward or backward)"


def copy_example(tmp_path: Path, name: str) -> Path:
    """The shipped example folder ``name`` with the templates its map refers to (``../../tiled``)."""
    shutil.copytree(SUITES / "examples" / name, tmp_path / "examples" / name)
    if not (tmp_path / "tiled").exists():
        shutil.copytree(SUITES / "tiled", tmp_path / "tiled")
    return tmp_path / "examples" / name


# --- TMX: the shipped loop --------------------------------------------------------------------------


def loop_tmx(tmp_path: Path) -> tuple[Path, ET.ElementTree[ET.Element]]:
    path = copy_example(tmp_path, "loop") / "map.tmx"
    return path, ET.parse(path)


def tmx_object(tree: ET.ElementTree[ET.Element], object_id: int) -> ET.Element:
    found = [element for element in tree.iter("object") if element.get("id") == str(object_id)]
    assert len(found) == 1, object_id
    return found[0]


def set_tmx_direction(element: ET.Element, value: str) -> None:
    block = element.find("properties")
    if block is None:
        block = ET.SubElement(element, "properties")
    for prop in block.findall("property"):
        block.remove(prop)
    ET.SubElement(block, "property", name="direction", value=value)


def failure(path: Path) -> LoadError:
    with pytest.raises(LoadError) as info:
        load_map(path)
    return info.value


def located(error: LoadError) -> list[tuple[str, int | None, str]]:
    assert isinstance(error, LoadErrors), error
    assert all(isinstance(inner, MapError) for inner in error.errors)
    return [
        (str(inner.location.path), inner.location.object_id, inner.problem)
        for inner in error.errors
        if inner.location is not None
    ]


def test_every_broken_object_of_a_tmx_map_is_reported_at_its_object(tmp_path: Path) -> None:
    path, tree = loop_tmx(tmp_path)
    set_tmx_direction(tmx_object(tree, 3), "sideways")
    tmx_object(tree, 6).set("type", "stright")  # overrides the template's class
    tmx_object(tree, 7).append(ET.fromstring('<polyline points="5,5"/>'))
    tmx_object(tree, 9).set("id", "2")  # object 2 comes first
    tmx_object(tree, 10).set("template", "../../tiled/nope.tx")
    tree.write(path)
    error = failure(path)
    found = located(error)
    assert [(where, object_id) for where, object_id, _ in found] == [
        (str(path), 3),
        (str(path), 6),
        (str(path), 7),
        (str(path), 2),
        (str(path), 10),
    ]
    problems = [problem for _, _, problem in found]
    assert problems[0] == SIDEWAYS
    assert problems[1].startswith("unknown class 'stright' on a polyline; did you mean 'straight'?")
    assert problems[2] == "polyline has 1 point(s); a segment needs at least 2"
    assert problems[3].startswith("id=2 is used by two objects (object #2 in layer 'segments' and object #9")
    assert problems[4].startswith("template '../../tiled/nope.tx' not found")
    assert str(error).startswith("5 errors:\n")
    assert f"  {path}: object 3: {SIDEWAYS}\n" in str(error)


def test_a_single_broken_tmx_object_raises_the_same_map_error_as_before(tmp_path: Path) -> None:
    path, tree = loop_tmx(tmp_path)
    set_tmx_direction(tmx_object(tree, 3), "sideways")
    tree.write(path)
    error = failure(path)
    assert type(error) is MapError
    assert str(error) == f"{path}: object 3: {SIDEWAYS}"
    assert error.location is not None and error.location.object_id == 3


def test_header_errors_are_reported_with_the_object_errors(tmp_path: Path) -> None:
    path, tree = loop_tmx(tmp_path)
    root = tree.getroot()
    root.set("orientation", "isometric")
    root.set("tilewidth", "wide")
    set_tmx_direction(tmx_object(tree, 4), "sideways")
    tree.write(path)
    found = located(failure(path))
    assert [(object_id, problem) for _, object_id, problem in found] == [
        (None, "the map's orientation is 'isometric'; fleetsim reads orthogonal maps only"),
        (None, "tilewidth is 'wide'; it must be an integer"),
        (4, SIDEWAYS),
    ]


@pytest.mark.parametrize(
    ("size", "refused"), [(2**31 - 1, False), (2**31, True), (10**400, True)], ids=["2^31-1", "2^31", "10^400"]
)
def test_a_map_size_beyond_tileds_32_bits_is_a_located_error_not_an_overflow(
    tmp_path: Path, size: int, refused: bool
) -> None:
    # (Found by the loader mutation test: a size this large made the header's float overflow.)
    path, tree = loop_tmx(tmp_path)
    root = tree.getroot()
    root.set("height", str(size))
    root.set("tileheight", str(size))
    tree.write(path)
    if refused:
        found = located(failure(path))
        largest = "it must be at most 2147483647 (Tiled keeps it in 32 bits)"
        assert [problem for _, _, problem in found] == [
            f"height is {str(size)!r}; {largest}",
            f"tileheight is {str(size)!r}; {largest}",
        ]
    else:
        load_map(path)  # the largest Tiled can hold loads (the objects lie far inside it)


def test_a_map_that_is_not_a_map_still_stops_at_that_one_error(tmp_path: Path) -> None:
    path, tree = loop_tmx(tmp_path)
    tree.getroot().tag = "tileset"
    set_tmx_direction(tmx_object(tree, 4), "sideways")
    tree.write(path)
    error = failure(path)
    assert type(error) is MapError and error.problem == "root element <tileset> must be <map>"


def test_a_broken_template_is_reported_once_at_its_first_instance(tmp_path: Path) -> None:
    path, tree = loop_tmx(tmp_path)
    for element in tree.iter("object"):
        if element.get("template", "").endswith("straight.tx"):
            element.set("template", "../../tiled/gone.tx")
    tree.write(path)
    error = failure(path)
    assert type(error) is MapError  # six instances, one error
    assert error.location is not None and error.location.object_id == 1
    assert "template '../../tiled/gone.tx' not found" in error.problem


def test_sixty_broken_objects_show_fifty_and_count_the_rest(tmp_path: Path) -> None:
    path, tree = loop_tmx(tmp_path)
    layer = tree.getroot().find("objectgroup")
    assert layer is not None
    for object_id in range(100, 160):
        element = ET.SubElement(layer, "object", id=str(object_id), template="../../tiled/straight.tx", x="0", y="0")
        set_tmx_direction(element, "sideways")
    tree.write(path)
    error = failure(path)
    assert isinstance(error, LoadErrors)
    assert [inner.location.object_id for inner in error.errors if inner.location] == list(range(100, 150))
    assert error.omitted == {str(path): 10}
    text = str(error)
    assert text.startswith("60 errors:\n")
    assert text.endswith(f"\n  ... and 10 more in {path}")


def test_a_broken_map_gives_no_site_map_either(tmp_path: Path) -> None:
    path, tree = loop_tmx(tmp_path)
    set_tmx_direction(tmx_object(tree, 3), "sideways")
    set_tmx_direction(tmx_object(tree, 4), "sideways")
    tree.write(path)
    with pytest.raises(LoadErrors) as info:
        load_site_map(path)
    assert [inner.location.object_id for inner in info.value.errors if inner.location] == [3, 4]


# --- JSON: the shipped crossing ---------------------------------------------------------------------


def crossing_json(tmp_path: Path) -> tuple[Path, dict[str, Any]]:
    path = copy_example(tmp_path, "crossing") / "map.json"
    return path, json.loads(path.read_text(encoding="utf-8"))


def json_objects(document: dict[str, Any]) -> dict[int, dict[str, Any]]:
    objects = [obj for layer in document["layers"] for obj in layer.get("objects", [])]
    return {obj["id"]: obj for obj in objects}


def test_every_broken_object_of_a_json_map_is_reported_at_its_object(tmp_path: Path) -> None:
    path, document = crossing_json(tmp_path)
    objects = json_objects(document)
    objects[2]["properties"] = [{"name": "direction", "type": "string", "value": "sideways"}]
    objects[3]["type"] = "curvy"
    objects[4]["x"] = "east"
    objects[5]["polyline"] = [{"x": 0, "y": 0}, {"x": "far", "y": 0}]
    objects[7]["id"] = 1
    objects[8]["template"] = "../../tiled/nope.tx"
    path.write_text(json.dumps(document), encoding="utf-8")
    found = located(failure(path))
    assert [object_id for _, object_id, _ in found] == [2, 3, 4, 5, 1, 8]
    assert {where for where, _, _ in found} == {str(path)}
    problems = [problem for _, _, problem in found]
    assert problems[0] == SIDEWAYS
    assert problems[1].startswith("unknown class 'curvy' on a polyline; did you mean 'curve'?")
    assert problems[2] == "x is 'east'; it must be a number"
    assert problems[3] == "point x is 'far'; it must be a number"
    assert problems[4].startswith("id=1 is used by two objects")
    assert problems[5].startswith("template '../../tiled/nope.tx' not found")


def test_a_single_broken_json_object_raises_the_same_map_error_as_before(tmp_path: Path) -> None:
    path, document = crossing_json(tmp_path)
    json_objects(document)[3]["type"] = "curvy"
    path.write_text(json.dumps(document), encoding="utf-8")
    error = failure(path)
    assert type(error) is MapError
    assert str(error).startswith(f"{path}: object 3: unknown class 'curvy' on a polyline; did you mean 'curve'?")


def test_json_layer_errors_skip_the_layer_and_keep_checking(tmp_path: Path) -> None:
    path, document = crossing_json(tmp_path)
    json_objects(document)[6]["properties"] = [{"name": "direction", "value": "sideways"}]
    document["layers"].insert(0, {"type": "objectgroup", "name": "hidden?", "visible": "maybe", "objects": []})
    document["layers"].append("not a layer")
    document["properties"] = [{"name": "meters_per_pixel", "type": "float", "value": -1}]
    path.write_text(json.dumps(document), encoding="utf-8")
    found = located(failure(path))
    assert [(object_id, problem) for _, object_id, problem in found] == [
        (None, "the map property meters_per_pixel is -1.0; it must be a positive number"),
        (None, "layer 'hidden?' visible is 'maybe'; it must be a boolean (true/false or 1/0)"),
        (6, SIDEWAYS),
        (None, "layer 'not a layer' must be a JSON object"),
    ]


# --- what must not change ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["corridor", "crossing", "loop", "mixed"])
def test_every_shipped_example_map_still_loads(tmp_path: Path, name: str) -> None:
    folder = copy_example(tmp_path, name)
    (path,) = (p for p in folder.iterdir() if p.name.startswith("map."))
    assert load_map(path).segments


def test_validate_shows_every_broken_object_of_a_scenario_map(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, tree = loop_tmx(tmp_path)
    set_tmx_direction(tmx_object(tree, 3), "sideways")
    tmx_object(tree, 8).set("type", "curv")
    tree.write(path)
    suite = tmp_path / "loop.fleetsim.yaml"
    suite.write_text(LOOP_SUITE, encoding="utf-8")
    status = main(["validate", str(suite)])
    out, err = capsys.readouterr()
    assert status == 1, out + err
    assert "Traceback" not in out + err
    assert f"{path}: object 3: {SIDEWAYS}" in out
    assert f"{path}: object 8: unknown class 'curv' on a polyline; did you mean 'curve'?" in out


def test_the_unbroken_loop_suite_validates(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    copy_example(tmp_path, "loop")
    suite = tmp_path / "loop.fleetsim.yaml"
    suite.write_text(LOOP_SUITE, encoding="utf-8")
    assert main(["validate", str(suite)]) == 0, capsys.readouterr().out
