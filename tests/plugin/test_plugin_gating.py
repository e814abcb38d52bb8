"""The plugin's gates end to end: hash lock files, run artifacts, the summary, baselines, pytest-xdist.

Every test builds a small project in the pytester folder from the shipped examples (a suite file named
``gating.fleetsim.yaml`` whose ``name`` is ``demo``, so artifact folders show the file stem is used).
Lock entries of the reference planner are computed once with the library, so a test can start from a
lock that is already recorded without spending two runs per scenario on it.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shlex
import shutil
import sys
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from result_document import RESULT_KEYS, schema_errors

from fleetsim.gating.lockfile import HashLock, LockEntry, lock_path_for
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.sim import run_scenario
from fleetsim.sim.report import SUMMARY_COLUMNS

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
RESERVING = "fleetsim.planners:ReservingPlanner"
LATE = "gating_planners:Late"
FOLDERS = {"crossing": "crossing", "corridor-passing-bay": "corridor", "loop-one-way": "loop"}
TWO = ("crossing", "corridor-passing-bay")
SUITE_FILE = "gating.fleetsim.yaml"
LOCK_FILE = "gating.fleetsim.lock.json"
NO_BASELINE = "*--fleetsim-compare: *missing.json: no such metrics file; write one with --fleetsim-metrics-json*"
WALL_CLOCK = {"wall_time", "planner_wall_time", "realtime_factor"}  # the only figures that may differ

SUITE_HEAD = """\
fleetsim: 1
name: demo
vehicle_types:
  agv:
    {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5,
     turn_capability: in_place, turn_rate: 90}
defaults:
  vehicle_type: agv
  time_limit: 300
scenarios:
"""

PLANNERS = """\
import itertools

from fleetsim.planners import ReservingPlanner


class Late(ReservingPlanner):
    '''The reference planner, but it answers its first few plan_routes calls with no plan.'''

    delay = 4

    def __init__(self):
        super().__init__()
        self._calls = 0

    def plan_routes(self, task, fleet, layout):
        self._calls += 1
        if self._calls <= self.delay:
            return []
        return super().plan_routes(task, fleet, layout)


class Later(Late):
    delay = 8


_made = itertools.count()


class Flaky(Late):
    '''Waits 4 calls in odd runs and 8 in even ones: two runs of a scenario never agree.'''

    def __init__(self):
        super().__init__()
        self.delay = (4, 8)[next(_made) % 2]
"""

# Logs every HashLock.save of the session's processes (controller and xdist workers alike).
SAVE_LOGGER = """\
import os

from fleetsim.gating.lockfile import HashLock

_save = HashLock.save


def _logged_save(self):
    written = _save(self)
    with open(os.path.join(os.path.dirname(__file__), "saves.log"), "a", encoding="utf-8") as log:
        log.write(f"{os.getpid()} {self.path.name} {written}\\n")
    return written


def pytest_configure(config):
    HashLock.save = _logged_save


def pytest_unconfigure(config):
    HashLock.save = _save
"""


# -- building projects ------------------------------------------------------------------------------


def make_project(root: Path, names: Iterable[str] = TWO, *, folders: Iterable[str] | None = None) -> Path:
    """Copy the example folders (``folders``, default: those of ``names``) under ``root`` and write a suite
    of ``names``; return the suite's path."""
    root.mkdir(parents=True, exist_ok=True)
    names = tuple(names)
    if not (root / "tiled").exists():
        shutil.copytree(SUITES / "tiled", root / "tiled")  # the example maps use these templates
    for name in folders if folders is not None else names:
        shutil.copytree(SUITES / "examples" / FOLDERS[name], root / "examples" / FOLDERS[name], dirs_exist_ok=True)
    suite = root / SUITE_FILE
    suite.write_text(
        SUITE_HEAD + "".join(f"  - name: {n}\n    dir: examples/{FOLDERS[n]}/\n" for n in names), encoding="utf-8"
    )
    return suite


def lock_text(sections: Mapping[str, Mapping[str, LockEntry]]) -> str:
    """The canonical text of a lock holding ``sections`` (planner -> scenario -> entry)."""
    lock = HashLock("unused.lock.json")
    for planner, entries in sections.items():
        for scenario, entry in entries.items():
            lock.set(planner, scenario, entry)
    return lock.dumps()


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, LockEntry]:
    """The reference planner's lock entry for each example scenario, computed with the library."""
    suite = load_suite(make_project(tmp_path_factory.mktemp("recorded"), FOLDERS))
    entries = {}
    for spec in suite.scenarios:
        result = run_scenario(load_scenario(spec, suite), ReservingPlanner(), planner_name=RESERVING, keep_trace=False)
        entries[spec.name] = LockEntry.from_run(result.trace_hash, result.steps, result.checkpoints)
    return entries


