"""The contact check in whole runs: the shipped scenarios, the two judgements switched on and off, the
expected clearance, ``stop_on: [contact]`` and the suite's ``checks`` block."""

from __future__ import annotations

import math
import shutil
from dataclasses import replace
from pathlib import Path

import pytest
from loop_switches import run_switched
from mcap.reader import make_reader

from fleetsim.enums import Progress, Traverse
from fleetsim.errors import SuiteError
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.recording.artifacts import write_run_artifacts
from fleetsim.recording.picture import contact_moment, failure_picture
from fleetsim.recording.replay import Frame, Pose
from fleetsim.scenario import Checks, Expectations, Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import Failure

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"


def _scenario(suite: str, name: str) -> Scenario:
    loaded = load_suite(SUITES / suite)
    return load_scenario(next(s for s in loaded.scenarios if s.name == name), loaded)


def _with(scenario: Scenario, **checks: object) -> Scenario:
    settings = scenario.settings
    return replace(scenario, settings=replace(settings, checks=replace(settings.checks, **checks)))


def test_head_on_in_the_corridor_is_a_reservation_alert_and_a_contact() -> None:
    result = run_scenario(_scenario("caught-bugs.fleetsim.yaml", "corridor-head-on"), BFSPlanner())
    assert result.passed  # the suite expects both
    assert result.collisions
    assert result.contact is not None
    contacts = result.contact.contacts
    [contact] = contacts
    assert contact.vehicles == (1, 2) and contact.time == pytest.approx(18.5)
    assert contact.depth == pytest.approx(0.6)  # they drove right through: the least way out, a width
    assert contact.until == pytest.approx(19.6)
    assert result.metrics.clearance == 0.0


@pytest.mark.parametrize(
    ("suite", "name"), [("caught-bugs.fleetsim.yaml", "corridor-head-on"), ("examples.fleetsim.yaml", "crossing")]
)
def test_a_few_vehicles_contact_report_is_the_same_cruising_in_arrays_or_stepped_one_by_one(
    suite: str, name: str
) -> None:
    # The loop tells the monitor of a few what moved: from the drivers one by one, or from the arrays'
    # columns when the vehicles cruise there (forced here; a few do not by default).
    scenario = replace(_scenario(suite, name), expect=Expectations())
    scenario = replace(scenario, settings=replace(scenario.settings, stop_on=()))  # on through the contacts
    batched, one_by_one = (run_switched(scenario, BFSPlanner(), batched=b) for b in (True, False))
    assert batched.contact is not None and batched.contact == one_by_one.contact
    assert batched.contact.contacts  # (BFSPlanner drives into the other)


def test_with_reservations_off_the_same_run_has_no_alert_and_fails_on_contact() -> None:
    scenario = _with(_scenario("caught-bugs.fleetsim.yaml", "corridor-head-on"), reservations=False)
    scenario = replace(scenario, expect=Expectations())  # nothing allowed
    result = run_scenario(scenario, BFSPlanner())
    assert not result.collisions
    kinds = [f.kind for f in result.failures]
    assert kinds.count("contact") == 1 and "collision" not in kinds
    first = next(f for f in result.failures if f.kind == "contact")
    assert first.message.startswith("vehicles 1 and 2 touched at t = ")
    assert "overlapping up to" in first.message


def test_with_contact_off_nothing_is_measured() -> None:
    result = run_scenario(
        _with(_scenario("caught-bugs.fleetsim.yaml", "corridor-head-on"), contact=False), BFSPlanner()
    )
    assert result.contact is None and result.metrics.clearance is None
    assert result.to_dict()["contact"] is None and result.to_dict()["metrics"]["clearance"] is None
    # The alerts it expects are still there; the contact it expects cannot be seen, and the run says why.
    [failure] = result.failures
    assert failure.kind == "expectation" and failure.details == {"expect": "contacts"}
    assert failure.message == "the scenario expects contacts, but its contact check is off (checks: contact)"


def test_expected_contacts_that_never_happen_fail_the_run() -> None:
    scenario = _scenario("examples.fleetsim.yaml", "crossing")
    [failure] = run_scenario(
        replace(scenario, expect=replace(scenario.expect, contacts="any")), ReservingPlanner()
    ).failures
    assert failure.kind == "expectation" and failure.details == {"expect": "contacts"}
    assert failure.message == "the scenario expects contacts, but no two footprints touched"


