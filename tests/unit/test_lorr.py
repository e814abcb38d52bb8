"""League of Robot Runners problems: the problem file's keys by edition, robots as vehicles, tasks as pooled
orders, the 2026 keys, and every located error of the problem, agent and task files."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from fleetsim.enums import Traverse
from fleetsim.errors import LoadError, LoadErrors, ScenarioFileError, SuiteError
from fleetsim.load.lorr.fleet import task_pool
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.orders import Shift
from fleetsim.scenario import Scenario

# 8 x 3 cells: a ring round a wall. Location = row * 8 + column.
GRID = ["........", ".@@@@@@.", "........"]


def write_problem(
    folder: Path,
    *,
    agents: list[int] | str | None = None,
    tasks: list[str] | str | None = None,
    version: str | None = "2024 LoRR",
    name: str = "problem.json",
    **keys: Any,
) -> Path:
    agents = [0, 7, 16] if agents is None else agents
    tasks = ["3,19", "20,4", "23"] if tasks is None else tasks
    (folder / "ring.map").write_text("type octile\nheight 3\nwidth 8\nmap\n" + "\n".join(GRID) + "\n")
    agent_text = agents if isinstance(agents, str) else f"{len(agents)}\n" + "".join(f"{a}\n" for a in agents)
    (folder / "ring.agents").write_text(agent_text)
    task_text = (
        tasks
        if isinstance(tasks, str)
        else f"# version for LoRR 2024\n{len(tasks)}\n" + "".join(f"{t}\n" for t in tasks)
    )
    (folder / "ring.tasks").write_text(task_text)
    problem: dict[str, Any] = {
        "mapFile": "ring.map",
        "agentFile": "ring.agents",
        "teamSize": 2,
        "taskFile": "ring.tasks",
        "numTasksReveal": 1.5,
    }
    if version is not None:
        problem["version"] = version
    problem.update(keys)
    path = folder / name
    path.write_text(json.dumps(problem, indent=4) + "\n")
    return path


def load_problem(folder: Path, entry: str = "", **problem: Any) -> Scenario:
    write_problem(folder, **problem)
    suite_path = folder / "ring.fleetsim.yaml"
    suite_path.write_text(f"fleetsim: 1\nname: ring\nscenarios:\n  - name: one\n    lorr: problem.json\n{entry}")
    suite = load_suite(suite_path)
    return load_scenario(suite.scenarios[0], suite)


def messages(error: LoadError) -> list[str]:
    return [str(e) for e in error.errors] if isinstance(error, LoadErrors) else [str(error)]


def test_robots_are_the_first_team_size_agents_and_tasks_are_orders_released_as_a_pool(tmp_path: Path) -> None:
    scenario = load_problem(tmp_path, "    horizon: 60\n")
    segments = scenario.layout.segments
    assert [v.id for v in scenario.vehicles] == [0, 1]  # the Start-Kit's agent ids
    # Agent 0 at location 0 (r0c0) faces right; agent 1 at 7 (r0c7) faces down (its left is free but r0c6
    # is not taken either: right comes first, and there is no right).
    first, second = scenario.vehicles
    assert segments[first.start_segment].name == "r0c0-r0c1" and first.traverse is Traverse.FORWARD
    assert segments[second.start_segment].name == "r0c7-r1c7" and second.traverse is Traverse.FORWARD
    assert [o.id for o in scenario.orders] == ["t0", "t1", "t2"]
    assert [len(o.stops) for o in scenario.orders] == [2, 2, 1]
    assert all(o.release == 0.0 and all(s.dwell == 0.0 for s in o.stops) for o in scenario.orders)
    assert scenario.order_pool == 3  # floor(1.5 x 2)
    assert scenario.shift == Shift(60.0) and scenario.settings.time_limit == 60.0
    assert scenario.dispatcher == "fleetsim.dispatchers:NearestVehicleDispatcher"
    assert scenario.lorr is not None
    assert (scenario.lorr.edition, scenario.lorr.team_size, scenario.lorr.task_pool, scenario.lorr.horizon) == (
        "2024",
        2,
        3,
        60,
    )
    assert scenario.vehicles[0].type.name == "movingai" and scenario.vehicles[0].type.max_speed == 1.0


def test_an_errand_is_the_segment_from_its_cell_toward_the_previous_errand(tmp_path: Path) -> None:
    scenario = load_problem(tmp_path)
    names = [[scenario.layout.segments[s.segment].name for s in o.stops] for o in scenario.orders]
    # t0: 3 (r0c3) toward its next errand 19 (r2c3): r0c3's neighbours are r0c4, r0c2 (r1c3 is wall);
    # equally far, so right first. 19 toward 3: r2c4 and r2c2 equally far, right first.
    # t2: a lone errand at 23 (r2c7): right, below, left, above: left (r2c6) is the first free one.
    assert names == [["r0c3-r0c4", "r2c3-r2c4"], ["r2c4-r2c5", "r0c4-r0c5"], ["r2c6-r2c7"]]


def test_the_pool_is_at_least_one_and_floors_the_product() -> None:
    assert (
        task_pool(1.5, 2) == 3 and task_pool(0.1, 3) == 1 and task_pool(2.0, 5) == 10 and task_pool(1e308, 8) == 2**31
    )


def test_a_2023_problem_has_no_version_one_location_per_task_and_may_say_robot_file(tmp_path: Path) -> None:
    path = write_problem(tmp_path, version=None, tasks=["3", "19"], taskAssignmentStrategy="greedy", numTasksReveal=2)
    raw = json.loads(path.read_text())
    raw["robotFile"] = raw.pop("agentFile")
    path.write_text(json.dumps(raw))
    suite = load_suite(path)  # a problem file run on its own
    scenario = load_scenario(suite.scenarios[0], suite)
    assert suite.name == "problem" and suite.scenarios[0].name == "problem"
    assert scenario.lorr is not None and scenario.lorr.edition == "2023" and scenario.lorr.horizon == 5000
    assert scenario.order_pool == 4
    assert any("taskAssignmentStrategy 'greedy' has no counterpart" in note for note in scenario.lorr.not_mapped)


def test_a_2023_task_with_several_locations_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match=r"ring.tasks:3:2: the line '3,19' has 2 locations; a task has one"):
        load_problem(tmp_path, version=None, tasks=["3,19"], numTasksReveal=1)


def test_2026_agent_size_scales_the_footprint_and_delays_become_random_stops(tmp_path: Path) -> None:
    delays = {"seed": 7, "minDelay": 2, "maxDelay": 6, "eventModel": "bernoulli", "pDelay": 0.01}
    scenario = load_problem(tmp_path, version="2026 LoRR", agentSize=2.0, agentCounter=10, delayConfig=delays)
    kind = scenario.vehicles[0].type
    assert (kind.length, kind.width) == (1.0, 1.0)  # agentSize x half a cell
    drawn = scenario.random_disturbances
    assert drawn is not None and drawn.seed == 7 and drawn.stop == (2.0, 6.0)
    assert drawn.stops_per_vehicle_hour == pytest.approx(36.0)  # 0.01 per timestep x 3600
    assert scenario.lorr is not None
    notes = " / ".join(scenario.lorr.not_mapped)
    assert "agentCounter 10 is not mapped" in notes and "not the Start-Kit's" in notes


def test_poisson_delays_spread_their_rate_over_the_team_and_gaussian_durations_are_named(tmp_path: Path) -> None:
    delays = {"eventModel": "poisson", "poissonLambda": 0.02, "durationModel": "gaussian", "maxDelay": 4}
    scenario = load_problem(tmp_path, version="2026 LoRR", delayConfig=delays)
    assert scenario.random_disturbances is not None
    assert scenario.random_disturbances.stops_per_vehicle_hour == pytest.approx(36.0)  # 0.02 / 2 robots x 3600
    assert scenario.random_disturbances.stop == (1.0, 4.0)
    assert scenario.lorr is not None and any("'gaussian'" in note for note in scenario.lorr.not_mapped)
    quiet = load_problem(tmp_path / "..", version="2026 LoRR", delayConfig={"pDelay": 0})
    assert quiet.random_disturbances is None


def test_agents_runs_the_first_n_and_task_rounds_repeats_the_file_with_ids_counting_on(tmp_path: Path) -> None:
    scenario = load_problem(tmp_path, "    agents: 3\n    task_rounds: 2\n")
    assert len(scenario.vehicles) == 3 and scenario.order_pool == 4  # floor(1.5 x 3)
    assert [o.id for o in scenario.orders] == ["t0", "t1", "t2", "t3", "t4", "t5"]
    assert scenario.orders[3].stops == scenario.orders[0].stops


def test_more_agents_than_the_file_has_is_an_error_at_the_suite_key(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match=r"fleetsim.yaml:6:13: agents=4, but the agent file ring.agents has 3"):
        load_problem(tmp_path, "    agents: 4\n")


def test_a_team_larger_than_the_agent_file_is_an_error_at_team_size(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match=r"problem.json:4:5: field '/teamSize': teamSize=5, but the agent file"):
        load_problem(tmp_path, teamSize=5)


PROBLEM_ERRORS = [
    ({"teamSize": "8"}, r"problem.json:4:5: field '/teamSize': teamSize=\"8\" must be a whole number"),
    ({"teamSize": 0}, r"teamSize=0 must be >= 1"),
    ({"version": "2025 LoRR"}, r"field '/version': version \"2025 LoRR\" is not a League of Robot Runners edition"),
    ({"numTasksReveal": -1}, r"numTasksReveal=-1 must be a number > 0"),
    ({"taskFile": "nope.tasks"}, r"field '/taskFile': taskFile: no such file 'nope.tasks'"),
    ({"mapFile": 3}, r"mapFile=3 must be a file name"),
    ({"teamsize": 2}, r"unknown key 'teamsize'; did you mean 'teamSize'\?"),
    ({"agentSize": 0}, r"agentSize=0 must be a number > 0"),
    ({"agentCounter": 1.5}, r"agentCounter=1.5 must be a whole number"),
    ({"taskAssignmentStrategy": "fastest"}, r"taskAssignmentStrategy=\"fastest\" must be one of greedy"),
    ({"delayConfig": {"pDelay": 2}}, r"field '/delayConfig/pDelay': delayConfig.pDelay=2 must be a number from 0 to 1"),
    ({"delayConfig": {"minDelay": 5, "maxDelay": 2}}, r"delayConfig.maxDelay=2 must be >= minDelay \(5\)"),
    ({"delayConfig": {"eventModel": "burst"}}, r"delayConfig.eventModel='burst' must be 'bernoulli' or 'poisson'"),
    ({"delayConfig": {"sed": 1}}, r"unknown key 'sed' of delayConfig; did you mean 'seed'\?"),
    ({"delayConfig": []}, r"delayConfig must be an object"),
]


@pytest.mark.parametrize(("keys", "words"), PROBLEM_ERRORS)
def test_a_bad_value_in_the_problem_file_is_located_at_its_key(
    tmp_path: Path, keys: dict[str, Any], words: str
) -> None:
    with pytest.raises(LoadError) as caught:
        load_problem(tmp_path, **keys)
    assert any(re.search(words, message) for message in messages(caught.value)), messages(caught.value)


def test_a_2023_problem_reveals_a_whole_number_of_tasks(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match=r"numTasksReveal=1.5 must be a whole number"):
        load_problem(tmp_path, version=None, tasks=["3"])


def test_a_missing_key_and_malformed_json_are_located(tmp_path: Path) -> None:
    path = write_problem(tmp_path)
    raw = json.loads(path.read_text())
    del raw["teamSize"]
    path.write_text(json.dumps(raw))
    with pytest.raises(ScenarioFileError, match=r"problem.json: field '/': required key 'teamSize' is missing"):
        load_scenario(load_suite(path).scenarios[0], load_suite(path))
    suite_path = tmp_path / "ring.fleetsim.yaml"
    suite_path.write_text("fleetsim: 1\nname: ring\nscenarios:\n  - name: one\n    lorr: problem.json\n")
    path.write_text('{\n  "teamSize": 2,\n  "mapFile": "ring.map",\n}\n')
    suite = load_suite(suite_path)
    with pytest.raises(
        ScenarioFileError, match=r"problem.json:4:1: the file is not valid JSON: a key in double quotes"
    ):
        load_scenario(suite.scenarios[0], suite)
    path.write_text("[1, 2]")
    with pytest.raises(
        ScenarioFileError, match=r"problem.json:1:1: field '/': a League of Robot Runners problem is a JSON object"
    ):
        load_scenario(suite.scenarios[0], suite)


def test_every_bad_line_of_the_agent_and_task_files_is_reported_at_once(tmp_path: Path) -> None:
    with pytest.raises(LoadErrors) as caught:
        load_problem(tmp_path, agents="3\n0\nx\n9\n", tasks="# c\n3\n3,99\n,4\n19,\n")
    assert messages(caught.value) == [
        f"{tmp_path / 'ring.agents'}:3:1: the agent's start is 'x': a location is a whole number (row × width + column)",
        f"{tmp_path / 'ring.agents'}:4:1: location 9 (row 1, column 1) is on a blocked cell '@' (line 6, column 2 of ring.map)",
        f"{tmp_path / 'ring.tasks'}:3:3: location 99 is off the map (8 x 3 cells: locations 0 to 23)",
        f"{tmp_path / 'ring.tasks'}:4:1: errand 1 of the task is empty: a location is a whole number (row × width + column)",
        f"{tmp_path / 'ring.tasks'}:5:4: errand 2 of the task is empty: a location is a whole number (row × width + column)",
    ]


@pytest.mark.parametrize(
    ("agents", "words"),
    [
        ("2\n0\n", r"ring.agents:2: line 1 says 2 agent\(s\), but 1 follow"),
        ("1\n0\n7\n", r"ring.agents:3: line 1 says 1 agent\(s\), but 2 follow; line 3 is one too many"),
        ("two\n0\n", r"ring.agents:1:1: the first line must be the number of agents \(a whole number\), not 'two'"),
        ("", r"ring.agents: the agent file is empty"),
    ],
)
def test_an_agent_file_whose_count_is_wrong_is_located(tmp_path: Path, agents: str, words: str) -> None:
    with pytest.raises(LoadError) as caught:
        load_problem(tmp_path, agents=agents)
    assert any(re.search(words, m) for m in messages(caught.value)), messages(caught.value)


def test_a_lorr_entry_takes_no_vehicles_and_horizon_needs_lorr(tmp_path: Path) -> None:
    write_problem(tmp_path)
    suite_path = tmp_path / "bad.fleetsim.yaml"
    suite_path.write_text(
        "fleetsim: 1\nname: bad\nscenarios:\n  - name: one\n    lorr: problem.json\n    vehicles: v.csv\n"
        "  - name: two\n    dir: .\n    horizon: 10\n"
    )
    with pytest.raises(SuiteError) as caught:
        load_suite(suite_path)
    text = str(caught.value)
    assert "scenarios[0]" in text and "scenarios[1]" in text


def test_a_problem_file_missing_is_an_error_at_the_suite_key(tmp_path: Path) -> None:
    suite_path = tmp_path / "x.fleetsim.yaml"
    suite_path.write_text("fleetsim: 1\nname: x\nscenarios:\n  - name: one\n    lorr: nope.json\n")
    with pytest.raises(SuiteError, match=r"x.fleetsim.yaml:5:11: scenarios\[0\].lorr: no such file"):
        load_suite(suite_path)