@pytest.fixture
def project(pytester: pytest.Pytester) -> pytest.Pytester:
    """A pytester folder that is its own rootdir and holds the test planners in ``gating_planners.py``."""
    pytester.makeini("[pytest]\naddopts = -p no:cacheprovider\n")
    pytester.makepyfile(gating_planners=PLANNERS)
    return pytester


@pytest.fixture
def under_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    """CI set: a missing hash fails its scenario (a lock entry that was never committed is a CI mistake)."""
    monkeypatch.setenv("CI", "true")


@pytest.fixture
def locally(monkeypatch: pytest.MonkeyPatch) -> None:
    """CI not set: a missing hash is reported, and the scenario's checks alone decide."""
    monkeypatch.delenv("CI", raising=False)


def write_lock(suite: Path, sections: Mapping[str, Mapping[str, LockEntry]]) -> Path:
    path = suite.with_name(LOCK_FILE)
    path.write_text(lock_text(sections), encoding="utf-8")
    return path


def age(path: Path) -> int:
    """Set ``path``'s mtime far into the past, so any rewrite shows; return it in nanoseconds."""
    old = 1_000_000_000 * 1_000_000_000
    os.utime(path, ns=(old, old))
    return old


# -- reading what a session left ---------------------------------------------------------------------


def fleetsim_table(result: pytest.RunResult) -> list[list[str]]:
    """The rows of the fleetsim summary table, header first, split into cells."""
    lines = result.outlines
    start = next(i for i, line in enumerate(lines) if re.fullmatch(r"=+ fleetsim =+", line))
    rows = []
    for line in lines[start + 1 :]:
        if not line.strip() or line.startswith("="):
            break
        rows.append(re.split(r"\s{2,}", line.strip()))
    return rows


def without_wall_clock(row: Mapping[str, Any]) -> dict[str, Any]:
    return {key: value for key, value in row.items() if key not in WALL_CLOCK}


def metric_rows(path: Path) -> list[dict[str, Any]]:
    document = json.loads(path.read_text(encoding="utf-8"))
    assert document["format"] == "fleetsim-metrics/1"
    return document["scenarios"]


def junit_cases(path: Path) -> dict[str, tuple[str, dict[str, str]]]:
    """name -> (outcome, properties) of each test case in a JUnit XML file."""
    cases = {}
    for case in ElementTree.parse(path).getroot().iter("testcase"):
        outcome = (
            "failed"
            if case.find("failure") is not None
            else "skipped"
            if case.find("skipped") is not None
            else "passed"
        )
        properties = {p.get("name"): p.get("value") for p in case.iter("property")}
        cases[case.get("name")] = (outcome, properties)
    return cases


def assert_canonical_lock(text: str) -> None:
    """Sorted JSON with one line per scenario entry, each line holding the whole entry."""
    document = json.loads(text)
    hashes = document["hashes"]
    assert list(hashes) == sorted(hashes)
    lines = text.splitlines()
    for planner, section in hashes.items():
        assert list(section) == sorted(section)
        for scenario, entry in section.items():
            mine = [line for line in lines if line.lstrip().startswith(json.dumps(scenario) + ": {")]
            owned = [line for line in mine if json.loads("{" + line.strip().rstrip(",") + "}")[scenario] == entry]
            assert owned, f"no line holds the whole entry {planner} / {scenario}"


def hint_in(result: pytest.RunResult) -> str:
    """The command a hash failure offers for recording."""
    commands = [line.strip() for line in result.outlines if line.strip().startswith("pytest ")]
    assert commands, result.stdout.str()
    return commands[0]


# -- 1. hash lock files ------------------------------------------------------------------------------