def test_stop_on_contact_ends_the_run_at_the_first_one() -> None:
    scenario = _scenario("caught-bugs.fleetsim.yaml", "corridor-head-on")
    scenario = replace(scenario, settings=replace(scenario.settings, stop_on=("contact",)))
    result = run_scenario(scenario, BFSPlanner())
    assert result.ended == "contact"
    assert result.contact is not None and len(result.contact.contacts) == 1
    assert result.sim_time == pytest.approx(result.contact.contacts[0].time, abs=0.1 + 1e-9)


@pytest.mark.parametrize("name", ["crossing", "loop-one-way", "corridor-passing-bay", "mixed-shapes"])
def test_the_reservation_rule_keeps_the_shipped_examples_out_of_contact_and_their_hashes_unchanged(name: str) -> None:
    scenario = _scenario("examples.fleetsim.yaml", name)
    checked, unchecked = (
        run_scenario(scenario, ReservingPlanner()),
        run_scenario(_with(scenario, contact=False), ReservingPlanner()),
    )
    assert checked.passed
    assert checked.contact is not None and checked.contact.contacts == ()
    assert checked.metrics.clearance is None or checked.metrics.clearance > 0
    assert checked.trace_hash == unchecked.trace_hash  # contacts and clearances enter no hash


def test_an_expected_clearance_fails_the_run_naming_the_closest_pair() -> None:
    scenario = _scenario("examples.fleetsim.yaml", "corridor-passing-bay")
    measured = run_scenario(scenario, ReservingPlanner()).contact
    assert measured is not None and measured.clearance is not None
    closest = measured.clearance.distance
    strict = replace(scenario, expect=replace(scenario.expect, clearance=closest + 0.01))
    [failure] = run_scenario(strict, ReservingPlanner()).failures
    a, b = measured.clearance.vehicles
    assert failure.kind == "expectation" and failure.details["expect"] == "clearance"
    assert f"vehicles {a} and {b} came within {closest:.3f} m of each other" in failure.message
    lenient = replace(scenario, expect=replace(scenario.expect, clearance=closest - 0.01))
    assert run_scenario(lenient, ReservingPlanner()).passed


def test_an_expected_clearance_with_the_contact_check_off_is_a_failure_that_says_so() -> None:
    scenario = _with(_scenario("examples.fleetsim.yaml", "crossing"), contact=False)
    scenario = replace(scenario, expect=replace(scenario.expect, clearance=0.3))
    [failure] = run_scenario(scenario, ReservingPlanner()).failures
    assert "its contact check is off" in failure.message


def _suite(tmp_path: Path, defaults: str, entry: str) -> Path:
    shutil.copytree(SUITES / "examples" / "crossing", tmp_path / "crossing")
    path = tmp_path / "checks.fleetsim.yaml"
    path.write_text(
        "fleetsim: 1\nname: checks\n"
        f"defaults:\n  {defaults}\n"
        f"scenarios:\n  - name: one\n    dir: crossing/\n    {entry}\n",
        encoding="utf-8",
    )
    return path


def test_an_entrys_checks_override_the_defaults_key_by_key(tmp_path: Path) -> None:
    path = _suite(tmp_path, "checks: {reservations: off, near_miss: 0.8}", "checks: {safety_margin: 0.1}")
    [spec] = load_suite(path).scenarios
    assert spec.settings.checks == Checks(reservations=False, contact=True, safety_margin=0.1, near_miss=0.8)


def test_a_misspelt_check_is_named(tmp_path: Path) -> None:
    path = _suite(tmp_path, "time_limit: 60", "checks: {contacts: false}")
    with pytest.raises(SuiteError, match=r"unknown key 'contacts'; did you mean 'contact'\?"):
        load_suite(path)


