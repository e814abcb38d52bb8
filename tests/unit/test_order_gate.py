"""A suite entry's ``gate`` (hash, measures or both): its default, its refusal beside bounds it would leave
unjudged (pytest's gating on measures alone: tests/plugin/test_plugin_gate.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
from dispatch_support import gate_suite as suite

from fleetsim import load_suite
from fleetsim.errors import SuiteError


@pytest.mark.parametrize(
    ("entry", "gate"),
    [
        ("", "hash"),
        ("    expect: {min_orders_per_hour: 1}\n", "both"),
        ("    expect: {overloaded: false}\n", "both"),
        ("    gate: measures\n    expect: {min_orders_per_hour: 1}\n", "measures"),
        ("    gate: measures\n", "measures"),
        ("    gate: both\n", "both"),
    ],
)
def test_the_gate_defaults_to_both_with_bounds_on_measures_else_hash(tmp_path: Path, entry: str, gate: str) -> None:
    assert load_suite(suite(tmp_path, entry)).scenarios[0].gate == gate


def test_a_hash_gate_beside_bounds_on_measures_is_refused_at_its_line(tmp_path: Path) -> None:
    with pytest.raises(SuiteError) as raised:
        load_suite(suite(tmp_path, "    gate: hash\n    expect: {max_service_time_p95: 100}\n"))
    assert ":11:" in str(raised.value)
    assert "scenarios[0].gate: 'hash' leaves the expect block's bounds on measures unjudged" in str(raised.value)


def test_an_unknown_gate_is_refused(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match=r"scenarios\[0\]\.gate"):
        load_suite(suite(tmp_path, "    gate: hashes\n"))