@pytest.mark.usefixtures("under_ci")
def test_under_ci_a_missing_hash_fails_with_a_command_that_records_it_beside_the_suite(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path / "suites", ["crossing"])
    command = f"pytest suites/{SUITE_FILE}::crossing --fleetsim-update-hashes --planner {RESERVING}"

    missing = project.runpytest_inprocess("suites", "--planner", RESERVING)
    missing.assert_outcomes(failed=1)
    missing.stdout.fnmatch_lines([f"FAILED suites/{SUITE_FILE}::crossing - hash-missing: *"])
    missing.stdout.fnmatch_lines(
        [
            f"*no trace hash is recorded for planner '{RESERVING}' in this scenario, and under CI a missing hash fails "
            "(a lock entry that was never committed is a CI mistake); record it where you develop with:",
            f"  *{command}",
            "*and commit the lock file beside the suite",
        ]
    )
    assert hint_in(missing) == command
    assert not suite.with_name(LOCK_FILE).exists()

    recording = project.runpytest_inprocess(*shlex.split(command)[1:])
    recording.assert_outcomes(passed=1)
    recording.stdout.fnmatch_lines([f"suites/{LOCK_FILE}: 1 hash(es) recorded (1 new, 0 changed, 0 unchanged)"])
    lock = suite.with_name(LOCK_FILE)
    assert lock.read_text(encoding="utf-8") == lock_text({RESERVING: {"crossing": recorded["crossing"]}})
    assert not (project.path / LOCK_FILE).exists()

    project.runpytest_inprocess("suites", "--planner", RESERVING).assert_outcomes(passed=1)


@pytest.mark.usefixtures("locally")
def test_locally_a_missing_hash_passes_as_not_recorded_and_the_summary_says_how_to_record_it(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path / "suites")
    command = f"pytest suites/{SUITE_FILE} --fleetsim-update-hashes --planner {RESERVING}"

    missing = project.runpytest_inprocess("suites", "--planner", RESERVING, "-v")

    missing.assert_outcomes(passed=2)  # the checks decide: no collision, every task done
    assert missing.ret == pytest.ExitCode.OK
    missing.stdout.fnmatch_lines([f"suites/{SUITE_FILE}::crossing PASSED (hash not recorded)*"])
    table = fleetsim_table(missing)
    hash_column = table[0].index("hash")
    assert [(row[0], row[1], row[hash_column]) for row in table[1:]] == [
        (name, "passed", "not recorded") for name in TWO
    ]
    missing.stdout.fnmatch_lines(
        ["2 scenarios: 2 passed; 2 trace hashes not recorded; record them with:", f"  {command}"]
    )
    assert not suite.with_name(LOCK_FILE).exists()

    recording = project.runpytest_inprocess(*shlex.split(command)[1:])
    recording.assert_outcomes(passed=2)
    assert suite.with_name(LOCK_FILE).read_text(encoding="utf-8") == lock_text(
        {RESERVING: {name: recorded[name] for name in TWO}}
    )
    again = project.runpytest_inprocess("suites", "--planner", RESERVING, "-v")
    again.assert_outcomes(passed=2)
    assert "not recorded" not in again.stdout.str()  # the narrow other side: recorded hashes are not news


@pytest.mark.usefixtures("locally")
def test_locally_the_record_command_names_only_the_unrecorded_scenarios_that_did_not_fail(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path, ("crossing", "corridor-passing-bay", "loop-one-way"))
    write_lock(suite, {RESERVING: {"crossing": recorded["crossing"]}})
    text = suite.read_text(encoding="utf-8").replace(
        "dir: examples/loop/\n", "dir: examples/loop/\n    expect: {deadlock: true}\n"
    )  # a deadlock the planner does not have: the scenario fails on its own check
    suite.write_text(text, encoding="utf-8")

    result = project.runpytest_inprocess("--planner", RESERVING)

    result.assert_outcomes(passed=2, failed=1)
    result.stdout.fnmatch_lines(
        [
            "3 scenarios: 2 passed, 1 failed; 2 trace hashes not recorded; "
            "record the hash of the 1 scenario that did not fail with:",
            f"  pytest {SUITE_FILE}::corridor-passing-bay --fleetsim-update-hashes --planner {RESERVING}",
        ]
    )


@pytest.mark.usefixtures("under_ci")
def test_under_ci_a_recorded_hash_still_passes(project: pytest.Pytester, recorded: dict[str, LockEntry]) -> None:
    write_lock(make_project(project.path), {RESERVING: {name: recorded[name] for name in TWO}})
    result = project.runpytest_inprocess("--planner", RESERVING)
    result.assert_outcomes(passed=2)
    assert "not recorded" not in result.stdout.str()


