"""Sweep specs: which planners run on which scenarios, how often (``fleetsim sweep SPEC.yaml``).

A sweep spec is YAML::

    fleetsim-sweep: 1
    name: reserving-vs-bfs
    planners: [fleetsim.planners:ReservingPlanner, fleetsim.planners:BFSPlanner]
    baseline: fleetsim.planners:ReservingPlanner     # the report's reference (default: the first planner)
    repetitions: 1                                   # runs of each (planner, scenario)
    planner_timeout: 10                              # s per planner call (exec: planners; 0 = none)
    record: failed                                   # failed | all | none: runs that keep their artifacts
    vehicle_types: {...}                             # as in a suite, for generated sources
    defaults: {time_limit: 60}                       # as in a suite, for generated sources
    dispatcher: mypkg.dispatch:MyDispatcher          # of every scenario with orders, whatever its suite names
    order_seeds: [1, 2, 3]                           # each scenario with an order stream once per seed
    sources:
      - suite: ../scenario_suites/examples.fleetsim.yaml   # a suite file or folder; FILE::NAME for one
      - name: warehouses                                   # a suite entry with 'generate', plus:
        generate: {layout: warehouse, size: [1, 2], vehicles: [2, 3], tasks: [1, 2]}
        count: 20                                          # scenarios to generate
        seed: 1                                            # base seed: the same scenarios every time

Generated sources are checked exactly as suite entries are (the suite schema, vehicle types, room for
the vehicles); every mistake is one :class:`SweepSpecError` at the file, line and column of the value.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from fleetsim.errors import LoadError, Location, SuiteError
from fleetsim.exec.spec import EXEC_PREFIX, VDA5050_PREFIX
from fleetsim.gating.generated import check_generate_block
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.yaml_source import Locate, YamlPath, load_yaml_with_marks
from fleetsim.load.suites.schema import check_against_schema, suite_schema
from fleetsim.load.suites.suite import (
    ScenarioSpec,
    Suite,
    load_suite,
    parse_scenario_entry,
    parse_settings,
    parse_vehicle_types,
)
from fleetsim.scenario import ScenarioSettings

__all__ = [
    "FORMAT",
    "GeneratedSource",
    "SuiteSource",
    "SweepDisturbances",
    "SweepSpec",
    "SweepSpecError",
    "load_sweep_spec",
]

FORMAT = 1
Record = Literal["failed", "all", "none"]
_KEYS = {
    "fleetsim-sweep",
    "name",
    "description",
    "planners",
    "baseline",
    "repetitions",
    "planner_timeout",
    "record",
    "vehicle_types",
    "defaults",
    "sources",
    "disturbances",
    "dispatcher",
    "order_seeds",
}
_SOURCE_KEYS = ("count", "seed")  # what a generated source adds to a suite entry
_DISTURBANCE_KEYS = ("seeds", "stop", "stops_per_vehicle_hour")


class SweepSpecError(LoadError):
    """A sweep spec is unusable; the message names the file, line, column and the bad value."""


@dataclass(frozen=True, slots=True)
class SuiteSource:
    """Every scenario of a suite file (or of the suites below a folder), or one (``name``)."""

    path: Path
    name: str | None = None


@dataclass(frozen=True, slots=True)
class GeneratedSource:
    """``count`` scenarios drawn from a generate block, reproducibly from ``seed``."""

    entry: ScenarioSpec  # the source as a suite entry (its generate block, settings and expect)
    suite: Suite  # the sweep spec read as a suite: its vehicle types
    count: int
    seed: int


@dataclass(frozen=True, slots=True)
class SweepDisturbances:
    """Every scenario runs once per seed with random stops drawn from it (a suite's
    ``random_disturbances`` with that seed, in place of any of its own)."""

    stops_per_vehicle_hour: float
    stop: tuple[float, float]
    seeds: tuple[int, ...]


@dataclass(frozen=True, slots=True)
class SweepSpec:
    path: Path
    name: str
    planners: tuple[str, ...]
    baseline: str
    repetitions: int
    planner_timeout: float | None
    record: Record
    sources: tuple[SuiteSource | GeneratedSource, ...]
    disturbances: SweepDisturbances | None = None
    dispatcher: str | None = None  # module:attr, for every scenario with transport orders
    order_seeds: tuple[int, ...] | None = None  # every scenario with an order stream runs once per seed


def _error(problem: str, locate: Locate, where: YamlPath, *, key: bool = False) -> SweepSpecError:
    return SweepSpecError(problem, locate(where, key=key))


def load_sweep_spec(path: Path | str) -> SweepSpec:
    """Read and check a sweep spec; every problem is one :class:`SweepSpecError`, located."""
    path = Path(path)
    data, locate = load_yaml_with_marks(path, error_type=SweepSpecError)
    if not isinstance(data, dict):
        raise SweepSpecError(
            f"a sweep spec must be a mapping with 'fleetsim-sweep: {FORMAT}', 'planners' and 'sources'",
            Location(path, 1),
        )
    _known_keys(data, sorted(_KEYS), locate, ())
    if data.get("fleetsim-sweep") != FORMAT:
        raise _error(
            f"fleetsim-sweep={data.get('fleetsim-sweep')!r} must be {FORMAT} (the sweep format version)",
            locate,
            ("fleetsim-sweep",),
        )
    planners = _planners(data.get("planners"), locate)
    baseline = data.get("baseline", planners[0])
    if baseline not in planners:
        raise _error(
            f"baseline={baseline!r} must be one of the planners ({', '.join(planners)})", locate, ("baseline",)
        )
    repetitions = _whole(data, "repetitions", 1, 1, locate)
    timeout = data.get("planner_timeout", 10)
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not timeout >= 0:
        raise _error(
            f"planner_timeout={timeout!r} must be a number of seconds >= 0 (0: none)", locate, ("planner_timeout",)
        )
    record = data.get("record", "failed")
    if record not in ("failed", "all", "none"):
        raise _error(f"record={record!r} must be failed, all or none", locate, ("record",))
    name = data.get("name", path.name.removesuffix(".yaml").removesuffix(".yml"))
    if not isinstance(name, str) or not name:
        raise _error(f"name={name!r} must be a non-empty string", locate, ("name",))
    return SweepSpec(
        path=path,
        name=name,
        planners=planners,
        baseline=baseline,
        repetitions=repetitions,
        planner_timeout=float(timeout) or None,
        record=record,
        sources=_sources(path, data, locate),
        disturbances=_disturbances(data.get("disturbances"), locate),
        dispatcher=_dispatcher(data.get("dispatcher"), locate),
        order_seeds=None if "order_seeds" not in data else _seeds(data["order_seeds"], locate, ("order_seeds",)),
    )


def _known_keys(
    data: Mapping[Any, Any], known: list[str], locate: Locate, where: YamlPath, what: str = "", *, listed: bool = True
) -> None:
    """An unknown key is an error at the key, with the closest known one (as suites say it) and, when
    ``listed``, all of them."""
    for key in data:
        if key not in known:
            hint = did_you_mean(str(key), known)
            every = f" (known: {', '.join(known)})" if listed else ""
            raise _error(f"{what}unknown key {key!r}{hint}{every}", locate, (*where, key), key=True)


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _disturbances(raw: Any, locate: Locate) -> SweepDisturbances | None:
    """``disturbances: {stops_per_vehicle_hour: R, stop: [MIN, MAX], seeds: [S, ...]}``, or None."""
    if raw is None:
        return None
    where: YamlPath = ("disturbances",)
    if isinstance(raw, dict):
        _known_keys(raw, list(_DISTURBANCE_KEYS), locate, where, "disturbances: ")
    if not isinstance(raw, dict) or "seeds" not in raw:
        raise _error(
            f"disturbances={raw!r} must be {{stops_per_vehicle_hour: R, stop: [MIN, MAX], seeds: [S, ...]}}",
            locate,
            where,
        )
    rate = raw.get("stops_per_vehicle_hour", 6)
    if not _number(rate) or not rate > 0:
        raise _error(
            f"stops_per_vehicle_hour={rate!r} must be a number > 0", locate, (*where, "stops_per_vehicle_hour")
        )
    stop = raw.get("stop", [5, 30])
    if not (isinstance(stop, list) and len(stop) == 2 and all(map(_number, stop)) and 0 < stop[0] <= stop[1]):
        raise _error(f"stop={stop!r} must be [MIN, MAX] seconds with 0 < MIN <= MAX", locate, (*where, "stop"))
    return SweepDisturbances(
        float(rate), (float(stop[0]), float(stop[1])), _seeds(raw["seeds"], locate, (*where, "seeds"))
    )


def _seeds(seeds: Any, locate: Locate, where: YamlPath) -> tuple[int, ...]:
    """A non-empty list of whole numbers >= 0, each once."""
    name = str(where[-1])
    if not isinstance(seeds, list) or not seeds:
        raise _error(f"{name}={seeds!r} must be a non-empty list of whole numbers >= 0", locate, where)
    for index, seed in enumerate(seeds):
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0 or seeds.index(seed) != index:
            raise _error(f"{name}[{index}]={seed!r} must be a whole number >= 0, listed once", locate, (*where, index))
    return tuple(seeds)


def _dispatcher(raw: Any, locate: Locate) -> str | None:
    """``dispatcher: module:attr``: its form only; workers import it (one that does not import there fails
    its runs, as a planner does)."""
    if raw is None:
        return None
    if not isinstance(raw, str) or not re.fullmatch(r"[\w.]+:[\w.]+", raw):
        raise _error(
            f"dispatcher={raw!r} must be a dispatcher spec, module:attr (e.g. fleetsim.dispatchers:NearestVehicleDispatcher)",
            locate,
            ("dispatcher",),
        )
    return raw


def _planners(raw: Any, locate: Locate) -> tuple[str, ...]:
    if not isinstance(raw, list) or not raw:
        raise _error(
            f"planners={raw!r} must be a non-empty list of planner specs (module:attr, exec:COMMAND or vda5050:...)",
            locate,
            ("planners",),
        )
    for index, spec in enumerate(raw):
        if not isinstance(spec, str) or not (
            spec.startswith((EXEC_PREFIX, VDA5050_PREFIX)) or re.fullmatch(r"[\w.]+:[\w.]+", spec)
        ):
            raise _error(
                f"planners[{index}]={spec!r} must be a planner spec: module:attr, exec:COMMAND or vda5050:...",
                locate,
                ("planners", index),
            )
        if raw.index(spec) != index:
            raise _error(f"planners[{index}]={spec!r} is listed twice", locate, ("planners", index))
    return tuple(raw)


def _whole(data: Mapping[str, Any], key: str, default: int, minimum: int, locate: Locate, where: YamlPath = ()) -> int:
    value = data.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise _error(f"{key}={value!r} must be a whole number >= {minimum}", locate, (*where, key))
    return value


def _sources(path: Path, data: Mapping[str, Any], locate: Locate) -> tuple[SuiteSource | GeneratedSource, ...]:
    raw = data.get("sources")
    if not isinstance(raw, list) or not raw:
        raise _error(
            f"sources={raw!r} must be a non-empty list of suites ('suite: PATH') and generated sources",
            locate,
            ("sources",),
        )
    entry_keys = sorted([*suite_schema()["$defs"]["scenario"]["properties"], *_SOURCE_KEYS])
    for index, source in enumerate(raw):
        if isinstance(source, dict):  # a generated source, a suite source, or a typo of either
            known = ["suite"] if "suite" in source else entry_keys if "generate" in source else ["suite", *entry_keys]
            _known_keys(source, known, locate, ("sources", index), f"sources[{index}]: ", listed=known == ["suite"])
    generated = [index for index, source in enumerate(raw) if isinstance(source, dict) and "generate" in source]
    suite = _as_suite(path, data, generated, locate)
    sources: list[SuiteSource | GeneratedSource] = []
    for index, source in enumerate(raw):
        if isinstance(source, dict) and "generate" in source:
            entry = suite.scenarios[generated.index(index)]
            count = _whole(source, "count", 1, 1, locate, ("sources", index))
            seed = _whole(source, "seed", 0, 0, locate, ("sources", index))
            sources.append(GeneratedSource(entry, suite, count, seed))
        elif isinstance(source, dict) and set(source) == {"suite"} and isinstance(source["suite"], str):
            sources.append(_suite_source(path, source["suite"], locate, ("sources", index, "suite")))
        else:
            raise _error(
                f"sources[{index}]={source!r} must be 'suite: PATH' or a suite entry with 'generate', 'count' and 'seed'",
                locate,
                ("sources", index),
            )
    return tuple(sources)


def _suite_source(path: Path, text: str, locate: Locate, where: YamlPath) -> SuiteSource:
    file, _, name = text.partition("::")
    target = path.parent / file
    if not target.exists():
        raise _error(f"suite={text!r}: {target} does not exist (paths are relative to the sweep spec)", locate, where)
    if name:
        try:
            names = [spec.name for spec in load_suite(target).scenarios]
        except LoadError as error:
            raise SweepSpecError(f"suite={text!r} does not load: {error}", locate(where)) from None
        if name not in names:
            raise _error(
                f"suite={text!r}: {file} has no scenario {name!r} (its scenarios: {', '.join(names)})", locate, where
            )
    return SuiteSource(target, name or None)


def _as_suite(path: Path, data: Mapping[str, Any], generated: list[int], locate: Locate) -> Suite:
    """The spec's vehicle types, defaults and generated sources read as a suite, so they are checked (and
    mean) exactly what they would in a suite file; errors point into the sweep spec."""
    entries = [{k: v for k, v in data["sources"][i].items() if k not in _SOURCE_KEYS} for i in generated]
    as_suite = {"fleetsim": 1, "name": "sweep", "scenarios": entries or [{"name": "none", "dir": "."}]}
    as_suite.update({k: data[k] for k in ("vehicle_types", "defaults") if k in data})

    def remapped(path: YamlPath, *, key: bool = False) -> Location:
        if len(path) >= 2 and path[0] == "scenarios" and isinstance(path[1], int) and path[1] < len(generated):
            path = ("sources", generated[path[1]], *path[2:])
        return locate(path, key=key)

    try:
        check_against_schema(as_suite, remapped)
        types = parse_vehicle_types(data.get("vehicle_types"), remapped)
        base = parse_settings(ScenarioSettings(), data.get("defaults", {}), types, remapped, ("defaults",))
        specs = tuple(
            parse_scenario_entry(path, k, entry, base, types, remapped, {}) for k, entry in enumerate(entries)
        )
        suite = Suite(path, str(data.get("name", "sweep")), "", types, specs)
        for spec in specs:
            check_generate_block(spec, suite)
    except SuiteError as error:
        problem = re.sub(r"^scenarios\[(\d+)\]", lambda m: f"sources[{generated[int(m.group(1))]}]", error.problem)
        raise SweepSpecError(problem, error.location) from None
    return suite
