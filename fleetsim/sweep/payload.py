"""A scenario as plain data, and back: what a sweep sends to its workers.

Workers get no paths into the machine that planned the sweep (they may be elsewhere: SLURM, Kubernetes),
only the scenario folder's contents (``map.json``, ``vehicles.csv``, ``tasks.csv`` as written by
:func:`fleetsim.strategies.save_scenario`) with the vehicle types, settings and expectations. A scenario
sent this way runs exactly as the loaded one does (the same trace hash).
"""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path
from typing import Any

from fleetsim.enums import ConflictModel, TurnCapability
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.scenario import Disturbance, Expectations, RandomDisturbances, Scenario, ScenarioSettings, VehicleType
from fleetsim.strategies import save_scenario

__all__ = ["scenario_from_payload", "scenario_payload"]


def _plain(value: Any) -> Any:
    """Enums as their words, tuples as lists: JSON-ready."""
    if isinstance(value, (TurnCapability, ConflictModel)):
        return value.value
    if isinstance(value, tuple):
        return [_plain(item) for item in value]
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
    }


def _tuple(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value


def scenario_from_payload(payload: dict[str, Any]) -> Scenario:
    """The scenario :func:`scenario_payload` describes, loaded as any scenario folder is."""
    types = {
        data["name"]: VehicleType(
            **{**data, "turn_capability": TurnCapability(data["turn_capability"]), "color": _tuple(data.get("color"))}
        )
        for data in payload["vehicle_types"]
    }
    raw = payload["settings"]
    settings = ScenarioSettings(
        **{**raw, "stop_on": tuple(raw["stop_on"]), "conflict_model": ConflictModel(raw["conflict_model"])}
    )
    expect = Expectations(**{key: _tuple(value) for key, value in payload["expect"].items()})
    with tempfile.TemporaryDirectory(prefix="fleetsim-sweep-") as folder:
        for name, text in payload["files"].items():
            (Path(folder) / Path(name).name).write_text(text, encoding="utf-8")
        scenario = load_scenario_dir(folder, vehicle_types=types, settings=settings)
    drawn = payload.get("random_disturbances")
    return dataclasses.replace(
        scenario, name=payload["name"], expect=expect, map_path=None, vehicles_path=None, tasks_path=None,
        disturbances=tuple(Disturbance(**d) for d in payload.get("disturbances", ())),
        random_disturbances=None if drawn is None else RandomDisturbances(**{**drawn, "stop": tuple(drawn["stop"])}),
    )  # fmt: skip
