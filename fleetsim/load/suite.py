"""Suites: ``*.fleetsim.yaml`` files that declare vehicle types, default settings and scenarios (SPEC §13).

Loading a suite checks the YAML against ``schemas/suite.schema.json`` and then what a schema cannot
say (unique names, known vehicle types, files that exist). It does not open the maps or CSV files:
that is :func:`fleetsim.load.scenario.load_scenario`, one scenario at a time.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

from fleetsim.enums import ConflictModel, TurnCapability
from fleetsim.errors import Location, SuiteError
from fleetsim.load.disturbances import HuntDisturbances, declared_disturbances, hunt_block, random_block
from fleetsim.load.map_options import MapOptions
from fleetsim.load.scenario_files import (
    MAP_FILE_NAMES,
    TASKS_FILE_NAME,
    VEHICLES_FILE_NAME,
    did_you_mean,
    map_candidates,
)
from fleetsim.load.suite_schema import check_against_schema, suite_error
from fleetsim.load.yaml_source import Locate, load_yaml_with_marks
from fleetsim.scenario import (
    DEFAULT_VEHICLE_TYPE,
    Disturbance,
    Expectations,
    RandomDisturbances,
    ScenarioSettings,
    VehicleType,
)

__all__ = [
    "SUITE_SUFFIX",
    "Generation",
    "ScenarioSpec",
    "Suite",
    "discover_suites",
    "load_suite",
    "parse_scenario_entry",
    "parse_settings",
    "parse_vehicle_types",
]

SUITE_SUFFIX = ".fleetsim.yaml"
SETTING_KEYS = tuple(f.name for f in fields(ScenarioSettings))


@dataclass(frozen=True, slots=True)
class Generation:
    """A suite entry's ``generate`` block: what Hypothesis may generate for it (see fleetsim.strategies)."""

    layout: str = "any"
    size: tuple[int, int] = (1, 3)
    vehicles: tuple[int, int] = (1, 3)
    tasks: tuple[int, int] = (1, 2)
    one_way: bool | None = None
    vehicle_types: tuple[str, ...] = ()  # names of the suite's vehicle types; () -> the entry's vehicle_type
    examples: int = 50


@dataclass(frozen=True, slots=True)
class ScenarioSpec:
    """One scenario entry of a suite, with its files resolved and its settings merged; nothing opened.

    Load it with [`load_scenario`][fleetsim.load.load_scenario].

    Attributes:
        name: The entry's ``name``, unique in the suite.
        suite_path: The suite file.
        line: The line of the entry in the suite file.
        map_path: The map file.
        vehicles_path: The ``vehicles.csv``.
        tasks_path: The ``tasks.csv``.
        settings: The suite's ``defaults`` merged with the entry's own settings.
        expect: The entry's ``expect``.
        tags: The entry's ``tags`` (pytest markers).
        xfail: The entry's ``xfail`` reason, or ``None``.
        description: The entry's ``description``.
        generate: The entry's ``generate`` block for scenarios Hypothesis generates, or ``None`` (then
            the three paths are the suite's folder).
        map_options: Which part of a LIF or RMF map to drive on.
        disturbances: Declared disturbances, in entry order.
        random_disturbances: Randomly drawn stops, or ``None``.
        hunt_disturbances: A Hypothesis search for stop schedules that fail the planner, or ``None``.
    """

    name: str
    suite_path: Path
    line: int
    map_path: Path
    vehicles_path: Path
    tasks_path: Path
    settings: ScenarioSettings
    expect: Expectations
    tags: tuple[str, ...]
    xfail: str | None
    description: str = ""
    generate: Generation | None = None
    map_options: MapOptions = field(default_factory=MapOptions)
    disturbances: tuple[Disturbance, ...] = ()
    random_disturbances: RandomDisturbances | None = None
    hunt_disturbances: HuntDisturbances | None = None

    @property
    def hunts(self) -> bool:
        """Whether the entry is a hunt (fleetsim.gating.generated): generated, or with ``hunt_disturbances``."""
        return self.generate is not None or self.hunt_disturbances is not None

    @property
    def hunt_examples(self) -> int:
        """How many examples the entry's hunt may try."""
        if self.generate is not None:
            return self.generate.examples
        return self.hunt_disturbances.examples if self.hunt_disturbances is not None else 0


