"""The rest of fleetsim applies unchanged to runs with a ``vda5050:`` planner (issue 33, point 8).

Sweeps: ``fleetsim sweep`` runs the shipped example master control beside an in-process planner on Dask
workers, each run with its own embedded broker and master control; the report names the spec whole and
says its runs were paced. Recording: a run's ``--record`` folder holds its trace and an MCAP file that
the independent ``mcap`` reader decodes, with the vehicles' poses, and a ``startPause`` from a test master
control shows there, in the trace and in the pictures as the vehicle standing still; a paced run that
fails gets its failure picture as any run. pytest items: the whole shipped example suite passes on two
xdist workers, its hashes shown as not gated and none recorded.
"""

from __future__ import annotations

import importlib.util
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from tooling import missing


def _require(module: str, what: str) -> None:
    """Skip the module when ``module`` is not installed, or fail when FLEETSIM_REQUIRE_TOOLS=1."""
    if importlib.util.find_spec(module.partition(".")[0]) is None or importlib.util.find_spec(module) is None:
        reason = f"{what} ({module}) is not installed: pip install 'fleetsim[vda5050]' 'fleetsim[sweep]'"
        missing(reason, module_level=True)


_require("paho.mqtt", "the MQTT client paho-mqtt")
_require("amqtt", "the MQTT broker amqtt")

from mcap.reader import make_reader  # noqa: E402
from mcap_ros2.decoder import DecoderFactory  # noqa: E402

from fleetsim.sweep.report import build_report, markdown, paced_note, short  # noqa: E402
from fleetsim.sweep.results import read_results  # noqa: E402
from fleetsim.sweep.spec import SweepSpecError, load_sweep_spec  # noqa: E402
from fleetsim.sweep.worker import planner_folder  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
EXAMPLES = ROOT / "scenario_suites" / "examples.fleetsim.yaml"
MASTER = "examples/vda5050/master_control.py"  # relative: the workers run where the sweep was started
RESERVING = "fleetsim.planners:ReservingPlanner"
VDA20 = f"vda5050:speed=20,exec={sys.executable} {MASTER}"
VDA21 = f"vda5050:version=2.1,speed=25,exec={sys.executable} {MASTER}"
TASKS = {"crossing": 2, "loop-one-way": 4}  # the sweep's two examples
EXAMPLES_TASKS = {**TASKS, "corridor-passing-bay": 2, "mixed-shapes": 3}


