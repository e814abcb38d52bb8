"""Generated suite entries: hunting, shrinking, saving and reporting counterexamples."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.cli import main
from fleetsim.gating.generated import counterexample_entry, hunt, record_counterexample
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.sim.record import RunOrigin

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
    saved = Path(record_counterexample(found, tmp_path / "results" / "random-loops", RunOrigin())["scenario"])
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
    assert found.counterexample is None and found.generated == 15


def test_fleetsim_run_and_validate_take_generated_entries(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write_suite(tmp_path)
    assert main(["validate", str(path)]) == 0
    assert (
        "ok   random-loops: generated (loop layouts of size 1-2, 1-3 vehicles, 1-2 tasks each, 30 examples)"
        in capsys.readouterr().out
    )
    status = main(["run", str(path), "--planner", "fleetsim.planners:BFSPlanner", "--record", str(tmp_path / "runs")])
    err = capsys.readouterr().err
    assert status == 1
    assert (
        "reduced it to a counterexample" in err
        and "It is saved as" in err
        and "  - name: random-loops-counterexample" in err
    )
    assert (tmp_path / "runs" / "hunting" / "random-loops" / "counterexample" / "map.json").is_file()
    assert (tmp_path / "runs" / "hunting" / "random-loops" / "run.mcap").is_file()


# -- issue 16, point 4 ------------------------------------------------------------------------------

WAREHOUSE_SUITE = """\
fleetsim: 1
name: crowded
vehicle_types:
  agv: {{length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}}
defaults:
  time_limit: 120
scenarios:
  - name: crowded-warehouse
    generate: {{layout: warehouse, size: {size}, vehicles: {vehicles}, tasks: [1, 1], examples: {examples}}}
