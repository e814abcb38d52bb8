"""A suite reports every mistake of its file at once (issue 32, point 1): every unknown key with its
did-you-mean, one message per bad value, the checks beyond the schema in every entry; capped at 50; one
mistake is still its own SuiteError; `fleetsim validate`, `fleetsim run` and pytest collection show them all."""

from __future__ import annotations

import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from fleetsim.cli import main
from fleetsim.errors import LoadErrors, SuiteError, SuiteErrors
from fleetsim.load.common.collect import CAP_PER_FILE
from fleetsim.load.common.yaml_source import load_yaml_with_marks
from fleetsim.load.suites.schema import check_against_schema
from fleetsim.load.suites.suite import load_suite

EXAMPLES = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples"
PLANNER = "fleetsim.planners:ReservingPlanner"

CLEAN = """\
fleetsim: 1
name: four
defaults:
  time_limit: 100
scenarios:
  - name: first
    dir: crossing
  - name: second
    dir: crossing
    expect:
      collisions: none
  - name: third
    dir: crossing
    expect:
      tasks: all
"""
FOUR_MISTAKES = (
    CLEAN.replace("defaults:", "defualts:")
    .replace("  - name: first\n    dir:", "  - name: first\n    dri:")
    .replace("collisions: none", "colision: none")
    .replace("tasks: all", "tasks: al")
)
FOUR_PROBLEMS = [
    ((3, 1), "unknown key 'defualts'; did you mean 'defaults'?"),
    ((7, 5), "scenarios[0]: unknown key 'dri'; did you mean 'dir'?"),
    ((11, 7), "scenarios[1].expect: unknown key 'colision'; did you mean 'collisions'?"),
    ((15, 14), "scenarios[2].expect.tasks: 'al' is not one of 'all' or a whole number >= 0"),
]


def write_suite(tmp_path: Path, text: str) -> Path:
    if not (tmp_path / "crossing").exists():
        shutil.copytree(EXAMPLES / "crossing", tmp_path / "crossing")
    path = tmp_path / "four.fleetsim.yaml"
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def errors_of(path: Path) -> list[SuiteError]:
    with pytest.raises(SuiteError) as caught:
        load_suite(path)
    error = caught.value
    if isinstance(error, SuiteErrors):
        assert all(isinstance(inner, SuiteError) for inner in error.errors)
        return [inner for inner in error.errors if isinstance(inner, SuiteError)]
    return [error]


def located(errors: list[SuiteError]) -> list[tuple[tuple[int | None, int | None], str]]:
    return [((e.location.line, e.location.column) if e.location else (None, None), e.problem) for e in errors]


def test_the_four_mistakes_of_the_issue_are_reported_together_each_at_its_place(tmp_path: Path) -> None:
    path = write_suite(tmp_path, FOUR_MISTAKES)
    with pytest.raises(SuiteErrors) as caught:
        load_suite(path)
    error = caught.value
    assert isinstance(error, LoadErrors) and isinstance(error, SuiteError)  # catching either works
    assert located(errors_of(path)) == FOUR_PROBLEMS
    assert error.location == error.errors[0].location
    lines = str(error).splitlines()
    assert lines[0] == "4 errors:"
    assert lines[1:] == [f"  {path}:{line}:{column}: {problem}" for (line, column), problem in FOUR_PROBLEMS]


def test_a_clean_suite_still_loads(tmp_path: Path) -> None:
    suite = load_suite(write_suite(tmp_path, CLEAN))
    assert [spec.name for spec in suite.scenarios] == ["first", "second", "third"]
    assert {spec.settings.time_limit for spec in suite.scenarios} == {100.0}


@pytest.mark.parametrize("shipped", sorted(EXAMPLES.parent.glob("*.fleetsim.yaml")), ids=lambda p: p.name)
def test_the_shipped_suites_load(shipped: Path) -> None:
    assert load_suite(shipped).scenarios


