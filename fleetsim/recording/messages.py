"""The ROS 2 messages of a recording, built with a strict serialiser.

Messages are ``rosbags`` typestore classes: dataclasses generated from the standard ROS 2 message
definitions, so a missing or misspelt field is a ``TypeError`` when the message is built, never a silent
zero (an invisible marker with alpha 0, say). The same typestore gives each type's CDR serialisation and
its ``ros2msg`` schema text. ``rosbags`` was chosen over hand-written CDR or ``mcap_ros2``'s dynamic writer
for exactly that strictness, and because it knows the standard types without a ROS installation.

Everything here is geometry and colour; what is shown when lives in :mod:`fleetsim.recording.recorder`.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from functools import cache
from itertools import pairwise
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_typestore

from fleetsim.layout.segment import Point

__all__ = [
    "RGBA",
    "FleetTransforms",
    "Stamp",
    "clock",
    "colour",
    "delete",
    "delete_all",
    "line_list",
    "line_strip",
    "log",
    "marker_array",
    "path_points",
    "points",
    "schema_text",
    "serialise",
    "stamp",
    "string",
    "text_marker",
    "tf_message",
    "transform",
]

RGBA = tuple[float, float, float, float]
Stamp = Any  # builtin_interfaces/msg/Time


@cache
def _store() -> Any:
    # Humble's definitions; Jazzy's messages used here are the same on the wire.
    return get_typestore(Stores.ROS2_HUMBLE)


def _type(name: str) -> Any:
    return _store().types[name]


def serialise(message: Any) -> bytes:
    """CDR bytes of ``message`` (little endian, as rosbag2 writes)."""
    data: memoryview = _store().serialize_cdr(message, message.__msgtype__)
    return bytes(data)


@cache
def schema_text(typename: str) -> bytes:
    """The ``ros2msg`` schema of ``typename`` with its dependencies, as MCAP's ros2 profile wants it."""
    text: str = _store().generate_msgdef(typename, ros_version=2)[0]
    return text.encode("utf-8")


def stamp(nanoseconds: int) -> Stamp:
    seconds, rest = divmod(nanoseconds, 1_000_000_000)
    return _type("builtin_interfaces/msg/Time")(sec=seconds, nanosec=rest)


def _header(time: Stamp, frame: str) -> Any:
    return _type("std_msgs/msg/Header")(stamp=time, frame_id=frame)


def clock(time: Stamp) -> Any:
    return _type("rosgraph_msgs/msg/Clock")(clock=time)


def string(text: str) -> Any:
    return _type("std_msgs/msg/String")(data=text)


def colour(rgba: RGBA) -> Any:
    red, green, blue, alpha = rgba
    return _type("std_msgs/msg/ColorRGBA")(r=float(red), g=float(green), b=float(blue), a=float(alpha))


