"""Real signals to real ``fleetsim run`` and ``pytest`` processes: nothing of a run is lost.

Each process starts in a session of its own with SIGINT at its default (as a terminal leaves it; a test
runner may have it ignored), and the signal goes to its process group, as a terminal's Ctrl-C does. A
planner in the test's folder (``slowplanner.py``) takes its time and writes a marker file at a chosen
call of a chosen run, so a signal is sent at a known moment without sleeping for a fixed time.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from fleetsim.sim.trace import complete_lines

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[2]
SUITE = ROOT / "scenario_suites" / "examples.fleetsim.yaml"
FLEETSIM = [sys.executable, "-c", "import sys; from fleetsim.cli import main; sys.exit(main())"]
WAIT = 90.0  # seconds at most for anything to happen on a slow, shared machine

SLOW_PLANNER = '''
"""ReservingPlanner, slowed down; at call SLOW_MARK_AFTER of run SLOW_RUN it writes its pid to SLOW_MARK
and then stalls for SLOW_STALL seconds (a planner busy in a long call)."""
import os, time
from pathlib import Path
from fleetsim.planners import ReservingPlanner

RUNS = [0]

class SlowPlanner(ReservingPlanner):
    def __init__(self):
        super().__init__()
        RUNS[0] += 1
        self.run, self.calls = RUNS[0], 0

    def _slow(self):
        self.calls += 1
        time.sleep(float(os.environ.get("SLOW_SECONDS", "0.004")))
        if self.run == int(os.environ.get("SLOW_RUN", "1")) and self.calls == int(os.environ.get("SLOW_MARK_AFTER", "40")):
            Path(os.environ["SLOW_MARK"]).write_text(str(os.getpid()))
            time.sleep(float(os.environ.get("SLOW_STALL", "0")))

    def plan_routes(self, task, fleet, layout):
        self._slow()
        return super().plan_routes(task, fleet, layout)

    def fix_legs(self, task, fleet, layout):
        self._slow()
        return super().fix_legs(task, fleet, layout)
'''

# fleetsim with a slow MCAP writer that marks the moment it is halfway through a recording.
SLOW_WRITER = [
    sys.executable,
    "-c",
    """
import os, sys, time
from pathlib import Path
from mcap.writer import Writer
added, count = Writer.add_message, [0]
def slow_add(self, *args, **kwargs):
    count[0] += 1
    if count[0] == 300:
        Path(os.environ["SLOW_MARK"]).write_text(str(os.getpid()))
    if count[0] >= 300:
        time.sleep(float(os.environ.get("SLOW_WRITE_SECONDS", "0.003")))
    return added(self, *args, **kwargs)
Writer.add_message = slow_add
from fleetsim.cli import main
sys.exit(main())
""",
]


class Run:
    """A process started as a terminal would start it, and the marker its planner or writer writes."""

    def __init__(self, command: list[str], folder: Path, **env: str) -> None:
        self.mark = folder / "mark"
        self.started = time.monotonic()
        environment = {
            **os.environ,
            "SLOW_MARK": str(self.mark),
            "PYTHONPATH": os.pathsep.join([str(ROOT), str(folder)]),
            **env,
        }
        environment.pop("CI", None)  # the hunts of the shipped suite are not at stake here
        self.process = subprocess.Popen(
            command, cwd=folder, env=environment, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )  # fmt: skip

    def wait_for(self, ready: Callable[[], bool]) -> None:
        while not ready():
            if self.process.poll() is not None:
                out, err = self.process.communicate()
                pytest.fail(
                    f"the process ended ({self.process.returncode}) before the moment to signal it:\n{out}\n{err}"
                )
            if time.monotonic() - self.started > WAIT:
                self.process.kill()
                pytest.fail("the moment to signal the process never came")
            time.sleep(0.02)

    def signal(self, *signals: int, gap: float = 0.0) -> None:
        for number in signals:
            os.killpg(self.process.pid, number)
            time.sleep(gap)

    def finish(self) -> tuple[int, str, str]:
        try:
            out, err = self.process.communicate(timeout=WAIT)
        except subprocess.TimeoutExpired:
            self.process.kill()
            out, err = self.process.communicate()
            pytest.fail(f"the process did not end after the signal:\n{out}\n{err}")
        return self.process.returncode, out, err


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    (tmp_path / "slowplanner.py").write_text(SLOW_PLANNER)
    return tmp_path


def run_command(record: Path, *extra: str, planner: str = "slowplanner:SlowPlanner") -> list[str]:
    return [*FLEETSIM, "run", str(SUITE), "--planner", planner, "--record", str(record), *extra]


def mcap_facts(path: Path) -> tuple[int, int]:
    """(messages, last /clock in ns), read by mcap + mcap_ros2 and checked against rosbags."""
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        decoded = [
            (channel.topic, message.log_time)
            for _, channel, message, _ in reader.iter_decoded_messages(log_time_order=False)
        ]
    seen = []
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as bag:
        for connection, timestamp, raw in bag.messages():
            bag.deserialize(raw, connection.msgtype)
            seen.append((connection.topic, timestamp))
    assert sorted(seen) == sorted(decoded), "both readers see the same messages"
    clock = [t for topic, t in decoded if topic == "/clock"]
    return len(decoded), clock[-1]


def trace_lines(folder: Path, *, whole: bool = True) -> list[str]:
    """The trace's lines, each a step record; ``whole``: the file must end with a complete line (an
    aborted clean-up may cut the last one, which readers leave out)."""
    lines, clean = complete_lines((folder / "trace.jsonl").read_text(encoding="utf-8"))
    assert clean or not whole
    for line in lines[1:]:
        _step, _vehicles, _plans, _events = json.loads(line)
    return lines


def no_temporary_files(root: Path) -> None:
    hidden = [p for p in root.rglob(".*") if p.is_file()]
    assert hidden == [], "no half-written file is left"


def check_interrupted_folder(folder: Path, signal_name: str) -> dict[str, Any]:
    """An interrupted run's folder: result, trace, picture of the last step, recording, all complete."""
    result = json.loads((folder / "result.json").read_text())
    assert result["status"] == "failed" and result["ended"] == "interrupted"
    first = result["failures"][0]
    assert first["kind"] == "interrupted" and first["signal"] == signal_name
    assert first["time"] == pytest.approx(result["sim_time"])
    lines = trace_lines(folder)
    assert len(lines) - 1 == result["steps"]
    assert json.loads(lines[-1])[3][-1] == ["interrupted", signal_name]
    assert hashlib.sha256((folder / "trace.jsonl").read_bytes()).hexdigest() == result["trace_hash"]
    picture = (folder / "failure.svg").read_text()
    assert f"step {result['steps'] - 1}" in picture and "interrupted" in picture
    messages, last_clock = mcap_facts(folder / "run.mcap")
    assert messages > 0 and last_clock == round(result["sim_time"] * 1e9)
    assert not (folder / "run.json").exists()
    return result