@dataclass(frozen=True, slots=True)
class Suite:
    """A loaded suite.

    Attributes:
        path: The suite file.
        name: Its ``name``.
        description: Its ``description``.
        vehicle_types: Its ``vehicle_types``, by name (read-only).
        scenarios: Its scenario entries, in file order.
        planner: The planner spec the suite is pinned to (it documents that planner), or ``None``.
    """

    path: Path
    name: str
    description: str
    vehicle_types: Mapping[str, VehicleType]
    scenarios: tuple[ScenarioSpec, ...]
    planner: str | None = None


def discover_suites(paths: Iterable[Path | str]) -> list[Path]:
    """Suite files among ``paths``, sorted: files as given, ``*.fleetsim.yaml`` found below directories.

    Hidden directories (``.git``, ``.venv``, ...) are not searched. A path that does not exist is an
    error rather than an empty result, so a typo on the command line is not a silent green run.
    """
    found: set[Path] = set()
    for path in map(Path, paths):
        if path.is_dir():
            found.update(
                candidate
                for candidate in path.rglob(f"*{SUITE_SUFFIX}")
                if candidate.is_file()
                and not any(part.startswith(".") for part in candidate.relative_to(path).parts[:-1])
            )
        elif path.is_file():
            found.add(path)
        else:
            raise SuiteError("no such file or directory", Location(path))
    return sorted(found)


def load_suite(path: Path | str) -> Suite:
    """Load and check a suite file.

    Every problem is one [`SuiteError`][fleetsim.errors.SuiteError] at its ``file:line:column``.
    """
    path = Path(path)
    data, locate = load_yaml_with_marks(path, error_type=SuiteError)
    if data is None:
        msg = "empty file: a suite needs at least 'fleetsim: 1', 'name' and 'scenarios'"
        raise SuiteError(msg, Location(path))
    check_against_schema(data, locate)
    vehicle_types = parse_vehicle_types(data.get("vehicle_types"), locate)
    defaults = data.get("defaults", {})
    base = parse_settings(ScenarioSettings(), defaults, vehicle_types, locate, ("defaults",))
    _check_unique_names(data["scenarios"], locate)
    base_options = defaults.get("map_options", {})
    scenarios = tuple(
        parse_scenario_entry(path, index, entry, base, vehicle_types, locate, base_options)
        for index, entry in enumerate(data["scenarios"])
    )
    return Suite(
        path=path,
        name=data["name"],
        description=data.get("description", ""),
        vehicle_types=MappingProxyType(vehicle_types),
        scenarios=scenarios,
        planner=data.get("planner"),
    )


# -- vehicle types --------------------------------------------------------------------------------


def _color(raw: str | list[float] | None) -> tuple[float, float, float, float] | None:
    if raw is None:
        return None
    if isinstance(raw, str):  # "#rrggbb", checked by the schema
        red, green, blue = (int(raw[i : i + 2], 16) / 255 for i in (1, 3, 5))
        return (red, green, blue, 1.0)
    rgba = [float(component) for component in raw] + [1.0] * (4 - len(raw))
    return (rgba[0], rgba[1], rgba[2], rgba[3])


def parse_vehicle_types(raw: Mapping[str, Any] | None, locate: Locate) -> dict[str, VehicleType]:
    if raw is None:
        return {DEFAULT_VEHICLE_TYPE.name: DEFAULT_VEHICLE_TYPE}
    seen: dict[str, str] = {}
    types = {}
    for name, spec in raw.items():
        # vehicles.csv names types case-insensitively, so names differing only in case are ambiguous.
        if name.casefold() in seen:
            msg = f"{name!r} differs from vehicle type {seen[name.casefold()]!r} only in case"
            raise suite_error(msg, ("vehicle_types",), locate(("vehicle_types", name), key=True))
        seen[name.casefold()] = name
        types[name] = VehicleType(
            name=name,
            length=float(spec["length"]),
            width=float(spec["width"]),
            height=float(spec["height"]),
            max_speed=float(spec["max_speed"]),
            acceleration=float(spec["acceleration"]),
            turn_capability=TurnCapability(spec["turn_capability"]),
            turn_rate=float(spec.get("turn_rate", 90.0)),
            color=_color(spec.get("color")),
        )
    return types


