"""The ROS 2 messages of a recording, built with a strict serialiser.

Messages are ``rosbags`` typestore classes: dataclasses generated from the standard ROS 2 message
definitions, so a missing or misspelt field is a ``TypeError`` when the message is built, never a silent
zero (an invisible marker with alpha 0, say). The same typestore gives each type's CDR serialisation and
its ``ros2msg`` schema text. ``rosbags`` was chosen over ``mcap_ros2``'s dynamic writer for exactly that
strictness, and because it knows the standard types without a ROS installation.

The messages written every step are the exception: markers are :class:`~fleetsim.recording.cdr.Marker`
tuples, as strict (every field required, by name) and packed directly (:mod:`fleetsim.recording.cdr`),
and the ``/tf`` of the whole fleet is laid out once (:class:`FleetTransforms`); both produce the
typestore's bytes exactly (:func:`marker_array_message` gives the typestore message a marker array
stands for).

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
from fleetsim.recording.cdr import NO_POINTS, Marker, MarkerArray, Points, Stamp, pack_marker_array

__all__ = [
    "RGBA",
    "FleetTransforms",
    "Marker",
    "MarkerArray",
    "Points",
    "Stamp",
    "arrow",
    "clock",
    "colour",
    "delete",
    "delete_all",
    "disc",
    "line_list",
    "line_strip",
    "log",
    "marker_array",
    "marker_array_message",
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


@cache
def _store() -> Any:
    # Humble's definitions; Jazzy's messages used here are the same on the wire.
    return get_typestore(Stores.ROS2_HUMBLE)


def _type(name: str) -> Any:
    return _store().types[name]


def serialise(message: Any) -> bytes:
    """CDR bytes of ``message`` (little endian, as rosbag2 writes)."""
    if isinstance(message, MarkerArray):
        return pack_marker_array(message)
    data: memoryview = _store().serialize_cdr(message, message.__msgtype__)
    return bytes(data)


@cache
def schema_text(typename: str) -> bytes:
    """The ``ros2msg`` schema of ``typename`` with its dependencies, as MCAP's ros2 profile wants it."""
    text: str = _store().generate_msgdef(typename, ros_version=2)[0]
    return text.encode("utf-8")


def stamp(nanoseconds: int) -> Stamp:
    return Stamp(*divmod(nanoseconds, 1_000_000_000))


def _time(time: Stamp) -> Any:
    return _type("builtin_interfaces/msg/Time")(sec=time.sec, nanosec=time.nanosec)


def _header(time: Stamp, frame: str) -> Any:
    return _type("std_msgs/msg/Header")(stamp=_time(time), frame_id=frame)


def clock(time: Stamp) -> Any:
    """The ``/clock`` message (the recorder packs it directly: :func:`fleetsim.recording.cdr.pack_clock`)."""
    return _type("rosgraph_msgs/msg/Clock")(clock=_time(time))


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
        # Per frame, the bytes after the stamp that never change: both strings and the padding after each.
        self._names: list[bytes] = []
        for child in self.children:
            parts, names, offset = _transform_layout(offset, parent, child)
            fields += parts
            self._names.append(names)
        self._struct = struct.Struct("".join(fields))
        sample = [(float(k), float(-k), 0.25 * k) for k in range(len(self.children))]
        self._fast = bool(self.children) and self._pack(1_234_567_890_123, sample) == self._slow(
            1_234_567_890_123, sample
        )

    def _pack(self, time_ns: int, poses: Sequence[tuple[float, float, float]]) -> bytes:
        seconds, nanoseconds = divmod(time_ns, 1_000_000_000)
        values: list[Any] = [b"\x00\x01\x00\x00", len(self.children)]
        sin, cos = math.sin, math.cos
        for names, (x, y, heading) in zip(self._names, poses, strict=True):
            values += (seconds, nanoseconds, names, x, y, 0.0, 0.0, 0.0, sin(heading / 2.0), cos(heading / 2.0))
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


def _transform_layout(offset: int, parent: str, child: str) -> tuple[list[str], bytes, int]:
    """``struct`` fields of one TransformStamped starting at CDR ``offset``, the bytes of its frame names
    (from the end of the stamp to the translation: each string's length, text and NUL, padded), and the
    offset after it."""
    parts = []
    pad = -offset % 4
    if pad:
        parts.append(f"{pad}x")
        offset += pad
    offset += 8  # stamp
    names = b""
    for text in (parent, child):
        names += bytes(-offset % 4)
        offset += -offset % 4
        encoded = text.encode() + b"\0"
        names += struct.pack("<I", len(encoded)) + encoded
        offset += 4 + len(encoded)
    names += bytes(-offset % 8)
    offset += -offset % 8
    parts.append(f"iI{len(names)}s7d")  # stamp, names, translation x y z, rotation x y z w
    offset += 56
    return parts, names, offset


