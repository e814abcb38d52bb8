"""The ``vda5050:`` planner spec: its options, its mistakes named, and a whole run from the command line
with the master control started as a child process that finds the broker in its environment."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import pytest
from runs import run_example

from fleetsim.exec.spec import load_planner_factory
from fleetsim.specs.python import PlannerSpecError
from fleetsim.vda5050.fleet import Vda5050Fleet
from fleetsim.vda5050.spec import _parse

ROOT = Path(__file__).resolve().parents[2]
MASTER = Path(__file__).with_name("scripted_master.py")


def test_the_options_set_the_vehicles_up() -> None:
    settings, command = _parse(
        "vda5050:version=2.1,speed=10,broker=mqtt://u:p@hall:1884,interface=agv,manufacturer=acme"
    )
    assert (settings.version, settings.speed, settings.interface_name, settings.manufacturer) == (
        "2.1",
        10.0,
        "agv",
        "acme",
    )
    assert settings.broker is not None and (settings.broker.host, settings.broker.port) == ("hall", 1884)
    assert command is None
    settings, command = _parse(f"vda5050:speed=5,exec={sys.executable} master.py --fast,yes")
    assert settings.speed == 5.0 and command == (sys.executable, "master.py", "--fast,yes")  # exec= takes the rest
    defaults, _ = _parse("vda5050:")
    assert (defaults.version, defaults.speed, defaults.broker) == ("2.0", 1.0, None)


def test_the_spec_makes_a_fresh_fleet_per_run() -> None:
    factory = load_planner_factory("vda5050:speed=50")
    one, other = factory(), factory()
    assert isinstance(one, Vda5050Fleet) and one is not other and one.settings.speed == 50.0


@pytest.mark.parametrize(
    ("spec", "words"),
    [
        ("vda5050:version=3.0", "version='3.0'; fleetsim's vehicles speak 2.0 or 2.1"),
        ("vda5050:speed=0", "speed='0' must be a number > 0"),
        ("vda5050:speed=fast", "speed='fast' must be a number > 0"),
        ("vda5050:sped=2", "'sped=2' is not an option"),
        ("vda5050:broker=http://x", "broker"),
        ("vda5050:interface=a/b", "interface='a/b' must be a non-empty topic level"),
        ("vda5050:exec=", "exec= names no command"),
        ("vda5050:broker=mqtt://127.0.0.1:1", "cannot reach the MQTT broker at mqtt://127.0.0.1:1"),
        ("vda5050:exec=no-such-master-control", "the master control's program 'no-such-master-control' is not on PATH"),
    ],
)
def test_each_mistake_is_named(spec: str, words: str) -> None:
    with pytest.raises(PlannerSpecError, match="planner spec") as caught:
        load_planner_factory(spec)
    assert words in str(caught.value)


def test_fleetsim_run_drives_the_vehicles_with_a_master_control_it_starts(tmp_path: Path) -> None:
    spec = f"vda5050:speed=20,exec={sys.executable} {MASTER}"
    done = run_example("crossing", spec)
    assert done.returncode == 0, done.stderr
    [result] = [json.loads(line) for line in done.stdout.splitlines()]
    assert result["status"] == "passed" and result["tasks"] == {"total": 2, "completed": 2}
    assert result["paced"] == 20.0  # the result says a wall clock paced it
    pacing = result["pacing"]  # and how it kept the pace, and how soon the orders took effect
    assert pacing["speed"] == 20.0 and pacing["late_steps"] >= 0 and pacing["lag_max"] >= 0
    latency = pacing["order_latency"]
    assert latency["orders"] >= 2 and 0 <= latency["median"] <= latency["p90"] <= latency["max"] < 5.0
    assert "VDA 5050 2.0 vehicles on mqtt://127.0.0.1:" in done.stderr  # where the broker is, said


def test_under_pytest_a_paced_run_is_judged_by_its_checks_and_its_hash_is_not_gated(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("CI", "true")  # where a missing hash would fail any other run
    for folder in ("examples", "tiled"):
        shutil.copytree(ROOT / "scenario_suites" / folder, pytester.path / folder)
    shutil.copy(ROOT / "scenario_suites" / "examples.fleetsim.yaml", pytester.path)
    spec = f"vda5050:speed=20,exec={sys.executable} {MASTER}"
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--planner", spec, "-k", "crossing", timeout=120)
    assert result.ret == pytest.ExitCode.OK, result.stdout.str()
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(
        [
            "crossing *passed *2/2 *not gated*",
            "*paced by a wall clock*not gated; the checks decide",
            "  crossing: paced at 20x; order latency median * ms, max * ms (* orders); *",
        ]
    )
    assert not (pytester.path / "examples.fleetsim.lock.json").exists()  # nothing recorded
