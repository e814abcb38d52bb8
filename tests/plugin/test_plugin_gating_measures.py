"""Baselines of shifts: ``--fleetsim-metrics-json`` carries a run's measures, ``--fleetsim-compare-fail
orders_per_hour:5%`` fails the scenario whose throughput dropped more than 5 %, and its own item is red (in
pytest's summary and in JUnit), not only the session.

The project is the shipped warehouse under a closed pool of four orders for five minutes
(``tests/data/sweep/pool-shift.yaml``), where throughput is what the dispatcher makes of the fleet.
"""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
RESERVING = "fleetsim.planners:ReservingPlanner"
NODE = "pool.fleetsim.yaml::pool"
COMPARE = ("--planner", RESERVING, "--fleetsim-compare", "base.json")
MEASURES = (
    "orders_per_hour",
    "service_time_median",
    "service_time_p95",
    "wait_for_pickup_p95",
    "deadline_misses",
    "utilisation",
    "empty_travel_share",
    "stalls",
)


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    """The pool suite beside a copy of the warehouse, and the test dispatchers; outside CI (no hash is
    recorded: these runs are gated on their measures)."""
    monkeypatch.delenv("CI", raising=False)
    pytester.makeini("[pytest]\naddopts = -p no:cacheprovider\n")
    shutil.copytree(ROOT / "scenario_suites" / "warehouse", pytester.path / "warehouse")
    shutil.copy(ROOT / "tests" / "data" / "sweep" / "pool-shift.yaml", pytester.path / "pool.fleetsim.yaml")
    shutil.copy(ROOT / "tests" / "data" / "sweep" / "sweep_dispatchers.py", pytester.path)
    return pytester


_SAVED: dict[str, str] = {}  # the metrics document of the first session, for the tests after it


def baseline(project: pytest.Pytester, scale: dict[str, float] | None = None) -> dict[str, Any]:
    """Run the suite (once per test module: the runs repeat to the step), save its metrics as ``base.json``
    with the measures named in ``scale`` multiplied by their factor; return the row as the run gave it."""
    path = project.path / "base.json"
    if "base.json" not in _SAVED:
        project.runpytest_inprocess("--planner", RESERVING, "--fleetsim-metrics-json", "base.json").assert_outcomes(
            passed=1
        )
        _SAVED["base.json"] = path.read_text(encoding="utf-8")
    document = json.loads(_SAVED["base.json"])
    (row,) = document["scenarios"]
    measured = dict(row)
    for name, factor in (scale or {}).items():
        row[name] = round(row[name] * factor, 6)
    path.write_text(json.dumps(document), encoding="utf-8")
    return measured


def junit_failure(path: Path) -> str | None:
    """The failure message of the one test case of a JUnit XML file, or None when it passed."""
    (case,) = ET.parse(path).getroot().iter("testcase")
    failure = case.find("failure")
    return None if failure is None else failure.get("message")


def test_the_metrics_document_carries_the_measures_of_a_shift(project: pytest.Pytester) -> None:
    row = baseline(project)
    assert row["orders_per_hour"] > 0 and row["service_time_p95"] >= row["service_time_median"] > 0
    assert 0 < row["utilisation"] <= 1 and 0 <= row["empty_travel_share"] <= 1
    assert (row["deadline_misses"], row["stalls"]) == (0, 0)
    assert all(name in row for name in MEASURES)


def test_a_throughput_drop_beyond_the_limit_fails_the_scenarios_own_item(project: pytest.Pytester) -> None:
    row = baseline(project, {"orders_per_hour": 1.06})

    result = project.runpytest_inprocess(*COMPARE, "--fleetsim-compare-fail", "orders_per_hour:5%", "--junitxml=j.xml")

    result.assert_outcomes(failed=1)  # red in pytest's summary...
    assert result.ret == pytest.ExitCode.TESTS_FAILED
    drop = f"orders_per_hour {round(row['orders_per_hour'] * 1.06, 6)} -> {row['orders_per_hour']} (-5.7%, limit 5%)"
    result.stdout.fnmatch_lines([f"regression: {drop} against the baseline", "*", "fleetsim compare: 1 compared, 1 regression", f"  {NODE}: {drop}"])  # fmt: skip
    result.stdout.fnmatch_lines([f"FAILED {NODE} - regression: orders_per_hour *"])
    assert str(junit_failure(project.path / "j.xml")).startswith(
        f"regression: {drop} against the baseline\n"
    )  # and JUnit
    document = json.loads((project.path / "fleetsim-results" / "pool" / "pool" / "result.json").read_text())
    (failure,) = document["failures"]  # the failed run's artifacts say why
    assert (failure["kind"], failure["metric"], failure["limit"]) == ("regression", "orders_per_hour", "5%")


def test_a_throughput_drop_within_the_limit_passes(project: pytest.Pytester) -> None:
    baseline(project, {"orders_per_hour": 1.04})

    result = project.runpytest_inprocess(*COMPARE, "--fleetsim-compare-fail", "orders_per_hour:5%", "--junitxml=j.xml")

    result.assert_outcomes(passed=1)
    assert result.ret == pytest.ExitCode.OK
    result.stdout.fnmatch_lines(["fleetsim compare: 1 compared, 0 regressions"])
    assert junit_failure(project.path / "j.xml") is None


def test_service_time_is_gated_lower_is_better(project: pytest.Pytester) -> None:
    row = baseline(project, {"service_time_p95": 0.9, "orders_per_hour": 0.5})  # the baseline served faster

    result = project.runpytest_inprocess(
        *COMPARE, "--fleetsim-compare-fail", "service_time_p95:5%", "--fleetsim-compare-fail", "orders_per_hour:5%"
    )

    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines([f"  {NODE}: service_time_p95 * -> {row['service_time_p95']} (+11.1%, limit 5%)"])
    assert f"{NODE}: orders_per_hour" not in result.stdout.str()  # twice the baseline's throughput is no regression


def test_a_worse_dispatcher_fails_its_scenario_against_the_baseline(project: pytest.Pytester) -> None:
    baseline(project)

    result = project.runpytest_inprocess(
        *COMPARE, "--dispatcher", "sweep_dispatchers:HighestIdleOnly", "--fleetsim-compare-fail", "orders_per_hour:5%"
    )

    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines([f"FAILED {NODE} - regression: orders_per_hour *"])
    assert "fleetsim compare: 1 compared, 1 regression" in result.stdout.str()


def test_under_xdist_the_regressed_item_is_red_where_it_ran(project: pytest.Pytester) -> None:
    baseline(project, {"orders_per_hour": 1.5})

    result = project.runpytest_subprocess(*COMPARE, "--fleetsim-compare-fail", "orders_per_hour:5%", "-n", "1")

    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(["*FAILED*pool.fleetsim.yaml::pool*regression: orders_per_hour*"])
