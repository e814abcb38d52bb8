"""The ``fleetsim`` command: validate, inspect and render, run in-process through ``main``."""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from fleetsim.cli import main

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
CROSSING_MAP = SUITES / "examples" / "crossing" / "map.json"


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def test_validate_accepts_every_shipped_suite(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(capsys, "validate", str(SUITES))
    assert status == 0, out + err
    assert "0 failed" in out
    for name in ("crossing", "loop-one-way", "corridor-passing-bay", "mixed-shapes"):
        assert f"ok   {name}:" in out


def test_validate_reports_a_located_error_and_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # The example map refers to the shipped templates by relative path: copy both.
    shutil.copytree(SUITES / "examples" / "crossing", tmp_path / "examples" / "crossing")
    shutil.copytree(SUITES / "tiled", tmp_path / "tiled")
    (tmp_path / "examples" / "crossing" / "tasks.csv").write_text("vehicle_id,goal_segment_id\n1,4\n2,99\n")
    suite = tmp_path / "bad.fleetsim.yaml"
    suite.write_text("fleetsim: 1\nname: bad\nscenarios:\n  - name: crossing\n    dir: examples/crossing/\n")
    status, out, err = run(capsys, "validate", str(suite))
    assert status == 1
    assert "FAIL crossing" in out
    assert "tasks.csv:3" in out and "99" in out
    assert "Traceback" not in out + err


def test_validate_of_a_broken_yaml_file_names_its_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    suite = tmp_path / "broken.fleetsim.yaml"
    suite.write_text("fleetsim: 1\nname: broken\nscenarios: [\n")
    status, out, _ = run(capsys, "validate", str(suite))
    assert status == 1
    assert f"{suite}:" in out


def test_inspect_json_lists_segments_connections_and_conflicts(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(capsys, "inspect", str(CROSSING_MAP), "--json")
    assert status == 0
    doc = json.loads(out)
    assert [s["id"] for s in doc["segments"]] == list(range(1, 9))
    first = doc["segments"][0]
    assert first["shape"] == "straight" and first["direction"] == "both"
    assert first["length"] == pytest.approx(4.0)
    assert first["waypoints"] == [[-8.0, 0.0], [-4.0, 0.0]]
    assert {"from": [2, "forward"], "to": [3, "forward"], "joint": "same"} in doc["connections"]
    assert {"from": [2, "forward"], "to": [7, "forward"], "joint": "turn_in_place"} in doc["connections"]
    conflicts = {entry["segment"]: entry["conflicts"] for entry in doc["conflicts"]}
    assert conflicts[2] == [1, 2, 3, 6, 7]
    assert 5 not in conflicts[1]


def test_inspect_radius_changes_the_conflicts(capsys: pytest.CaptureFixture[str]) -> None:
    _, small, _ = run(capsys, "inspect", str(CROSSING_MAP), "--json", "--radius", "0.5")
    _, large, _ = run(capsys, "inspect", str(CROSSING_MAP), "--json", "--radius", "3")
    small_conflicts = {e["segment"]: e["conflicts"] for e in json.loads(small)["conflicts"]}
    large_conflicts = {e["segment"]: e["conflicts"] for e in json.loads(large)["conflicts"]}
    # The outer west and south arms are 5.66 m apart: only a 3 m radius makes them conflict.
    assert 5 not in small_conflicts[1]
    assert 5 in large_conflicts[1]


def test_inspect_text_shows_the_sections(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(capsys, "inspect", str(CROSSING_MAP))
    assert status == 0
    for heading in ("segments", "connections", "conflicts", "lint"):
        assert f"\n{heading}" in out
    assert "2 forward -> 3 forward: same" in out


def test_inspect_of_a_missing_map_is_a_one_line_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, _out, err = run(capsys, "inspect", str(tmp_path / "nope.json"))
    assert status == 1
    assert "nope.json" in err and "Traceback" not in err


def _stroke_of(svg: ET.Element, segment: int) -> str:
    ns = {"svg": "http://www.w3.org/2000/svg"}
    for line in svg.iterfind(".//svg:polyline", ns):
        if line.get("data-segment") == str(segment):
            return line.get("stroke", "")
    raise AssertionError(f"segment {segment} not drawn")


def test_render_highlight_colours_segment_successors_and_conflicts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out_svg = tmp_path / "pic" / "crossing.svg"
    status, _out, _ = run(capsys, "render", str(CROSSING_MAP), "-o", str(out_svg), "--highlight", "2")
    assert status == 0 and out_svg.exists()
    svg = ET.parse(out_svg).getroot()
    # Yellow: the highlighted segment, although its U-turns make it one of its own successors.
    assert _stroke_of(svg, 2) == "#f2c200"
    assert _stroke_of(svg, 3) == "#2e9e3f"  # green: straight on
    assert _stroke_of(svg, 7) == "#2e9e3f"  # green: turn north at the junction
    assert _stroke_of(svg, 1) == "#2e9e3f"  # green: back west (segment 2 is two-way)
    assert _stroke_of(svg, 6) == "#2e9e3f"
    assert _stroke_of(svg, 5) == "#3b4a6b"  # far away: plain
    texts = {t.text for t in svg.iter("{http://www.w3.org/2000/svg}text")}
    assert {str(i) for i in range(1, 9)} <= texts


def test_render_marks_conflicting_but_unconnected_segments_grey(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out_svg = tmp_path / "loop.svg"
    loop = SUITES / "examples" / "loop" / "map.tmx"
    # Segment 4 is the one-way right-hand side; with a 2.5 m radius the top and bottom straights
    # near the corners come within reach without being connected to it.
    status, _, _ = run(capsys, "render", str(loop), "-o", str(out_svg), "--highlight", "4", "--radius", "2.5")
    assert status == 0
    svg = ET.parse(out_svg).getroot()
    assert _stroke_of(svg, 4) == "#f2c200"
    assert _stroke_of(svg, 5) == "#2e9e3f"
    assert _stroke_of(svg, 2) == "#9a9a9a"
    assert _stroke_of(svg, 3) == "#9a9a9a"  # leads *into* 4, but 4 does not lead to it


def test_render_draws_one_arrow_per_allowed_direction(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out_svg = tmp_path / "loop.svg"
    run(capsys, "render", str(SUITES / "examples" / "loop" / "map.tmx"), "-o", str(out_svg))
    svg = ET.parse(out_svg).getroot()
    arrows = list(svg.iter("{http://www.w3.org/2000/svg}polygon"))
    # 10 segments, 3 of them one-way: 7 * 2 + 3 * 1 arrows.
    assert len(arrows) == 17


def test_render_unknown_highlight_is_an_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = run(capsys, "render", str(CROSSING_MAP), "-o", str(tmp_path / "x.svg"), "--highlight", "42")
    assert status == 1
    assert "highlight=42" in err
    assert not (tmp_path / "x.svg").exists()


@pytest.mark.parametrize(
    ("command", "usage"),
    [
        (["validate", "--help"], "usage: fleetsim validate"),
        (["render", "--help"], "usage: fleetsim render"),
        (["sweep", "--help"], "usage: fleetsim sweep"),
        (["sweep", "report", "--help"], "usage: fleetsim sweep report"),
    ],
)
def test_every_command_answers_help_with_its_usage_and_description(
    command: list[str], usage: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exited:
        main(command)
    out = capsys.readouterr().out
    assert exited.value.code == 0 and out.startswith(usage)
    assert len(out.splitlines()) > 4  # the description (the command's docstring) and the options follow