# -- one mistake, one message ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("change", "line_column", "problem"),
    [
        pytest.param(
            ("defaults:", "defualts:"), (3, 1), "unknown key 'defualts'; did you mean 'defaults'?", id="top-key"
        ),
        pytest.param(  # not also "give 'dir', all of 'map', 'vehicles' and 'tasks'": the same mistake
            ("  - name: first\n    dir:", "  - name: first\n    dri:"),
            (7, 5),
            "scenarios[0]: unknown key 'dri'; did you mean 'dir'?",
            id="misspelt-dir",
        ),
        pytest.param(
            ("tasks: all", "tasks: al"),
            (15, 14),
            "scenarios[2].expect.tasks: 'al' is not one of 'all' or a whole number >= 0",
            id="oneOf-value",
        ),
        pytest.param(
            ("collisions: none", "collisions: [1, x]"),
            (11, 23),
            "scenarios[1].expect.collisions[1]: 'x' is not a whole number (it is a string)",
            id="oneOf-branch-item",
        ),
        pytest.param(
            ("time_limit: 100", "time_limit: .nan"),
            (4, 15),
            "defaults.time_limit: nan is not a finite number",
            id="nan-not-also-a-bound",
        ),
        pytest.param(
            ("  - name: first\n", "  - nmae: first\n"),
            (6, 5),
            "scenarios[0]: unknown key 'nmae'; did you mean 'name'?",
            id="misspelt-name",
        ),
        pytest.param(
            ("scenarios:", "scenario:"), (5, 1), "unknown key 'scenario'; did you mean 'scenarios'?", id="scenarios"
        ),
        pytest.param(
            ("name: third\n    dir: crossing\n", "name: third\n    dir: crosing\n"),
            (13, 10),
            "scenarios[2].dir: no such directory",
            id="missing-dir",
        ),
    ],
)
def test_one_mistake_is_one_suite_error_as_before(
    tmp_path: Path, change: tuple[str, str], line_column: tuple[int, int], problem: str
) -> None:
    assert change[0] in CLEAN
    with pytest.raises(SuiteError) as caught:
        load_suite(write_suite(tmp_path, CLEAN.replace(*change, 1)))
    assert type(caught.value) is SuiteError
    assert caught.value.location is not None
    assert (caught.value.location.line, caught.value.location.column) == line_column
    assert caught.value.problem.startswith(problem)


def test_a_misspelt_vehicle_types_is_not_also_every_unknown_type_name(tmp_path: Path) -> None:
    types = (
        "vehicle_type:\n  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5,"
        " turn_capability: in_place}\n"
    )
    text = CLEAN.replace("defaults:\n", f"{types}defaults:\n  vehicle_type: agv\n")
    assert located(errors_of(write_suite(tmp_path, text))) == [
        ((3, 1), "unknown key 'vehicle_type'; did you mean 'vehicle_types'?")
    ]


def test_a_misspelt_required_key_is_one_message_not_also_the_missing_key(tmp_path: Path) -> None:
    types = (
        "vehicle_types:\n  agv: {lenght: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5,"
        " turn_capability: in_place}\n"
    )
    text = CLEAN.replace("defaults:\n", f"{types}defaults:\n")
    assert located(errors_of(write_suite(tmp_path, text))) == [
        ((4, 9), "vehicle_types.agv: unknown key 'lenght'; did you mean 'length'?")
    ]


# -- several mistakes -----------------------------------------------------------------------------


def test_two_unknown_keys_of_one_mapping_are_both_reported(tmp_path: Path) -> None:
    text = CLEAN.replace("    dir: crossing\n", "    dir: crossing\n    paint: red\n    tag: [x]\n", 1)
    assert [problem for _, problem in located(errors_of(write_suite(tmp_path, text)))] == [
        "scenarios[0]: unknown key 'paint'",
        "scenarios[0]: unknown key 'tag'; did you mean 'tags'?",
    ]


def test_a_mistake_repeated_in_every_entry_is_reported_in_each(tmp_path: Path) -> None:
    text = CLEAN.replace("    dir: crossing\n", "    dir: crossing\n    colour: red\n")
    assert [where for where, _ in located(errors_of(write_suite(tmp_path, text)))] == [(8, 5), (11, 5), (16, 5)]


EVERY_KIND = """\
fleetsim: 1
name: every-kind
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
  tug: {length: 2.0, width: 1.0, height: 1.0, max_speed: 2.0, acceleration: 1.0, turn_capability: curve}
  AGV: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
defaults:
  vehicle_type: agx
scenarios:
  - name: a
    dir: nowhere
  - name: b
    dir: nowhere-else
    vehicle_type: crane
  - name: a
    map: m.json
    vehicles: crossing/vehicles.csv
    tasks: t.csv
    disturbances:
      - {vehicle: 1, at: 3, on_segment: 2, stop: 4}
      - {vehicle: 1, stop: 4}
  - name: g
    generate: {size: [3, 1], vehicle_types: [agv, crne]}
    hunt_disturbances: {count: [4, 1], stop: [9, 2]}
  - name: gd
    generate: {layout: loop}
    disturbances: []
    tags: [xfail]
"""