def _type_name(name: str, types: Mapping[str, VehicleType], locate: Locate, where: tuple[Any, ...]) -> str:
    """The canonical spelling of a vehicle type name (matched case-insensitively, as in vehicles.csv)."""
    for known in types:
        if known.casefold() == name.casefold():
            return known
    msg = f"{name!r} is not a vehicle type of this suite ({', '.join(types)}){did_you_mean(name, types)}"
    raise suite_error(msg, where, locate(where))


# -- settings and expectations --------------------------------------------------------------------


def parse_settings(
    base: ScenarioSettings,
    raw: Mapping[str, Any],
    types: Mapping[str, VehicleType],
    locate: Locate,
    where: tuple[Any, ...],
) -> ScenarioSettings:
    """``base`` with the setting keys of ``raw`` applied (values already checked by the schema)."""
    changes: dict[str, Any] = {}
    for key in SETTING_KEYS:
        if key not in raw:
            continue
        value = raw[key]
        if key == "vehicle_type":
            value = _type_name(value, types, locate, (*where, key))
        elif key == "stop_on":
            value = tuple(value)
        elif key == "conflict_model":
            value = ConflictModel(value)
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            value = float(value)
        changes[key] = value
    if base.vehicle_type is None and "vehicle_type" not in changes and len(types) == 1:
        changes["vehicle_type"] = next(iter(types))  # a suite's only vehicle type is its default
    return replace(base, **changes)


def _word_or_tuple(value: Any) -> Any:
    """``"none"``/``"any"`` as they are, a list as a tuple (the schema has checked which)."""
    return value if isinstance(value, str) else tuple(value)


def _expectations(raw: Mapping[str, Any]) -> Expectations:
    max_makespan = raw.get("max_makespan")
    return Expectations(
        tasks=raw.get("tasks", "all"),
        collisions=_word_or_tuple(raw.get("collisions", "none")),
        rejections=_word_or_tuple(raw.get("rejections", "none")),
        deadlock=raw.get("deadlock", False),
        max_makespan=None if max_makespan is None else float(max_makespan),
    )


# -- scenarios ------------------------------------------------------------------------------------


def _check_unique_names(entries: list[Mapping[str, Any]], locate: Locate) -> None:
    # Case-insensitive: scenario names become artifact file names, and some file systems fold case.
    first: dict[str, tuple[str, int]] = {}
    for index, entry in enumerate(entries):
        name = entry["name"]
        if name.casefold() in first:
            other, other_index = first[name.casefold()]
            line = locate(("scenarios", other_index, "name")).line
            same = "" if other == name else f" (as {other!r}: names may not differ only in case)"
            msg = f"scenario name {name!r} is already used on line {line}{same}"
            where = ("scenarios", index, "name")
            raise suite_error(msg, where, locate(where))
        first[name.casefold()] = (name, index)


def parse_scenario_entry(
    suite_path: Path,
    index: int,
    entry: Mapping[str, Any],
    base: ScenarioSettings,
    types: Mapping[str, VehicleType],
    locate: Locate,
    base_options: Mapping[str, Any],
) -> ScenarioSpec:
    where = ("scenarios", index)
    generate = None
    if "generate" in entry:
        generate = _generation(entry["generate"], types, locate, (*where, "generate"))
        map_path = vehicles_path = tasks_path = suite_path.parent
    else:
        map_path, vehicles_path, tasks_path = _scenario_files(suite_path.parent, entry, locate, where)
    return ScenarioSpec(
        name=entry["name"],
        suite_path=suite_path,
        line=locate(where).line or 1,
        map_path=map_path,
        vehicles_path=vehicles_path,
        tasks_path=tasks_path,
        settings=parse_settings(base, entry, types, locate, where),
        expect=_expectations(entry.get("expect", {})),
        tags=tuple(entry.get("tags", ())),
        xfail=entry.get("xfail"),
        description=entry.get("description", ""),
        generate=generate,
        map_options=MapOptions(**{**base_options, **entry.get("map_options", {})}),
        **_disturbance_keys(entry, generate is not None, locate, where),
    )


