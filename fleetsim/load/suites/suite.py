"""Suites: ``*.fleetsim.yaml`` files that declare vehicle types, default settings and scenarios (SPEC §13).

Loading a suite checks the YAML against ``schemas/suite.schema.json`` and then what a schema cannot
say (unique names, known vehicle types, files that exist). Every mistake of the file is reported at
once, each at its line; a suite with any mistake is not loaded. It does not open the maps or CSV files:
that is :func:`fleetsim.load.suites.scenario.load_scenario`, one scenario at a time.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

from fleetsim.enums import ConflictModel, TurnCapability
from fleetsim.errors import Location, SuiteError
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.common.yaml_source import Locate, load_yaml_with_marks
from fleetsim.load.suites.disturbances import HuntDisturbances, declared_disturbances, hunt_block, random_block
from fleetsim.load.suites.entry_tables import check_entry_tables
from fleetsim.load.suites.lorr_entry import LorrEntry, is_lorr_problem, lorr_files, problem_map, problem_name
from fleetsim.load.suites.orders_entry import DEFAULT_ORDER_KEYS, ORDER_KEYS, OrderSetup, order_setup
from fleetsim.load.suites.planner_setup import PLANNER_KEYS, planner_setup
from fleetsim.load.suites.scen_entry import ScenSetup, scen_files
from fleetsim.load.suites.schema import SchemaCheck, raise_suite_errors, schema_check, suite_error, suite_schema
from fleetsim.load.tables.scenario_files import (
    MAP_FILE_NAMES,
    TASKS_FILE_NAME,
    VEHICLES_FILE_NAME,
    map_candidates,
)
from fleetsim.orders import MEASURES, MeasureBound
from fleetsim.scenario import (
    DEFAULT_VEHICLE_TYPE,
    Checks,
    Disturbance,
    Expectations,
    PlannerSetup,
    RandomDisturbances,
    ScenarioSettings,
    VehicleType,
)

Gate = Literal["hash", "measures", "both"]

__all__ = [
    "SUITE_SUFFIX",
    "Gate",
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
        planner_setup: What the entry gives its planner: ``planner_options`` (over the defaults'), the
            scenario's folder and the data ``files``.
        order_setup: Its orders (``orders``, ``order_stream``), ``stations``, ``shift`` and ``dispatcher``,
            over the defaults' (`fleetsim.load.suites.orders_entry`).
        gate: What a change of behaviour fails on: ``hash`` (the recorded trace hash), ``measures`` (the
            ``expect`` bounds on measures; no hash is recorded or compared) or ``both``.
        scen: A MovingAI scenario file that gives the vehicles and tasks (``scen`` and ``agents``), or
            ``None``; then ``vehicles_path`` and ``tasks_path`` are that file.
        lorr: A League of Robot Runners problem that gives the map, vehicles and orders (``lorr``,
            ``horizon``, ``agents`` and ``task_rounds``), or ``None``; then ``vehicles_path`` and ``tasks_path`` are the
            problem file, and ``map_path`` the map it names (the problem file when it names none that exists).
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
    planner_setup: PlannerSetup = field(default_factory=PlannerSetup)
    order_setup: OrderSetup = field(default_factory=OrderSetup)
    gate: Gate = "hash"
    scen: ScenSetup | None = None
    lorr: LorrEntry | None = None

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

    One problem is a [`SuiteError`][fleetsim.errors.SuiteError] at its ``file:line:column``; several
    (every unknown key, every bad value, every missing folder, ...) are one
    [`SuiteErrors`][fleetsim.errors.SuiteErrors] listing each, in file order (at most 50, then "... and N
    more"). A suite with any problem is not loaded.
    """
    path = Path(path)
    if is_lorr_problem(path):
        return _problem_suite(path)
    data, locate = load_yaml_with_marks(path, error_type=SuiteError)
    if data is None:
        msg = "empty file: a suite needs at least 'fleetsim: 1', 'name' and 'scenarios'"
        raise SuiteError(msg, Location(path))
    check = schema_check(data, locate)
    found = ErrorCollector(cap=sys.maxsize)  # every error, sorted into file order before the cap
    for error in check.errors:
        found.add(error)
    suite = _read_suite(path, data, locate, check, found) if isinstance(data, dict) else None
    errors = ErrorCollector()
    reported: set[str] = set()  # a broken default several entries inherit is one mistake, told once
    for each in sorted(found.errors, key=lambda error: _position(error, path)):
        if str(each) not in reported:
            reported.add(str(each))
            errors.add(each)
    raise_suite_errors(errors)
    assert suite is not None  # no error, so every part was read
    return suite


