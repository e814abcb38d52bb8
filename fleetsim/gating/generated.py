"""Generated suite entries: Hypothesis hunts for a scenario the planner fails, and shrinks it.

A suite entry with ``generate`` describes scenarios instead of naming files (:class:`Generation`). The
planner runs on up to ``examples`` of them, each judged against the entry's ``expect``; the first that
fails is shrunk by Hypothesis toward a small layout with few vehicles and tasks (each shrink step is a
complete run). Under CI (``CI`` set) the search is derandomised, so a gate gives the same verdict on
every run; elsewhere each run explores new scenarios. Generated runs are not hash-gated (their hashes
would change with every new example), and a counterexample is saved as an ordinary scenario folder
with a suite entry to paste in, so the bug stays covered after it is fixed.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, Phase, find, settings
from hypothesis.errors import NoSuchExample

from fleetsim.load.scenario import default_vehicle_type
from fleetsim.load.suite import ScenarioSpec, Suite
from fleetsim.planning.protocol import Planner
from fleetsim.recording.artifacts import write_run_artifacts
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Expectations, Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult
from fleetsim.strategies import GenerationSpec, save_scenario, scenarios

__all__ = ["COUNTEREXAMPLE_FOLDER", "Hunt", "counterexample_entry", "generation_spec", "hunt", "counterexample_story", "in_ci", "record_counterexample"]

COUNTEREXAMPLE_FOLDER = "counterexample"


@dataclass(frozen=True, slots=True)
class Hunt:
    """What a hunt found: the runs it tried, and the shrunk counterexample with its run (if any)."""

    tried: int
    counterexample: Scenario | None = None
    result: RunResult | None = None


def in_ci() -> bool:
    """CI services set ``CI``; there the search is derandomised (the same scenarios every time)."""
    return os.environ.get("CI", "").lower() not in ("", "0", "false", "no")


def generation_spec(spec: ScenarioSpec, suite: Suite) -> GenerationSpec:
    """The strategy parameters of a generated entry, its vehicle types resolved in the suite."""
    generate = spec.generate
    if generate is None:
        msg = f"scenario {spec.name!r} is not generated"
        raise ValueError(msg)
    if generate.vehicle_types:
        types = tuple(suite.vehicle_types[name] for name in generate.vehicle_types)
    else:  # the type a vehicles.csv row without one gets, so a saved counterexample loads the same
        types = (default_vehicle_type(suite.vehicle_types, spec.settings) or DEFAULT_VEHICLE_TYPE,)
    return GenerationSpec(
        layout=generate.layout,
        size=generate.size,
        vehicles=generate.vehicles,
        tasks=generate.tasks,
        one_way=generate.one_way,
        vehicle_types=types,
        settings=spec.settings,
    )


def hunt(
    spec: ScenarioSpec,
    suite: Suite,
    make_planner: Callable[[], Planner],
    *,
    identity: str,
    planner_timeout: float | None = 10.0,
    derandomize: bool | None = None,
) -> Hunt:
    """Run generated scenarios of ``spec`` until one fails its ``expect``; shrink it and run it again."""
    assert spec.generate is not None
    strategy = scenarios(generation_spec(spec, suite), name=spec.name)
    tried = 0

    def judged(scenario: Scenario) -> Scenario:
        return replace(scenario, expect=spec.expect)

    def fails(scenario: Scenario) -> bool:
        nonlocal tried
        tried += 1
        run = run_scenario(judged(scenario), make_planner(), planner_name=identity, planner_timeout=planner_timeout, keep_trace=False)
        return not run.passed

    search = settings(
        max_examples=spec.generate.examples,
        derandomize=in_ci() if derandomize is None else derandomize,
        database=None,  # nothing written into the user's project; a counterexample is saved as a folder
        deadline=None,
        phases=(Phase.generate, Phase.shrink),
        suppress_health_check=list(HealthCheck),
    )
    try:
        found = find(strategy, fails, settings=search)
    except NoSuchExample:
        return Hunt(tried)
    counterexample = judged(found)
    result = run_scenario(counterexample, make_planner(), planner_name=identity, planner_timeout=planner_timeout, keep_trace=True)
    return Hunt(tried, counterexample, result)


def _expect_lines(expect: Expectations) -> list[str]:
    defaults = Expectations()
    lines = []
    for key in ("tasks", "collisions", "rejections", "deadlock", "max_makespan"):
        value = getattr(expect, key)
        if value != getattr(defaults, key):
            shown = list(value) if isinstance(value, tuple) else value
            lines.append(f"      {key}: {str(shown).lower() if isinstance(shown, bool) else shown}")
    return ["    expect:", *lines] if lines else []


def counterexample_entry(spec: ScenarioSpec, folder: Path, suite_path: Path) -> str:
    """A suite entry for the saved counterexample, to paste under ``scenarios:``."""
    where = Path(os.path.relpath(folder, suite_path.parent)).as_posix()
    lines = [
        f"  - name: {spec.name}-counterexample",
        f"    description: shrunk counterexample found by generating {spec.name}",
        f"    dir: {where}/",
        *_expect_lines(spec.expect),
    ]
    return "\n".join(lines) + "\n"


def record_counterexample(found: Hunt, folder: Path, extra: Mapping[str, Any], *, record_every: int = 1) -> dict[str, str]:
    """The shrunk counterexample's run artifacts in ``folder`` and the scenario itself as a folder
    (map, vehicles.csv, tasks.csv) under it; their paths by kind, the scenario folder as ``scenario``."""
    assert found.counterexample is not None and found.result is not None
    paths = write_run_artifacts(folder, found.result, extra, scenario=found.counterexample, record_every=record_every)
    paths["scenario"] = str(save_scenario(found.counterexample, folder / COUNTEREXAMPLE_FOLDER))
    return paths


def counterexample_story(found: Hunt, saved: str, suite: str, entry: str) -> str:
    """What a report says about a saved counterexample (paths as the reader should see them)."""
    return (
        f"Hypothesis tried {found.tried} generated scenario(s) and shrank the first failing one; it is saved as "
        f"{saved}/. To keep it as a regression scenario, add to {suite}:\n\n{entry}"
    )
