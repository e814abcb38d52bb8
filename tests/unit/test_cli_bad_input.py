"""Each kind of bad input, fed to ``fleetsim validate``, gives one located error line and no traceback."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from fleetsim.cli import main

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
SUITE_TEXT = """\
fleetsim: 1
name: broken
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
scenarios:
  - name: crossing
    dir: examples/crossing/
"""


def _edit(relative: str, old: str, new: str) -> Callable[[Path], None]:
    def apply(root: Path) -> None:
        path = root / relative
        text = path.read_text(encoding="utf-8")
        assert old in text, f"{old!r} not in {path}"
        path.write_text(text.replace(old, new, 1), encoding="utf-8")

    return apply


def _cut(relative: str, after: str) -> Callable[[Path], None]:
    """Cut the file short just after the first ``after`` (a download or a copy that stopped)."""

    def apply(root: Path) -> None:
        path = root / relative
        text = path.read_text(encoding="utf-8")
        path.write_text(text[: text.index(after) + len(after)], encoding="utf-8")

    return apply


def _both(*edits: Callable[[Path], None]) -> Callable[[Path], None]:
    def apply(root: Path) -> None:
        for edit in edits:
            edit(root)

    return apply


MAP = "examples/crossing/map.json"
VEHICLES = "examples/crossing/vehicles.csv"
TASKS = "examples/crossing/tasks.csv"
SUITE = "broken.fleetsim.yaml"

# (what is broken, how to break it, what the one error line must contain)
CASES = [
    ("missing template", _edit(MAP, "straight.tx", "straigth.tx"), ["map.json", "object 1", "straigth.tx"]),
    (
        "unknown direction",
        _edit(MAP, '"id":2,', '"id":2,"properties":[{"name":"direction","type":"string","value":"sideways"}],'),
        ["map.json", "object 2", "'sideways'"],
    ),
    (
        "non-orthogonal map",
        _edit(MAP, '"orientation":"orthogonal"', '"orientation":"isometric"'),
        ["map.json", "'isometric'"],
    ),
    ("infinite map", _edit(MAP, '"infinite":false', '"infinite":true'), ["map.json", "infinite"]),
    ("no segments", _edit(MAP, '"objects":[', '"objects":[],"unused":['), ["map.json", "no segments"]),
    (
        # Its task moved to vehicle 1 too: a task of vehicle 2 would be a second error (vehicle 2 is gone).
        "duplicate vehicle id",
        _both(_edit(VEHICLES, "2,5,forward", "1,5,forward"), _edit(TASKS, "2,8,", "1,8,")),
        ["vehicles.csv:3", "vehicle_id", "1"],
    ),
    ("unknown segment in vehicles.csv", _edit(VEHICLES, "2,5,forward", "2,55,forward"), ["vehicles.csv:3", "55"]),
    (
        "wrong-way start",
        _both(
            _edit(MAP, '"id":5,', '"id":5,"properties":[{"name":"direction","type":"string","value":"forward"}],'),
            _edit(VEHICLES, "2,5,forward", "2,5,backward"),
        ),
        ["vehicles.csv:3", "segment_orientation"],
    ),
    ("unknown segment in tasks.csv", _edit(TASKS, "2,8,", "2,88,"), ["tasks.csv:3", "88"]),
    (
        "missing CSV header",
        _edit(VEHICLES, "vehicle_id,start_segment_id,segment_orientation,progress_direction\n", ""),
        ["vehicles.csv:1", "missing header", "1,1,forward,forward"],
    ),
    (
        "map cut short in a string",
        _cut(MAP, '"orientation":"orth'),
        [
            "map.json:70:",
            "not valid JSON: a string that starts here runs to the end of the file (is the file cut short?)",
        ],
    ),
    (
        "map cut short between items",
        _cut(MAP, '"infinite":false,'),
        ["map.json:3:", "a key in double quotes is expected here; the file ends there (is it cut short?)"],
    ),
    ("YAML syntax error", _edit(SUITE, "name: broken", "name: [broken"), [f"{SUITE}:"]),
    (
        "schema violation",
        _edit(SUITE, "turn_capability: in_place", "turn_capability: hover"),
        [f"{SUITE}:4:", "'hover'"],
    ),
]


@pytest.fixture
def workspace(tmp_path: Path) -> Path:
    shutil.copytree(SUITES / "examples" / "crossing", tmp_path / "examples" / "crossing")
    shutil.copytree(SUITES / "tiled", tmp_path / "tiled")
    (tmp_path / SUITE).write_text(SUITE_TEXT, encoding="utf-8")
    return tmp_path


def test_the_unbroken_workspace_validates(workspace: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(workspace / SUITE)]) == 0, capsys.readouterr().out


@pytest.mark.parametrize(("name", "breaking", "expected"), CASES, ids=[case[0] for case in CASES])
def test_bad_input_gives_one_located_error(
    workspace: Path,
    capsys: pytest.CaptureFixture[str],
    name: str,
    breaking: Callable[[Path], None],
    expected: list[str],
) -> None:
    breaking(workspace)
    status = main(["validate", str(workspace / SUITE)])
    out, err = capsys.readouterr()
    assert status == 1
    assert "Traceback" not in out + err
    error_lines = [line.strip() for line in out.splitlines() if line.startswith("     ")]
    assert len(error_lines) == 1, out
    for fragment in expected:
        assert fragment in error_lines[0], error_lines[0]


def test_a_map_of_another_file_type_is_named_in_words(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "map.csv"
    path.write_text("vehicle_id\n", encoding="utf-8")
    assert main(["inspect", str(path)]) == 1
    err = capsys.readouterr().err
    assert (
        err
        == f"fleetsim: error: {path}: this is not a map file: a map is a Tiled map (.json, .tmj, .tmx), a LIF file (.lif.json), an RMF building map (.building.yaml) or a MovingAI grid map (.map), and this file ends in '.csv'\n"
    )
