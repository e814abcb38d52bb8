"""``fleetsim inspect`` given something other than a map file: a scenario folder, a folder, a suite."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from fleetsim.cli import main

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
EXAMPLES = SUITES / "examples.fleetsim.yaml"


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture
def project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The working folder holds the shipped examples (their suite, scenario folders and templates)."""
    shutil.copytree(SUITES / "examples", tmp_path / "suites" / "examples")
    shutil.copytree(SUITES / "tiled", tmp_path / "suites" / "tiled")
    shutil.copy(EXAMPLES, tmp_path / "suites")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_a_scenario_folder_is_inspected_as_its_map(project: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(capsys, "inspect", "suites/examples/crossing", "--json")
    assert status == 0
    assert out == run(capsys, "inspect", "suites/examples/crossing/map.json", "--json")[1]


def test_a_folder_lists_the_maps_below_it_as_inspect_commands(
    project: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(capsys, "inspect", ".")
    assert status == 2 and out == ""
    assert err.splitlines() == [
        "fleetsim: error: .: a folder, not a map; inspect reads a map file (Tiled .json, .tmj or .tmx; LIF .lif.json; "
        "RMF .building.yaml) or a scenario folder with one map. The maps below it (4):",
        "  fleetsim inspect suites/examples/corridor/map.tmj",
        "  fleetsim inspect suites/examples/crossing/map.json",
        "  fleetsim inspect suites/examples/loop/map.tmx",
        "  fleetsim inspect suites/examples/mixed/map.json",
    ]
    assert "no suffix" not in err


def test_a_suite_lists_the_maps_its_scenarios_drive_on(project: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = run(capsys, "inspect", "suites/examples.fleetsim.yaml")
    assert status == 2
    assert "suites/examples.fleetsim.yaml: a suite, not a map;" in err
    assert "The maps its scenarios drive on (4):\n  fleetsim inspect suites/examples/corridor/map.tmj\n" in err


def test_a_long_list_of_maps_is_cut_with_a_count(project: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for index in range(12):
        shutil.copytree("suites/examples/crossing", f"more/{index:02}")
    _, _, err = run(capsys, "inspect", "more")
    lines = err.splitlines()
    assert lines[0].endswith("The maps below it (12):") and len(lines) == 12
    assert lines[1] == "  fleetsim inspect more/00/map.json" and lines[-1] == "  ... and 2 more"


def test_a_folder_without_maps_says_so(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "notes.json").write_text("{}")  # a .json alone is not taken for a map
    status, _, err = run(capsys, "inspect", str(tmp_path))
    assert status == 2 and err.rstrip().endswith("There is no map below this folder.")


def test_a_scenario_folder_with_two_maps_names_both(project: Path, capsys: pytest.CaptureFixture[str]) -> None:
    shutil.copy("suites/examples/loop/map.tmx", "suites/examples/crossing/map.tmx")
    status, _, err = run(capsys, "inspect", "suites/examples/crossing")
    assert status == 2
    assert "a scenario folder with 2 maps (suites/examples/crossing/map.json, suites/examples/crossing/map.tmx)" in err


def test_a_file_that_is_not_a_map_keeps_its_located_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "README").write_text("hello")
    status, _, err = run(capsys, "inspect", str(tmp_path / "README"))
    assert status == 1
    assert "this is not a map file" in err and "no suffix" in err  # a file is judged as the file it is
