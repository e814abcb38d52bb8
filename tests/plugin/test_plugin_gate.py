"""pytest gating a suite entry on its measures alone (``gate: measures``): no hash recorded or compared,
even in CI, the summary saying so, and a missed bound failing the entry's own test item."""

from __future__ import annotations

import pytest

from tests.unit.dispatch_support import gate_suite as suite


def test_pytest_gates_a_measures_entry_without_a_hash_and_says_so(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = suite(pytester.path, "    gate: measures\n    expect: {min_orders_per_hour: 1}\n")
    result = pytester.runpytest_subprocess(
        str(path), "--planner", "fleetsim.planners:ReservingPlanner", "-p", "no:cacheprovider"
    )
    result.assert_outcomes(passed=1)
    assert not (pytester.path / "gate.fleetsim.lock.json").exists()
    table = result.stdout.str()
    assert "measures" in table.split("orders:")[0]  # the hash column
    assert table.split("orders:")[1].splitlines()[2].rstrip().endswith("measures")
    # Under CI a missing hash fails a hash-gated entry; one gated on measures has none to miss.
    monkeypatch.setenv("CI", "true")
    hashed = pytester.runpytest_subprocess(
        str(suite(pytester.path / "hashed", "")),
        "--planner",
        "fleetsim.planners:ReservingPlanner",
        "-p",
        "no:cacheprovider",
    )
    hashed.assert_outcomes(failed=1)
    ci = pytester.runpytest_subprocess(
        str(path), "--planner", "fleetsim.planners:ReservingPlanner", "-p", "no:cacheprovider"
    )
    ci.assert_outcomes(passed=1)
    failed = pytester.runpytest_subprocess(
        str(suite(pytester.path / "tight", "    gate: measures\n    expect: {min_orders_per_hour: 10000}\n")),
        "--planner",
        "fleetsim.planners:ReservingPlanner",
        "-p",
        "no:cacheprovider",
    )
    failed.assert_outcomes(failed=1)
    assert "orders_per_hour" in failed.stdout.str() and "below min_orders_per_hour 10000" in failed.stdout.str()