def _disturbance_keys(
    entry: Mapping[str, Any], generated: bool, locate: Locate, where: tuple[Any, ...]
) -> dict[str, Any]:
    keys: dict[str, Any] = {}
    if "disturbances" in entry:
        if generated:
            msg = (
                "a generated scenario's vehicles are not known in advance: use random_disturbances or hunt_disturbances"
            )
            raise suite_error(msg, (*where, "disturbances"), locate((*where, "disturbances"), key=True))
        keys["disturbances"] = declared_disturbances(entry["disturbances"], (*where, "disturbances"), locate)
    if "random_disturbances" in entry:
        keys["random_disturbances"] = random_block(
            entry["random_disturbances"], (*where, "random_disturbances"), locate
        )
    if "hunt_disturbances" in entry:
        keys["hunt_disturbances"] = hunt_block(entry["hunt_disturbances"], (*where, "hunt_disturbances"), locate)
    return keys


def _generation(
    raw: Mapping[str, Any], types: Mapping[str, VehicleType], locate: Locate, where: tuple[Any, ...]
) -> Generation:
    ranges = {}
    for key in ("size", "vehicles", "tasks"):
        if key in raw:
            low, high = raw[key]
            if low > high:
                msg = f"{key}={[low, high]!r} must be [min, max] with min <= max"
                raise suite_error(msg, (*where, key), locate((*where, key)))
            ranges[key] = (low, high)
    names = tuple(
        _type_name(name, types, locate, (*where, "vehicle_types", k))
        for k, name in enumerate(raw.get("vehicle_types", ()))
    )
    return Generation(
        layout=raw.get("layout", "any"),
        one_way=raw.get("one_way"),
        vehicle_types=names,
        examples=raw.get("examples", 50),
        **ranges,
    )


def _scenario_files(
    root: Path, entry: Mapping[str, Any], locate: Locate, where: tuple[Any, ...]
) -> tuple[Path, Path, Path]:
    """map, vehicles and tasks paths: named ones relative to the suite, the rest from ``dir``."""
    folder = None
    if "dir" in entry:
        folder = root / entry["dir"]
        if not folder.is_dir():
            where_dir = (*where, "dir")
            raise suite_error(f"no such directory: {str(folder)!r}", where_dir, locate(where_dir))
    paths = []
    for key, default_name in (("map", None), ("vehicles", VEHICLES_FILE_NAME), ("tasks", TASKS_FILE_NAME)):
        if key in entry:
            path = root / entry[key]
            if not path.is_file():
                raise suite_error(f"no such file: {str(path)!r}", (*where, key), locate((*where, key)))
        else:
            assert folder is not None  # the schema requires dir when a file is not named
            path = _folder_file(folder, default_name, (*where, "dir"), locate)
        paths.append(path)
    return paths[0], paths[1], paths[2]


def _folder_file(folder: Path, name: str | None, where: tuple[Any, ...], locate: Locate) -> Path:
    """``name`` in the scenario folder, or (``None``) its one map file."""
    if name is not None:
        if not (folder / name).is_file():
            raise suite_error(f"{str(folder)!r} has no {name}", where, locate(where))
        return folder / name
    candidates = map_candidates(folder)
    if not candidates:
        names = f"{', '.join(MAP_FILE_NAMES[:-1])} or {MAP_FILE_NAMES[-1]}"
        raise suite_error(f"{str(folder)!r} has no {names}", where, locate(where))
    if len(candidates) > 1:
        names = " and ".join(candidate.name for candidate in candidates)
        msg = f"{str(folder)!r} has both {names}; keep one, or name the map with 'map'"
        raise suite_error(msg, where, locate(where))
    return candidates[0]
