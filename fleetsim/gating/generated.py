"""Generated suite entries: Hypothesis hunts for a scenario the planner fails, and shrinks it.

A suite entry with ``generate`` describes scenarios instead of naming files (:class:`Generation`). The
planner runs on up to ``examples`` of them, each judged against the entry's ``expect``; the first that
fails is shrunk by Hypothesis toward a small layout with few vehicles and tasks (each shrink step is a
complete run). Under CI (``CI`` set) the search is derandomised, so a gate gives the same verdict on
every run; elsewhere each run explores new scenarios. Generated runs are not hash-gated (their hashes
would change with every new example), and a counterexample is saved as an ordinary scenario folder
with a suite entry to paste in, so the bug stays covered after it is fixed.

A hunt writes nothing into the working directory: Hypothesis gets no example database (a
counterexample is kept as a scenario folder instead) and keeps its caches, which it would otherwise
put in ``.hypothesis/`` under the working directory, in a temporary folder removed afterwards.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, Phase, configuration, find, settings
from hypothesis.errors import HypothesisWarning, NoSuchExample
from hypothesis.strategies import SearchStrategy

from fleetsim.errors import Location, SuiteError
from fleetsim.gating.disturbance_hunt import disturbance_lines, disturbed, stop_schedules
from fleetsim.gating.verify import in_ci
from fleetsim.load.suites.scenario import default_vehicle_type, load_scenario
from fleetsim.load.suites.suite import ScenarioSpec, Suite
from fleetsim.planning.protocol import Planner
from fleetsim.recording.artifacts import start_run_folder, write_run_artifacts
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Disturbance, Expectations, Scenario
from fleetsim.sim.interrupt import StopSignals
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.record import RunOrigin
from fleetsim.sim.result import RunResult
from fleetsim.strategies import GenerationSpec, NoRoomError, save_scenario, scenarios

__all__ = [
    "COUNTEREXAMPLE_FOLDER",
    "DEFAULT_ARTIFACTS",
    "Hunt",
    "check_generate_block",
    "counterexample_entry",
    "counterexample_story",
    "counts_story",
    "generation_spec",
    "hunt",
    "hunt_facts",
    "hunt_label",
    "hypothesis_storage_elsewhere",
    "in_ci",
    "record_counterexample",
]

COUNTEREXAMPLE_FOLDER = "counterexample"
DEFAULT_ARTIFACTS = Path("fleetsim-results")  # under the working directory, as pytest's --fleetsim-artifacts


@dataclass(frozen=True, slots=True)
class Hunt:
    """What a hunt ran and found.

    ``generated``: scenarios Hypothesis generated and the planner ran on (at most the entry's
    ``examples``; when one failed, it is the last of them). ``shrink_runs``: runs of smaller variants
    of the failing one while Hypothesis shrank it, its final replay of the shrunk one included.
    ``counterexample`` and ``result``: the shrunk scenario and one more run of it that keeps the trace
    for the recording; without a counterexample, ``result`` is the last generated scenario's run (an
    ``interrupted`` one when a stop signal ended the hunt: nothing is shrunk then).
    """

    generated: int
    shrink_runs: int = 0
    counterexample: Scenario | None = None
    result: RunResult | None = None

    @property
    def ran(self) -> int:
        """Every run of the hunt: generated, shrink runs and the recorded run of the counterexample."""
        return self.generated + self.shrink_runs + (self.counterexample is not None)


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


def check_generate_block(spec: ScenarioSpec, suite: Suite) -> None:
    """Raise the located :class:`SuiteError` of a generate block no layout has room for; else nothing."""
    _strategy(spec, suite)


def _strategy(spec: ScenarioSpec, suite: Suite) -> SearchStrategy[Scenario]:
    """The entry's scenarios strategy; a generate block no layout has room for is a :class:`SuiteError`.
    With ``hunt_disturbances`` each scenario (the entry's own, or each generated one) gets stops drawn."""
    if spec.generate is None:
        assert spec.hunt_disturbances is not None
        base = load_scenario(spec, suite)
        return stop_schedules(base, spec.hunt_disturbances).map(
            lambda ds: replace(base, disturbances=base.disturbances + ds)
        )
    try:
        generated = scenarios(generation_spec(spec, suite), name=spec.name)
        return generated if spec.hunt_disturbances is None else disturbed(generated, spec.hunt_disturbances)
    except NoRoomError as error:
        problem = error.describe(
            f"generate.vehicles={list(error.vehicles)!r}", f"size {list(error.size)!r}", "larger layouts (size)"
        )
        raise SuiteError(
            f"scenario {spec.name!r}: {problem}", Location(spec.suite_path, spec.line, field="generate")
        ) from None


class _Stopped(BaseException):
    """A stop signal ended a run of the hunt: Hypothesis must not take it for a failure to shrink (it
    lets a BaseException through)."""


@contextmanager
def hypothesis_storage_elsewhere() -> Iterator[None]:
    """Hypothesis's caches in a temporary folder for the hunt, not ``.hypothesis/`` in the working
    directory; whatever folder it used before (the user's own tests may run in this process) after."""
    before = vars(configuration).get("__hypothesis_home_directory")
    with tempfile.TemporaryDirectory(prefix="fleetsim-hypothesis-") as folder:
        configuration.set_hypothesis_home_dir(folder)
        try:
            yield
        finally:
            configuration.set_hypothesis_home_dir(before)


def hunt(
    spec: ScenarioSpec,
    suite: Suite,
    make_planner: Callable[[], Planner],
    *,
    identity: str,
    planner_timeout: float | None = 10.0,
    derandomize: bool | None = None,
    stop: StopSignals | None = None,
    record_to: tuple[Path, Mapping[str, Any]] | None = None,
) -> Hunt:
    """Run generated scenarios of ``spec`` until one fails its ``expect``; shrink it and run it again.

    A generate block no layout of its size has room for is a :class:`SuiteError` before anything runs.
    ``stop``: the active stop signals; a run they interrupt ends the hunt. ``record_to``: the artifact
    folder of the counterexample and its ``run.json`` content; its last run streams its trace there
    (:func:`record_counterexample` with ``streamed=True`` completes the folder).
    """
    assert spec.hunts
    strategy = _strategy(spec, suite)
    generated = shrink_runs = 0
    shrinking = False
    last: RunResult | None = None  # a passing hunt's summary row shows the last run

    def judged(scenario: Scenario) -> Scenario:
        return replace(scenario, expect=spec.expect)

    def fails(scenario: Scenario) -> bool:
        nonlocal generated, shrink_runs, shrinking, last
        # find() reports one bug, so Hypothesis stops generating at the first failure: every run after
        # it is a shrink run.
        if shrinking:
            shrink_runs += 1
        else:
            generated += 1
        last = run_scenario(
            judged(scenario),
            make_planner(),
            planner_name=identity,
            planner_timeout=planner_timeout,
            keep_trace=False,
            stop=stop,
        )
        if last.ended == "interrupted":
            raise _Stopped
        shrinking = shrinking or not last.passed
        return not last.passed

    search = settings(
        max_examples=spec.hunt_examples,
        derandomize=in_ci() if derandomize is None else derandomize,
        database=None,  # a counterexample is saved as a scenario folder instead
        deadline=None,
        phases=(Phase.generate, Phase.shrink),
        suppress_health_check=list(HealthCheck),
    )
    try:
        with hypothesis_storage_elsewhere(), warnings.catch_warnings():
            # find() describes the failing example for a report it does not show; a scenario's repr
            # is large, and the warning about that would only confuse (the counterexample is saved).
            warnings.filterwarnings("ignore", "Generating overly large repr", HypothesisWarning)
            found = find(strategy, fails, settings=search)
    except NoSuchExample:
        return Hunt(generated, result=last)
    except _Stopped:
        return Hunt(generated, shrink_runs, result=last)
    counterexample = judged(found)
    trace_file = start_run_folder(*record_to) if record_to is not None else None
    result = run_scenario(
        counterexample, make_planner(), planner_name=identity, planner_timeout=planner_timeout, keep_trace=True, stop=stop,
        trace_file=trace_file,
    )  # fmt: skip
    return Hunt(generated, shrink_runs, counterexample, result)


def _expect_lines(expect: Expectations) -> list[str]:
    defaults = Expectations()
    lines = []
    for key in ("tasks", "collisions", "rejections", "deadlock", "max_makespan"):
        value = getattr(expect, key)
        if value != getattr(defaults, key):
            shown = list(value) if isinstance(value, tuple) else value
            lines.append(f"      {key}: {str(shown).lower() if isinstance(shown, bool) else shown}")
    return ["    expect:", *lines] if lines else []


def counterexample_entry(
    spec: ScenarioSpec, folder: Path, suite_path: Path, disturbances: tuple[Disturbance, ...] = ()
) -> str:
    """A suite entry for the saved counterexample, to paste under ``scenarios:`` (with the
    disturbances of its run as a ``disturbances:`` list)."""
    where = Path(os.path.relpath(folder, suite_path.parent)).as_posix()
    lines = [
        f"  - name: {spec.name}-counterexample",
        f"    description: shrunk counterexample found by {'generating' if spec.generate is not None else 'hunting disturbances in'} {spec.name}",
        f"    dir: {where}/",
        *_expect_lines(spec.expect),
        *disturbance_lines(disturbances),
    ]
    return "\n".join(lines) + "\n"


def record_counterexample(
    found: Hunt, folder: Path, origin: RunOrigin, *, record_every: int = 1, streamed: bool = False
) -> dict[str, str]:
    """The shrunk counterexample's run artifacts in ``folder`` (its ``result.json`` the record of a run
    from ``origin``) and the scenario itself as a folder (map, vehicles.csv, tasks.csv) under it; their
    paths by kind, the scenario folder as ``scenario``. ``streamed``: its run streamed its trace into
    ``folder`` (``hunt``'s ``record_to``)."""
    assert found.counterexample is not None and found.result is not None
    paths = write_run_artifacts(
        folder, found.result, origin, scenario=found.counterexample, record_every=record_every, streamed=streamed
    )
    paths["scenario"] = str(save_scenario(found.counterexample, folder / COUNTEREXAMPLE_FOLDER))
    return paths


def counts_story(found: Hunt, examples: int) -> str:
    """How many scenarios a hunt ran, in words."""
    if found.counterexample is None:
        return f"Hypothesis ran {found.generated} generated scenario(s) (at most {examples}, the entry's examples); none failed."
    return (
        f"Hypothesis ran {found.generated} generated scenario(s) (at most {examples}, the entry's examples); the last failed, "
        f"and {found.shrink_runs} shrink run(s) reduced it to a counterexample, which ran once more to be recorded "
        f"({found.ran} runs in all)."
    )


def counterexample_story(found: Hunt, examples: int, saved: str, suite: str, entry: str) -> str:
    """What a report says about a saved counterexample (paths as the reader should see them)."""
    return f"{counts_story(found, examples)} It is saved as {saved}/. To keep it as a regression scenario, add to {suite}:\n\n{entry}"


def hunt_label(name: str, found: Hunt) -> str:
    """The entry's name in a summary table, with what its hunt ran."""
    if found.counterexample is None:
        return f"{name} ({found.generated} generated)"
    return f"{name} ({found.generated} generated, {found.shrink_runs} shrink runs)"


def hunt_facts(found: Hunt) -> dict[str, int]:
    """The counts a result document records for a generated entry."""
    return {"generated": found.generated, "shrink_runs": found.shrink_runs}
