"""``fleetsim render --trace``: a step of a recorded run as SVG, and clean errors for bad input."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.cli import main
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.recording.artifacts import TRACE_FILE, write_run_artifacts
from fleetsim.recording.picture import failure_picture
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.record import RunOrigin

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"


def crossing() -> Scenario:
    suite = load_suite(SUITE)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == "crossing"), suite)


@pytest.fixture
def collided(tmp_path: Path) -> Path:
    """The artifact folder of the BFS planner's collision in the crossing, as the pytest plugin writes it."""
    folder = tmp_path / "artifacts" / "examples" / "crossing"
    write_run_artifacts(folder, run_scenario(crossing(), BFSPlanner(), keep_trace=True), RunOrigin(str(SUITE)))
    return folder


def render(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    status = main(["render", *argv])
    out, err = capsys.readouterr()
    return status, out, err


def picture(path: Path) -> ET.Element:
    return ET.parse(path).getroot()


def texts(root: ET.Element, name: str) -> list[str]:
    return [e.text or "" for e in root.iter() if name in e.get("class", "").split()]


def alert_segments(root: ET.Element) -> set[int]:
    return {int(e.get("data-segment", "0")) for e in root.iter() if e.get("class") == "alert"}


def test_a_given_step_is_drawn(collided: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    output = tmp_path / "step0.svg"
    status, out, err = render(capsys, "--trace", str(collided), "--step", "0", "-o", str(output))
    assert (status, err) == (0, "")
    assert f"wrote {output} (crossing, step 0 of 1" in out
    root = picture(output)
    assert texts(root, "caption-text") == ["t = 0.10 s — crossing, step 0 of 1"]
    assert alert_segments(root) == set()  # the alerts come with the plans of step 1
    assert len([e for e in root.iter() if e.get("class") == "vehicle"]) == 2


def test_by_default_the_failure_step_is_drawn_as_failure_picture_draws_it(
    collided: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "failure.svg"
    status, out, _ = render(capsys, "--trace", str(collided), "-o", str(output))
    assert status == 0 and "step 1 of 1" in out
    root = picture(output)
    assert texts(root, "caption-text") == [
        "t = 0.20 s — possible collision on segment 2: primary 1; secondary 2"
    ]  # the frame's own time
    assert alert_segments(root) == {2, 3, 6, 7}
    expected = failure_picture(crossing(), run_scenario(crossing(), BFSPlanner(), keep_trace=True))
    assert expected is not None and output.read_text(encoding="utf-8") == expected[1]


def test_the_trace_file_itself_can_be_named(collided: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    output = tmp_path / "failure.svg"
    status, _, _ = render(capsys, "--trace", str(collided / TRACE_FILE), "-o", str(output))
    assert status == 0 and alert_segments(picture(output)) == {2, 3, 6, 7}


def test_a_passed_run_is_drawn_at_its_last_step(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    result = run_scenario(crossing(), ReservingPlanner(), keep_trace=True)
    folder = tmp_path / "passed"
    write_run_artifacts(folder, result, RunOrigin(str(SUITE)))
    output = tmp_path / "last.svg"
    status, out, _ = render(capsys, "--trace", str(folder), "-o", str(output))
    assert status == 0
    assert f"step {result.steps - 1} of {result.steps - 1}" in out
    assert texts(picture(output), "caption-text")[0].endswith(
        f"crossing, step {result.steps - 1} of {result.steps - 1}"
    )


def test_a_trace_without_result_json_needs_suite(
    collided: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lone = tmp_path / "lone" / TRACE_FILE
    lone.parent.mkdir()
    lone.write_text((collided / TRACE_FILE).read_text())
    output = tmp_path / "out.svg"
    status, _, err = render(capsys, "--trace", str(lone), "-o", str(output))
    assert status == 2 and "--suite SUITE::SCENARIO" in err and str(lone) in err
    status, _, err = render(capsys, "--trace", str(lone), "--suite", f"{SUITE}::crossing", "-o", str(output))
    assert (status, err) == (0, "")
    assert texts(picture(output), "caption-text") == [
        "t = 0.20 s — crossing, step 1 of 1"
    ]  # no result: no failure known


def test_a_step_out_of_range_is_a_usage_error(
    collided: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "out.svg"
    status, out, err = render(capsys, "--trace", str(collided), "--step", "5", "-o", str(output))
    assert status == 2 and out == ""
    assert err == f"fleetsim: error: {collided / TRACE_FILE}: --step=5 must be between 0 and 1 (the run's last step)\n"
    assert not output.exists()


def test_a_missing_trace_is_a_usage_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "untraced"
    write_run_artifacts(folder, run_scenario(crossing(), BFSPlanner(), keep_trace=False), RunOrigin(str(SUITE)))
    status, _, err = render(capsys, "--trace", str(folder), "-o", str(tmp_path / "out.svg"))
    assert status == 2
    assert err == f"fleetsim: error: {folder}: no {TRACE_FILE} in this folder (the run did not keep its trace)\n"
    status, _, err = render(capsys, "--trace", str(tmp_path / "nowhere"), "-o", str(tmp_path / "out.svg"))
    assert (status, err) == (2, f"fleetsim: error: {tmp_path / 'nowhere'}: no such file or directory\n")


def test_a_trace_of_another_scenario_is_a_usage_error(
    collided: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = collided / TRACE_FILE
    header, *steps = trace.read_text().splitlines()
    trace.write_text("\n".join([json.dumps({**json.loads(header), "vehicles": [1, 2, 3]}), *steps]) + "\n")
    status, _, err = render(capsys, "--trace", str(collided), "-o", str(tmp_path / "out.svg"))
    assert status == 2
    assert err.startswith(f"fleetsim: error: {trace}: trace vehicles=[1, 2, 3] must be scenario 'crossing'")
    assert err.count("\n") == 1


def test_an_unknown_scenario_in_suite_is_named_with_a_suggestion(
    collided: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, _, err = render(
        capsys, "--trace", str(collided), "--suite", f"{SUITE}::crosing", "-o", str(tmp_path / "o.svg")
    )
    assert status == 2 and "no scenario 'crosing'" in err and "did you mean 'crossing'?" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["-o", "out.svg"],  # neither MAP nor --trace
        ["map.json", "--trace", "run", "-o", "out.svg"],  # both
        ["map.json", "--step", "3", "-o", "out.svg"],  # --step draws a recorded run
    ],
)
def test_mixing_map_and_trace_options_is_a_usage_error(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = render(capsys, *argv)
    assert status == 2 and err.startswith("fleetsim: error: ") and err.count("\n") == 1
