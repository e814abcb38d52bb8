"""The Tiled map loader on small maps written into tmp_path, in both TMX and JSON (SPEC §3)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from fleetsim.enums import Direction, Shape
from fleetsim.errors import MapError
from fleetsim.load.tiled import templates as tiled_templates
from fleetsim.load.tiled.reader import TiledMap, load_map

# --- maps as Tiled JSON dicts, rendered to either format ------------------------------------------
# The tests describe maps in Tiled's JSON structure; `tmx_text` renders the same structure as TMX,
# so one description exercises both readers.

Json = dict[str, Any]


def poly(object_id: int | None, points: Any = ((0, 0), (32, 0)), **keys: Any) -> Json:
    """A polyline object; ``props`` become properties, ``shape`` the class (default straight)."""
    obj: Json = {} if object_id is None else {"id": object_id}
    if points is not None:
        obj["polyline"] = [{"x": x, "y": y} for x, y in points]
    shape = keys.pop("shape", "straight")
    if shape is not None:
        obj["type"] = shape
    props = keys.pop("props", {})
    if props:
        obj["properties"] = [prop(name, value) for name, value in props.items()]
    obj.update(keys)
    return obj


def prop(name: str, value: Any, **extra: Any) -> Json:
    kind = (
        "bool"
        if isinstance(value, bool)
        else "int"
        if isinstance(value, int)
        else ("float" if isinstance(value, float) else "string")
    )
    return {"name": name, "type": kind, "value": value, **extra}


def layer(*objects: Json, **keys: Any) -> Json:
    return {"type": "objectgroup", "name": "segments", "objects": list(objects), **keys}


def group(*layers: Json, **keys: Any) -> Json:
    return {"type": "group", "name": "group", "layers": list(layers), **keys}


def tiled_map(*layers: Json, width: int = 20, height: int = 10, tile: int = 32, **keys: Any) -> Json:
    return {
        "type": "map",
        "orientation": "orthogonal",
        "infinite": False,
        "width": width,
        "height": height,
        "tilewidth": tile,
        "tileheight": tile,
        "layers": list(layers),
        **keys,
    }


def _attr(value: Any) -> str:
    text = ("1" if value else "0") if isinstance(value, bool) else str(value)
    return text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")


def _xml_properties(props: list[Json]) -> str:
    if not props:
        return ""
    lines = []
    for p in props:
        value = str(p["value"]).lower() if isinstance(p["value"], bool) else p["value"]
        extra = "".join(f' {k}="{_attr(v)}"' for k, v in p.items() if k not in ("name", "value"))
        lines.append(f'<property name="{_attr(p["name"])}"{extra} value="{_attr(value)}"/>')
    return "<properties>" + "".join(lines) + "</properties>"


def xml_object(obj: Json) -> str:
    attrs = "".join(f' {k}="{_attr(v)}"' for k, v in obj.items() if k not in ("polyline", "properties", "polygon"))
    body = _xml_properties(obj.get("properties", []))
    for kind in ("polyline", "polygon"):
        if kind in obj:
            points = " ".join(f"{p['x']},{p['y']}" for p in obj[kind])
            body += f'<{kind} points="{points}"/>'
    return f"<object{attrs}>{body}</object>"


def _xml_layer(item: Json) -> str:
    tag = {"tilelayer": "layer"}.get(item["type"], item["type"])
    attrs = "".join(
        f' {k}="{_attr(v)}"' for k, v in item.items() if k not in ("type", "objects", "layers", "properties")
    )
    if tag == "group":
        inner = "".join(_xml_layer(child) for child in item["layers"])
    elif tag == "objectgroup":
        inner = "".join(xml_object(obj) for obj in item["objects"])
    else:
        inner = ""
    return f"<{tag}{attrs}>{inner}</{tag}>"


def tmx_text(document: Json) -> str:
    attrs = "".join(f' {k}="{_attr(v)}"' for k, v in document.items() if k not in ("type", "layers", "properties"))
    body = _xml_properties(document.get("properties", []))
    body += "".join(_xml_layer(item) for item in document["layers"])
    return f'<?xml version="1.0" encoding="UTF-8"?>\n<map version="1.8"{attrs}>{body}</map>\n'


def save(directory: Path, name: str, document: Json) -> Path:
    path = directory / name
    if path.suffix == ".tmx":
        path.write_text(tmx_text(document), encoding="utf-8")
    else:
        path.write_text(json.dumps(document, indent=1), encoding="utf-8")
    return path


def save_template(directory: Path, name: str, obj: Json) -> Path:
    path = directory / name
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".tx":
        path.write_text(f'<?xml version="1.0"?>\n<template>{xml_object(obj)}</template>\n')
    else:
        path.write_text(json.dumps({"type": "template", "object": obj}))
    return path


@pytest.fixture(params=[".tmx", ".json"])
def suffix(request: pytest.FixtureRequest) -> str:
    return str(request.param)


def load(tmp_path: Path, suffix: str, document: Json) -> TiledMap:
    return load_map(save(tmp_path, "map" + suffix, document))


def waypoints(loaded: TiledMap, object_id: int) -> tuple[tuple[float, float], ...]:
    return next(s.waypoints for s in loaded.segments if s.id == object_id)


def assert_points_close(actual: Any, expected: Any, tol: float = 1e-9) -> None:
    assert len(actual) == len(expected)
    for (ax, ay), (ex, ey) in zip(actual, expected, strict=True):
        assert ax == pytest.approx(ex, abs=tol) and ay == pytest.approx(ey, abs=tol), (actual, expected)


# --- the world frame ----------------------------------------------------------------------------


def test_json_and_tmx_of_the_same_map_give_the_same_segments(tmp_path: Path) -> None:
    document = tiled_map(
        layer(
            poly(
                3,
                ((0, 0), (10.123456, 20.654321), (40, 5)),
                x=100.5,
                y=60.25,
                rotation=17.5,
                shape="curve",
                props={"direction": "forward"},
            ),
            poly(1, ((0, 0), (64, 0)), x=320, y=160),
        )
    )
    from_tmx = load_map(save(tmp_path, "map.tmx", document))
    from_json = load_map(save(tmp_path, "map.json", document))
    assert [(s.id, s.shape, s.direction) for s in from_tmx.segments] == [
        (s.id, s.shape, s.direction) for s in from_json.segments
    ]
    for a, b in zip(from_tmx.segments, from_json.segments, strict=True):
        assert_points_close(a.waypoints, b.waypoints, tol=1e-6)


def test_world_frame_has_its_origin_at_the_map_centre_and_y_up(tmp_path: Path, suffix: str) -> None:
    # 20 x 10 tiles of 32 px: the centre is pixel (320, 160); one tile is one metre.
    loaded = load(tmp_path, suffix, tiled_map(layer(poly(1, ((0, 0), (32, -64)), x=320, y=160))))
    assert loaded.segments[0].waypoints == ((0.0, 0.0), (1.0, 2.0))
    assert (loaded.width_px, loaded.height_px, loaded.meters_per_pixel) == (640.0, 320.0, 1 / 32)


def test_tmj_suffix_is_read_as_json(tmp_path: Path) -> None:
    loaded = load(tmp_path, ".tmj", tiled_map(layer(poly(1, x=320, y=160))))
    assert loaded.segments[0].waypoints == ((0.0, 0.0), (1.0, 0.0))


def test_meters_per_pixel_map_property_overrides_one_tile_per_metre(tmp_path: Path, suffix: str) -> None:
    document = tiled_map(layer(poly(1, ((0, 0), (32, 0)), x=320, y=0)), properties=[prop("meters_per_pixel", 0.5)])
    loaded = load(tmp_path, suffix, document)
    assert loaded.meters_per_pixel == 0.5
    assert loaded.segments[0].waypoints == ((0.0, 80.0), (16.0, 80.0))


def test_default_scale_is_one_over_tile_width(tmp_path: Path, suffix: str) -> None:
    loaded = load(tmp_path, suffix, tiled_map(layer(poly(1, ((0, 0), (16, 0)), x=160, y=80)), tile=16))
    assert loaded.meters_per_pixel == 1 / 16
    assert loaded.segments[0].waypoints == ((0.0, 0.0), (1.0, 0.0))


def test_offsets_of_nested_groups_and_the_object_layer_add_up(tmp_path: Path, suffix: str) -> None:
    inner = layer(poly(1, x=300, y=100), offsetx=-4, offsety=24)
    document = tiled_map(group(group(inner, offsetx=8, offsety=4, name="inner"), offsetx=16, offsety=32))
    loaded = load(tmp_path, suffix, document)
    # (300 + 16 + 8 - 4, 100 + 32 + 4 + 24) = (320, 160): the map centre.
    assert loaded.segments[0].waypoints == ((0.0, 0.0), (1.0, 0.0))


def test_rotation_turns_points_clockwise_on_screen_about_the_object_origin(tmp_path: Path, suffix: str) -> None:
    document = tiled_map(
        layer(
            poly(1, ((0, 0), (10, 0)), x=320, y=160, rotation=90),
            poly(2, ((0, 0), (10, 0)), x=320, y=160, rotation=-45),
        ),
        properties=[prop("meters_per_pixel", 1.0)],
    )
    loaded = load(tmp_path, suffix, document)
    # 90° clockwise on screen: pixel (10, 0) -> (0, 10), i.e. 10 px down the screen = world -y.
    assert waypoints(loaded, 1) == ((0.0, 0.0), (0.0, -10.0))
    half = 10 / math.sqrt(2)
    assert_points_close(waypoints(loaded, 2), ((0, 0), (half, half)))


def test_segments_are_sorted_by_id(tmp_path: Path, suffix: str) -> None:
    document = tiled_map(layer(poly(9), poly(2)), layer(poly(5), name="more"))
    assert [s.id for s in load(tmp_path, suffix, document).segments] == [2, 5, 9]


# --- classes and visibility ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "shape"),
    [
        ("straight", Shape.STRAIGHT),
        ("Straight", Shape.STRAIGHT),
        ("CURVE", Shape.CURVE),
        ("s_curve", Shape.S_CURVE),
        ("S_Curve", Shape.S_CURVE),
        ("scurve", Shape.S_CURVE),
        ("s-curve", Shape.S_CURVE),
    ],
)
def test_shape_class_names_and_aliases_are_case_insensitive(
    tmp_path: Path, suffix: str, name: str, shape: Shape
) -> None:
    assert load(tmp_path, suffix, tiled_map(layer(poly(1, shape=name)))).segments[0].shape is shape


def test_class_attribute_of_tiled_1_9_is_read_like_type(tmp_path: Path, suffix: str) -> None:
    loaded = load(tmp_path, suffix, tiled_map(layer(poly(4, shape=None, **{"class": "curve"}))))
    assert loaded.segments[0].shape is Shape.CURVE


def test_invisible_layers_groups_and_objects_are_skipped(tmp_path: Path, suffix: str) -> None:
    document = tiled_map(
        layer(poly(1), poly(2, visible=False)),
        layer(poly(3), visible=False, name="hidden"),
        group(layer(poly(4)), visible=False),
        group(layer(poly(5)), visible=True),
    )
    assert [s.id for s in load(tmp_path, suffix, document).segments] == [1, 5]


def test_unknown_class_on_a_polyline_is_an_error_naming_file_object_and_class(tmp_path: Path, suffix: str) -> None:
    document = tiled_map(layer(poly(1), poly(7, shape="wall")))
    with pytest.raises(MapError) as caught:
        load(tmp_path, suffix, document)
    assert str(caught.value) == (
        f"{tmp_path / ('map' + suffix)}: object 7: unknown class 'wall' on a polyline (segments are "
        "polylines of class straight, curve, s_curve or path; clear the class to have fleetsim ignore this polyline)"
    )
    assert caught.value.location is not None and caught.value.location.object_id == 7


@pytest.mark.parametrize(("typo", "meant"), [("stright", "straight"), ("Curv", "curve"), ("s-curv", "s_curve")])
def test_a_misspelt_class_on_a_polyline_says_did_you_mean(tmp_path: Path, suffix: str, typo: str, meant: str) -> None:
    with pytest.raises(MapError, match=f"object 7: unknown class '{typo}' on a polyline; did you mean '{meant}'"):
        load(tmp_path, suffix, tiled_map(layer(poly(1), poly(7, shape=typo))))


def test_a_polyline_without_a_class_is_ignored_without_a_warning(tmp_path: Path, suffix: str) -> None:
    loaded = load(tmp_path, suffix, tiled_map(layer(poly(1), poly(8, shape=""))))
    assert [s.id for s in loaded.segments] == [1] and loaded.warnings == ()


def test_an_unknown_class_on_a_rectangle_is_ignored(tmp_path: Path, suffix: str) -> None:
    rectangle = {"id": 2, "type": "stright", "x": 1, "y": 1, "width": 10, "height": 10}
    loaded = load(tmp_path, suffix, tiled_map(layer(poly(1), rectangle)))
    assert [s.id for s in loaded.segments] == [1] and loaded.warnings == ()


def test_non_polyline_objects_and_other_layers_are_ignored(tmp_path: Path, suffix: str) -> None:
    rectangle = {"id": 2, "type": "", "x": 1, "y": 1, "width": 10, "height": 10}
    polygon = {"id": 3, "type": "", "x": 1, "y": 1, "polygon": [{"x": 0, "y": 0}, {"x": 5, "y": 5}]}
    tiles = {"type": "tilelayer", "name": "ground", "width": 20, "height": 10}
    loaded = load(tmp_path, suffix, tiled_map(tiles, layer(poly(1), rectangle, polygon)))
    assert [s.id for s in loaded.segments] == [1] and loaded.warnings == ()


def test_shape_class_on_a_non_polyline_is_a_warning(tmp_path: Path, suffix: str) -> None:
    polygon = {"id": 3, "type": "curve", "polygon": [{"x": 0, "y": 0}, {"x": 5, "y": 5}]}
    loaded = load(tmp_path, suffix, tiled_map(layer(poly(1), polygon)))
    (warning,) = loaded.warnings
    assert "object 3" in warning and "polygon" in warning


# --- direction -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        ("both", Direction.BOTH),
        ("Forward", Direction.FORWARD),
        ("BACKWARD", Direction.BACKWARD),
        ("bidirectional", Direction.BOTH),
        ("two_way", Direction.BOTH),
        (0, Direction.BOTH),
        (1, Direction.FORWARD),
        (2, Direction.BACKWARD),
    ],
)
def test_direction_is_a_name_alias_or_enum_index(
    tmp_path: Path, suffix: str, value: object, expected: Direction
) -> None:
    loaded = load(tmp_path, suffix, tiled_map(layer(poly(1, props={"direction": value}))))
    assert loaded.segments[0].direction is expected


def test_direction_enum_with_propertytype_attribute_is_accepted(tmp_path: Path, suffix: str) -> None:
    obj = poly(1, properties=[prop("direction", 2, propertytype="direction"), prop("note", "x", propertytype="other")])
    assert load(tmp_path, suffix, tiled_map(layer(obj))).segments[0].direction is Direction.BACKWARD


def test_absent_direction_means_both(tmp_path: Path, suffix: str) -> None:
    assert load(tmp_path, suffix, tiled_map(layer(poly(1)))).segments[0].direction is Direction.BOTH


# --- templates -----------------------------------------------------------------------------------

TEMPLATE_OBJECT = poly(
    None, ((0, 0), (64, 0), (64, 64)), shape="curve", rotation=90, props={"direction": "forward", "colour": "red"}
)


@pytest.mark.parametrize("template_suffix", [".tx", ".tj"])
def test_template_supplies_keys_the_instance_does_not_state(tmp_path: Path, suffix: str, template_suffix: str) -> None:
    save_template(tmp_path, "templates/bend" + template_suffix, TEMPLATE_OBJECT)
    instance = {"id": 5, "template": "templates/bend" + template_suffix, "x": 320, "y": 160}
    segment = load(tmp_path, suffix, tiled_map(layer(instance))).segments[0]
    assert (segment.id, segment.shape, segment.direction) == (5, Shape.CURVE, Direction.FORWARD)
    assert segment.waypoints == ((0.0, 0.0), (0.0, -2.0), (-2.0, -2.0))  # rotated 90° clockwise


@pytest.mark.parametrize("template_suffix", [".tx", ".tj"])
def test_instance_keys_override_template_keys(tmp_path: Path, suffix: str, template_suffix: str) -> None:
    save_template(tmp_path, "bend" + template_suffix, TEMPLATE_OBJECT)
    instance = poly(5, ((0, 0), (0, 32)), shape="S-Curve", rotation=0, x=320, y=160, template="bend" + template_suffix)
    segment = load(tmp_path, suffix, tiled_map(layer(instance))).segments[0]
    assert segment.shape is Shape.S_CURVE
    assert segment.waypoints == ((0.0, 0.0), (0.0, -1.0))


def test_instance_property_overrides_template_property(tmp_path: Path, suffix: str) -> None:
    save_template(tmp_path, "bend.tx", TEMPLATE_OBJECT)
    instance = {"id": 5, "template": "bend.tx", "properties": [prop("direction", "backward")]}
    segment = load(tmp_path, suffix, tiled_map(layer(instance))).segments[0]
    assert segment.direction is Direction.BACKWARD


def test_properties_merge_by_name_with_template_direction_kept(tmp_path: Path, suffix: str) -> None:
    save_template(tmp_path, "bend.tj", TEMPLATE_OBJECT)
    instance = {"id": 5, "template": "bend.tj", "properties": [prop("colour", "blue")]}
    assert load(tmp_path, suffix, tiled_map(layer(instance))).segments[0].direction is Direction.FORWARD


def test_template_path_with_backslashes_is_relative_to_the_map_file(tmp_path: Path, suffix: str) -> None:
    save_template(tmp_path, "shared/bend.tx", TEMPLATE_OBJECT)
    (tmp_path / "maps").mkdir()
    instance = {"id": 5, "template": "..\\shared\\bend.tx"}
    loaded = load_map(save(tmp_path / "maps", "map" + suffix, tiled_map(layer(instance))))
    assert loaded.segments[0].shape is Shape.CURVE


def test_template_invisible_object_is_skipped_unless_instance_shows_it(tmp_path: Path, suffix: str) -> None:
    save_template(tmp_path, "hidden.tx", {**TEMPLATE_OBJECT, "visible": False})
    document = tiled_map(layer({"id": 1, "template": "hidden.tx"}, {"id": 2, "template": "hidden.tx", "visible": True}))
    assert [s.id for s in load(tmp_path, suffix, document).segments] == [2]


def test_tileset_element_in_a_tx_template_is_ignored(tmp_path: Path, suffix: str) -> None:
    (tmp_path / "t.tx").write_text(
        '<?xml version="1.0"?>\n<template>'
        '<tileset firstgid="1" source="tiles.tsx"/>' + xml_object(TEMPLATE_OBJECT) + "</template>"
    )
    assert load(tmp_path, suffix, tiled_map(layer({"id": 1, "template": "t.tx"}))).segments[0].id == 1


def test_template_used_many_times_is_read_once_per_load(
    tmp_path: Path, suffix: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    save_template(tmp_path, "bend.tx", TEMPLATE_OBJECT)
    reads: list[Path] = []
    original = tiled_templates.read_text_file

    def counting_read_text(path: Path, error_type: Any, where: Any = None) -> str:
        reads.append(path)
        return original(path, error_type, where)

    monkeypatch.setattr(tiled_templates, "read_text_file", counting_read_text)
    objects = [{"id": i, "template": "bend.tx", "x": i * 40, "y": 100} for i in range(1, 51)]
    assert len(load(tmp_path, suffix, tiled_map(layer(*objects))).segments) == 50
    assert reads.count(tmp_path / "bend.tx") == 1