@pytest.mark.parametrize(("sig", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_stop_signal_ends_the_running_scenario_with_its_files_and_prints_the_summary(
    folder: Path, sig: int, status: int
) -> None:
    run = Run(run_command(folder / "rec"), folder, SLOW_RUN="2")  # during the second scenario
    run.wait_for(run.mark.exists)
    run.signal(sig)
    code, out, err = run.finish()
    assert code == status, out + err
    name = signal.Signals(sig).name
    assert "crossing              passed" in out or "crossing  " in out
    assert "loop-one-way" in out and "interrupted" in out
    assert "2 scenario(s) with slowplanner:SlowPlanner: 1 passed, 1 interrupted" in out
    assert f"interrupted by {name}; 2 scenario(s) not run" in out
    assert "Traceback" not in out + err
    check_interrupted_folder(folder / "rec" / "examples" / "loop-one-way", name)
    assert sorted(p.name for p in (folder / "rec" / "examples").iterdir()) == ["crossing", "loop-one-way"]
    no_temporary_files(folder / "rec")


def test_a_slow_planner_call_is_cut_short(folder: Path) -> None:
    run = Run(run_command(folder / "rec", "--planner-timeout", "0"), folder, SLOW_STALL="300")
    run.wait_for(run.mark.exists)
    run.signal(signal.SIGINT)
    code, out, err = run.finish()  # not after the planner's 300 s
    assert code == 130, out + err
    assert time.monotonic() - run.started < WAIT
    check_interrupted_folder(folder / "rec" / "examples" / "crossing", "SIGINT")


def test_a_planner_process_is_ended_like_at_any_run_end(folder: Path) -> None:
    planner = "exec:python -m fleetsim.exec slowplanner:SlowPlanner"
    run = Run(run_command(folder / "rec", "--planner-timeout", "0", planner=planner), folder, SLOW_STALL="300")
    run.wait_for(run.mark.exists)
    pid = int(run.mark.read_text())
    run.signal(signal.SIGTERM)  # the planner process has a session of its own: the signal reaches fleetsim only
    code, out, err = run.finish()
    assert code == 143, out + err
    check_interrupted_folder(folder / "rec" / "examples" / "crossing", "SIGTERM")
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        pytest.fail(f"the planner process {pid} outlived the run")


def test_a_signal_while_a_recording_is_written_lets_it_finish(folder: Path) -> None:
    run = Run(
        [*SLOW_WRITER, *run_command(folder / "rec")[3:]], folder, SLOW_SECONDS="0", SLOW_MARK_AFTER="-1"
    )  # only the writer marks
    run.wait_for(run.mark.exists)
    run.signal(signal.SIGINT)
    code, out, err = run.finish()
    assert code == 130, out + err
    assert "1 scenario(s) with slowplanner:SlowPlanner: 1 passed" in out
    assert "interrupted by SIGINT; 3 scenario(s) not run" in out
    crossing = folder / "rec" / "examples" / "crossing"
    result = json.loads((crossing / "result.json").read_text())
    assert result["status"] == "passed" and "mcap" in result["artifacts"]
    _messages, last_clock = mcap_facts(crossing / "run.mcap")
    assert last_clock == round(result["sim_time"] * 1e9)
    no_temporary_files(folder / "rec")


def test_a_second_signal_while_a_recording_is_written_aborts_and_record_rebuilds_it(folder: Path) -> None:
    run = Run(
        [*SLOW_WRITER, *run_command(folder / "rec")[3:]],
        folder,
        SLOW_SECONDS="0",
        SLOW_MARK_AFTER="-1",
        SLOW_WRITE_SECONDS="0.05",
    )  # only the writer marks, and then it writes slowly enough for two signals to arrive while it writes
    run.wait_for(run.mark.exists)
    run.signal(signal.SIGINT, signal.SIGINT, gap=0.1)
    code, out, err = run.finish()
    assert code == 130, out + err
    assert "Traceback" not in out + err
    crossing = folder / "rec" / "examples" / "crossing"
    assert not (crossing / "run.mcap").exists(), "the recording was cut short: nothing half-written is left"
    no_temporary_files(folder / "rec")
    result = json.loads((crossing / "result.json").read_text())  # written before the recording
    assert result["status"] == "passed" and "mcap" not in result["artifacts"]
    assert len(trace_lines(crossing)) - 1 == result["steps"]
    done = subprocess.run(
        [*FLEETSIM, "record", "--trace", str(crossing)], capture_output=True, text=True, timeout=WAIT, check=False
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "note:" not in done.stdout, "a complete trace does not end early"
    _messages, last_clock = mcap_facts(crossing / "run.mcap")
    assert last_clock == round(result["sim_time"] * 1e9)


def test_two_signals_in_a_row_during_a_run_abort_leaving_only_complete_files(folder: Path) -> None:
    run = Run(run_command(folder / "rec"), folder)
    run.wait_for(run.mark.exists)
    run.signal(signal.SIGINT, signal.SIGINT)
    code, out, err = run.finish()
    assert code == 130, out + err
    assert "Traceback" not in out + err
    crossing = folder / "rec" / "examples" / "crossing"
    trace_lines(crossing, whole=False)  # every line but a last one cut short is a step record
    if (crossing / "result.json").exists():
        json.loads((crossing / "result.json").read_text())
    if (crossing / "run.mcap").exists():
        mcap_facts(crossing / "run.mcap")
    no_temporary_files(folder / "rec")


def test_a_killed_run_leaves_a_trace_that_record_and_render_rebuild(folder: Path) -> None:
    run = Run(run_command(folder / "rec"), folder, SLOW_MARK_AFTER="0")
    crossing = folder / "rec" / "examples" / "crossing"
    trace = crossing / "trace.jsonl"
    run.wait_for(lambda: trace.exists() and trace.read_text().count("\n") >= 101)  # the first checkpoint
    run.signal(signal.SIGKILL)
    code, _, _ = run.finish()
    assert code == -signal.SIGKILL
    assert not (crossing / "result.json").exists() and (crossing / "run.json").exists()
    lines = trace.read_text().split("\n")
    steps = len(lines) - 2  # the header; the last, maybe partial, line is left out
    done = subprocess.run(
        [*FLEETSIM, "record", "--trace", str(crossing)], capture_output=True, text=True, timeout=WAIT, check=False
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"the trace ends early, at step {steps - 1} (t = {steps * 0.1:.2f} s): the run did not end" in done.stdout
    _, last_clock = mcap_facts(crossing / "run.mcap")
    assert last_clock == round(steps * 0.1 * 1e9)
    picture = folder / "step.svg"
    done = subprocess.run(
        [*FLEETSIM, "render", "--trace", str(crossing), "-o", str(picture)],
        capture_output=True,
        text=True,
        timeout=WAIT,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    caption = " ".join(re.findall(r'class="caption-text"[^>]*>([^<]*)<', picture.read_text()))
    assert f"step {steps - 1} of {steps - 1} (the trace ends here: the run did not end)" in caption


@pytest.mark.parametrize(("sig", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_pytest_reports_the_interrupted_scenario_then_its_own_interrupt_summary(
    folder: Path, sig: int, status: int
) -> None:
    results = folder / "results"
    command = [
        sys.executable, "-m", "pytest", str(SUITE), "--planner", "slowplanner:SlowPlanner", "--fleetsim-artifacts", str(results),
        "-p", "no:xdist", "-p", "no:randomly", "-v",
    ]  # fmt: skip
    run = Run(command, folder, SLOW_RUN="2")
    run.wait_for(run.mark.exists)
    run.signal(sig)
    code, out, err = run.finish()
    name = signal.Signals(sig).name
    assert code == status, out + err
    assert "examples.fleetsim.yaml::loop-one-way INTERRUPTED" in out
    assert f"Interrupted: {name} stopped the session during" in out
    assert "loop-one-way  interrupted" in out  # the fleetsim summary
    assert "examples.fleetsim.yaml::corridor-passing-bay" not in out, "no further scenario runs"
    check_interrupted_folder(results / "examples" / "loop-one-way", name)
    no_temporary_files(results)