@pytest.mark.usefixtures("under_ci")
def test_record_command_works_from_the_folder_pytest_was_run_in(
    project: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    suite = make_project(project.path / "suites", ["crossing"])  # the rootdir (tox.ini) is one level up
    monkeypatch.chdir(suite.parent)

    missing = project.runpytest_inprocess(SUITE_FILE, "--planner", RESERVING)
    missing.stdout.fnmatch_lines([f"FAILED {SUITE_FILE}::crossing - hash-missing: *"])  # pytest's own id
    recording = project.runpytest_inprocess(*shlex.split(hint_in(missing))[1:])

    recording.assert_outcomes(passed=1)
    assert suite.with_name(LOCK_FILE).exists()


def test_recording_keeps_other_planners_and_writes_sorted_lines(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path)  # crossing before corridor-passing-bay: the file must sort them
    other = {LATE: {"crossing": recorded["loop-one-way"]}}  # sorts after the reference planner
    lock = write_lock(suite, other)

    result = project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-update-hashes")

    result.assert_outcomes(passed=2)
    result.stdout.fnmatch_lines([f"{LOCK_FILE}: 2 hash(es) recorded (2 new, 0 changed, 0 unchanged)"])
    text = lock.read_text(encoding="utf-8")
    assert text == lock_text({RESERVING: {name: recorded[name] for name in TWO}, **other})
    assert_canonical_lock(text)
    assert text.index(RESERVING) < text.index(LATE)
    assert text.index('"corridor-passing-bay"') < text.index('"crossing"')


def test_recording_an_unchanged_lock_leaves_the_file_untouched(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path, ["crossing"])
    lock = write_lock(suite, {RESERVING: {"crossing": recorded["crossing"]}, LATE: {"crossing": recorded["crossing"]}})
    before, mtime, inode = lock.read_bytes(), age(lock), lock.stat().st_ino

    result = project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-update-hashes")

    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines([f"{LOCK_FILE}: 1 hash(es) recorded (0 new, 0 changed, 1 unchanged) (file unchanged)"])
    assert (lock.read_bytes(), lock.stat().st_mtime_ns, lock.stat().st_ino) == (before, mtime, inode)


def test_changed_planner_behaviour_fails_with_hash_mismatch_from_the_first_checkpoint(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    make_project(project.path, ["crossing"])
    project.makepyfile(subject="from fleetsim.planners import ReservingPlanner as Planner\n")
    project.runpytest_inprocess("--planner", "subject:Planner", "--fleetsim-update-hashes").assert_outcomes(passed=1)
    project.runpytest_inprocess("--planner", "subject:Planner").assert_outcomes(passed=1)

    # The same planner identity now waits for a few calls before its first plan.
    project.makepyfile(subject="from gating_planners import Late as Planner  # now waits before planning\n")
    shutil.rmtree(project.path / "__pycache__", ignore_errors=True)
    result = project.runpytest_inprocess("--planner", "subject:Planner")

    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            f"*the trace hash * differs from the recorded {recorded['crossing'].hash[:12]}: the planner's behaviour "
            "changed between t = 0 s and t = 10 s (the first differing checkpoint is at step 99)",
            f"FAILED {SUITE_FILE}::crossing - hash-mismatch: *",  # the whole run's: no moment of its own
        ]
    )
    assert hint_in(result) == f"pytest {SUITE_FILE}::crossing --fleetsim-update-hashes --planner subject:Planner"


@pytest.mark.parametrize(
    ("checkpoints", "time", "window"),
    [
        (
            lambda c: [c[0], "0" * 16],
            "10.00",
            "between t = 10 s and t = 20 s (the first differing checkpoint is at step 199)",
        ),
        (lambda c: c, "20.00", "after t = 20 s, where every checkpoint both runs share agrees"),
        (lambda c: [], "0.00", "(no checkpoint both runs have narrows it down)"),
    ],
    ids=["second-checkpoint-edited", "only-hash-edited", "no-checkpoints"],
)
def test_edited_lock_fails_with_hash_mismatch_saying_when_behaviour_changed(
    project: pytest.Pytester, recorded: dict[str, LockEntry], checkpoints: Any, time: str, window: str
) -> None:
    true = recorded["crossing"]
    assert len(true.checkpoints) == 2  # 220 steps of 0.1 s: checkpoints after 10 s and 20 s
    edited = LockEntry("f" * 64, true.steps, tuple(checkpoints(list(true.checkpoints))))
    write_lock(make_project(project.path, ["crossing"]), {RESERVING: {"crossing": edited}})

    result = project.runpytest_inprocess("--planner", RESERVING)

    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "  hash-mismatch:",
            f"    the trace hash {true.hash[:12]} differs from the recorded ffffffffffff: the planner's behaviour changed *",
            f"FAILED {SUITE_FILE}::crossing - hash-mismatch: *",
        ]
    )
    assert window in result.stdout.str()


