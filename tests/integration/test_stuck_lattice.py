"""The stuck-fleet example of the documentation (docs/reviewing.md): 30 vehicles on a 21 x 21 grid with a greedy planner.

Whatever the planner does about it, every vehicle that still has a task at the end must be explained:
a reason, the vehicles and segments involved, a root cause in the headline, and all of it in the picture.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType

from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.planners import GreedyPlanner
from fleetsim.recording.artifacts import write_run_artifacts
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.diagnosis import REASONS
from fleetsim.sim.loop import run_scenario

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


def lattice_module() -> ModuleType:
    spec = importlib.util.spec_from_file_location("lattice", BENCHMARKS / "lattice.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_stuck_vehicle_of_the_dense_lattice_is_explained_and_drawn(tmp_path: Path) -> None:
    lattice = lattice_module()
    folder = lattice.write_lattice_scenario(tmp_path / "lattice", 21, 30, seed=1)
    scenario = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=600.0))
    result = run_scenario(scenario, GreedyPlanner())
    assert result.status == "failed" and result.ended in ("deadlock", "time-limit")
    paths = write_run_artifacts(tmp_path / "run", result, scenario=scenario)
    document = json.loads(Path(paths["result"]).read_text(encoding="utf-8"))
    [stuck] = [f for f in document["failures"] if f["kind"] in ("deadlock", "timeout")]

    pending_vehicles = sorted({task.vehicle_id for task in result.pending})
    assert [finding["vehicle"] for finding in stuck["vehicles"]] == pending_vehicles
    roots = {vehicle for root in stuck["roots"] for vehicle in root["vehicles"]}
    for finding in stuck["vehicles"]:
        assert finding["reason"] in REASONS
        assert finding["text"].startswith(f"vehicle {finding['vehicle']} (task {finding['task']}")
        if finding["reason"] in ("waits-for", "blocked-by-idle"):
            assert (
                finding["blocked_by"] and finding["contested"] and finding["leg"]["segment"] in scenario.layout.segments
            )
            # Its wait ends at a root cause: its chain's last vehicle, or a cycle it belongs to.
            assert finding.get("chain", [finding["vehicle"]])[-1] in roots or finding["vehicle"] in roots
        else:
            assert finding["vehicle"] in roots  # nobody's fault but its own (or the planner's)
    # The headline names the root cause most vehicles wait behind.
    first = stuck["roots"][0]
    assert first["text"] in stuck["message"]
    svg = Path(paths["picture"]).read_text(encoding="utf-8")
    drawn = {(int(a), int(b)) for a, b in (part.split('" data-to="') for part in _attribute_pairs(svg))}
    waits = {(finding["vehicle"], other) for finding in stuck["vehicles"] for other in finding.get("blocked_by", ())}
    assert waits <= drawn
    assert svg.count('class="root-cause"') == len(roots)


def _attribute_pairs(svg: str) -> list[str]:
    return [chunk.split('">', 1)[0] for chunk in svg.split('data-from="')[1:]]