def _problem_suite(path: Path) -> Suite:
    """A League problem file run on its own (``fleetsim run PROBLEM.json``): a suite of one scenario named
    after the file, with the default horizon, settings and expectations."""
    name = problem_name(path)
    map_path = problem_map(path)
    spec = ScenarioSpec(
        name=name, suite_path=path, line=1, map_path=map_path, vehicles_path=path, tasks_path=path,
        settings=ScenarioSettings(), expect=Expectations(), tags=(), xfail=None,
        description=f"the League of Robot Runners problem {path.name}", lorr=LorrEntry(path),
    )  # fmt: skip
    return Suite(path, name, spec.description, MappingProxyType({}), (spec,))


def _position(error: SuiteError | Exception, suite: Path) -> tuple[int, int, int]:
    """The suite's own errors in file order, then those of the files it names (CSV rows) as found."""
    location = getattr(error, "location", None)
    if location is None:
        return (0, 0, 0)
    if Path(location.path) != suite:
        return (1, 0, 0)
    return (0, location.line or 0, location.column or 0)


_ALL_CLEAN = SchemaCheck()  # for data the schema has passed


def _read_suite(
    path: Path, data: Mapping[str, Any], locate: Locate, check: SchemaCheck, errors: ErrorCollector
) -> Suite | None:
    """The suite, or ``None`` when a part of it could not be read; each problem goes to ``errors``."""
    names = _type_names(data, check)
    vehicle_types = _vehicle_types(data.get("vehicle_types"), locate, check, errors)
    raw_defaults = data.get("defaults", {})
    defaults = raw_defaults if isinstance(raw_defaults, dict) else {}
    base = _settings(ScenarioSettings(), defaults, names, locate, ("defaults",), check, errors)
    entries = data.get("scenarios")
    if not isinstance(entries, list):
        return None
    _check_unique_names(entries, locate, errors)
    base_options = defaults.get("map_options", {}) if check.clean(("defaults", "map_options")) else None
    planner = {key: defaults[key] for key in PLANNER_KEYS if key in defaults}
    base_planner = planner if all(check.clean(("defaults", key)) for key in PLANNER_KEYS) else None
    orders = {key: defaults[key] for key in DEFAULT_ORDER_KEYS if key in defaults}
    base_orders = orders if all(check.clean(("defaults", key)) for key in DEFAULT_ORDER_KEYS) else None
    base_gate = defaults.get("gate") if check.clean(("defaults", "gate")) else None
    scenarios = [
        _scenario_entry(
            path, index, entry, base, names, locate, base_options, check, errors, base_planner, base_orders, base_gate
        )
        for index, entry in enumerate(entries)
    ]
    if errors or vehicle_types is None or any(spec is None for spec in scenarios):
        return None
    return Suite(
        path=path,
        name=data["name"],
        description=data.get("description", ""),
        vehicle_types=MappingProxyType(vehicle_types),
        scenarios=tuple(spec for spec in scenarios if spec is not None),
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
    """The ``vehicle_types`` of schema-checked data; the first problem is raised."""
    errors = ErrorCollector()
    types = _vehicle_types(raw, locate, _ALL_CLEAN, errors)
    _raise_first(errors)
    assert types is not None
    return types


def _raise_first(errors: ErrorCollector) -> None:
    if errors:
        raise errors.errors[0]


def _type_names(data: Mapping[str, Any], check: SchemaCheck) -> tuple[str, ...] | None:
    """The suite's vehicle type names (also those whose description is broken), or ``None`` when they
    cannot be known: ``vehicle_types`` is no mapping, or seems misspelt (an unknown key close to it)."""
    raw = data.get("vehicle_types")
    if raw is None:
        unknown = [key for key in data if isinstance(key, str) and key not in suite_schema()["properties"]]
        misspelt = any(did_you_mean(key, ["vehicle_types"]) for key in unknown)
        return None if misspelt else (DEFAULT_VEHICLE_TYPE.name,)
    if not isinstance(raw, dict):
        return None
    folded: set[str] = set()
    names = []
    for name in raw:
        if isinstance(name, str) and name.casefold() not in folded:
            folded.add(name.casefold())
            names.append(name)
    return tuple(names)


def _vehicle_types(
    raw: Any, locate: Locate, check: SchemaCheck, errors: ErrorCollector
) -> dict[str, VehicleType] | None:
    """The vehicle types by name, or ``None`` when one could not be read."""
    if raw is None:
        return {DEFAULT_VEHICLE_TYPE.name: DEFAULT_VEHICLE_TYPE}
    if not isinstance(raw, dict):
        return None
    seen: dict[str, str] = {}
    types: dict[str, VehicleType] | None = {}
    for name, spec in raw.items():
        if not isinstance(name, str) or not check.clean(("vehicle_types", name)):
            types = None
            continue
        # vehicles.csv names types case-insensitively, so names differing only in case are ambiguous.
        if name.casefold() in seen:
            msg = f"{name!r} differs from vehicle type {seen[name.casefold()]!r} only in case"
            errors.add(suite_error(msg, ("vehicle_types",), locate(("vehicle_types", name), key=True)))
            continue
        seen[name.casefold()] = name
        if types is not None:
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


def _type_name(name: str, types: Collection[str], locate: Locate, where: tuple[Any, ...]) -> str:
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
    """``base`` with the setting keys of ``raw`` applied (values already checked by the schema); the
    first problem is raised."""
    errors = ErrorCollector()
    settings = _settings(base, raw, tuple(types), locate, where, _ALL_CLEAN, errors)
    _raise_first(errors)
    return settings


def _settings(
    base: ScenarioSettings,
    raw: Mapping[str, Any],
    types: Collection[str] | None,
    locate: Locate,
    where: tuple[Any, ...],
    check: SchemaCheck,
    errors: ErrorCollector,
) -> ScenarioSettings:
    """``base`` with the setting keys of ``raw`` applied; a value the schema refused is left out, and a
    vehicle type is looked up only when the suite's types are known (``types`` is not ``None``)."""
    changes: dict[str, Any] = {}
    for key in SETTING_KEYS:
        if key not in raw or not check.clean((*where, key)):
            continue
        value = raw[key]
        if key == "vehicle_type":
            if types is None:
                continue
            try:
                value = _type_name(value, types, locate, (*where, key))
            except SuiteError as error:
                errors.add(error)
                continue
        elif key == "stop_on":
            value = tuple(value)
        elif key == "conflict_model":
            value = ConflictModel(value)
        elif key == "checks":  # key by key over what the defaults say
            value = _checks(base.checks, value)
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            value = float(value)
        changes[key] = value
    if base.vehicle_type is None and "vehicle_type" not in changes and types is not None and len(types) == 1:
        changes["vehicle_type"] = next(iter(types))  # a suite's only vehicle type is its default
    return replace(base, **changes)


def _checks(base: Checks, raw: Mapping[str, Any]) -> Checks:
    """``base`` with the keys of a ``checks`` block applied (the schema has checked them)."""
    return Checks(
        reservations=bool(raw.get("reservations", base.reservations)),
        contact=bool(raw.get("contact", base.contact)),
        safety_margin=float(raw.get("safety_margin", base.safety_margin)),
        near_miss=float(raw.get("near_miss", base.near_miss)),
    )


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
        contacts=raw.get("contacts", "none"),
        clearance=None if raw.get("clearance") is None else float(raw["clearance"]),
        measures=tuple(
            MeasureBound(key[4:], "min" if key.startswith("min_") else "max", float(value))
            for key, value in raw.items()
            if key[:4] in ("min_", "max_") and key[4:] in MEASURES
        ),
        overloaded=raw.get("overloaded"),
    )