def test_stale_entries_are_reported_in_check_mode_and_pruned_on_update(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path, ["crossing"], folders=TWO)  # corridor-passing-bay left the suite
    both = {name: recorded[name] for name in TWO}
    lock = write_lock(suite, {RESERVING: both, LATE: both})
    before = lock.read_bytes()
    stale = f"{RESERVING} / corridor-passing-bay, {LATE} / corridor-passing-bay"

    check = project.runpytest_inprocess("--planner", RESERVING)

    check.assert_outcomes(passed=1)
    check.stdout.fnmatch_lines(
        [
            f"{LOCK_FILE} holds 2 stale entries for scenarios no longer in the suite ({stale}); "
            "--fleetsim-update-hashes prunes them"
        ]
    )
    assert lock.read_bytes() == before

    update = project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-update-hashes")

    update.assert_outcomes(passed=1)
    update.stdout.fnmatch_lines(
        [f"{LOCK_FILE}: 1 hash(es) recorded (0 new, 0 changed, 1 unchanged), 2 stale entries pruned ({stale})"]
    )
    crossing = {"crossing": recorded["crossing"]}
    assert lock.read_text(encoding="utf-8") == lock_text({RESERVING: crossing, LATE: crossing})


@pytest.mark.usefixtures("locally")
def test_nondeterministic_planner_is_refused_naming_the_first_diverging_step(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path, ["crossing"])
    lock = write_lock(suite, {RESERVING: {"crossing": recorded["crossing"]}})
    before, mtime = lock.read_bytes(), age(lock)

    result = project.runpytest_inprocess("--planner", "gating_planners:Flaky", "--fleetsim-update-hashes")

    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines([f"{LOCK_FILE}: 0 hash(es) recorded (0 new, 0 changed, 0 unchanged) (file unchanged)"])
    assert (lock.read_bytes(), lock.stat().st_mtime_ns) == (before, mtime)
    text = result.stdout.str()
    found = re.search(
        r"nondeterministic at t=(\S+) s: the planner is not deterministic: .*first divergence at step (\d+) \(t = (\S+) s\)",
        text,
    )
    assert found, text
    assert "Nothing was recorded." in text
    # The first run waited 4 calls, the second 8: their traces, recorded apart, first differ at that step.
    first = json.loads((project.path / "fleetsim-results/gating/crossing/result.json").read_text(encoding="utf-8"))
    assert first["failures"][0]["kind"] == "nondeterministic"
    later = project.runpytest_inprocess(
        "--planner", "gating_planners:Later", "--fleetsim-artifacts", "later", "--fleetsim-record", "all"
    )
    later.assert_outcomes(passed=1)  # its hash is not recorded, which fails it only under CI
    a = (project.path / "fleetsim-results/gating/crossing/trace.jsonl").read_text(encoding="utf-8").splitlines()
    b = (project.path / "later/gating/crossing/trace.jsonl").read_text(encoding="utf-8").splitlines()
    step = next(
        json.loads(x)[0] for x, y in zip(a[1:], b[1:], strict=False) if x != y
    )  # the runs may end at different steps
    assert step > 0  # both runs start by waiting, so the divergence is not simply the first step
    assert int(found[2]) == step
    assert float(found[1]) == float(found[3]) == pytest.approx((step + 1) * 0.1)


# -- 2. artifacts ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        ([], {"fleetsim-results/gating/corridor-passing-bay"}),
        (["--fleetsim-record", "failed"], {"fleetsim-results/gating/corridor-passing-bay"}),
        (
            ["--fleetsim-record", "all"],
            {"fleetsim-results/gating/corridor-passing-bay", "fleetsim-results/gating/crossing"},
        ),
        (["--fleetsim-record", "none"], set()),
        (["--fleetsim-artifacts", "out/runs"], {"out/runs/gating/corridor-passing-bay"}),
    ],
    ids=["default", "failed", "all", "none", "other-root"],
)
@pytest.mark.usefixtures("under_ci")
def test_record_option_decides_which_runs_leave_artifacts_and_where(
    project: pytest.Pytester, recorded: dict[str, LockEntry], options: list[str], expected: set[str]
) -> None:
    write_lock(make_project(project.path), {RESERVING: {"crossing": recorded["crossing"]}})  # corridor: hash-missing

    result = project.runpytest_inprocess("--planner", RESERVING, *options)

    result.assert_outcomes(passed=1, failed=1)
    names = ("result.json", "trace.jsonl", "run.mcap", "fleetsim.rviz", "failure.svg", "view.html")
    files = {str(p.relative_to(project.path)) for p in project.path.rglob("*") if p.name in names}
    failed = {folder for folder in expected if folder.endswith("corridor-passing-bay")}
    assert files == {
        f"{folder}/{name}" for folder in expected for name in names if name != "failure.svg" or folder in failed
    }
    # Only the failure reports; with CI set, pytest's short summary repeats whole messages.
    reports = result.outlines[
        : next(i for i, line in enumerate(result.outlines) if "short test summary" in line or "fleetsim ===" in line)
    ]
    listed = [line for line in reports if line.startswith("artifacts: ")]
    if "none" in options:
        assert listed == []
    else:
        folder = next(f for f in expected if f.endswith("corridor-passing-bay"))
        shown = ["failure.svg", "view.html", "run.mcap", "fleetsim.rviz", "trace.jsonl", "result.json"]
        lines = [("artifacts: " if i == 0 else "           ") + f"{folder}/{name}" for i, name in enumerate(shown)]
        start = reports.index(lines[0])
        assert reports[start : start + len(lines)] == lines
        assert len(listed) == 1  # only the failing scenario's report


