"""pytest --fleetsim-live: each scenario's run paced and shown on the live page; its hash gates as ever."""

from __future__ import annotations

import pytest
from plugin_helpers import RESERVING, copy_example_suites


@pytest.fixture(autouse=True)
def _not_in_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CI", raising=False)


def test_a_live_session_passes_the_recorded_hashes(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_inprocess(
        "examples.fleetsim.yaml",
        "-k",
        "crossing or corridor",
        "--planner",
        RESERVING,
        "--fleetsim-live",
        "--fleetsim-speed",
        "50",
        "--fleetsim-no-open",
    )
    out = result.stdout.str()
    assert result.ret == pytest.ExitCode.OK, out
    result.assert_outcomes(passed=2)
    assert "live: watch the runs at http://127.0.0.1:" in out
    assert "live: crossing ran at 50x real time;" in out
    assert "hash mismatch" not in out


def test_live_is_refused_with_xdist_and_a_bad_speed(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_inprocess("--planner", RESERVING, "--fleetsim-live", "-n", "2")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert "--fleetsim-live shows one run at a time, in this process: run without -n" in result.stderr.str()
    result = pytester.runpytest_inprocess("--planner", RESERVING, "--fleetsim-live", "--fleetsim-speed", "fast")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert "--fleetsim-speed='fast' must be a multiple of real time from 0.01 to 1000, or 'max'" in result.stderr.str()