# -- scenarios ------------------------------------------------------------------------------------


def _check_unique_names(entries: list[Any], locate: Locate, errors: ErrorCollector) -> None:
    """Each entry whose name is already used (entries without a name are the schema's to report)."""
    # Case-insensitive: scenario names become artifact file names, and some file systems fold case.
    first: dict[str, tuple[str, int]] = {}
    for index, entry in enumerate(entries):
        name = entry.get("name") if isinstance(entry, dict) else None
        if not isinstance(name, str):
            continue
        if name.casefold() in first:
            other, other_index = first[name.casefold()]
            line = locate(("scenarios", other_index, "name")).line
            same = "" if other == name else f" (as {other!r}: names may not differ only in case)"
            msg = f"scenario name {name!r} is already used on line {line}{same}"
            where = ("scenarios", index, "name")
            errors.add(suite_error(msg, where, locate(where)))
            continue
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
    """One schema-checked scenario entry; the first problem is raised."""
    errors = ErrorCollector()
    spec = _scenario_entry(suite_path, index, entry, base, tuple(types), locate, base_options, _ALL_CLEAN, errors)
    _raise_first(errors)
    assert spec is not None
    return spec


def _scenario_entry(
    suite_path: Path,
    index: int,
    entry: Any,
    base: ScenarioSettings,
    types: Collection[str] | None,
    locate: Locate,
    base_options: Mapping[str, Any] | None,
    check: SchemaCheck,
    errors: ErrorCollector,
    base_planner: Mapping[str, Any] | None = MappingProxyType({}),
    base_orders: Mapping[str, Any] | None = MappingProxyType({}),
    base_gate: Gate | None = None,
) -> ScenarioSpec | None:
    """The entry, or ``None`` when a part of it could not be read; each problem goes to ``errors``.
    ``base_planner``: the defaults' ``planner_options`` and ``files`` (``None``: they are broken);
    ``base_orders``: the defaults' order keys (``None``: they are broken).

    A part the schema refused is not looked at further (it is reported already); the files are checked
    when the entry is whole (a misspelt ``dir`` leaves it without one, which is the same mistake).
    """
    where = ("scenarios", index)
    if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
        return None
    complete = True
    generate = None
    paths: tuple[Path, Path, Path] | None = None
    scen: ScenSetup | None = None
    lorr: LorrEntry | None = None
    files_missing = False
    if "generate" in entry:
        paths = (suite_path.parent,) * 3
        if check.clean((*where, "generate")) and types is not None:
            with errors.collecting():
                generate = _generation(entry["generate"], types, locate, (*where, "generate"))
        complete = generate is not None
    elif "scen" in entry:
        if check.intact(where) and all(check.clean((*where, key)) for key in ("scen", "map", "agents")):
            with errors.collecting():
                paths, scen = scen_files(suite_path.parent, entry, locate, where)
    elif "lorr" in entry:
        if check.intact(where) and all(
            check.clean((*where, key)) for key in ("lorr", "horizon", "agents", "task_rounds")
        ):
            with errors.collecting():
                paths, lorr = lorr_files(suite_path.parent, entry, locate, where)
    elif check.intact(where) and all(check.clean((*where, key)) for key in ("dir", "map", "vehicles", "tasks")):
        with errors.collecting():
            paths = _scenario_files(suite_path.parent, entry, locate, where)
        files_missing = paths is None
    settings = _settings(base, entry, types, locate, where, check, errors)
    if files_missing:  # a dir, say: the errors of the entry's CSV files that exist are reported with it
        check_entry_tables(suite_path.parent, entry, settings.vehicle_type, types, errors)
    disturbances = _disturbance_keys(entry, "generate" in entry, locate, where, check, errors)
    setup = None
    if paths is not None and base_planner is not None and all(check.clean((*where, k)) for k in PLANNER_KEYS):
        folder = suite_path.parent / entry["dir"] if "dir" in entry else suite_path.parent
        with errors.collecting():
            setup = planner_setup(entry, base_planner, folder, locate, where)
    orders = None
    if paths is not None and base_orders is not None:  # the keys the schema passed, so all mistakes show
        clean = {key: value for key, value in entry.items() if key not in ORDER_KEYS or check.clean((*where, key))}
        if "generate" in entry:  # its files are the schema's mistake (reported), orders.csv too
            clean.pop("orders", None)
        with errors.collecting():
            orders = _order_setup(suite_path.parent, clean, base_orders, types, locate, where)
        orders = orders if len(clean) == len(entry) else None
    expect = entry.get("expect", {})
    options = entry.get("map_options", {})
    # Read only what the schema passed (a value it refused is reported already, and is no number).
    expectations = _expectations(expect) if isinstance(expect, dict) and check.clean((*where, "expect")) else None
    gate = _gate(entry.get("gate", base_gate), expectations, locate, where, errors)
    if (
        not complete
        or paths is None
        or setup is None
        or orders is None
        or disturbances is None
        or base_options is None
        or not check.clean(where)
        or expectations is None
        or gate is None
        or not isinstance(options, dict)
    ):
        return None
    return ScenarioSpec(
        name=entry["name"],
        suite_path=suite_path,
        line=locate(where).line or 1,
        map_path=paths[0],
        vehicles_path=paths[1],
        tasks_path=paths[2],
        settings=settings,
        expect=expectations,
        gate=gate,
        tags=tuple(entry.get("tags", ())),
        xfail=entry.get("xfail"),
        description=entry.get("description", ""),
        generate=generate,
        map_options=MapOptions(**{**base_options, **options}),
        planner_setup=setup,
        order_setup=orders,
        scen=scen,
        lorr=lorr,
        **disturbances,
    )


