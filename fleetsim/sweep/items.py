"""A sweep spec expanded into runs: one plain-data item per (planner, scenario, repetition).

Generated sources are drawn here, on the machine that plans the sweep, reproducibly: Hypothesis's
generation phase alone, driven by a random generator seeded with the source's ``seed``, gives the same
scenarios in the same order in every process (whatever ``PYTHONHASHSEED``), and the first ``count``
distinct ones are the source's scenarios; a larger ``count`` keeps the earlier ones.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import random
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any, TypedDict

from hypothesis import HealthCheck, Phase, find, settings
from hypothesis.errors import HypothesisWarning, NoSuchExample

from fleetsim.errors import LoadError
from fleetsim.gating.generated import generation_spec, hypothesis_storage_elsewhere
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import discover_suites, load_suite
from fleetsim.scenario import RandomDisturbances, Scenario
from fleetsim.sim.record import RunOrigin
from fleetsim.strategies import scenarios
from fleetsim.sweep.payload import scenario_payload
from fleetsim.sweep.spec import GeneratedSource, SuiteSource, SweepDisturbances, SweepSpec

__all__ = ["RunItem", "expand", "generate_scenarios", "scenario_id"]


class RunItem(TypedDict):
    """One run, as plain data a worker anywhere can take (JSON-ready)."""

    key: str  # unique in the sweep: planner, scenario id, repetition
    id: str  # the scenario: SUITE::NAME (pytest's node id) or SPEC::SOURCE#INDEX for a generated one
    planner: str
    source: str  # "suite" | "generated"
    seed: int | None  # a generated scenario's own seed: the source's base seed + its index
    repetition: int
    vehicles: int  # fleet size, for the report's metric-vs-fleet-size plot
    scenario: dict[str, Any] | None  # scenario_payload(); None when it did not load
    origin: dict[str, Any]  # the suite entry, as RunOrigin's fields: suite, line, xfail, planner_options
    load_error: str | None
    planner_timeout: float | None
    record: str  # failed | all | none
    artifacts: str  # root of the run folders


def scenario_id(path: Path, name: str) -> str:
    """``path::name`` with ``path`` relative to the working directory when below it, as pytest names items."""
    relative = os.path.relpath(path)
    shown = Path(relative if not relative.startswith("..") else path.resolve()).as_posix()
    return f"{shown}::{name}"


def generate_scenarios(source: GeneratedSource) -> list[Scenario]:
    """The source's ``count`` scenarios, the same for the same seed on any machine."""
    strategy = scenarios(generation_spec(source.entry, source.suite), name=source.entry.name)
    found: list[Scenario] = []
    seen: set[str] = set()

    def collect(scenario: Scenario) -> bool:
        digest = hashlib.sha256(json.dumps(scenario_payload(scenario)["files"], sort_keys=True).encode()).hexdigest()
        if digest not in seen:
            seen.add(digest)
            found.append(scenario)
        return len(found) >= source.count

    draw = settings(
        phases=[Phase.generate], database=None, max_examples=max(100, source.count * 20), deadline=None,
        suppress_health_check=list(HealthCheck), derandomize=False,
    )  # fmt: skip
    with hypothesis_storage_elsewhere(), warnings.catch_warnings():
        warnings.filterwarnings("ignore", "Generating overly large repr", HypothesisWarning)
        with contextlib.suppress(NoSuchExample):  # fewer distinct scenarios than asked for: the space is small
            find(strategy, collect, settings=draw, random=random.Random(source.seed))
    return [_named(scenario, f"{source.entry.name}-{index}") for index, scenario in enumerate(found)]


def _named(scenario: Scenario, name: str) -> Scenario:
    return replace(scenario, name=name)


Case = tuple[str, str, int | None, Scenario | None, str | None, dict[str, Any]]


