"""Sweep specs: located errors, never a traceback; reproducible generated sources; Dask optional."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from fleetsim.cli.main import main
from fleetsim.sweep.items import expand
from fleetsim.sweep.spec import SweepSpecError, load_sweep_spec

GOOD = """fleetsim-sweep: 1
name: small
planners: [fleetsim.planners:ReservingPlanner, fleetsim.planners:BFSPlanner]
defaults: {time_limit: 30}
sources:
  - name: warehouses
    generate: {layout: warehouse, size: [1, 2], vehicles: [1, 2], tasks: [1, 2]}
    count: 4
    seed: 5
"""


def _spec(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.sweep.yaml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("old", "new", "line", "words"),
    [
        (
            "planners: [fleetsim.planners:ReservingPlanner, fleetsim.planners:BFSPlanner]",
            "planners: [not a spec]",
            3,
            "planners[0]='not a spec'",
        ),
        ("    count: 4", "    count: -4", 8, "count=-4 must be a whole number >= 1"),
        ("size: [1, 2]", "size: [3, 2]", 7, "size=[3, 2] must be [min, max]"),
        ("layout: warehouse", "layout: spiral", 7, "'spiral'"),
        ("defaults: {time_limit: 30}", "defaults: {time_limit: fast}", 4, "'fast'"),
        (
            "name: small",
            "name: small\nbaseline: other:Planner",
            3,
            "baseline='other:Planner' must be one of the planners",
        ),
        (
            "name: small",
            "name: small\ndisturbances: {seeds: [1, 1]}",
            3,
            "seeds[1]=1 must be a whole number >= 0, listed once",
        ),
        (
            "name: small",
            "name: small\ndisturbances: {stop: [30, 5], seeds: [1]}",
            3,
            "stop=[30, 5] must be [MIN, MAX] seconds",
        ),
        (
            "name: small",
            "name: small\ndisturbances: {stops_per_vehicle_hour: 0, seeds: [1]}",
            3,
            "stops_per_vehicle_hour=0 must be a number > 0",
        ),
        ("name: small", "name: small\ndisturbances: {stop: [5, 10]}", 3, "disturbances={'stop': [5, 10]} must be"),
    ],
)
def test_bad_spec_value_is_a_located_error(tmp_path: Path, old: str, new: str, line: int, words: str) -> None:
    path = _spec(tmp_path, GOOD.replace(old, new))
    with pytest.raises(SweepSpecError) as caught:
        load_sweep_spec(path)
    assert caught.value.location is not None and caught.value.location.path == path
    assert caught.value.location.line == line, str(caught.value)
    assert words in str(caught.value)


@pytest.mark.parametrize(
    ("old", "new", "line", "column", "words"),
    [
        ("planners:", "planers:", 3, 1, "unknown key 'planers'; did you mean 'planners'? (known: baseline,"),
        ("defaults:", "defualts:", 4, 1, "unknown key 'defualts'; did you mean 'defaults'?"),
        ("    count: 4", "    cont: 4", 8, 5, "sources[0]: unknown key 'cont'; did you mean 'count'?"),
        ("    generate:", "    generat:", 7, 5, "sources[0]: unknown key 'generat'; did you mean 'generate'?"),
        ("  - name: warehouses", "  - suit: a.fleetsim.yaml\n  - name: warehouses", 6, 5,
         "sources[0]: unknown key 'suit'; did you mean 'suite'?"),
        ("name: small", "name: small\ndisturbances: {seed: [1]}", 3, 16,
         "disturbances: unknown key 'seed'; did you mean 'seeds'? (known: seeds, stop, stops_per_vehicle_hour)"),
    ],
)  # fmt: skip
def test_mistyped_spec_key_is_located_with_the_key_it_means(
    tmp_path: Path, old: str, new: str, line: int, column: int, words: str
) -> None:
    with pytest.raises(SweepSpecError) as caught:
        load_sweep_spec(_spec(tmp_path, GOOD.replace(old, new)))
    assert caught.value.location is not None
    assert (caught.value.location.line, caught.value.location.column) == (line, column), str(caught.value)
    assert words in str(caught.value)


def test_unknown_key_like_no_known_one_gets_no_suggestion(tmp_path: Path) -> None:
    with pytest.raises(SweepSpecError) as caught:
        load_sweep_spec(_spec(tmp_path, GOOD.replace("name: small", "name: small\nxyzzy: 1")))
    assert "unknown key 'xyzzy' (known: baseline," in str(caught.value)
    assert "did you mean" not in str(caught.value)
    assert load_sweep_spec(_spec(tmp_path, GOOD)).name == "small"  # narrowly: the spec as written loads


def test_bad_spec_on_the_command_line_is_one_located_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _spec(tmp_path, GOOD.replace("    seed: 5", "    seed: 5\n  - suite: nowhere.fleetsim.yaml"))
    assert main(["sweep", str(path), "-o", str(tmp_path / "r.jsonl")]) == 1
    err = capsys.readouterr().err
    assert f"{path}:10:" in err and "nowhere.fleetsim.yaml" in err and "Traceback" not in err


def test_generated_sources_are_the_same_for_the_same_seed(tmp_path: Path) -> None:
    spec = load_sweep_spec(_spec(tmp_path, GOOD))
    first, second = expand(spec, tmp_path), expand(spec, tmp_path)
    assert [i["scenario"] for i in first] == [i["scenario"] for i in second]
    assert len(first) == 8 and len({i["key"] for i in first}) == 8
    other = load_sweep_spec(_spec(tmp_path, GOOD.replace("seed: 5", "seed: 6")))
    assert [i["scenario"] for i in expand(other, tmp_path)] != [i["scenario"] for i in first]


def test_a_faulty_planner_fails_its_run_not_the_sweep(tmp_path: Path) -> None:
    from fleetsim.sweep.worker import run_item

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "data" / "sweep"))
    try:
        spec = load_sweep_spec(
            _spec(tmp_path, GOOD.replace("fleetsim.planners:BFSPlanner", "sweep_planners:Exploding"))
        )
        rows = [run_item(item) for item in expand(spec, tmp_path / "runs")]
    finally:
        sys.path.pop(0)
    exploding = [row for row in rows if row["planner"] == "sweep_planners:Exploding"]
    assert exploding and all(
        row["status"] == "failed" and "boom in the constructor" in row["error"] for row in exploding
    )
    assert all(row["status"] == "passed" for row in rows if row not in exploding)


def test_sweep_without_dask_says_how_to_install_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    assert main(["sweep", str(_spec(tmp_path, GOOD)), "-o", str(tmp_path / "r.jsonl")]) == 1
    assert "pip install 'fleetsim[sweep]'" in capsys.readouterr().err


def test_sweep_results_feed_fleetsim_compare(tmp_path: Path) -> None:
    from fleetsim.gating.baseline import BaselineError, read_metrics
    from fleetsim.sim.record import RunOrigin
    from fleetsim.sweep.items import RunItem
    from fleetsim.sweep.results import ResultsFile
    from fleetsim.sweep.worker import failed_row

    def row(planner: str, source: str, sid: str) -> dict[str, object]:
        item = RunItem(key=f"{planner} | {sid} | 1", id=sid, planner=planner, source=source, seed=None, repetition=1, vehicles=1,
                       scenario=None, origin=RunOrigin().keys(), load_error="x", planner_timeout=None, record="none", artifacts=str(tmp_path))  # fmt: skip
        return failed_row(item, "x")

    path = tmp_path / "r.jsonl"
    with ResultsFile(path, {"name": "n"}, resume=False) as results:
        for planner in ("a:P", "b:P"):
            results.add(row(planner, "suite", "s.fleetsim.yaml::one"))
            results.add(row(planner, "generated", "x.sweep.yaml::gen#0"))
    assert list(read_metrics(path, planner="b:P")) == ["s.fleetsim.yaml::one"]
    assert read_metrics(path, planner="b:P")["s.fleetsim.yaml::one"].planner == "b:P"
    with pytest.raises(BaselineError, match="a sweep of 2 planners"):
        read_metrics(path, planner="c:P")


def test_disturbance_seeds_run_every_scenario_once_per_seed(tmp_path: Path) -> None:
    """The pairs stay pairs: each (scenario, seed) is one id, run by every planner with the same stops."""
    spec = load_sweep_spec(
        _spec(tmp_path, GOOD + "disturbances: {stops_per_vehicle_hour: 600, stop: [5, 10], seeds: [3, 4]}\n")
    )
    items = expand(spec, tmp_path)
    assert len(items) == 16 and len({i["key"] for i in items}) == 16
    assert sorted({i["id"].rsplit("~", 1)[1] for i in items}) == ["d3", "d4"]
    drawn = {i["id"]: i["scenario"]["random_disturbances"] for i in items if i["scenario"] is not None}
    assert {(d["seed"], d["stops_per_vehicle_hour"], tuple(d["stop"])) for d in drawn.values()} == {
        (3, 600.0, (5.0, 10.0)),
        (4, 600.0, (5.0, 10.0)),
    }
    assert load_sweep_spec(_spec(tmp_path, GOOD)).disturbances is None  # narrowly: without the key, no stops


def test_a_scenario_sent_to_a_worker_keeps_its_disturbances() -> None:
    """Declared and drawn disturbances travel with the scenario: the run hashes as the suite's own."""
    from fleetsim import load_scenario, load_suite, run_scenario
    from fleetsim.planners import ReservingPlanner
    from fleetsim.sweep.payload import scenario_from_payload, scenario_payload

    root = Path(__file__).resolve().parents[2] / "scenario_suites"
    for file, name in (
        ("disturbances.fleetsim.yaml", "random-stops-at-the-junction"),
        ("caught-bugs.fleetsim.yaml", "late-crossing-stop"),
    ):
        suite = load_suite(root / file)
        scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)
        assert scenario.disturbances or scenario.random_disturbances
        sent = scenario_from_payload(scenario_payload(scenario))
        assert (sent.disturbances, sent.random_disturbances) == (scenario.disturbances, scenario.random_disturbances)
        assert (
            run_scenario(sent, ReservingPlanner()).trace_hash == run_scenario(scenario, ReservingPlanner()).trace_hash
        )
