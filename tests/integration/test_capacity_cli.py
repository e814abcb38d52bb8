"""``fleetsim capacity`` end to end: a real search of the shipped small site on local Dask workers, its
results file, report page and gate, a search resumed from its runs, and the input it refuses."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from browser import chromium_run, requested
from tooling import required_tool

pytest.importorskip("distributed")

from fleetsim.cli.main import main
from fleetsim.sweep.results import read_results

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "examples" / "capacity" / "small-site.fleetsim.yaml"
PLANNER = "fleetsim.planners:ReservingPlanner"
SEARCH = ["--seeds", "1,2", "--resolution", "50%"]


@pytest.fixture(scope="module")
def searched(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """One real search (2 seeds, to 50 %) on 2 local worker processes: its results file and printed summary."""
    out = tmp_path_factory.mktemp("capacity") / "capacity.json"
    capture = tmp_path_factory.mktemp("stdout") / "summary.md"
    status = main(["capacity", f"{SMALL}::shift", "--planner", PLANNER, *SEARCH, "--workers", "2", "-o", str(out), "--markdown", str(capture)])  # fmt: skip
    assert status == 0
    return out, capture.read_text(encoding="utf-8")


def test_the_search_brackets_the_small_sites_capacity_over_both_seeds(searched: tuple[Path, str]) -> None:
    out, summary = searched
    document = json.loads(out.read_text(encoding="utf-8"))
    assert document["format"] == "fleetsim-capacity/1"
    assert (document["stop"], document["entry_rate"], document["seeds"]) == ("resolution", 30.0, [1, 2])
    low, high = document["sustained"], document["unsustained"]
    assert low is not None and high is not None and low < high <= 1.5 * low
    assert document["capacity"] == low
    for rate in document["rates"]:
        assert [run["seed"] for run in rate["runs"]] == [1, 2]
        assert rate["sustained"] == (rate["rate"] <= low) == all(run["sustained"] for run in rate["runs"])
    _, rows = read_results(out.with_suffix(".runs.jsonl"))  # the runs: a sweep results file
    assert len(rows) == document["runs"] == 2 * len(document["rates"])
    assert {row["id"] for row in rows} >= {f"examples/capacity/small-site.fleetsim.yaml::shift~r{low:g}~o1"}
    assert (
        f"**capacity {low:g} orders/h: sustained by every seed (1, 2) at {low:g}, not at {high:g} orders/h**" in summary
    )


def test_the_report_page_is_well_formed_and_holds_the_throughput_and_service_time_svg(
    searched: tuple[Path, str],
) -> None:
    page = searched[0].with_suffix(".html").read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and page.rstrip().endswith("</body></html>")
    assert "Content-Security-Policy" in page and "<script" not in page
    plots = []
    start = 0
    while (start := page.find("<svg", start)) >= 0:
        end = page.index("</svg>", start) + len("</svg>")
        plots.append(ET.fromstring(page[start:end]))  # each plot is well-formed XML
        start = end
    assert [plot.get("data-plot") for plot in plots] == ["capacity-throughput", "capacity-service-time"]
    assert plots[0].find("{http://www.w3.org/2000/svg}title").text == "throughput against offered rate"  # type: ignore[union-attr]


def test_the_report_page_renders_in_headless_chromium_and_fetches_nothing(searched: tuple[Path, str]) -> None:
    chromium = required_tool("chromium", "Chromium 'chromium'", "apt install chromium")
    page = searched[0].with_suffix(".html")
    work = page.parent
    shot, netlog = work / "shot.png", work / "net.json"
    done = chromium_run(
        chromium, page, work, f"--screenshot={shot}", "--window-size=1100,1400", f"--log-net-log={netlog}"
    )
    assert shot.is_file() and shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", done.stderr[-2000:]
    dom = chromium_run(chromium, page, work, "--dump-dom").stdout
    assert 'data-plot="capacity-throughput"' in dom and 'data-plot="capacity-service-time"' in dom
    assert "orders/h" in dom
    assert requested(netlog) <= {page.as_uri()}, requested(netlog)


def test_a_resumed_search_reruns_nothing_gives_the_same_results_and_gates_them(
    searched: tuple[Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "capacity.json"
    runs = searched[0].with_suffix(".runs.jsonl").read_text(encoding="utf-8").splitlines(keepends=True)
    # The rows in another order, as runs finishing in another order would write them.
    out.with_suffix(".runs.jsonl").write_text("".join([runs[0], *reversed(runs[1:])]), encoding="utf-8")
    capsys.readouterr()
    args = ["capacity", f"{SMALL}::shift", "--planner", PLANNER, *SEARCH, "-o", str(out), "--resume"]
    assert main([*args, "--baseline", str(searched[0]), "--fail-if", "capacity < baseline - 5%"]) == 0
    assert out.read_text(encoding="utf-8") == searched[0].read_text(encoding="utf-8")
    printed = capsys.readouterr()
    assert "- ok  capacity < baseline - 5%" in printed.out
    assert "orders/h: sustained" in printed.err
    assert main([*args, "--baseline", "1000", "--fail-if", "capacity < baseline - 5%"]) == 1
    assert "- FAIL  capacity < baseline - 5%: capacity" in capsys.readouterr().out


def test_runs_of_another_search_are_not_resumed(searched: tuple[Path, str], capsys: pytest.CaptureFixture[str]) -> None:
    other = "fleetsim.dispatchers:OldestFirstDispatcher"
    args = ["capacity", f"{SMALL}::shift", "--planner", PLANNER, "--dispatcher", other, "-o", str(searched[0]), "--resume"]  # fmt: skip
    assert main(args) == 2
    assert "the runs of another search" in capsys.readouterr().err


def _refused(capsys: pytest.CaptureFixture[str], *args: str) -> str:
    assert main(["capacity", *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fleetsim: error: ") and "Traceback" not in err
    return err


def test_an_entry_without_an_order_stream_is_refused_naming_the_entry(capsys: pytest.CaptureFixture[str]) -> None:
    examples = ROOT / "scenario_suites" / "examples.fleetsim.yaml"
    err = _refused(capsys, f"{examples}::crossing", "--planner", PLANNER)
    assert f"{examples}:" in err and "scenario 'crossing' has no order stream" in err


@pytest.mark.parametrize(
    ("stream", "says"),
    [
        (
            "{seed: 1, arrivals: {pool: 3}, stops: [{from: pick}, {from: drop}]}",
            "has pool arrivals, not a Poisson rate",
        ),
        ("{seed: 1, arrivals: {poisson: 30}, limit: 9, stops: [{from: pick}, {from: drop}]}", "limit: 9 orders"),
    ],
)
def test_an_entry_whose_stream_has_no_rate_to_scale_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], stream: str, says: str
) -> None:
    suite = tmp_path / "pool.fleetsim.yaml"
    text = SMALL.read_text(encoding="utf-8").replace("dir: small-site/", f"dir: {SMALL.parent / 'small-site'}/")
    start = text.index("order_stream:")
    end = text.index("\n", start)
    suite.write_text(text[:start] + f"order_stream: {stream}" + text[end:], encoding="utf-8")
    err = _refused(capsys, f"{suite}::shift", "--planner", PLANNER)
    assert f"{suite}:" in err and "scenario 'shift'" in err and says in err


@pytest.mark.parametrize(
    ("options", "says"),
    [
        (["--fail-if", "throughput < baseline"], "unknown metric 'throughput'; known: capacity"),
        (["--fail-if", "capacity < baseline - 5%"], "--fail-if needs --baseline"),
        (
            ["--baseline", "nowhere.json", "--fail-if", "capacity < baseline"],
            "nowhere.json: no such capacity results file",
        ),
        (["--max-rate", "fast"], "--max-rate='fast' must be a positive number of orders per hour"),
        (["--max-rate", "20"], "it starts at the entry's rate, 30"),
        (["--resolution", "half"], "--resolution='half' must be a percentage"),
        (["--seeds", "1,x"], "--seeds='1,x' must be whole numbers"),
        (["--tolerance", "150%"], "--tolerance='150%' must be a percentage from 0 to below 100"),
        (["--max-service-p95", "soon"], "--max-service-p95='soon' must be a number of seconds > 0"),
        (["--planner", "fleetsim.planners:NoSuch"], "'fleetsim.planners' has no attribute 'NoSuch'"),
    ],
)
def test_bad_options_are_refused_before_any_run(
    capsys: pytest.CaptureFixture[str], options: list[str], says: str
) -> None:
    assert says in _refused(capsys, f"{SMALL}::shift", "--planner", PLANNER, *options)


def test_a_scenario_not_in_the_suite_is_refused_with_the_names_it_has(capsys: pytest.CaptureFixture[str]) -> None:
    assert f"{SMALL} has no scenario 'nope' (its scenarios: shift)" in _refused(capsys, f"{SMALL}::nope", "--planner", PLANNER)  # fmt: skip
    assert "must name one suite entry: SUITE.fleetsim.yaml::NAME" in _refused(capsys, str(SMALL), "--planner", PLANNER)