@pytest.mark.usefixtures("under_ci")
def test_result_json_and_junit_xml_describe_every_recorded_run(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    write_lock(make_project(project.path), {RESERVING: {"crossing": recorded["crossing"]}})

    result = project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-record", "all", "--junitxml", "junit.xml")

    result.assert_outcomes(passed=1, failed=1)
    cases = junit_cases(project.path / "junit.xml")
    assert set(cases) == set(TWO)
    for name, status, kinds in [("crossing", "passed", []), ("corridor-passing-bay", "failed", ["hash-missing"])]:
        folder = f"fleetsim-results/gating/{name}"
        document = json.loads((project.path / folder / "result.json").read_text(encoding="utf-8"))
        assert set(document) >= RESULT_KEYS
        assert schema_errors(document) == []  # the result.json the plugin writes
        assert (document["scenario"], document["planner"], document["status"]) == (name, RESERVING, status)
        assert [failure["kind"] for failure in document["failures"]] == kinds
        assert document["trace_hash"] == recorded[name].hash
        assert document["steps"] == recorded[name].steps
        assert (
            hashlib.sha256((project.path / folder / "trace.jsonl").read_bytes()).hexdigest() == document["trace_hash"]
        )
        tasks = document["tasks"]
        outcome, properties = cases[name]
        assert outcome == status
        assert properties["fleetsim_trace_hash"] == document["trace_hash"]
        assert properties["fleetsim_tasks"] == f"{tasks['completed']}/{tasks['total']}" == "2/2"
        assert properties["fleetsim_makespan"] == f"{document['metrics']['makespan']:.3f}"
        assert properties["fleetsim_artifact_result"] == f"{folder}/result.json"
        assert properties["fleetsim_artifact_trace"] == f"{folder}/trace.jsonl"


# -- 3. summary and baselines ------------------------------------------------------------------------


@pytest.mark.usefixtures("under_ci")  # corridor-passing-bay fails for want of a recorded hash
def test_summary_table_and_metrics_json_have_one_row_per_scenario(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    write_lock(make_project(project.path), {RESERVING: {"crossing": recorded["crossing"]}})

    result = project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-metrics-json", "metrics.json")

    result.assert_outcomes(passed=1, failed=1)
    rows = {row["id"]: row for row in metric_rows(project.path / "metrics.json")}
    assert list(rows) == [f"{SUITE_FILE}::corridor-passing-bay", f"{SUITE_FILE}::crossing"]  # sorted by id
    table = fleetsim_table(result)
    assert table[0] == list(SUMMARY_COLUMNS)  # the same columns as fleetsim run
    assert [row[:2] for row in table[1:]] == [["crossing", "passed"], ["corridor-passing-bay", "failed"]]  # suite order
    for cells in table[1:]:
        row = rows[f"{SUITE_FILE}::{cells[0]}"]
        assert row["outcome"] == cells[1]
        assert row["trace_hash"] == recorded[cells[0]].hash
        assert row["planner"] == RESERVING
        clearance = "> 2 m" if row["clearance"] is None else f"{row['clearance']:.2f} m"
        assert (
            cells[2:10]
            == [
                f"{row['tasks_completed']}/{row['tasks_total']}",
                f"{row['makespan']:.1f} s",
                str(row["alerts"]),
                str(row["contacts"]),
                clearance,
                str(row["rejections"]),
                "0",  # route errors: the reference planner finds every route
                "not recorded" if cells[0] == "corridor-passing-bay" else row["trace_hash"][:12],
            ]
        )
        assert re.fullmatch(r"\d+x", cells[10])
    result.stdout.fnmatch_lines(["metrics of 2 scenario(s) written to *metrics.json"])


def save_baseline(
    project: pytest.Pytester, recorded: dict[str, LockEntry], lower_by: Mapping[str, float]
) -> dict[str, float]:
    """Run the suite and save its metrics with each scenario's makespan made ``lower_by`` times lower;
    return the current makespans."""
    write_lock(make_project(project.path), {RESERVING: {name: recorded[name] for name in TWO}})
    project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-metrics-json", "base.json").assert_outcomes(
        passed=2
    )
    path = project.path / "base.json"
    document = json.loads(path.read_text(encoding="utf-8"))
    current = {}
    for row in document["scenarios"]:
        name = row["id"].partition("::")[2]
        current[name] = row["makespan"]
        row["makespan"] = round(row["makespan"] / lower_by[name], 6)
    path.write_text(json.dumps(document), encoding="utf-8")
    return current


def test_makespan_regression_beyond_the_limit_fails_the_scenarios_own_item_and_the_session(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    current = save_baseline(project, recorded, {"crossing": 1.06, "corridor-passing-bay": 1.04})

    result = project.runpytest_inprocess(
        "--planner", RESERVING, "--fleetsim-compare", "base.json", "--fleetsim-compare-fail", "makespan:5%"
    )

    result.assert_outcomes(passed=1, failed=1)  # the regressed scenario's item is red, not only the exit status
    assert result.ret == pytest.ExitCode.TESTS_FAILED
    result.stdout.fnmatch_lines(
        [
            f"regression: makespan * -> {current['crossing']} (+6.0%, limit 5%) against the baseline",
            "*",
            "broken: the baseline (--fleetsim-compare-fail)",
        ]
    )
    result.stdout.fnmatch_lines([f"FAILED {SUITE_FILE}::crossing - regression: makespan *"])
    result.stdout.fnmatch_lines(
        [
            "compared with base.json:",
            "fleetsim compare: 2 compared, 1 regression",
            f"  {SUITE_FILE}::crossing: makespan * -> {current['crossing']} (+6.0%, limit 5%)",
        ]
    )
    assert "corridor-passing-bay: makespan" not in result.stdout.str()  # 4% worse: within the limit


def test_makespan_within_the_limit_passes_the_session(project: pytest.Pytester, recorded: dict[str, LockEntry]) -> None:
    save_baseline(project, recorded, {"crossing": 1.04, "corridor-passing-bay": 1.04})

    result = project.runpytest_inprocess(
        "--planner", RESERVING, "--fleetsim-compare", "base.json", "--fleetsim-compare-fail", "makespan:5%"
    )

    result.assert_outcomes(passed=2)
    assert result.ret == pytest.ExitCode.OK
    result.stdout.fnmatch_lines(["fleetsim compare: 2 compared, 0 regressions"])


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (
            ["--fleetsim-compare", "base.json", "--fleetsim-compare-fail", "speed:5%"],
            "*unknown metric 'speed'*known: *makespan*",
        ),
        (["--fleetsim-compare", "missing.json", "--fleetsim-compare-fail", "makespan:5%"], NO_BASELINE),
        (["--fleetsim-compare", "missing.json"], NO_BASELINE),
        (["--fleetsim-compare-fail", "makespan:5%"], "*--fleetsim-compare-fail needs --fleetsim-compare PATH*"),
    ],
    ids=["unknown-metric", "missing-baseline", "missing-baseline-without-limits", "limit-without-baseline"],
)
def test_bad_compare_options_are_usage_errors(project: pytest.Pytester, options: list[str], message: str) -> None:
    make_project(project.path, ["crossing"])
    (project.path / "base.json").write_text('{"format": "fleetsim-metrics/1", "scenarios": []}', encoding="utf-8")

    result = project.runpytest_inprocess("--planner", RESERVING, *options)

    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines([f"ERROR: {message}"])
    assert not (project.path / "fleetsim-results").exists()  # nothing ran


