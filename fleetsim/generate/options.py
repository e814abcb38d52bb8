"""What ``fleetsim generate warehouse`` is asked for: the options of a generated warehouse, checked.

Every option is checked before anything is built or written, and a bad one is a
[`GenerateError`][fleetsim.generate.GenerateError] naming the option and its value ("aisles=0 must be at
least 2"); the command line shows it as a usage error (exit status 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from fleetsim.errors import FleetsimError
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE

__all__ = ["MAP_FORMATS", "REFERENCE_DISPATCHER", "GenerateError", "WarehouseOptions"]

MapFormat = Literal["tiled", "lif"]
MAP_FORMATS: tuple[MapFormat, ...] = ("tiled", "lif")
REFERENCE_DISPATCHER = "fleetsim.dispatchers:NearestVehicleDispatcher"


class GenerateError(FleetsimError, ValueError):
    """An option a generator cannot build from: its name, its value and what it must be.

    Attributes:
        option: The option's name as the Python API spells it (``aisle_length``); the command line's is
            ``--aisle-length``.
        value: The value given.
        reason: What the value must be, or why it cannot be built ("must be at least 2").
    """

    def __init__(self, option: str, value: object, reason: str) -> None:
        self.option = option
        self.value = value
        self.reason = reason
        super().__init__(f"{option}={value!r} {reason}")

    def command_line(self) -> str:
        """The message as the command line words it: ``--aisles 0: must be at least 2``."""
        flag = "OUT_DIR" if self.option == "out_dir" else "--" + self.option.replace("_", "-")
        return f"{flag} {self.value}: {self.reason}"


@dataclass(frozen=True, slots=True)
class WarehouseOptions:
    """A warehouse to generate (``fleetsim generate warehouse``'s options; lengths in metres).

    Attributes:
        aisles: How many parallel aisles (at least 2: the outer two close the loop).
        aisle_length: Metres between the two cross aisles.
        aisle_spacing: Metres between the centre lines of neighbouring aisles.
        vehicles: How many vehicles; each starts on a parking place of its own.
        pick_stations: Pick stations, spread over the aisles (lay-bys beside them).
        drop_stations: Drop stations at the dock, beyond the top cross aisle.
        parking: Parking places beyond the bottom cross aisle; ``None``: one per vehicle.
        one_way: Aisles of alternating directions and cross aisles one way round (a loop), else every
            aisle and cross aisle two-way. Station lay-bys and parking rows are one-way in both.
        vehicle_length: The vehicles' length (the spacing of the layout follows their size).
        vehicle_width: The vehicles' width.
        map_format: ``"tiled"`` (``map.json``) or ``"lif"`` (``map.lif.json``, VDA 5050 LIF 1.0).
        seed: The seed of the suite's order stream.
        dispatcher: The dispatcher spec (``module:attribute``) the suite names, or ``None`` for none (then
            ``fleetsim run --dispatcher`` names one).
    """

    aisles: int = 6
    aisle_length: float = 20.0
    aisle_spacing: float = 5.0
    vehicles: int = 8
    pick_stations: int = 12
    drop_stations: int = 4
    parking: int | None = None
    one_way: bool = True
    vehicle_length: float = DEFAULT_VEHICLE_TYPE.length
    vehicle_width: float = DEFAULT_VEHICLE_TYPE.width
    map_format: MapFormat = "tiled"
    seed: int = 1
    dispatcher: str | None = REFERENCE_DISPATCHER

    def __post_init__(self) -> None:
        _whole("aisles", self.aisles, 2, "(the outer two aisles close the loop)")
        _whole("vehicles", self.vehicles, 1)
        _whole("pick_stations", self.pick_stations, 1, "(the order stream draws its first stop from them)")
        _whole("drop_stations", self.drop_stations, 1, "(the order stream draws its last stop from them)")
        if self.parking is not None:
            _whole("parking", self.parking, 1)
            if self.vehicles > self.parking:
                reason = f"must not exceed the {self.parking} parking places: every vehicle starts on one of its own"
                raise GenerateError("vehicles", self.vehicles, reason)
        _whole("seed", self.seed, 0)
        for name in ("aisle_length", "aisle_spacing", "vehicle_length", "vehicle_width"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise GenerateError(name, value, "must be a number of metres > 0")
        if self.dispatcher is not None:
            module, _, attribute = self.dispatcher.partition(":")
            if not module.strip() or not attribute.strip() or any(c.isspace() for c in self.dispatcher):
                raise GenerateError(
                    "dispatcher", self.dispatcher, "must be module:attribute, e.g. " + REFERENCE_DISPATCHER
                )
        if self.map_format not in MAP_FORMATS:
            raise GenerateError("map_format", self.map_format, f"must be one of {', '.join(MAP_FORMATS)}")

    @property
    def parking_places(self) -> int:
        """How many parking places: ``parking``, or one per vehicle."""
        return self.vehicles if self.parking is None else self.parking


def _whole(name: str, value: object, least: int, why: str = "") -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < least:
        raise GenerateError(name, value, f"must be a whole number >= {least}" + (f" {why}" if why else ""))