def _cases(spec: SweepSpec) -> list[Case]:
    """(id, source kind, seed, scenario or None, load error, origin) for every scenario of every source
    (with the spec's ``order_seeds``, every order stream seed; with its ``disturbances``, every disturbance
    seed); the origin is the suite entry's facts for the record (a generated source's scenarios have none)."""
    cases: list[Case] = []
    for source in spec.sources:
        if isinstance(source, SuiteSource):
            for file in discover_suites([source.path]):
                suite = load_suite(file)  # a suite that does not load stops the sweep before it starts
                for entry in suite.scenarios:
                    if entry.generate is not None or (source.name is not None and entry.name != source.name):
                        continue  # a suite's hunts are pytest's; a sweep generates through its own sources
                    key = scenario_id(file, entry.name)
                    origin = RunOrigin.of_entry(key.rpartition("::")[0], entry).keys()
                    try:
                        cases.append((key, "suite", None, load_scenario(entry, suite), None, origin))
                    except LoadError as error:
                        cases.append((key, "suite", None, None, str(error), origin))
        else:
            for index, scenario in enumerate(generate_scenarios(source)):
                cases.append(
                    (
                        f"{scenario_id(spec.path, source.entry.name)}#{index}",
                        "generated",
                        source.seed + index,
                        scenario,
                        None,
                        RunOrigin().keys(),
                    )
                )
    if spec.dispatcher is not None:
        cases = [(*case[:3], _dispatched(case[3], spec.dispatcher), *case[4:]) for case in cases]
    if spec.order_seeds is not None:
        cases = _order_seeded(cases, spec.order_seeds)
    return cases if spec.disturbances is None else _disturbed(cases, spec.disturbances)


def _dispatched(scenario: Scenario | None, dispatcher: str) -> Scenario | None:
    """The spec's dispatcher for a scenario with transport orders, whatever its suite names (as
    ``--dispatcher`` does for ``fleetsim run`` and pytest)."""
    if scenario is None or not (scenario.orders or scenario.order_stream is not None):
        return scenario
    return replace(scenario, dispatcher=dispatcher)


def _order_seeded(cases: list[Case], seeds: tuple[int, ...]) -> list[Case]:
    """Each case with an order stream once per seed (``ID~oSEED``), its stream drawn from that seed; the
    others (fixed tasks, ``orders.csv``, a scenario that did not load) once, as they are."""
    out: list[Case] = []
    for key, kind, seed, scenario, error, origin in cases:
        stream = None if scenario is None else scenario.order_stream
        if scenario is None or stream is None:
            out.append((key, kind, seed, scenario, error, origin))
            continue
        for drawn in seeds:
            seeded = replace(scenario, order_stream=replace(stream, seed=drawn))
            out.append((f"{key}~o{drawn}", kind, seed, seeded, error, origin))
    return out


def _disturbed(cases: list[Case], drawn: SweepDisturbances) -> list[Case]:
    """Each case once per disturbance seed (``ID~dSEED``), with random stops drawn from that seed."""
    out: list[Case] = []
    for key, kind, seed, scenario, error, origin in cases:
        for stops in drawn.seeds:
            random_stops = RandomDisturbances(stops, drawn.stops_per_vehicle_hour, drawn.stop)
            disturbed = None if scenario is None else replace(scenario, random_disturbances=random_stops)
            out.append((f"{key}~d{stops}", kind, seed, disturbed, error, origin))
    return out


def expand(spec: SweepSpec, artifacts: Path) -> list[RunItem]:
    """Every run of the sweep, ordered by key (the order is irrelevant to the results, but fixed)."""
    items: list[RunItem] = []
    for scenario_key, kind, seed, scenario, error, origin in _cases(spec):
        payload = scenario_payload(scenario) if scenario is not None else None
        for planner in spec.planners:
            for repetition in range(1, spec.repetitions + 1):
                items.append(
                    RunItem(
                        key=f"{planner} | {scenario_key} | {repetition}",
                        id=scenario_key if repetition == 1 else f"{scenario_key}@{repetition}",
                        planner=planner,
                        source=kind,
                        seed=seed,
                        repetition=repetition,
                        vehicles=len(scenario.vehicles) if scenario is not None else 0,
                        scenario=payload,
                        origin=origin,
                        load_error=error,
                        planner_timeout=spec.planner_timeout,
                        record=spec.record,
                        artifacts=str(artifacts.resolve()),
                    )
                )
    return sorted(items, key=lambda item: item["key"])
