"""Does the viewer keep up with a large site? 1,000 vehicles on a 10,000-segment map, in headless Chromium.

    python benchmarks/view.py [--vehicles 1000] [--aisles 2.5] [--seconds 60] [--repeat 5] [--play 4] [--speed 10]

A generated warehouse (``warehouse.write_fleet_scenario``: 2.5 aisles per vehicle gives a 36 x 36
lattice of 10,368 segments for 1,000 vehicles) is simulated for ``--seconds`` with BFSPlanner, and the
run is written as the viewer's self-contained page (``fleetsim view --html``). Then, ``--repeat`` times,
each in a fresh browser page of Debian's Chromium (Playwright, ``executable_path``):

- load: wall seconds from asking for the page to the page being ready (its document unpacked and every
  step indexed), and the page's own figure for it;
- frame rate: the page plays the run at ``--speed`` (10x by default: 100 steps a second, more than the
  browser draws, so every frame shows a new step) with plans and reservations drawn for ``--play``
  seconds; the rate is taken from the browser's own frame timing (the ``requestAnimationFrame``
  timestamps of the frames it drew), as frames over the time between the first and the last.

Medians over the repeats. Targets (issue 35): >= 30 frames per second, a 60 s recording of 1,000
vehicles loads in under 3 s.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import write_fleet_scenario


def make_page(folder: Path, vehicles: int, aisles: float, seconds: float) -> tuple[Path, dict[str, Any]]:
    """Simulate the site and write its viewer page; the page and what making it took."""
    from fleetsim.load.suites.scenario import load_scenario_dir
    from fleetsim.planners import BFSPlanner
    from fleetsim.scenario import ScenarioSettings
    from fleetsim.sim.loop import run_scenario
    from fleetsim.view import recorded_view

    write_fleet_scenario(folder / "site", vehicles, seed=1, aisles_per_vehicle=aisles)
    scenario = load_scenario_dir(folder / "site", settings=ScenarioSettings(time_limit=seconds, stop_on=()))
    result = run_scenario(scenario, BFSPlanner())
    assert result.trace is not None
    started = time.perf_counter()
    page = recorded_view(scenario, result.trace.lines, result.to_dict(), result.failures)
    built = time.perf_counter() - started
    path = folder / "view.html"
    path.write_text(page, encoding="utf-8")
    return path, {
        "segments": len(scenario.layout.segments),
        "vehicles": len(scenario.vehicles),
        "steps": result.steps,
        "trace_mb": sum(len(line) + 1 for line in result.trace.lines) / 1e6,
        "page_mb": path.stat().st_size / 1e6,
        "build_s": built,
    }


def measure(browser: Any, page_path: Path, play: float, speed: str) -> dict[str, float]:
    page = browser.new_page(viewport={"width": 1280, "height": 800})
    started = time.perf_counter()
    page.goto(page_path.as_uri())
    page.wait_for_function("() => window.fleetsimView && window.fleetsimView.ready", timeout=120_000)
    loaded = time.perf_counter() - started
    own = float(page.evaluate("fleetsimView.loadMs")) / 1000
    page.select_option("#speed", speed)
    page.evaluate("fleetsimView.frameTimes.length = 0")
    page.click("#play")
    page.wait_for_timeout(play * 1000)
    times = page.evaluate("fleetsimView.frameTimes.slice()")
    page.click("#play")
    page.close()
    fps = (len(times) - 1) / ((times[-1] - times[0]) / 1000) if len(times) > 1 else 0.0
    return {"load_s": loaded, "page_load_s": own, "fps": fps, "frames": float(len(times))}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--vehicles", type=int, default=1000)
    parser.add_argument("--aisles", type=float, default=2.5, help="aisles per vehicle (2.5: ~10,000 segments)")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--play", type=float, default=4.0, help="wall seconds of playing per repeat")
    parser.add_argument("--speed", default="10", help="the page's speed while playing (default: 10)")
    parser.add_argument("--keep", metavar="DIR", help="keep the page (view.html) and the site in DIR")
    parser.add_argument("--chromium", default=shutil.which("chromium") or "chromium")
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(args.keep) if args.keep else Path(temporary)
        page_path = folder / "view.html"
        if args.keep and page_path.exists():
            made = None
        else:
            page_path, made = make_page(folder, args.vehicles, args.aisles, args.seconds)
        if made is not None:
            print(
                f"{made['vehicles']} vehicles, {made['segments']} segments, {made['steps']} steps: "
                f"trace {made['trace_mb']:.1f} MB, page {made['page_mb']:.1f} MB (built in {made['build_s']:.2f} s)"
            )
        rows = []
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=args.chromium, args=["--no-sandbox"])
            for repeat in range(args.repeat):
                row = measure(browser, page_path, args.play, args.speed)
                rows.append(row)
                print(
                    f"  repeat {repeat + 1}: load {row['load_s']:.2f} s (the page's own {row['page_load_s']:.2f} s), "
                    f"{row['fps']:.1f} frames/s over {row['frames']:.0f} frames"
                )
            browser.close()
    load = statistics.median(r["load_s"] for r in rows)
    fps = statistics.median(r["fps"] for r in rows)
    print(f"median: load {load:.2f} s (target < 3 s), {fps:.1f} frames/s (target >= 30)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
