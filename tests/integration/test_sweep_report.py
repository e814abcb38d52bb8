"""The sweep report in a real headless Chromium: it renders its tables and plots and fetches nothing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from browser import chromium_run as _chromium
from browser import requested as _requested
from sweep_support import write_spec
from tooling import required_tool

from fleetsim.cli.main import main
from fleetsim.sweep.items import expand
from fleetsim.sweep.results import ResultsFile
from fleetsim.sweep.spec import load_sweep_spec
from fleetsim.sweep.worker import run_item


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("report")
    spec = load_sweep_spec(
        write_spec(folder, ("fleetsim.planners:ReservingPlanner", "fleetsim.planners:BFSPlanner"), count=8)
    )
    results = folder / "results.jsonl"
    with ResultsFile(results, {"name": "small", "baseline": spec.baseline}, resume=False) as file:
        for item in expand(spec, folder / "runs"):
            file.add(run_item(item))  # the runs in process: this test is about the page
    assert main(["sweep", "report", str(results), "--markdown", str(folder / "summary.md")]) == 0
    return folder


def test_report_renders_in_headless_chromium_without_requests(report: Path) -> None:
    chromium = required_tool("chromium", "Chromium 'chromium'", "apt install chromium")
    page = report / "results.html"
    shot = report / "shot.png"
    netlog = report / "net.json"
    done = _chromium(
        chromium, page, report, f"--screenshot={shot}", "--window-size=1100,1400", f"--log-net-log={netlog}"
    )
    assert shot.is_file() and shot.stat().st_size > 10_000, done.stderr[-2000:]
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    dom = _chromium(chromium, page, report, "--dump-dom").stdout
    for plot in ('data-plot="distribution"', 'data-plot="fleet-size"', 'data-plot="paired-differences"'):
        assert plot in dom
    for table in ('id="planners"', 'id="comparison-0"'):
        assert table in dom
    assert "ReservingPlanner" in dom and "BFSPlanner" in dom
    assert _requested(netlog) <= {page.as_uri()}, _requested(netlog)


def test_the_net_log_sees_a_request_a_page_makes(report: Path) -> None:
    """The control for the test above: a page that loads an image from elsewhere shows in the net log."""
    chromium = required_tool("chromium", "Chromium 'chromium'", "apt install chromium")
    page = report / "leaky.html"
    page.write_text('<html><body><img src="http://127.0.0.1:9/pixel.png"></body></html>', encoding="utf-8")
    netlog = report / "leaky-net.json"
    _chromium(chromium, page, report, "--dump-dom", f"--log-net-log={netlog}")
    assert "http://127.0.0.1:9/pixel.png" in _requested(netlog)


def test_markdown_summary_compares_with_the_baseline(report: Path) -> None:
    text = (report / "summary.md").read_text(encoding="utf-8")
    assert "# Sweep report: small" in text
    assert "| BFSPlanner | 8 | 0 |" in text and "| ReservingPlanner | 8 | 0 |" in text
    assert "## BFSPlanner against ReservingPlanner" in text
    assert "95% percentile bootstrap interval" in text
    assert "| throughput (tasks/h) | 8 |" in text


def test_report_is_the_same_whatever_order_the_rows_finished_in(report: Path, tmp_path: Path) -> None:
    lines = (report / "results.jsonl").read_text(encoding="utf-8").splitlines()
    shuffled = tmp_path / "results.jsonl"
    shuffled.write_text("\n".join([lines[0], *reversed(lines[1:])]) + "\n", encoding="utf-8")
    assert (
        main(
            [
                "sweep",
                "report",
                str(shuffled),
                "--markdown",
                str(tmp_path / "summary.md"),
                "--html",
                str(tmp_path / "r.html"),
            ]
        )
        == 0
    )
    assert (tmp_path / "summary.md").read_text() == (report / "summary.md").read_text()
    assert json.loads(lines[0])["format"] == "fleetsim-sweep-results/2"


def test_fail_if_gates_on_the_interval_with_exit_codes(report: Path, capsys: pytest.CaptureFixture[str]) -> None:
    results = str(report / "results.jsonl")
    html = ["--html", str(report / "gate.html")]
    # BFSPlanner cannot match ReservingPlanner's success rate beyond doubt on these scenarios...
    assert main(["sweep", "report", results, *html, "--fail-if", "success < baseline - 200%"]) == 0
    assert main(["sweep", "report", results, *html, "--fail-if", "alerts > baseline + 1000"]) == 0
    # ...and a condition that asks nothing of the data cannot hold beyond the interval in both directions.
    assert main(["sweep", "report", results, *html, "--fail-if", "throughput > baseline + 1000000"]) == 0
    assert main(["sweep", "report", results, *html, "--fail-if", "throughput < baseline + 1000000"]) == 1
    assert "FAIL  fleetsim.planners:BFSPlanner: throughput < baseline + 1000000" in capsys.readouterr().out
    assert main(["sweep", "report", results, *html, "--fail-if", "speed < baseline"]) == 2
    assert "unknown metric 'speed'" in capsys.readouterr().err


def test_contacts_and_the_least_clearance_are_summed_up_and_compared(report: Path) -> None:
    records = [json.loads(line) for line in (report / "results.jsonl").read_text(encoding="utf-8").splitlines()[1:]]
    text = (report / "summary.md").read_text(encoding="utf-8")
    header = next(line for line in text.splitlines() if line.startswith("| planner |"))
    columns = [cell.strip() for cell in header.strip("|").split("|")]
    assert "contacts" in columns and "least clearance (m)" in columns
    for planner in ("ReservingPlanner", "BFSPlanner"):
        mine = [r for r in records if r["planner"].endswith(planner)]
        row = next(line for line in text.splitlines() if line.startswith(f"| {planner} |"))
        cells = dict(zip(columns, (cell.strip() for cell in row.strip("|").split("|")), strict=True))
        assert cells["contacts"] == str(sum(len(r["contact"]["contacts"]) for r in mine))
        least = min(r["metrics"]["clearance"] for r in mine if r["metrics"]["clearance"] is not None)
        assert cells["least clearance (m)"] == f"{least:.4g}"
    # The reservation rule keeps footprints apart (the property test's guarantee); BFSPlanner's do touch.
    assert sum(len(r["contact"]["contacts"]) for r in records if r["planner"].endswith("ReservingPlanner")) == 0
    assert "| contacts | 8 |" in text and "| clearance (m) | " in text


def test_the_worst_scenarios_link_to_their_viewer_pages(tmp_path: Path) -> None:
    spec_path = write_spec(tmp_path, ("fleetsim.planners:ReservingPlanner", "fleetsim.planners:BFSPlanner"), count=8)
    spec_path.write_text(
        spec_path.read_text(encoding="utf-8").replace("record: none", "record: failed"), encoding="utf-8"
    )
    spec = load_sweep_spec(spec_path)
    results = tmp_path / "results.jsonl"
    with ResultsFile(results, {"name": "small", "baseline": spec.baseline}, resume=False) as file:
        for item in expand(spec, tmp_path / "runs"):
            file.add(run_item(item))
    assert main(["sweep", "report", str(results), "--markdown", str(tmp_path / "summary.md")]) == 0
    html = (tmp_path / "results.html").read_text(encoding="utf-8")
    worst = html.split('<ul class="worst">', 1)[1].split("</ul>", 1)[0]
    views = [
        part.split('"', 1)[0] for part in worst.split('<a href="')[1:] if part.split('"', 1)[0].endswith("view.html")
    ]
    assert views, worst
    for link in views:
        assert (tmp_path / link).read_text(encoding="utf-8").startswith("<!doctype html>")
    assert "([watch it](" in (tmp_path / "summary.md").read_text(encoding="utf-8")