# -- 4. pytest-xdist ---------------------------------------------------------------------------------


@pytest.mark.usefixtures("under_ci")  # corridor-passing-bay fails for want of a recorded hash
def test_xdist_gives_the_serial_ids_outcomes_and_hashes(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    names = ("crossing", "corridor-passing-bay", "loop-one-way")
    write_lock(make_project(project.path, names), {RESERVING: {n: recorded[n] for n in ("crossing", "loop-one-way")}})
    common = ("--planner", RESERVING)

    serial = project.runpytest_inprocess(*common, "--fleetsim-metrics-json", "serial.json", "--junitxml", "serial.xml")
    spread = project.runpytest_subprocess(
        *common, "-n", "2", "--fleetsim-metrics-json", "spread.json", "--junitxml", "spread.xml", timeout=120
    )

    serial.assert_outcomes(passed=2, failed=1)
    spread.assert_outcomes(passed=2, failed=1)
    assert "2 workers [3 items]" in spread.stdout.str()
    rows = [
        [without_wall_clock(row) for row in metric_rows(project.path / f"{run}.json")] for run in ("serial", "spread")
    ]
    assert rows[0] == rows[1]
    assert [(row["id"], row["outcome"], row["trace_hash"]) for row in rows[0]] == [
        (f"{SUITE_FILE}::corridor-passing-bay", "failed", recorded["corridor-passing-bay"].hash),
        (f"{SUITE_FILE}::crossing", "passed", recorded["crossing"].hash),
        (f"{SUITE_FILE}::loop-one-way", "passed", recorded["loop-one-way"].hash),
    ]
    assert junit_cases(project.path / "serial.xml") == junit_cases(project.path / "spread.xml")
    assert [row[:7] for row in fleetsim_table(serial)] == [
        row[:7] for row in fleetsim_table(spread)
    ]  # suite order, both


def test_xdist_update_writes_the_lock_once_as_a_serial_update_does(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path)
    lock = suite.with_name(LOCK_FILE)
    common = ("--planner", RESERVING, "--fleetsim-update-hashes")
    project.runpytest_inprocess(*common).assert_outcomes(passed=2)
    serial = lock.read_text(encoding="utf-8")
    assert serial == lock_text({RESERVING: {name: recorded[name] for name in TWO}})
    lock.unlink()

    project.makeconftest(SAVE_LOGGER)
    spread = project.runpytest_subprocess(*common, "-n", "2", timeout=120)

    spread.assert_outcomes(passed=2)
    assert "2 workers [2 items]" in spread.stdout.str()
    assert lock.read_text(encoding="utf-8") == serial
    saves = (project.path / "saves.log").read_text(encoding="utf-8").splitlines()
    assert len(saves) == 1 and saves[0].endswith(f" {LOCK_FILE} True"), saves
    assert [line for line in spread.outlines if "hash(es) recorded" in line] == [
        f"{LOCK_FILE}: 2 hash(es) recorded (2 new, 0 changed, 0 unchanged)"
    ]


@pytest.mark.usefixtures("under_ci")
def test_a_failed_runs_artifacts_hold_a_readable_recording_and_picture(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    write_lock(make_project(project.path), {RESERVING: {"crossing": recorded["crossing"]}})

    result = project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-record-every", "5")

    result.assert_outcomes(passed=1, failed=1)
    folder = project.path / "fleetsim-results" / "gating" / "corridor-passing-bay"
    with (folder / "run.mcap").open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        clock = [
            message.log_time for _, channel, message, _ in reader.iter_decoded_messages() if channel.topic == "/clock"
        ]
    assert clock and clock[-1] == round(recorded["corridor-passing-bay"].steps * 0.1 * 1e9)
    assert len(clock) < recorded["corridor-passing-bay"].steps / 2  # every 5th step, plus changes
    picture = ET.parse(folder / "failure.svg").getroot()
    assert "hash-missing" in "".join(picture.itertext())


def test_a_record_rate_below_one_step_is_a_usage_error(project: pytest.Pytester) -> None:
    make_project(project.path)

    result = project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-record-every", "0")

    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*--fleetsim-record-every=0 must be a whole number of steps >= 1*"])


def test_an_exec_planner_is_gated_like_any_other_and_records_the_in_process_hashes(
    project: pytest.Pytester, recorded: dict[str, LockEntry]
) -> None:
    suite = make_project(project.path)
    spec = f"exec:{sys.executable} -m fleetsim.exec {RESERVING}"

    result = project.runpytest_inprocess("--planner", spec, "--fleetsim-update-hashes", "-n", "2")

    result.assert_outcomes(passed=2)
    lock = HashLock.load(lock_path_for(suite))
    assert {name: lock.get(spec, name) for name in TWO} == {name: recorded[name] for name in TWO}
    again = project.runpytest_inprocess("--planner", spec)
    again.assert_outcomes(passed=2)
