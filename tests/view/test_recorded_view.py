"""A recorded run in the viewer, in headless Chromium: what it draws is the trace; time control works."""

from __future__ import annotations

import json
import math
import shutil
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

import pytest
from viewer import EXAMPLES, ready, state, wait_drawn

from fleetsim.cli.main import main
from fleetsim.cli.recorded import read_recorded_run
from fleetsim.recording.replay import frame_at
from fleetsim.view import recorded_page, view_document
from fleetsim.view.document import outcome_part


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Three recorded runs: mixed-shapes with ReservingPlanner (passes, 393 steps), loop-one-way with
    BFSPlanner (fails on a collision alert at its last step, 50) and the same run going on after its
    failure (``stop_on: []``, to t = 20 s: 200 steps, failed at step 50)."""
    root = tmp_path_factory.mktemp("recorded")
    for name, planner in (("mixed-shapes", "ReservingPlanner"), ("loop-one-way", "BFSPlanner")):
        main(["run", f"{EXAMPLES}::{name}", "--planner", f"fleetsim.planners:{planner}", "--record", str(root)])
    text = EXAMPLES.read_text(encoding="utf-8")
    head = text[: text.index("scenarios:")].replace("time_limit: 300", "time_limit: 20\n  stop_on: []")
    loop = EXAMPLES.parent / "examples" / "loop"
    suite = root / "onward.fleetsim.yaml"
    suite.write_text(f"{head}scenarios:\n  - name: loop-one-way\n    dir: {loop}/\n", encoding="utf-8")
    main(["run", f"{suite}::loop-one-way", "--planner", "fleetsim.planners:BFSPlanner", "--record", str(root)])
    return {
        "passing": root / "examples" / "mixed-shapes",
        "failing": root / "examples" / "loop-one-way",
        "failing-midway": root / "onward" / "loop-one-way",
    }


def _open(page: Any, html: Path) -> None:
    page.goto(html.as_uri())
    ready(page)


def _assert_drawn_is_traced(page: Any, run_folder: Path, step: int) -> None:
    run = read_recorded_run(run_folder, None)
    frame = frame_at(run.scenario, run.lines, step)
    shown = wait_drawn(page, step)
    assert sorted(int(v) for v in shown["poses"]) == sorted(frame.poses)
    for vid, pose in frame.poses.items():
        x, y, heading = shown["poses"][str(vid)]
        assert (x, y) == pytest.approx((pose.x, pose.y), abs=1e-9), (step, vid)
        assert heading == pytest.approx(pose.heading, abs=1e-9), (step, vid)


def test_the_run_folder_has_the_view_and_fleetsim_view_writes_the_same_page(
    runs: dict[str, Path], tmp_path: Path
) -> None:
    for folder in runs.values():
        result = json.loads((folder / "result.json").read_text(encoding="utf-8"))
        assert result["artifacts"]["view"] == str(folder / "view.html")
        out = tmp_path / f"{folder.name}.html"
        assert main(["view", str(folder), "--html", str(out)]) == 0
        assert out.read_text(encoding="utf-8") == (folder / "view.html").read_text(encoding="utf-8")
        # a result.json or a trace.jsonl names the same run
        assert main(["view", str(folder / "result.json"), "--html", str(tmp_path / "again.html")]) == 0
        assert (tmp_path / "again.html").read_bytes() == out.read_bytes()


def test_drawn_vehicles_at_scrubbed_times_are_where_the_trace_puts_them(page: Any, runs: dict[str, Path]) -> None:
    folder = runs["passing"]
    _open(page, folder / "view.html")
    last = state(page)["last"]
    assert last == 392
    for step in (0, 1, 57, 250, 131, last):  # forwards, back past a kept copy of the fleet, to the end
        page.evaluate(f"fleetsimView.seek({step})")
        _assert_drawn_is_traced(page, folder, step)
    # the scrub bar as a user drags it
    page.locator("#scrub").fill("200")
    _assert_drawn_is_traced(page, folder, 200)
    assert state(page)["shown"].startswith("t = 20.10 s \u00b7 step 200 of 392")


def test_a_compressed_page_draws_the_same(page: Any, runs: dict[str, Path], tmp_path: Path) -> None:
    folder = runs["passing"]
    run = read_recorded_run(folder, None)
    outcome = outcome_part(run.document, run.failures, run.scenario.settings.time_step, run.last_step)
    html = recorded_page(view_document(run.scenario, run.lines, {}, outcome), compress_from=0)
    assert 'data-encoding="gzip+base64"' in html
    (tmp_path / "packed.html").write_text(html, encoding="utf-8")
    _open(page, tmp_path / "packed.html")
    page.evaluate("fleetsimView.seek(321)")
    _assert_drawn_is_traced(page, folder, 321)


def test_play_pause_speed_and_step_move_the_shown_time(page: Any, runs: dict[str, Path]) -> None:
    _open(page, runs["passing"] / "view.html")
    assert state(page)["time"] == pytest.approx(0.1)
    page.select_option("#speed", "10")
    page.click("#play")
    started = time.monotonic()
    page.wait_for_timeout(1000)
    page.click("#play")  # pause
    elapsed = time.monotonic() - started
    paused = state(page)
    assert not paused["playing"]
    # 10x: about ten simulated seconds per wall second (the browser's frames make it coarse)
    assert 0.5 * 10 * elapsed < paused["time"] < 1.5 * 10 * elapsed + 0.5, (paused, elapsed)
    page.wait_for_timeout(400)
    assert state(page)["time"] == paused["time"]  # paused: the time stands
    assert state(page)["shown"].startswith(f"t = {paused['time']:.2f} s \u00b7 step {paused['step']} of 392")
    page.click("#forward")
    assert state(page)["step"] == paused["step"] + 1
    page.click("#back")
    page.click("#back")
    assert state(page)["step"] == paused["step"] - 1
    page.keyboard.press("ArrowRight")
    assert state(page)["step"] == paused["step"]
    page.select_option("#speed", "max")
    page.keyboard.press(" ")
    page.wait_for_function("() => fleetsimView.state().step === 392 && !fleetsimView.state().playing", timeout=15_000)
    page.select_option("#speed", "0.1")
    page.evaluate("fleetsimView.seek(10)")
    page.click("#play")
    page.wait_for_timeout(1000)
    slow = state(page)
    assert slow["step"] in (10, 11, 12), slow  # 0.1x: a step per wall second


def test_next_event_and_failure_jump_to_their_steps(page: Any, runs: dict[str, Path]) -> None:
    folder = runs["passing"]
    run = read_recorded_run(folder, None)
    with_events = [json.loads(line)[0] for line in run.lines[1:] if json.loads(line)[3]]
    _open(page, folder / "view.html")
    assert page.locator("#to-failure").is_disabled()  # it passed
    for expected in with_events[:3]:
        page.click("#next-event")
        assert state(page)["step"] == expected
    rows = page.locator("#events li")
    assert rows.count() == len(with_events)  # one completed task each
    rows.nth(2).click()
    assert state(page)["step"] == with_events[2]

    failing = runs["failing"]
    result = json.loads((failing / "result.json").read_text(encoding="utf-8"))
    _open(page, failing / "view.html")
    page.click("#to-failure")
    failure_time = result["failures"][0]["time"]
    assert state(page)["time"] == pytest.approx(failure_time)
    assert page.locator("#status").inner_text().startswith("failed \u2014 collision")
    assert page.locator('#events li[data-kind="alert"]').count() >= 1
    assert page.locator('#events li[data-kind="failure"]').count() == 1


def test_a_failed_run_opens_paused_at_its_failure_and_home_goes_to_the_start(page: Any, runs: dict[str, Path]) -> None:
    folder = runs["failing-midway"]
    result = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    assert result["status"] == "failed" and result["failures"][0]["time"] == pytest.approx(5.1)
    _open(page, folder / "view.html")
    opened = state(page)
    assert (opened["step"], opened["last"], opened["playing"]) == (50, 199, False), opened
    assert opened["time"] == pytest.approx(result["failures"][0]["time"])
    _assert_drawn_is_traced(page, folder, 50)
    assert state(page)["shown"].startswith("t = 5.10 s \u00b7 step 50 of 199")
    # as `f` leaves it: the failure is the shown step's event
    assert page.locator('#events li.current[data-kind="failure"]').count() == 1
    page.wait_for_timeout(300)
    assert state(page)["step"] == 50  # paused there
    page.keyboard.press("Home")
    assert state(page)["step"] == 0
    _assert_drawn_is_traced(page, folder, 0)
    page.keyboard.press("f")
    assert state(page)["step"] == 50
    # a passed run opens at its start, as before
    _open(page, runs["passing"] / "view.html")
    assert state(page)["step"] == 0
    _assert_drawn_is_traced(page, runs["passing"], 0)


def test_hovering_a_vehicle_shows_its_state_plan_and_task(page: Any, runs: dict[str, Path]) -> None:
    _open(page, runs["passing"] / "view.html")
    page.evaluate("fleetsimView.seek(40)")
    x, y = page.evaluate("fleetsimView.screenOf(1)")
    box = page.locator("#canvas").bounding_box()
    page.mouse.move(box["x"] + x, box["y"] + y)
    tip = page.locator("#tooltip")
    tip.wait_for(state="visible")
    text = tip.inner_text()
    assert text.startswith("vehicle 1 (agv)")
    assert "segment " in text and "m/s" in text and "heading" in text
    assert "task 2 \u2192 segment 4 (0 of 2 done)" in text
    assert "plan: " in text and "fixed" in text
    page.mouse.move(box["x"] + 2, box["y"] + 2)
    tip.wait_for(state="hidden")


def test_the_self_contained_page_makes_no_request(browser: Any, runs: dict[str, Path], tmp_path: Path) -> None:
    """Every request the page makes is refused and listed (a refusing proxy); the page needs none."""
    for html in (runs["failing"] / "view.html", _leaky(tmp_path)):
        context = browser.new_context()
        asked: list[str] = []

        context.route("**/*", _refusing(asked, html.as_uri()))
        page = context.new_page()
        page.goto(html.as_uri())
        page.wait_for_timeout(500)
        if html.name == "view.html":
            ready(page)
            page.click("#play")
            page.wait_for_timeout(500)
            assert asked == [html.as_uri()], asked
        else:  # the control: a request the page makes is seen
            assert "http://127.0.0.1:9/pixel.png" in asked, asked
        context.close()


def _refusing(asked: list[str], allowed: str) -> Any:
    def refuse(route: Any) -> None:
        asked.append(route.request.url)
        if route.request.url == allowed:
            route.continue_()
        else:
            route.abort()

    return refuse


def _leaky(folder: Path) -> Path:
    page = folder / "leaky.html"
    page.write_text('<html><body><img src="http://127.0.0.1:9/pixel.png"></body></html>', encoding="utf-8")
    return page


def test_a_killed_runs_trace_replays_up_to_where_it_ends_and_says_so(
    page: Any, runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    killed = tmp_path / "killed"
    shutil.copytree(runs["passing"], killed)
    lines = (killed / "trace.jsonl").read_text(encoding="utf-8").split("\n")
    (killed / "trace.jsonl").write_text("\n".join(lines[:121]) + "\n" + lines[121][:15], encoding="utf-8")
    about = json.loads((killed / "result.json").read_text(encoding="utf-8"))
    (killed / "result.json").unlink()
    (killed / "run.json").write_text(
        json.dumps({k: about[k] for k in ("suite", "scenario", "planner")}), encoding="utf-8"
    )
    capsys.readouterr()
    assert main(["view", str(killed), "--html", str(killed / "view.html")]) == 0
    out = capsys.readouterr().out
    assert "the last line is cut short" in out and "the trace ends early, at step 119 (t = 12.00 s)" in out
    _open(page, killed / "view.html")
    assert state(page)["last"] == 119
    assert "the trace ends early, at step 119" in page.locator("#notes").inner_text()
    page.evaluate("fleetsimView.seek(119)")
    _assert_drawn_is_traced(page, runs["passing"], 119)


def test_fleetsim_view_serves_the_page_on_a_loopback_port(page: Any, runs: dict[str, Path]) -> None:
    process = subprocess.Popen(
        [sys.executable, "-m", "fleetsim", "view", str(runs["failing"]), "--no-open"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        assert line.startswith("viewing loop-one-way, steps 0-50 up to t = 5.10 s at http://127.0.0.1:"), line
        url = line.split(" at ", 1)[1].split(" ", 1)[0]
        with urllib.request.urlopen(url, timeout=10) as response:
            assert response.headers["Content-Type"] == "text/html; charset=utf-8"
            assert b'id="fleetsim-data"' in response.read()
        with pytest.raises(urllib.error.HTTPError, match="404"):
            urllib.request.urlopen(url + "trace.jsonl", timeout=10)
        page.goto(url)
        ready(page)
        assert state(page)["last"] == 50
        # as view.html: at the failure (its last step here), the start one key away
        assert state(page)["step"] == 50 and state(page)["time"] == pytest.approx(5.1)
        page.keyboard.press("Home")
        assert state(page)["step"] == 0
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=10) == 0
    finally:
        process.kill()
        process.wait()


def test_bad_runs_get_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["view", str(tmp_path / "nowhere")]) == 2
    assert f"{tmp_path / 'nowhere'}: no such file or directory" in capsys.readouterr().err
    (tmp_path / "result.json").write_text("{}", encoding="utf-8")
    assert main(["view", str(tmp_path / "result.json")]) == 2
    assert "no trace.jsonl beside it" in capsys.readouterr().err


def test_the_drawn_headings_point_where_the_vehicles_drive(page: Any, runs: dict[str, Path]) -> None:
    """A vehicle driving nose first moves the way its heading points (the drawn nose is its front)."""
    folder = runs["passing"]
    _open(page, folder / "view.html")
    page.evaluate("fleetsimView.seek(30)")
    before = wait_drawn(page, 30)["poses"]  # once that step is drawn
    page.evaluate("fleetsimView.seek(35)")
    after = wait_drawn(page, 35)["poses"]
    x0, y0, heading = before["2"]
    x1, y1, _ = after["2"]
    assert math.hypot(x1 - x0, y1 - y0) > 0.1
    assert math.cos(math.atan2(y1 - y0, x1 - x0) - heading) > 0.9
