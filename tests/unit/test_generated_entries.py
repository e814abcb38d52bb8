"""Generated suite entries: hunting, shrinking, saving and reporting counterexamples."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.cli import main
from fleetsim.gating.generated import counterexample_entry, hunt, record_counterexample
from fleetsim.planners import BFSPlanner, ReservingPlanner

SUITE = """\
fleetsim: 1
name: hunting
vehicle_types:
  agv: {{length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}}
defaults:
  time_limit: 120
scenarios:
  - name: random-loops
    generate: {{layout: {layout}, size: [1, 2], vehicles: [1, 3], tasks: [1, 2], examples: {examples}}}
"""


def write_suite(folder: Path, layout: str = "loop", examples: int = 30) -> Path:
    path = folder / "hunting.fleetsim.yaml"
    path.write_text(SUITE.format(layout=layout, examples=examples), encoding="utf-8")
    return path


def test_a_faulty_planner_is_caught_and_the_counterexample_shrunk(tmp_path: Path) -> None:
    # BFSPlanner ignores a task's goal direction: one vehicle on the smallest loop shows it.
    suite = load_suite(write_suite(tmp_path))
    [spec] = suite.scenarios
    found = hunt(spec, suite, BFSPlanner, identity="bfs", derandomize=True)
    assert found.counterexample is not None and found.result is not None
    assert not found.result.passed and found.result.failures[0].kind == "rejection"
    assert "goal-direction" in found.result.failures[0].message
    assert len(found.counterexample.vehicles) == 1 and len(found.counterexample.tasks) == 1
    assert len(found.counterexample.layout.segments) == 8, "the smallest loop: four sides, four corners"
    again = hunt(spec, suite, BFSPlanner, identity="bfs", derandomize=True)
    assert again.counterexample is not None
    same = [(c.layout.segments, c.vehicles, c.tasks) for c in (again.counterexample, found.counterexample)]
    assert same[0] == same[1], "derandomised: the same counterexample every time"


def test_the_saved_counterexample_pasted_into_the_suite_runs_as_an_ordinary_scenario(tmp_path: Path) -> None:
    path = write_suite(tmp_path)
    suite = load_suite(path)
    [spec] = suite.scenarios
    found = hunt(spec, suite, BFSPlanner, identity="bfs", derandomize=True)
    assert found.counterexample is not None
    saved = Path(record_counterexample(found, tmp_path / "results" / "random-loops", {})["scenario"])
    entry = counterexample_entry(spec, saved, path)
    assert entry.startswith("  - name: random-loops-counterexample\n")
    assert "    dir: results/random-loops/counterexample/\n" in entry
    path.write_text(path.read_text(encoding="utf-8") + entry, encoding="utf-8")
    pasted = load_suite(path)
    loaded = load_scenario(pasted.scenarios[1], pasted)
    assert loaded.layout.segments == found.counterexample.layout.segments
    assert [(v.id, v.start_segment, v.traverse) for v in loaded.vehicles] == [
        (v.id, v.start_segment, v.traverse) for v in found.counterexample.vehicles
    ]
    assert loaded.tasks == found.counterexample.tasks


def test_a_sound_planner_passes_the_hunt(tmp_path: Path) -> None:
    suite = load_suite(write_suite(tmp_path, examples=15))
    [spec] = suite.scenarios
    found = hunt(spec, suite, ReservingPlanner, identity="reserving", derandomize=True)
    assert found.counterexample is None and found.tried == 15


def test_fleetsim_run_and_validate_take_generated_entries(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write_suite(tmp_path)
    assert main(["validate", str(path)]) == 0
    assert "ok   random-loops: generated (loop layouts of size 1-2, 1-3 vehicles, 1-2 tasks each, 30 examples)" in capsys.readouterr().out
    status = main(["run", str(path), "--planner", "fleetsim.planners:BFSPlanner", "--record", str(tmp_path / "runs")])
    err = capsys.readouterr().err
    assert status == 1
    assert "shrank the first failing one; it is saved as" in err and "  - name: random-loops-counterexample" in err
    assert (tmp_path / "runs" / "hunting" / "random-loops" / "counterexample" / "map.json").is_file()
    assert (tmp_path / "runs" / "hunting" / "random-loops" / "run.mcap").is_file()