def test_a_contacts_picture_shows_both_footprints_at_its_moment_and_where() -> None:
    scenario = _scenario("caught-bugs.fleetsim.yaml", "corridor-head-on")
    scenario = replace(scenario, expect=Expectations(collisions="any"))  # contacts not allowed
    result = run_scenario(scenario, BFSPlanner())
    [failure] = result.failures
    assert failure.kind == "contact"
    found = failure_picture(scenario, result)
    assert found is not None
    step, svg = found
    assert step == round(failure.time / scenario.settings.time_step) - 1
    assert svg.count('class="contact-footprint"') == 2 and 'class="contact-place"' in svg
    assert "contact: vehicles 1 and 2 touched at t = 18.50 s" in svg
    passed = run_scenario(_scenario("caught-bugs.fleetsim.yaml", "corridor-head-on"), BFSPlanner())
    assert passed.passed and failure_picture(scenario, passed) is None  # expected contacts: no picture


def test_the_moment_of_a_contact_is_interpolated_between_the_frames() -> None:
    def frame(time: float, x1: float, heading: float) -> Frame:
        poses = {
            1: Pose(1, Traverse.FORWARD, Progress.FORWARD, x1, 0.0, heading, 1.0),
            2: Pose(2, Traverse.FORWARD, Progress.FORWARD, 5.0, 0.0, 0.0, 0.0),
        }
        return Frame(0, time, poses, {}, (), (), (), ())

    failure = Failure("contact", 0.125, "touched", {"vehicles": [1, 2], "x": 4.0, "y": 0.0})
    moment = contact_moment(failure, frame(0.2, 4.0, 3.0), frame(0.1, 2.0, -3.0))
    assert moment is not None
    one = moment["footprints"][0]
    assert one["x"] == pytest.approx(2.5)  # a quarter of the way
    assert math.remainder(one["heading"] - (-3.0 - 0.25 * (2 * math.pi - 6.0)), math.tau) == pytest.approx(0.0)
    assert contact_moment(replace(failure, kind="collision"), frame(0.2, 4.0, 0.0), None) is None


def test_the_recording_marks_each_contact_at_its_step_for_an_independent_reader(tmp_path: Path) -> None:
    scenario = _scenario("caught-bugs.fleetsim.yaml", "corridor-head-on")
    result = run_scenario(scenario, BFSPlanner())
    assert result.contact is not None
    [contact] = result.contact.contacts
    paths = write_run_artifacts(tmp_path / "run", result, scenario=scenario)
    with open(paths["mcap"], "rb") as stream:
        messages = [
            (c.topic, msg.log_time) for _, c, msg in make_reader(stream).iter_messages(topics=["/fleetsim/contacts"])
        ]
    [(_, log_time)] = messages
    step_end = math.ceil(contact.time / scenario.settings.time_step - 1e-9) * scenario.settings.time_step
    assert log_time == pytest.approx(step_end * 1e9, abs=1e3)  # the end of the step it began in
    with open(paths["mcap"], "rb") as stream:
        logs = [bytes(msg.data) for _, c, msg in make_reader(stream).iter_messages(topics=["/rosout"])]
    assert any(b"contact: vehicles 1 and 2 touched at t = 18.50 s" in data for data in logs)


def test_the_summary_table_shows_contacts_and_clearance_or_that_they_were_not_judged() -> None:
    from fleetsim.sim.report import SUMMARY_COLUMNS, summary_cells

    def cells(result: object) -> dict[str, str]:
        return dict(zip(SUMMARY_COLUMNS, summary_cells("s", "passed", result), strict=True))  # type: ignore[arg-type]

    head_on = run_scenario(_scenario("caught-bugs.fleetsim.yaml", "corridor-head-on"), BFSPlanner())
    assert (cells(head_on)["contacts"], cells(head_on)["clearance"]) == ("1", "0.00 m")
    scenario = _scenario("examples.fleetsim.yaml", "corridor-passing-bay")
    apart = run_scenario(scenario, ReservingPlanner())
    assert apart.contact is not None and apart.contact.clearance is not None
    assert cells(apart)["clearance"] == f"{apart.contact.clearance.distance:.2f} m" and cells(apart)["contacts"] == "0"
    off = run_scenario(_with(scenario, contact=False), ReservingPlanner())
    assert (cells(off)["contacts"], cells(off)["clearance"]) == ("-", "-")
    far = replace(apart, contact=replace(apart.contact, clearance=None))  # no two came within reach
    assert cells(far)["clearance"] == "> 2 m"
