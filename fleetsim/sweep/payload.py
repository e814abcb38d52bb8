"""A scenario as plain data, and back: what a sweep sends to its workers.

Workers get no paths into the machine that planned the sweep (they may be elsewhere: SLURM, Kubernetes),
only the scenario folder's contents (``map.json``, ``vehicles.csv``, ``tasks.csv`` as written by
:func:`fleetsim.strategies.save_scenario`) with the vehicle types, settings and expectations (bounds on
measures included), the transport orders (and their pool), order stream, station sets, shift and dispatcher spec of a
scenario with orders (and the League problem it came from), and what the suite entry gives its planner: its ``planner_options`` and the bytes of
its data ``files`` (a folder listed there sends every file below it), which a worker puts at the same
relative paths in the folder its planner gets as ``scenario_dir``. A scenario sent this way runs exactly as
the loaded one does (the same trace hash).
"""

from __future__ import annotations

import base64
import dataclasses
import enum
import tempfile
from collections.abc import Mapping
from pathlib import Path, PurePosixPath
from types import MappingProxyType
from typing import Any

from fleetsim.enums import ConflictModel, Progress, TurnCapability
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.orders import Arrivals, LorrSetup, MeasureBound, Order, OrderStream, Shift, Station, Stop, StopDraw
from fleetsim.scenario import (
    Checks,
    Disturbance,
    Expectations,
    PlannerSetup,
    RandomDisturbances,
    Scenario,
    ScenarioSettings,
    VehicleType,
)
from fleetsim.strategies import save_scenario

__all__ = ["scenario_from_payload", "scenario_payload"]