def _gate(
    given: Gate | None, expect: Expectations | None, locate: Locate, where: tuple[Any, ...], errors: ErrorCollector
) -> Gate | None:
    """The entry's ``gate``: as given, else ``both`` when its ``expect`` bounds a measure, else ``hash``.
    A hash gate beside bounds on measures would leave them unjudged: a located error (``None``)."""
    bounded = expect is not None and (bool(expect.measures) or expect.overloaded is not None)
    if given is None:
        return "both" if bounded else "hash"
    if given == "hash" and bounded:
        msg = "'hash' leaves the expect block's bounds on measures unjudged; use 'both' (or 'measures')"
        errors.add(suite_error(msg, (*where, "gate"), locate((*where, "gate"))))
        return None
    return given


def _order_setup(
    root: Path,
    entry: Mapping[str, Any],
    defaults: Mapping[str, Any],
    types: Collection[str] | None,
    locate: Locate,
    where: tuple[Any, ...],
) -> OrderSetup:
    """The entry's order keys; vehicle types are looked up when the suite's are known."""

    def type_name(name: str, here: tuple[Any, ...]) -> str:
        return name if types is None else _type_name(name, types, locate, here)

    folder = root / entry["dir"] if "dir" in entry else None
    return order_setup(entry, defaults, root, folder, locate, where, type_name)


