"""CDR bytes of the marker messages, packed directly from their values (``visualization_msgs`` on Humble).

A recording writes thousands of markers: every step's sim time, and every plan that changed, each a line
strip along tens of points. Built as ``rosbags`` typestore objects and serialised field by field (each
point a message of its own), they were the largest part of writing a recording. Here a marker is a :class:`Marker` (a named tuple
with every field fleetsim varies, all required, so a missing or misspelt one is a ``TypeError`` exactly
as with the typestore's classes) and its points are packed once into :class:`Points`; a
:class:`MarkerArray` is then packed with a few ``struct`` calls, the parts fleetsim never varies (identity
orientation, no lifetime, texture or mesh) as constant bytes.

The bytes are exactly the typestore's (``tests/unit/test_cdr.py`` checks them against
:func:`fleetsim.recording.messages.marker_array_message` serialised by ``rosbags``): little-endian CDR,
each field aligned to its size relative to the end of the 4-byte encapsulation header, strings as a
length with the terminating NUL, padding zero, and a sequence's elements aligned only if it has any.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from functools import lru_cache
from typing import NamedTuple

__all__ = ["CLOCK_SIZE", "Marker", "MarkerArray", "Points", "Stamp", "pack_clock", "pack_marker_array"]

RGBA = tuple[float, float, float, float]
_ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little endian
_ZEROS = bytes(8)
_U32 = struct.Struct("<I")
_STAMP = struct.Struct("<iI")
_IDS = struct.Struct("<iii")  # id, type, action
# pose (position, orientation), scale, colour (float32), lifetime (sec, nanosec), frame_locked
_BODY = struct.Struct("<10d4fiI?")
_POINT = struct.Struct("<3d")
_CLOCK = struct.Struct("<4siI")
CLOCK_SIZE = _CLOCK.size


def _string(text: str) -> bytes:
    """A CDR string after its alignment: length with the NUL, the UTF-8 bytes, the NUL."""
    data = text.encode("utf-8")
    return _U32.pack(len(data) + 1) + data + b"\0"


@lru_cache(maxsize=4096)  # a few hundred pairs at most, each used thousands of times
def _names(frame_id: str, ns: str) -> bytes:
    """``header.frame_id`` and ``ns`` from a 4-aligned offset, padded to the next 4-aligned one."""
    frame_bytes, ns_bytes = _string(frame_id), _string(ns)
    return frame_bytes + bytes(-len(frame_bytes) % 4) + ns_bytes + bytes(-len(ns_bytes) % 4)


_EMPTY_STRING = _string("")
# From ``colors`` to ``uv_coordinates``, which fleetsim leaves empty: the bytes between the points and the
# text, starting 4-aligned (after the points' count or float64s) and ending 4-aligned.
_BEFORE_TEXT = b"".join(
    (
        _U32.pack(0),  # colors: none
        _EMPTY_STRING + bytes(3),  # texture_resource, then padding to the texture's stamp
        _STAMP.pack(0, 0),  # texture.header.stamp
        _EMPTY_STRING + bytes(3),  # texture.header.frame_id
        _EMPTY_STRING + bytes(3),  # texture.format
        _U32.pack(0),  # texture.data: no bytes
        _U32.pack(0),  # uv_coordinates: none
    )
)
# After the text (which leaves the offset 4-aligned once padded): mesh_resource, mesh_file and
# mesh_use_embedded_materials, all empty or false.
_AFTER_TEXT = _EMPTY_STRING + bytes(3) + _EMPTY_STRING + bytes(3) + _U32.pack(0) + b"\0"


class Stamp(NamedTuple):
    """A ``builtin_interfaces/msg/Time``: whole seconds and the nanoseconds after them."""

    sec: int
    nanosec: int


class Points(NamedTuple):
    """A ``geometry_msgs/msg/Point[]`` packed: ``length`` points as little-endian float64 x, y, z."""

    length: int
    data: bytes

    @classmethod
    def of(cls, points: Iterable[tuple[float, float, float]]) -> Points:
        flat: list[float] = []
        for point in points:
            if len(point) != 3:
                msg = f"point={point!r} must be (x, y, z)"
                raise ValueError(msg)
            flat += point
        return cls(len(flat) // 3, struct.pack(f"<{len(flat)}d", *flat))

    @classmethod
    def joined(cls, parts: Iterable[Points]) -> Points:
        """The points of ``parts`` one after the other."""
        listed = list(parts)
        return cls(sum(part.length for part in listed), b"".join(part.data for part in listed))

    def rest(self) -> Points:
        """All points but the first."""
        return Points(self.length - 1, self.data[_POINT.size :]) if self.length else self

    def unpacked(self) -> list[tuple[float, float, float]]:
        return list(_POINT.iter_unpack(self.data))


NO_POINTS = Points(0, b"")


class Marker(NamedTuple):
    """A ``visualization_msgs/msg/Marker`` by the fields fleetsim varies, named as in the message.

    A named tuple, not a dataclass: thousands are made per recording. The rest of the message is fixed:
    orientation identity (``position`` is ``pose.position``), lifetime 0 (forever), no per-point colours,
    texture, UV coordinates or mesh.
    """

    stamp: Stamp  # header.stamp
    frame_id: str  # header.frame_id
    ns: str
    id: int
    type: int
    action: int
    position: tuple[float, float, float]
    scale: tuple[float, float, float]
    color: RGBA
    frame_locked: bool
    points: Points
    text: str

    def restamped(self, stamp: Stamp, marker_id: int) -> Marker:
        """This marker at ``stamp`` with the id ``marker_id`` (for markers sent again and again)."""
        return _new(Marker, (stamp, self[1], self[2], marker_id, *self[4:]))


_new = tuple.__new__


class MarkerArray(NamedTuple):
    """A ``visualization_msgs/msg/MarkerArray``."""

    markers: tuple[Marker, ...]


def pack_marker_array(array: MarkerArray) -> bytes:
    """The CDR bytes of ``array``, with the encapsulation header (as the typestore serialises it)."""
    buffer = bytearray(_ENCAPSULATION)
    buffer += _U32.pack(len(array.markers))
    for marker in array.markers:
        _pack_marker(buffer, marker)
    return bytes(buffer)


def _pack_marker(buffer: bytearray, marker: Marker) -> None:
    # Offsets count from the end of the 4-byte encapsulation header, so an offset's remainder mod 4 is
    # len(buffer)'s, and the padding to 8 is (4 - len(buffer)) % 8.
    (stamp, frame_id, ns, marker_id, kind, action, position, scale, color, frame_locked, points, text) = marker
    buffer += _ZEROS[: -len(buffer) % 4]
    head, names, offset = _head(frame_id, ns, len(buffer) % 8)
    buffer += head.pack(
        *stamp, names, marker_id, kind, action, *position, 0.0, 0.0, 0.0, 1.0, *scale, *color, 0, 0, frame_locked
    )
    buffer += _tail(points, text, offset)


@lru_cache(maxsize=4096)  # a few hundred name pairs at most, each at two offsets
def _head(frame_id: str, ns: str, offset: int) -> tuple[struct.Struct, bytes, int]:
    """A marker from its stamp to its ``frame_locked``, starting at ``offset`` mod 8 (0 or 4): its layout
    (stamp, names, id, type, action, padding, pose, scale, colour, lifetime, frame_locked), the names'
    bytes, and the offset mod 8 after it."""
    names = _names(frame_id, ns)
    after_ids = offset + _STAMP.size + len(names) + _IDS.size
    padding = (4 - after_ids) % 8
    layout = struct.Struct(f"<iI{len(names)}siii{padding}x10d4fiI?")
    return layout, names, (after_ids + padding + _BODY.size) % 8


# Keyed by bytes and text only: floats would make 0.0 and -0.0 one key, and they differ in CDR.
@lru_cache(maxsize=4096)  # a recording sends most markers again and again with a new stamp or id
def _tail(points: Points, text: str, offset: int) -> bytes:
    """A marker's bytes from its points on, starting at ``offset`` mod 8."""
    buffer = bytearray(offset)  # so that the padding below is as at the marker's place
    buffer += _ZEROS[: -len(buffer) % 4]
    buffer += _U32.pack(points.length)
    if points.length:
        buffer += _ZEROS[: (4 - len(buffer)) % 8]
        buffer += points.data
    buffer += _BEFORE_TEXT
    text_bytes = _string(text)
    buffer += text_bytes
    buffer += _ZEROS[: -len(text_bytes) % 4]
    buffer += _AFTER_TEXT
    return bytes(buffer[offset:])


def pack_clock(stamp: Stamp) -> bytes:
    """The CDR bytes of a ``rosgraph_msgs/msg/Clock`` at ``stamp``."""
    return _CLOCK.pack(_ENCAPSULATION, *stamp)