def test_every_kind_of_check_reports_each_of_its_mistakes(tmp_path: Path) -> None:
    found = located(errors_of(write_suite(tmp_path, EVERY_KIND)))
    expected = [
        (6, "vehicle_types: 'AGV' differs from vehicle type 'agv' only in case"),
        (8, "defaults.vehicle_type: 'agx' is not a vehicle type of this suite (agv, tug); did you mean 'agv'?"),
        (11, "scenarios[0].dir: no such directory"),
        (13, "scenarios[1].dir: no such directory"),
        (14, "scenarios[1].vehicle_type: 'crane' is not a vehicle type"),
        (15, "scenarios[2].name: scenario name 'a' is already used on line 10"),
        (16, "scenarios[2].map: no such file"),
        (18, "scenarios[2].tasks: no such file"),
        (20, "scenarios[2].disturbances[0]: {'vehicle': 1, 'at': 3, 'on_segment': 2, 'stop': 4} has both"),
        (21, "scenarios[2].disturbances[1]: {'vehicle': 1, 'stop': 4} has neither"),
        (23, "scenarios[3].generate.size: size=[3, 1] must be [min, max] with min <= max"),
        (23, "scenarios[3].generate.vehicle_types[1]: 'crne' is not a vehicle type"),
        (24, "scenarios[3].hunt_disturbances.count: count=[4, 1] must be"),
        (24, "scenarios[3].hunt_disturbances.stop: stop=[9, 2] must be"),
        (27, "scenarios[4].disturbances: a generated scenario's vehicles are not known in advance"),
        (28, "scenarios[4].tags[0]: 'xfail' must not be one of pytest's built-in markers"),
    ]
    assert len(found) == len(expected)
    for ((line, _), problem), (want_line, want) in zip(found, expected, strict=True):
        assert (line, problem[: len(want)]) == (want_line, want)


def test_at_most_fifty_errors_then_how_many_more(tmp_path: Path) -> None:
    count = CAP_PER_FILE + 12
    entries = "".join(f"  - {{name: s{k}, dir: crossing, colour: red}}\n" for k in range(count))
    path = write_suite(tmp_path, f"fleetsim: 1\nname: many\nscenarios:\n{entries}")
    with pytest.raises(SuiteErrors) as caught:
        load_suite(path)
    error = caught.value
    assert len(error.errors) == CAP_PER_FILE
    assert error.omitted == {str(path): 12}
    assert [e.location.line for e in error.errors if e.location] == list(range(4, 4 + CAP_PER_FILE))
    assert str(error).splitlines()[0] == f"{count} errors:"
    assert str(error).splitlines()[-1] == f"  ... and 12 more in {path}"


def test_check_against_schema_still_raises_the_one_most_relevant_error(tmp_path: Path) -> None:
    data, locate = load_yaml_with_marks(write_suite(tmp_path, FOUR_MISTAKES))
    with pytest.raises(SuiteError) as caught:
        check_against_schema(data, locate)
    assert type(caught.value) is SuiteError
    assert caught.value.problem == "unknown key 'defualts'; did you mean 'defaults'?"


# -- the three ways of loading a suite show them all ----------------------------------------------


def test_validate_prints_every_error_of_the_suite(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write_suite(tmp_path, FOUR_MISTAKES)
    assert main(["validate", str(path)]) == 1
    out = capsys.readouterr().out
    assert f"FAIL {path}\n     4 errors:\n" in out
    for (line, column), problem in FOUR_PROBLEMS:
        assert f"\n       {path}:{line}:{column}: {problem}\n" in out


def test_run_reports_every_error_of_the_suite(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write_suite(tmp_path, FOUR_MISTAKES)
    assert main(["run", str(path), "--planner", PLANNER]) == 1
    out = capsys.readouterr().out
    assert "4 errors:" in out
    for (line, column), problem in FOUR_PROBLEMS:
        assert f"{path}:{line}:{column}: {problem}" in out


def test_pytest_collection_reports_every_error_of_the_suite(tmp_path: Path) -> None:
    path = write_suite(tmp_path, FOUR_MISTAKES)
    command = [sys.executable, "-m", "pytest", path.name, "--planner", PLANNER, "-p", "no:cacheprovider"]
    done = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, check=False, timeout=120)
    assert done.returncode == 2, done.stdout + done.stderr  # interrupted: an error during collection
    assert "ERROR collecting four.fleetsim.yaml" in done.stdout
    assert "4 errors:" in done.stdout
    for (line, column), problem in FOUR_PROBLEMS:
        assert f"{path}:{line}:{column}: {problem}" in done.stdout
    assert "Traceback" not in done.stdout