def _disturbance_keys(
    entry: Mapping[str, Any],
    generated: bool,
    locate: Locate,
    where: tuple[Any, ...],
    check: SchemaCheck,
    errors: ErrorCollector,
) -> dict[str, Any] | None:
    """The entry's disturbance keys as ScenarioSpec fields, or ``None`` when one could not be read."""
    keys: dict[str, Any] = {}
    complete = True
    readers: dict[str, Callable[[Any, tuple[Any, ...], Locate], object]] = {
        "disturbances": declared_disturbances,
        "random_disturbances": random_block,
        "hunt_disturbances": hunt_block,
    }
    for key, read in readers.items():
        if key not in entry:
            continue
        here = (*where, key)
        if key == "disturbances" and generated:
            msg = (
                "a generated scenario's vehicles are not known in advance: use random_disturbances or hunt_disturbances"
            )
            errors.add(suite_error(msg, here, locate(here, key=True)))
            complete = False
            continue
        if not check.clean(here):
            complete = False
            continue
        try:
            keys[key] = read(entry[key], here, locate)
        except SuiteError as error:
            errors.add(error)
            complete = False
    return keys if complete else None


def _generation(raw: Mapping[str, Any], types: Collection[str], locate: Locate, where: tuple[Any, ...]) -> Generation:
    """The ``generate`` block; every problem is raised (several as one SuiteErrors)."""
    errors = ErrorCollector()
    ranges = {}
    for key in ("size", "vehicles", "tasks"):
        if key in raw:
            low, high = raw[key]
            if low > high:
                msg = f"{key}={[low, high]!r} must be [min, max] with min <= max"
                errors.add(suite_error(msg, (*where, key), locate((*where, key))))
            ranges[key] = (low, high)
    names = []
    for k, name in enumerate(raw.get("vehicle_types", ())):
        with errors.collecting():
            names.append(_type_name(name, types, locate, (*where, "vehicle_types", k)))
    raise_suite_errors(errors)
    return Generation(
        layout=raw.get("layout", "any"),
        one_way=raw.get("one_way"),
        vehicle_types=tuple(names),
        examples=raw.get("examples", 50),
        **ranges,
    )


def _scenario_files(
    root: Path, entry: Mapping[str, Any], locate: Locate, where: tuple[Any, ...]
) -> tuple[Path, Path, Path]:
    """map, vehicles and tasks paths: named ones relative to the suite, the rest from ``dir``; every
    missing one is raised (several as one SuiteErrors)."""
    errors = ErrorCollector()
    folder = None
    if "dir" in entry:
        folder = root / entry["dir"]
        if not folder.is_dir():
            where_dir = (*where, "dir")
            errors.add(suite_error(f"no such directory: {str(folder)!r}", where_dir, locate(where_dir)))
            folder = None  # its files cannot be looked for
    paths = []
    for key, default_name in (("map", None), ("vehicles", VEHICLES_FILE_NAME), ("tasks", TASKS_FILE_NAME)):
        path = root  # stands in for what could not be found (then an error is raised)
        if key in entry:
            path = root / entry[key]
            if not path.is_file():
                errors.add(suite_error(f"no such file: {str(path)!r}", (*where, key), locate((*where, key))))
        elif folder is not None:  # the schema requires dir when a file is not named
            with errors.collecting():
                path = _folder_file(folder, default_name, (*where, "dir"), locate)
        paths.append(path)
    raise_suite_errors(errors)
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