def _plain(value: Any) -> Any:
    """Enums as their words, tuples as lists, dataclasses and mappings as objects: JSON-ready."""
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, (tuple, list)):
        return [_plain(item) for item in value]
    if isinstance(value, Mapping):
        return {str(key): _plain(item) for key, item in value.items()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    return value


def scenario_payload(scenario: Scenario) -> dict[str, Any]:
    """``scenario`` as JSON-ready data: its folder's files, vehicle types, settings and ``expect``."""
    with tempfile.TemporaryDirectory(prefix="fleetsim-sweep-") as folder:
        save_scenario(scenario, Path(folder))
        files = {path.name: path.read_text(encoding="utf-8") for path in sorted(Path(folder).iterdir())}
    return {
        "name": scenario.name,
        "files": files,
        "vehicle_types": [
            {f.name: _plain(getattr(vt, f.name)) for f in dataclasses.fields(vt)}
            for vt in scenario.vehicle_types.values()
        ],
        "settings": {f.name: _plain(getattr(scenario.settings, f.name)) for f in dataclasses.fields(scenario.settings)},
        "expect": {f.name: _plain(getattr(scenario.expect, f.name)) for f in dataclasses.fields(scenario.expect)},
        "disturbances": [dataclasses.asdict(d) for d in scenario.disturbances],
        "random_disturbances": None
        if scenario.random_disturbances is None
        else dataclasses.asdict(scenario.random_disturbances),
        "planner_setup": _setup_payload(scenario.planner_setup),
        "orders": _plain(scenario.orders),
        "order_pool": scenario.order_pool,
        "order_stream": _plain(scenario.order_stream),
        "stations": _plain(scenario.stations),
        "shift": _plain(scenario.shift),
        "dispatcher": scenario.dispatcher,
        "lorr": _plain(scenario.lorr),
    }


def _setup_payload(setup: PlannerSetup) -> dict[str, Any]:
    """The entry's planner options and the bytes of its data files (base64), by path in its folder."""
    files: dict[str, str] = {}
    for name in setup.files:
        assert setup.folder is not None  # the suite loader gives files a folder and checks they are in it
        path = setup.folder / name
        for found in sorted(path.rglob("*")) if path.is_dir() else [path]:
            if found.is_file():
                relative = found.relative_to(setup.folder).as_posix()
                files[relative] = base64.b64encode(found.read_bytes()).decode("ascii")
    return {"options": dict(setup.options), "where": setup.where, "files": files}


def _tuple(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value


def scenario_from_payload(payload: dict[str, Any], scenario_dir: Path | None = None) -> Scenario:
    """The scenario :func:`scenario_payload` describes, loaded as any scenario folder is; the entry's data
    files are written into ``scenario_dir`` (which must outlive the run), the folder its planner gets."""
    types = {
        data["name"]: VehicleType(
            **{**data, "turn_capability": TurnCapability(data["turn_capability"]), "color": _tuple(data.get("color"))}
        )
        for data in payload["vehicle_types"]
    }
    raw = payload["settings"]
    settings = ScenarioSettings(**{
        **raw, "stop_on": tuple(raw["stop_on"]), "conflict_model": ConflictModel(raw["conflict_model"]),
        "checks": Checks(**raw["checks"]),
    })  # fmt: skip
    sent = payload["expect"]
    bounds = tuple(MeasureBound(**bound) for bound in sent.get("measures", ()))
    expect = Expectations(**{key: _tuple(value) for key, value in sent.items() if key != "measures"}, measures=bounds)
    with tempfile.TemporaryDirectory(prefix="fleetsim-sweep-") as folder:
        for name, text in payload["files"].items():
            (Path(folder) / Path(name).name).write_text(text, encoding="utf-8")
        scenario = load_scenario_dir(folder, vehicle_types=types, settings=settings)
    drawn = payload.get("random_disturbances")
    return dataclasses.replace(
        scenario, name=payload["name"], expect=expect, map_path=None, vehicles_path=None, tasks_path=None,
        disturbances=tuple(Disturbance(**d) for d in payload.get("disturbances", ())),
        random_disturbances=None if drawn is None else RandomDisturbances(**{**drawn, "stop": tuple(drawn["stop"])}),
        planner_setup=_setup_from(payload.get("planner_setup"), scenario_dir),
        orders=tuple(_order(order) for order in payload.get("orders", ())),
        order_pool=payload.get("order_pool"),
        order_stream=_stream(payload.get("order_stream")),
        stations=MappingProxyType({
            name: tuple(Station(**station) for station in members) for name, members in payload.get("stations", {}).items()
        }),
        shift=None if payload.get("shift") is None else Shift(**payload["shift"]),
        dispatcher=payload.get("dispatcher"),
        lorr=_lorr(payload.get("lorr")),
    )  # fmt: skip


def _lorr(sent: dict[str, Any] | None) -> LorrSetup | None:
    return None if sent is None else LorrSetup(**{**sent, "not_mapped": tuple(sent["not_mapped"])})


def _progress(value: str | None) -> Progress | None:
    return None if value is None else Progress(value)


def _names(value: list[str] | None) -> tuple[str, ...] | None:
    return None if value is None else tuple(value)


def _order(sent: dict[str, Any]) -> Order:
    """An order as :func:`scenario_payload` sent it (its ``orders.csv`` line kept, for messages)."""
    stops = tuple(Stop(stop["segment"], _progress(stop["progress"]), stop["dwell"]) for stop in sent["stops"])
    return Order(
        sent["id"], stops, sent["release"], sent["deadline"], _names(sent["vehicle_types"]), sent["priority"],
        sent["line"],
    )  # fmt: skip


def _stream(sent: dict[str, Any] | None) -> OrderStream | None:
    """An order stream as :func:`scenario_payload` sent it."""
    if sent is None:
        return None
    draws = tuple(
        StopDraw(tuple(d["stations"]), d["weighted"], tuple(d["dwell"]), tuple(d["count"]), _progress(d["progress"]))
        for d in sent["stops"]
    )
    return OrderStream(
        sent["seed"], Arrivals(**sent["arrivals"]), draws, sent["deadline"], _names(sent["vehicle_types"]),
        sent["priority"], sent["limit"],
    )  # fmt: skip


def _setup_from(sent: dict[str, Any] | None, folder: Path | None) -> PlannerSetup:
    """The planner setup a payload sent, its data files written below ``folder``."""
    if sent is None:
        return PlannerSetup(folder=folder)
    for name, data in sent["files"].items():
        path = PurePosixPath(name)
        if path.is_absolute() or ".." in path.parts or folder is None:  # only what scenario_payload writes
            msg = f"planner_setup.files: {name!r} must be a path inside the scenario's folder"
            raise ValueError(msg)
        target = folder.joinpath(*path.parts)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(base64.b64decode(data))
    files = tuple(sorted(sent["files"]))
    return PlannerSetup(MappingProxyType(dict(sent["options"])), folder, files, sent.get("where", ""))