"""


def write_warehouse_suite(folder: Path, size: str = "[1, 2]", vehicles: str = "[2, 4]", examples: int = 5) -> Path:
    path = folder / "crowded.fleetsim.yaml"
    path.write_text(WAREHOUSE_SUITE.format(size=size, vehicles=vehicles, examples=examples), encoding="utf-8")
    return path


def test_fleetsim_run_without_record_saves_the_counterexample_under_fleetsim_results_and_prints_the_entry(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    write_suite(tmp_path, examples=5)
    status = main(["run", "hunting.fleetsim.yaml", "--planner", "fleetsim.planners:BFSPlanner"])
    captured = capsys.readouterr()
    assert status == 1
    folder = Path("fleetsim-results") / "hunting" / "random-loops"
    assert f"It is saved as {folder / 'counterexample'}/" in captured.err
    assert "  - name: random-loops-counterexample\n" in captured.err
    assert f"    dir: {(folder / 'counterexample').as_posix()}/\n" in captured.err
    assert sorted(p.name for p in (folder / "counterexample").iterdir()) == ["map.json", "tasks.csv", "vehicles.csv"]
    assert (folder / "run.mcap").is_file() and (folder / "result.json").is_file()


def test_the_counts_say_exactly_how_many_scenarios_ran(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("CI", "1")  # fleetsim run derandomised, to find what hunt(derandomize=True) finds
    suite = load_suite(write_suite(tmp_path, examples=5))
    [spec] = suite.scenarios
    made: list[BFSPlanner] = []

    def planner() -> BFSPlanner:
        made.append(BFSPlanner())
        return made[-1]

    found = hunt(spec, suite, planner, identity="bfs", derandomize=True)
    assert found.counterexample is not None
    assert 1 <= found.generated <= 5, "no more generated scenarios than examples: 5"
    assert found.shrink_runs > 0
    assert found.ran == found.generated + found.shrink_runs + 1 == len(made), "one more run records the counterexample"

    path = write_suite(tmp_path, examples=5)
    assert (
        main(["run", str(path), "--planner", "fleetsim.planners:BFSPlanner", "--record", str(tmp_path / "runs")]) == 1
    )
    err = capsys.readouterr().err
    document = json.loads((tmp_path / "runs" / "hunting" / "random-loops" / "result.json").read_text(encoding="utf-8"))
    assert (document["generated"], document["shrink_runs"]) == (found.generated, found.shrink_runs)
    assert (
        f"Hypothesis ran {found.generated} generated scenario(s) (at most 5, the entry's examples); the last failed, "
        f"and {found.shrink_runs} shrink run(s) reduced it to a counterexample, which ran once more to be recorded "
        f"({found.ran} runs in all)."
    ) in " ".join(err.split())


def test_a_passing_hunt_counts_the_examples_it_ran(tmp_path: Path) -> None:
    suite = load_suite(write_suite(tmp_path, examples=6))
    [spec] = suite.scenarios
    made: list[ReservingPlanner] = []

    def planner() -> ReservingPlanner:
        made.append(ReservingPlanner())
        return made[-1]

    found = hunt(spec, suite, planner, identity="reserving", derandomize=True)
    assert (
        found.counterexample is None and (found.generated, found.shrink_runs, found.ran) == (6, 0, 6) and len(made) == 6
    )
    assert found.result is not None and found.result.passed, "the last run, for the summary row"


def test_a_passing_generated_entry_has_a_summary_row_with_the_examples_it_ran(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_suite(tmp_path, examples=4)
    assert main(["run", str(path), "--planner", "fleetsim.planners:ReservingPlanner"]) == 0
    table = capsys.readouterr().out.splitlines()
    [row] = [line for line in table if line.startswith("random-loops")]
    cells = row.split()
    assert cells[:4] == ["random-loops", "(4", "generated)", "passed"], row
    assert "-" not in cells[4:6], "the last example's tasks and makespan"
    assert not (tmp_path / "fleetsim-results").exists(), "a passing hunt saves nothing"


def test_a_generate_block_whose_layouts_cannot_hold_its_vehicles_is_refused_with_its_place(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_warehouse_suite(tmp_path, size="[1, 1]", vehicles="[4, 5]")
    status = main(["run", str(path), "--planner", "fleetsim.planners:ReservingPlanner", "--json"])
    captured = capsys.readouterr()
    assert status == 1
    [document] = [json.loads(line) for line in captured.out.splitlines()]
    assert document["ended"] == "load-error" and document["trace_hash"] is None
    message = document["failures"][0]["message"]
    assert message == (
        f"{path}:8: field 'generate': scenario 'crowded-warehouse': generate.vehicles=[4, 5] needs room for 5 vehicles "
        "with non-conflicting starts, but warehouse layouts of size [1, 1] have room for 1 (vehicle radius 0.58 m); "
        "allow larger layouts (size) or fewer vehicles"
    )


def test_fleetsim_validate_refuses_a_generate_block_no_layout_has_room_for(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_warehouse_suite(tmp_path, size="[1, 1]", vehicles="[4, 5]")
    assert main(["validate", str(path)]) == 1
    out = capsys.readouterr().out
    assert (
        "  FAIL crowded-warehouse\n" in out
        and f"{path}:8: field 'generate'" in out
        and "0 scenario(s) valid, 1 failed" in out
    )


def test_fleetsim_validate_accepts_a_generate_block_with_room(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_warehouse_suite(tmp_path, size="[1, 2]", vehicles="[2, 4]")
    assert main(["validate", str(path)]) == 0
    assert "  ok   crowded-warehouse: generated" in capsys.readouterr().out


def test_vehicles_range_is_honoured_in_a_hunt(tmp_path: Path) -> None:
    suite = load_suite(write_warehouse_suite(tmp_path, size="[1, 2]", vehicles="[2, 4]", examples=8))
    [spec] = suite.scenarios
    counts: list[int] = []

    class Counting(ReservingPlanner):
        def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
            counts.append(len(fleet.vehicles))
            return super().plan_routes(task, fleet, layout)

    hunt(spec, suite, Counting, identity="counting", derandomize=True)
    assert counts and min(counts) >= 2 and max(counts) <= 4, sorted(set(counts))