def transform(time: Stamp, parent: str, child: str, x: float, y: float, heading: float) -> Any:
    """A planar transform: ``child`` at (x, y) in ``parent``, turned ``heading`` radians about z."""
    types = _store().types
    return types["geometry_msgs/msg/TransformStamped"](
        header=_header(time, parent),
        child_frame_id=child,
        transform=types["geometry_msgs/msg/Transform"](
            translation=types["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=0.0),
            rotation=types["geometry_msgs/msg/Quaternion"](
                x=0.0, y=0.0, z=math.sin(heading / 2.0), w=math.cos(heading / 2.0)
            ),
        ),
    )


def tf_message(transforms: Sequence[Any]) -> Any:
    return _type("tf2_msgs/msg/TFMessage")(transforms=list(transforms))


class FleetTransforms:
    """CDR bytes of the ``/tf`` message of a fixed set of frames, packed with one ``struct`` call.

    A TFMessage for 100 vehicles is 600 message objects to build and serialise field by field each step,
    which would make recording cost several times the simulation. Its layout, though, is the same every
    step (same frames, same order, so the same string lengths and alignment padding), so it is laid out
    once as a ``struct`` format. The layout is checked byte for byte against the typestore's own
    serialisation of a sample message when it is built; if they ever differed, :meth:`serialise` would
    use the typestore instead.
    """

    def __init__(self, parent: str, children: Sequence[str]) -> None:
        self.parent = parent
        self.children = tuple(children)
        fields = ["<4sI"]  # encapsulation header (CDR little endian), then the sequence length
        offset = 4  # CDR aligns relative to the end of the encapsulation header
        for child in self.children:
            parts, offset = _transform_layout(offset, parent, child)
            fields += parts
        self._struct = struct.Struct("".join(fields))
        # Per frame, the fields after the stamp that never change: both strings with their lengths.
        self._heads = []
        for child in self.children:
            parent_bytes, child_bytes = parent.encode() + b"\0", child.encode() + b"\0"
            self._heads.append((len(parent_bytes), parent_bytes, len(child_bytes), child_bytes))
        sample = [(float(k), float(-k), 0.25 * k) for k in range(len(self.children))]
        self._fast = bool(self.children) and self._pack(1_234_567_890_123, sample) == self._slow(
            1_234_567_890_123, sample
        )

    def _pack(self, time_ns: int, poses: Sequence[tuple[float, float, float]]) -> bytes:
        seconds, nanoseconds = divmod(time_ns, 1_000_000_000)
        values: list[Any] = [b"\x00\x01\x00\x00", len(self.children)]
        sin, cos = math.sin, math.cos
        for head, (x, y, heading) in zip(self._heads, poses, strict=True):
            values += (seconds, nanoseconds, *head, x, y, 0.0, 0.0, 0.0, sin(heading / 2.0), cos(heading / 2.0))
        return self._struct.pack(*values)

    def _slow(self, time_ns: int, poses: Sequence[tuple[float, float, float]]) -> bytes:
        time = stamp(time_ns)
        return serialise(
            tf_message(
                [transform(time, self.parent, child, *pose) for child, pose in zip(self.children, poses, strict=True)]
            )
        )

    def serialise(self, time_ns: int, poses: Sequence[tuple[float, float, float]]) -> bytes:
        """The message at ``time_ns`` with each frame at its ``(x, y, heading)``, in ``children`` order."""
        if len(poses) != len(self.children):
            msg = f"poses={len(poses)} must give one pose per frame ({len(self.children)})"
            raise ValueError(msg)
        return self._pack(time_ns, poses) if self._fast else self._slow(time_ns, poses)


def _transform_layout(offset: int, parent: str, child: str) -> tuple[list[str], int]:
    """``struct`` fields of one TransformStamped starting at CDR ``offset``, and the offset after it."""
    parts = []

    def align(size: int) -> None:
        nonlocal offset
        pad = -offset % size
        if pad:
            parts.append(f"{pad}x")
            offset += pad

    align(4)
    parts.append("iI")  # stamp
    offset += 8
    for text in (parent, child):
        align(4)
        length = len(text.encode()) + 1
        parts.append(f"I{length}s")
        offset += 4 + length
    align(8)
    parts.append("7d")  # translation x y z, rotation x y z w
    offset += 56
    return parts, offset


def _pose(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
    types = _store().types
    return types["geometry_msgs/msg/Pose"](
        position=types["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=float(z)),
        orientation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
    )


@cache
def _unused_parts() -> tuple[Any, Any, Any, Any]:
    """The parts of a marker fleetsim never varies: identity pose, no lifetime, no texture, no mesh.

    Made once and shared by every marker (messages are only ever serialised, never modified).
    """
    types = _store().types
    no_texture = types["sensor_msgs/msg/CompressedImage"](header=_header(stamp(0), ""), format="", data=_no_bytes())
    no_mesh = types["visualization_msgs/msg/MeshFile"](filename="", data=_no_bytes())
    return _pose(), types["builtin_interfaces/msg/Duration"](sec=0, nanosec=0), no_texture, no_mesh


@cache
def _colour(rgba: RGBA) -> Any:
    return colour(rgba)


def _marker(
    time: Stamp,
    frame: str,
    namespace: str,
    marker_id: int,
    kind: int,
    *,
    action: int = 0,
    pose: Any = None,
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0),
    rgba: RGBA = (1.0, 1.0, 1.0, 1.0),
    points: Sequence[Any] = (),
    text: str = "",
    frame_locked: bool = False,
) -> Any:
    types = _store().types
    identity, forever, no_texture, no_mesh = _unused_parts()
    return types["visualization_msgs/msg/Marker"](
        header=_header(time, frame),
        ns=namespace,
        id=marker_id,
        type=kind,
        action=action,
        pose=pose if pose is not None else identity,
        scale=types["geometry_msgs/msg/Vector3"](x=scale[0], y=scale[1], z=scale[2]),
        color=_colour(rgba),
        lifetime=forever,
        frame_locked=frame_locked,
        points=list(points),
        colors=[],
        texture_resource="",
        texture=no_texture,
        uv_coordinates=[],
        text=text,
        mesh_resource="",
        mesh_file=no_mesh,
        mesh_use_embedded_materials=False,
    )


def _no_bytes() -> Any:
    return np.zeros(0, dtype=np.uint8)  # the typestore wants uint8[] fields as numpy arrays


def points(polyline: Sequence[Point], z: float = 0.0) -> list[Any]:
    """A polyline as LINE_LIST points: each piece as a pair (so the count is always even)."""
    point = _type("geometry_msgs/msg/Point")
    return [
        point(x=float(x), y=float(y), z=float(z))
        for (ax, ay), (bx, by) in pairwise(polyline)
        for x, y in ((ax, ay), (bx, by))
    ]


def line_list(time: Stamp, namespace: str, marker_id: int, pairs: Sequence[Any], width: float, rgba: RGBA) -> Any:
    """One LINE_LIST marker in ``map`` through ``pairs`` (from :func:`points`; shared, never modified)."""
    return _marker(time, "map", namespace, marker_id, 5, scale=(width, 0.0, 0.0), rgba=rgba, points=pairs)


def path_points(polyline: Sequence[Point], z: float = 0.0) -> list[Any]:
    """A polyline as LINE_STRIP points, in order."""
    point = _type("geometry_msgs/msg/Point")
    return [point(x=float(x), y=float(y), z=float(z)) for x, y in polyline]


def line_strip(
    time: Stamp, namespace: str, marker_id: int, path: Sequence[Any], width: float, rgba: RGBA, frame: str = "map"
) -> Any:
    """One LINE_STRIP marker in ``frame`` (locked to it unless ``map``) along ``path`` (from :func:`path_points`)."""
    return _marker(
        time,
        frame,
        namespace,
        marker_id,
        4,
        scale=(width, 0.0, 0.0),
        rgba=rgba,
        points=path,
        frame_locked=frame != "map",
    )


def text_marker(
    time: Stamp,
    frame: str,
    namespace: str,
    marker_id: int,
    text: str,
    at: tuple[float, float, float],
    size: float,
    rgba: RGBA,
    frame_locked: bool = False,
) -> Any:
    """A TEXT_VIEW_FACING marker (``scale.z`` is the letter height)."""
    return _marker(
        time, frame, namespace, marker_id, 9, pose=_pose(*at), scale=(0.0, 0.0, size), rgba=rgba, text=text,
        frame_locked=frame_locked,
    )  # fmt: skip


def arrow(
    time: Stamp,
    namespace: str,
    marker_id: int,
    start: tuple[float, float, float],
    end: tuple[float, float, float],
    shaft: float,
    rgba: RGBA,
) -> Any:
    """An ARROW marker in ``map`` from ``start`` to ``end`` (head diameter and length follow the shaft)."""
    point = _type("geometry_msgs/msg/Point")
    ends = [
        point(x=float(start[0]), y=float(start[1]), z=float(start[2])),
        point(x=float(end[0]), y=float(end[1]), z=float(end[2])),
    ]
    return _marker(
        time, "map", namespace, marker_id, 0, scale=(shaft, 2.5 * shaft, 3.0 * shaft), rgba=rgba, points=ends
    )


def disc(
    time: Stamp, namespace: str, marker_id: int, at: tuple[float, float, float], diameter: float, rgba: RGBA
) -> Any:
    """A flat CYLINDER marker in ``map`` centred at ``at`` (a ring-like mark round a vehicle)."""
    return _marker(time, "map", namespace, marker_id, 3, pose=_pose(*at), scale=(diameter, diameter, 0.04), rgba=rgba)


def delete_all(time: Stamp, namespace: str) -> Any:
    """DELETEALL: the content of an array topic is replaced, not added to."""
    return _marker(time, "map", namespace, 0, 0, action=3)


def delete(time: Stamp, namespace: str, marker_id: int) -> Any:
    """DELETE one marker (a vehicle's plan lost its fixed or its planned part)."""
    return _marker(time, "map", namespace, marker_id, 5, action=2)


def marker_array(markers: Sequence[Any]) -> Any:
    return _type("visualization_msgs/msg/MarkerArray")(markers=list(markers))


def log(time: Stamp, level: int, message: str) -> Any:
    """An ``rcl_interfaces/msg/Log`` record from the simulator (``/rosout``)."""
    return _type("rcl_interfaces/msg/Log")(
        stamp=time, level=level, name="fleetsim", msg=message, file="", function="", line=0
    )