def _fleetsim(*words: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """``python -m fleetsim WORDS`` from the repository's root, as a user types it there."""
    return subprocess.run(
        [sys.executable, "-m", "fleetsim", *words], cwd=ROOT, capture_output=True, text=True, timeout=timeout
    )


# -- sweeps ------------------------------------------------------------------------------------------


def _spec(folder: Path, planners: list[str]) -> Path:
    listed = "".join(f"  - {json.dumps(p)}\n" for p in planners)
    sources = "".join(f"  - suite: {json.dumps(f'{EXAMPLES}::{name}')}\n" for name in TASKS)
    path = folder / "vda.sweep.yaml"
    path.write_text(f"fleetsim-sweep: 1\nname: vda\nplanners:\n{listed}record: all\nsources:\n{sources}")
    return path


def test_a_sweep_spec_takes_a_vda5050_planner_and_names_a_misspelt_one(tmp_path: Path) -> None:
    assert load_sweep_spec(_spec(tmp_path, [RESERVING, VDA20])).planners == (RESERVING, VDA20)
    with pytest.raises(SweepSpecError, match=r"planners\[1\]='vda5050speed=20' must be a planner spec.*vda5050:"):
        load_sweep_spec(_spec(tmp_path, [RESERVING, "vda5050speed=20"]))


def test_the_report_shows_exec_and_vda5050_specs_whole_and_module_specs_by_their_attribute() -> None:
    assert short(VDA20) == VDA20
    assert short("vda5050:broker=mqtt://host:1883") == "vda5050:broker=mqtt://host:1883"  # no cut at the port
    assert short("exec:node planner.js") == "exec:node planner.js"
    assert short(RESERVING) == "ReservingPlanner"


def test_no_two_planners_share_a_run_folder_and_each_is_one_folder_deep() -> None:
    assert planner_folder(RESERVING) == "fleetsim.planners-ReservingPlanner"  # as before
    long = f"vda5050:speed=20,exec=/opt/some/long/path/to/a/python/interpreter/bin/python3 {MASTER}"
    other = long.replace("master_control.py", "master_control_v2.py")  # the same first 60 characters
    assert long[:60] == other[:60]
    folders = {planner_folder(spec) for spec in (long, other, VDA20, VDA21, "exec:node planners/a.js")}
    assert len(folders) == 5
    assert all("/" not in f and len(f) <= 60 and re.fullmatch(r"[A-Za-z0-9._=,-]+", f) for f in folders), folders


@pytest.fixture(scope="module")
def sweep(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, subprocess.CompletedProcess[str]]:
    """Three planners on two examples, on two Dask workers: the four VDA 5050 runs share the workers,
    each with its own embedded broker and its own master control."""
    pytest.importorskip("distributed")
    folder = tmp_path_factory.mktemp("sweep")
    results = folder / "results.jsonl"
    done = _fleetsim("sweep", str(_spec(folder, [RESERVING, VDA20, VDA21])), "-o", str(results), "--workers", "2")
    assert done.returncode == 0, done.stderr
    return results, done


def test_every_run_of_the_sweep_completes_its_tasks_and_says_whether_it_was_paced(
    sweep: tuple[Path, subprocess.CompletedProcess[str]],
) -> None:
    results, done = sweep
    _, rows = read_results(results)
    assert sorted((r["planner"], r["id"].rpartition("::")[2]) for r in rows) == sorted(
        (p, name) for p in (RESERVING, VDA20, VDA21) for name in TASKS
    )
    for row in rows:
        name = row["id"].rpartition("::")[2]
        assert row["error"] is None and row["status"] == "passed", (row["planner"], name, row["failures"])
        assert row["tasks"] == {"total": TASKS[name], "completed": TASKS[name]}
        assert row.get("paced") == {RESERVING: None, VDA20: 20.0, VDA21: 25.0}[row["planner"]]
    # each VDA 5050 run had a broker of its own (the workers' stderr reaches the sweep's)
    ports = re.findall(r"VDA 5050 (2\.[01]) vehicles on mqtt://127\.0\.0\.1:(\d+)", done.stderr)
    assert sorted(version for version, _ in ports) == ["2.0", "2.0", "2.1", "2.1"], done.stderr
    assert len({port for _, port in ports}) == 4


def test_each_run_of_the_sweep_keeps_its_own_folder_with_its_recording(
    sweep: tuple[Path, subprocess.CompletedProcess[str]],
) -> None:
    results, _ = sweep
    _, rows = read_results(results)
    runs = results.with_name(results.name + ".runs")
    assert sorted(p.name for p in runs.iterdir()) == sorted(planner_folder(p) for p in (RESERVING, VDA20, VDA21))
    folders = {row["artifacts"]["folder"] for row in rows}
    assert len(folders) == len(rows) == 6
    for row in rows:
        folder = Path(row["artifacts"]["folder"])
        assert folder.parent.parent.parent == runs  # RUNS/PLANNER/SUITE/SCENARIO
        assert (folder / "run.mcap").stat().st_size > 0 and (folder / "trace.jsonl").exists()
        assert json.loads((folder / "result.json").read_text()).get("paced") == row.get("paced")


def test_the_sweep_report_names_the_master_controls_whole_and_says_their_runs_were_paced(
    sweep: tuple[Path, subprocess.CompletedProcess[str]],
) -> None:
    results, _ = sweep
    page = results.with_name("report.html")
    done = _fleetsim("sweep", "report", str(results), "--html", str(page), "--markdown", str(page.with_suffix(".md")))
    assert done.returncode == 0, done.stderr
    summary = page.with_suffix(".md").read_text()
    planners = [line.split(" | ")[0].lstrip("| ") for line in summary.splitlines() if line.startswith("| ")]
    assert {VDA20, VDA21, "ReservingPlanner"} <= set(planners)
    assert f"## {VDA20} against ReservingPlanner" in summary
    note = next(line for line in summary.splitlines() if line.startswith("Paced by a wall clock"))
    assert f"{VDA20} (20x real time)" in note and f"{VDA21} (25x real time)" in note
    assert "ReservingPlanner" not in note
    assert 'id="paced"' in page.read_text() and "25x real time" in page.read_text()
    # no paced run, no note
    _, rows = read_results(results)
    alone = build_report("x", [r for r in rows if r["planner"] == RESERVING], RESERVING, [], results.parent)
    assert paced_note(alone) is None and "Paced by a wall clock" not in markdown(alone)


# -- recording ---------------------------------------------------------------------------------------

# A master control for these tests: the scripted one (tests/vda5050/scripted_master.py), which pauses
# vehicle 1 once it drives; with ``lift`` it lifts the pause after half a second of wall time.
PAUSING_MASTER = f"""
import os, signal, sys, threading
from urllib.parse import urlsplit
sys.path.insert(0, {str(HERE)!r})
from scripted_master import ScriptedMaster

url = urlsplit(os.environ["FLEETSIM_MQTT_URL"])
stopped = threading.Event()
signal.signal(signal.SIGTERM, lambda *_: stopped.set())
master = ScriptedMaster(
    url.hostname, url.port, interface=os.environ["FLEETSIM_VDA5050_INTERFACE"],
    manufacturer=os.environ["FLEETSIM_VDA5050_MANUFACTURER"], version=os.environ["FLEETSIM_VDA5050_VERSION"],
)
ones = lambda: [s for s in master.history if s["serialNumber"] == "1"]
assert master.wait_until(lambda: any(s["orderId"] and s["driving"] for s in ones()), timeout=30)
master.instant("1", {{"actionType": "startPause", "actionId": "p1"}})
assert master.wait_until(lambda: any(s.get("paused") and not s["driving"] for s in ones()), timeout=30)
if sys.argv[1:] == ["lift"]:
    stopped.wait(0.5)
    master.instant("1", {{"actionType": "stopPause", "actionId": "p2"}})
stopped.wait()
master.close()
"""


def _pausing_spec(folder: Path, *words: str) -> str:
    script = folder / "pausing_master.py"
    script.write_text(PAUSING_MASTER)
    return f"vda5050:speed=20,exec={sys.executable} {script} {' '.join(words)}".rstrip()


def _steps(trace: Path) -> list[list[Any]]:
    return [json.loads(line) for line in trace.read_text().splitlines()[1:]]


def _pause_steps(steps: list[list[Any]]) -> tuple[int, int | None]:
    """The steps whose events pause vehicle 1 and lift its pause (None: never lifted)."""
    paused = [s[0] for s in steps if ["disturb", 1, "pause"] in s[3]]
    resumed = [s[0] for s in steps if ["resume", 1, "pause"] in s[3]]
    assert len(paused) == 1 and len(resumed) <= 1, (paused, resumed)
    return paused[0], resumed[0] if resumed else None


def _read_mcap(path: Path) -> list[tuple[str, int, Any]]:
    """(topic, log time, decoded message) of every message, decoded by mcap_ros2 from the file's schemas."""
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        return [(c.topic, m.log_time, value) for _, c, m, value in reader.iter_decoded_messages()]


def _poses(messages: list[tuple[str, int, Any]], frame: str) -> list[tuple[int, float, float]]:
    return [
        (time, t.transform.translation.x, t.transform.translation.y)
        for topic, time, value in messages
        if topic == "/tf"
        for t in value.transforms
        if t.child_frame_id == frame
    ]


@pytest.fixture(scope="module")
def paused_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """The crossing, recorded, with vehicle 1 paused on its way for a while and then driving on."""
    folder = tmp_path_factory.mktemp("paused")
    record = folder / "record"
    done = _fleetsim(
        "run", f"{EXAMPLES}::crossing", "--planner", _pausing_spec(folder, "lift"), "--record", str(record), "--json"
    )
    assert done.returncode == 0, done.stderr
    [result] = [json.loads(line) for line in done.stdout.splitlines() if line.strip()]
    return Path(result["artifacts"]["folder"]), result


def test_a_recorded_paced_run_writes_its_trace_and_recording_as_any_run(
    paused_run: tuple[Path, dict[str, Any]],
) -> None:
    folder, result = paused_run
    assert result["status"] == "passed" and result["paced"] == 20.0
    assert result["tasks"] == {"total": 2, "completed": 2}
    assert {"trace", "mcap", "rviz", "result"} <= set(result["artifacts"])
    assert not (folder / "failure.svg").exists()  # a passed run has no failure to picture
    assert json.loads((folder / "result.json").read_text())["paced"] == 20.0


def _rest(steps: list[list[Any]], paused: int, resumed: int) -> tuple[int, tuple[int, int]]:
    """The step at which vehicle 1, paused at step ``paused``, stands (it brakes first), and where (mm)."""
    braking = [v for s in steps if paused <= s[0] < resumed for v in s[1] if v[0] == 1]
    rest = next(s[0] for s in steps if paused <= s[0] < resumed and any(v[0] == 1 and v[7] == 0 for v in s[1]))
    return rest, (braking[-1][4], braking[-1][5])


def test_the_pause_is_in_the_trace_as_the_vehicle_braking_and_standing_still(
    paused_run: tuple[Path, dict[str, Any]],
) -> None:
    folder, _ = paused_run
    steps = _steps(folder / "trace.jsonl")
    paused, resumed = _pause_steps(steps)
    assert resumed is not None and resumed - paused >= 50  # half a second at 20x: ten simulated seconds
    rest, place = _rest(steps, paused, resumed)
    speeds = [v[7] for s in steps if paused <= s[0] <= rest for v in s[1] if v[0] == 1]
    assert speeds == sorted(speeds, reverse=True) and speeds[-1] == 0  # it braked, never sped up
    assert rest - paused <= 20  # at 0.5 m/s², from at most 1 m/s: within 2 s
    standing = [v for s in steps if rest < s[0] < resumed for v in s[1] if v[0] == 1]
    assert all(v[7] == 0 and (v[4], v[5]) == place for v in standing), standing  # still, where it stopped
    after = [v for s in steps if s[0] >= resumed for v in s[1] if v[0] == 1]
    assert any(v[7] > 0 for v in after) and any((v[4], v[5]) != place for v in after)  # it drove on


def test_the_mcap_recording_reads_with_the_poses_and_the_pause(paused_run: tuple[Path, dict[str, Any]]) -> None:
    folder, _ = paused_run
    steps = _steps(folder / "trace.jsonl")
    paused, resumed = _pause_steps(steps)
    assert resumed is not None
    rest, place = _rest(steps, paused, resumed)
    messages = _read_mcap(folder / "run.mcap")
    step_ns = 100_000_000  # the examples' time step, 0.1 s; a step's messages are stamped at its end
    one = _poses(messages, "vehicle_1")
    held = {(round(x, 3), round(y, 3)) for time, x, y in one if (rest + 1) * step_ns <= time <= resumed * step_ns}
    assert held == {(place[0] / 1000, place[1] / 1000)}  # it stood still through the pause, where the trace says
    assert len([time for time, _, _ in one if (rest + 1) * step_ns <= time <= resumed * step_ns]) >= 30
    assert len({(round(x, 3), round(y, 3)) for _, x, y in one}) > 50  # and drove before and after
    assert len({(round(x, 3), round(y, 3)) for _, x, y in _poses(messages, "vehicle_2")}) > 50
    logs = [value.msg for topic, _, value in messages if topic == "/rosout"]
    assert "vehicle 1 disturbed: pause" in logs and "vehicle 1 resumes: pause" in logs
    outlines = [
        (time, [k.text for k in value.markers if k.ns == "disturbed_label"])
        for topic, time, value in messages
        if topic == "/fleetsim/disturbed"
    ]
    assert [labels for _, labels in outlines] == [["STOP"], []]  # shown when it begins, cleared when it ends
    assert outlines[0][0] == (paused + 1) * step_ns and outlines[1][0] == (resumed + 1) * step_ns


def test_a_picture_of_the_pause_outlines_the_stopped_vehicle(paused_run: tuple[Path, dict[str, Any]]) -> None:
    folder, _ = paused_run
    paused, resumed = _pause_steps(_steps(folder / "trace.jsonl"))
    assert resumed is not None
    for step, stopped in ((paused + 10, True), (resumed + 10, False)):
        picture = folder / f"step-{step}.svg"
        done = _fleetsim("render", "--trace", str(folder), "--step", str(step), "-o", str(picture))
        assert done.returncode == 0, done.stderr
        assert ('data-disturbed="stop"' in picture.read_text()) == stopped


def test_a_paced_run_that_fails_gets_its_failure_picture_and_recording(tmp_path: Path) -> None:
    suite = tmp_path / "paused.fleetsim.yaml"
    types = EXAMPLES.read_text().partition("vehicle_types:")[2].partition("defaults:")[0]
    suite.write_text(
        f"fleetsim: 1\nname: paused\nvehicle_types:{types}defaults: {{vehicle_type: agv, time_limit: 20}}\n"
        f"scenarios:\n  - name: crossing\n    dir: {ROOT / 'scenario_suites' / 'examples' / 'crossing'}/\n"
    )
    record = tmp_path / "record"
    done = _fleetsim(
        "run", f"{suite}::crossing", "--planner", _pausing_spec(tmp_path), "--record", str(record), "--json"
    )
    assert done.returncode == 1, done.stderr
    [result] = [json.loads(line) for line in done.stdout.splitlines() if line.strip()]
    assert result["status"] == "failed" and result["paced"] == 20.0, result["failures"]
    assert result["tasks"]["completed"] < 2
    folder = Path(result["artifacts"]["folder"])
    picture = (folder / "failure.svg").read_text()
    assert picture.count('class="vehicle-disturbed"') == 1 and 'data-disturbed="stop"' in picture
    _, resumed = _pause_steps(_steps(folder / "trace.jsonl"))
    assert resumed is None  # never lifted: it stood to the end
    messages = _read_mcap(folder / "run.mcap")
    assert _poses(messages, "vehicle_1") and "vehicle 1 disturbed: pause" in [
        value.msg for topic, _, value in messages if topic == "/rosout"
    ]


# -- pytest items ------------------------------------------------------------------------------------
# (tests/vda5050/test_spec.py runs the crossing under CI with no lock file; here the whole shipped
# suite, on two xdist workers, beside the shipped lock file and asked to record hashes)


def test_the_whole_example_suite_passes_under_pytest_on_two_workers_and_records_no_hash(
    pytester: pytest.Pytester,
) -> None:
    pytest.importorskip("xdist")
    for folder in ("examples", "tiled"):
        shutil.copytree(ROOT / "scenario_suites" / folder, pytester.path / folder)
    for name in ("examples.fleetsim.yaml", "examples.fleetsim.lock.json"):
        shutil.copy(ROOT / "scenario_suites" / name, pytester.path)
    lock = (pytester.path / "examples.fleetsim.lock.json").read_bytes()
    # Paced at 10x, not 20x: two workers, each with its broker traffic and master control, beside the
    # rest of a parallel test run, fell 0.35 s behind a 20x pace, and a master control's order made for
    # a vehicle that had driven on was refused (a real race of a paced run, not what this test is about).
    spec = f"vda5050:speed=10,exec={sys.executable} {ROOT / MASTER}"
    result = pytester.runpytest_subprocess(
        "-p", "no:cacheprovider", "-n", "2", "--planner", spec, "--fleetsim-update-hashes", timeout=180
    )
    assert result.ret == pytest.ExitCode.OK, result.stdout.str()
    result.assert_outcomes(passed=4)
    result.stdout.fnmatch_lines_random(
        [f"{name} *passed *{tasks}/{tasks} *not gated*" for name, tasks in EXAMPLES_TASKS.items()]
    )
    result.stdout.fnmatch_lines(["4 scenarios paced by a wall clock*not gated; the checks decide"])
    assert (pytester.path / "examples.fleetsim.lock.json").read_bytes() == lock  # the planner's hashes untouched