def _marker(
    time: Stamp,
    frame: str,
    namespace: str,
    marker_id: int,
    kind: int,
    *,
    action: int = 0,
    at: tuple[float, float, float] = (0.0, 0.0, 0.0),
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0),
    rgba: RGBA = (1.0, 1.0, 1.0, 1.0),
    points: Points = NO_POINTS,
    text: str = "",
    frame_locked: bool = False,
) -> Marker:
    return Marker(
        stamp=time,
        frame_id=frame,
        ns=namespace,
        id=marker_id,
        type=kind,
        action=action,
        position=(float(at[0]), float(at[1]), float(at[2])),
        scale=(float(scale[0]), float(scale[1]), float(scale[2])),
        color=(float(rgba[0]), float(rgba[1]), float(rgba[2]), float(rgba[3])),
        frame_locked=frame_locked,
        points=points,
        text=text,
    )


def points(polyline: Sequence[Point], z: float = 0.0) -> Points:
    """A polyline as LINE_LIST points: each piece as a pair (so the count is always even)."""
    return Points.of((x, y, z) for (ax, ay), (bx, by) in pairwise(polyline) for x, y in ((ax, ay), (bx, by)))


def line_list(time: Stamp, namespace: str, marker_id: int, pairs: Points, width: float, rgba: RGBA) -> Marker:
    """One LINE_LIST marker in ``map`` through ``pairs`` (from :func:`points`)."""
    return _marker(time, "map", namespace, marker_id, 5, scale=(width, 0.0, 0.0), rgba=rgba, points=pairs)


def path_points(polyline: Sequence[Point], z: float = 0.0) -> Points:
    """A polyline as LINE_STRIP points, in order."""
    return Points.of((x, y, z) for x, y in polyline)


def line_strip(
    time: Stamp, namespace: str, marker_id: int, path: Points, width: float, rgba: RGBA, frame: str = "map"
) -> Marker:
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
) -> Marker:
    """A TEXT_VIEW_FACING marker (``scale.z`` is the letter height)."""
    return _marker(
        time, frame, namespace, marker_id, 9, at=at, scale=(0.0, 0.0, size), rgba=rgba, text=text,
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
) -> Marker:
    """An ARROW marker in ``map`` from ``start`` to ``end`` (head diameter and length follow the shaft)."""
    ends = Points.of([start, end])
    return _marker(
        time, "map", namespace, marker_id, 0, scale=(shaft, 2.5 * shaft, 3.0 * shaft), rgba=rgba, points=ends
    )


def disc(
    time: Stamp, namespace: str, marker_id: int, at: tuple[float, float, float], diameter: float, rgba: RGBA
) -> Marker:
    """A flat CYLINDER marker in ``map`` centred at ``at`` (a ring-like mark round a vehicle)."""
    return _marker(time, "map", namespace, marker_id, 3, at=at, scale=(diameter, diameter, 0.04), rgba=rgba)


def delete_all(time: Stamp, namespace: str) -> Marker:
    """DELETEALL: the content of an array topic is replaced, not added to."""
    return _marker(time, "map", namespace, 0, 0, action=3)


def delete(time: Stamp, namespace: str, marker_id: int) -> Marker:
    """DELETE one marker (a vehicle's plan lost its fixed or its planned part)."""
    return _marker(time, "map", namespace, marker_id, 5, action=2)


def marker_array(markers: Sequence[Marker]) -> MarkerArray:
    return MarkerArray(tuple(markers))


def marker_array_message(array: MarkerArray) -> Any:
    """``array`` as the typestore's message (what :func:`serialise` packs it as, field for field)."""
    types = _store().types
    vector, point, quaternion = (
        types["geometry_msgs/msg/Vector3"],
        types["geometry_msgs/msg/Point"],
        types["geometry_msgs/msg/Quaternion"],
    )
    no_bytes = np.zeros(0, dtype=np.uint8)  # the typestore wants uint8[] fields as numpy arrays
    markers = [
        types["visualization_msgs/msg/Marker"](
            header=_header(marker.stamp, marker.frame_id),
            ns=marker.ns,
            id=marker.id,
            type=marker.type,
            action=marker.action,
            pose=types["geometry_msgs/msg/Pose"](
                position=point(x=marker.position[0], y=marker.position[1], z=marker.position[2]),
                orientation=quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
            scale=vector(x=marker.scale[0], y=marker.scale[1], z=marker.scale[2]),
            color=colour(marker.color),
            lifetime=types["builtin_interfaces/msg/Duration"](sec=0, nanosec=0),
            frame_locked=marker.frame_locked,
            points=[point(x=x, y=y, z=z) for x, y, z in marker.points.unpacked()],
            colors=[],
            texture_resource="",
            texture=types["sensor_msgs/msg/CompressedImage"](header=_header(Stamp(0, 0), ""), format="", data=no_bytes),
            uv_coordinates=[],
            text=marker.text,
            mesh_resource="",
            mesh_file=types["visualization_msgs/msg/MeshFile"](filename="", data=no_bytes),
            mesh_use_embedded_materials=False,
        )
        for marker in array.markers
    ]
    return types["visualization_msgs/msg/MarkerArray"](markers=markers)


def log(time: Stamp, level: int, message: str) -> Any:
    """An ``rcl_interfaces/msg/Log`` record from the simulator (``/rosout``)."""
    return _type("rcl_interfaces/msg/Log")(
        stamp=_time(time), level=level, name="fleetsim", msg=message, file="", function="", line=0
    )
