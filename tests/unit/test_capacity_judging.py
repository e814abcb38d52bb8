"""Capacity's judgements: a run's result document against the criteria, the gate, the results file, the report."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import pytest

from fleetsim.capacity.criteria import Criteria, Judgement, judge_run
from fleetsim.capacity.gate import Baseline, GateError, judge_capacity, parse_baseline, parse_gate
from fleetsim.capacity.report import html_page, markdown
from fleetsim.capacity.results import CAPACITY_FORMAT, CapacityResultsError, read_capacity, write_capacity

CRITERIA = Criteria(tolerance=0.1)


def record(failures: tuple[dict[str, Any], ...] = (), **measures: Any) -> dict[str, Any]:
    """A result document's keys that capacity reads: a run of 5 vehicles over a 1-hour window that kept up."""
    figures = {
        "window": [300.0, 3900.0], "released": 60, "completed": 59, "orders_per_hour": 59.0,
        "service_time": {"count": 59, "median": 150.0, "p95": 300.0, "max": 320.0},
        "backlog_slope": 0.5, "overloaded": False, "stalls": 0,
    }  # fmt: skip
    status = "failed" if failures else "passed"
    return {"status": status, "failures": list(failures), "measures": figures | measures, "vehicles": 5}


def test_a_run_that_keeps_up_sustains_its_rate_and_carries_its_figures() -> None:
    run = judge_run(record(), CRITERIA)
    assert run == Judgement(True, "", 60, 59, 59.0, 60.0, 150.0, 300.0, 0.5, False)
    assert Judgement.from_dict(run.to_dict()) == run


def test_a_failed_run_sustains_nothing_but_the_entrys_own_expectations_do_not_count() -> None:
    collision = {"kind": "collision", "time": 12.0, "message": "possible collision on segment 3"}
    expectation = {"kind": "expectation", "time": 3900.0, "message": "orders_per_hour 59 < 80"}
    assert judge_run(record((expectation,)), CRITERIA).sustained
    failed = judge_run(record((expectation, collision)), CRITERIA)
    assert not failed.sustained
    assert failed.reason == "the run failed: collision: possible collision on segment 3"


def test_a_run_that_never_ran_names_why() -> None:
    row = {
        "status": "failed",
        "failures": [],
        "measures": None,
        "error": "the planner cannot be loaded on this worker: x",
    }
    assert judge_run(row, CRITERIA).reason == "the run did not run: the planner cannot be loaded on this worker: x"


@pytest.mark.parametrize(
    ("measures", "reason"),
    [
        ({"stalls": 2}, "2 vehicle(s) stalled"),
        ({"overloaded": True, "backlog_slope": 12.34}, "overloaded: the backlog grew (+12.3 orders/h)"),
        ({"completed": 53}, "throughput fell behind: 53 of 60 orders completed (7 short, 6 allowed)"),
    ],
)
def test_a_run_that_stalls_overloads_or_falls_behind_does_not_sustain_its_rate(
    measures: dict[str, Any], reason: str
) -> None:
    run = judge_run(record(**measures), CRITERIA)
    assert (run.sustained, run.reason) == (False, reason)


def test_falling_behind_by_the_tolerance_or_by_one_order_per_vehicle_is_still_keeping_up() -> None:
    assert judge_run(record(completed=54), CRITERIA).sustained  # 6 short of 60: 10 %
    assert judge_run(record(released=20, completed=15, window=[0.0, 1200.0]), CRITERIA).sustained  # 5 vehicles
    assert not judge_run(record(released=20, completed=14, window=[0.0, 1200.0]), CRITERIA).sustained


def test_a_result_document_without_the_fleet_size_shows_it_in_its_measures() -> None:
    run = {**record(released=20, completed=14, window=[0.0, 1200.0]), "vehicles": None}
    run["measures"] |= {"orders_per_hour": 42.0, "orders_per_vehicle_hour": 7.0}  # 6 vehicles
    assert judge_run(run, CRITERIA).sustained


def test_the_service_time_bound_applies_only_when_given_and_a_run_without_service_times_misses_it() -> None:
    bounded = Criteria(tolerance=0.1, max_service_p95=250.0)
    assert judge_run(record(), CRITERIA).sustained
    assert judge_run(record(), bounded).reason == "service time p95 300 s above 250 s"
    assert judge_run(record(service_time=None), bounded).reason == "service time p95 none above 250 s"


def test_a_run_without_measures_of_orders_does_not_sustain_a_rate() -> None:
    assert judge_run({"status": "passed", "failures": [], "measures": None}, CRITERIA).reason == (
        "the run has no measures of orders"
    )


# -- the gate -------------------------------------------------------------------------------------


def test_a_gate_reads_capacity_against_the_baseline() -> None:
    condition = parse_gate(" capacity <  baseline - 5% ")
    assert (condition.metric, condition.operator, condition.offset, condition.relative) == ("capacity", "<", -5.0, True)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("throughput < baseline", "unknown metric 'throughput'; known: capacity"),
        ("capacity < 5%", "must read METRIC OP baseline .*'capacity < baseline - 2%'"),
        ("capacity ~ baseline", "must read METRIC OP baseline"),
    ],
)
def test_a_gate_that_does_not_parse_says_so_with_its_text(text: str, message: str) -> None:
    with pytest.raises(GateError, match=message):
        parse_gate(text)


@pytest.mark.parametrize(
    ("text", "sustained", "unsustained", "holds"),
    [
        ("capacity < baseline - 5%", 130.0, 140.0, True),  # failed 140 <= 142.5: below the bound for sure
        ("capacity < baseline - 5%", 140.0, 145.0, False),  # the capacity may be 144: not below for sure
        ("capacity < baseline - 5%", 140.0, None, False),  # sustained up to the maximum rate
        ("capacity < baseline - 5%", None, 10.0, True),  # nothing sustained
        ("capacity < baseline - 10", 130.0, 140.0, True),
        ("capacity <= baseline - 10", 130.0, 141.0, False),
        ("capacity > baseline + 10%", 170.0, 180.0, True),
        ("capacity > baseline + 10%", 165.0, 180.0, False),
        ("capacity >= baseline + 10%", 165.0, 180.0, True),
    ],
)
def test_a_gate_holds_only_when_the_whole_bracket_is_on_its_side(
    text: str, sustained: float | None, unsustained: float | None, holds: bool
) -> None:
    (verdict,) = judge_capacity((parse_gate(text),), Baseline(150.0, "--baseline"), sustained, unsustained)
    assert verdict.holds is holds
    assert verdict.line().startswith("FAIL" if holds else "ok")


def test_a_verdict_line_shows_the_capacity_the_bound_and_the_baseline() -> None:
    (verdict,) = judge_capacity(
        (parse_gate("capacity < baseline - 5%"),), Baseline(150.0, "main.json: s::x"), 130.0, 140.0
    )
    assert verdict.line() == (
        "FAIL  capacity < baseline - 5%: capacity 130 orders/h (lowest rate not sustained: 140), "
        "bound 142.5 orders/h (baseline 150, main.json: s::x)"
    )


def test_a_baseline_is_a_number_or_a_capacity_results_file(tmp_path: Path) -> None:
    assert parse_baseline("120.5") == Baseline(120.5, "--baseline")
    path = tmp_path / "capacity.json"
    write_capacity(path, {"format": CAPACITY_FORMAT, "capacity": 97.5, "scenario": "s.fleetsim.yaml::shift"})
    assert parse_baseline(str(path)) == Baseline(97.5, f"{path}: s.fleetsim.yaml::shift")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "no such capacity results file"),
        ("{", "invalid JSON"),
        ('{"format": "fleetsim-sweep-results/2"}', "format='fleetsim-sweep-results/2': not a capacity results file"),
        (f'{{"format": "{CAPACITY_FORMAT}", "capacity": "many"}}', "capacity='many' must be a number"),
    ],
)
def test_a_baseline_file_that_is_not_a_capacity_results_file_is_refused_with_its_name(
    tmp_path: Path, content: str | None, message: str
) -> None:
    path = tmp_path / "base.json"
    if content is not None:
        path.write_text(content, encoding="utf-8")
    with pytest.raises(CapacityResultsError, match=message) as caught:
        read_capacity(path)
    assert str(path) in str(caught.value)


def test_a_negative_baseline_is_refused() -> None:
    with pytest.raises(GateError, match="--baseline='-1' must be a capacity results file or a number"):
        parse_baseline("-1")


# -- the report -----------------------------------------------------------------------------------


def document() -> dict[str, Any]:
    def run(seed: int, sustained: bool, throughput: float) -> dict[str, Any]:
        reason = "" if sustained else "overloaded: the backlog grew (+9.0 orders/h)"
        figures = Judgement(sustained, reason, 10, 9, throughput, 60.0, 100.0, 200.0, 1.0, not sustained)
        return {"seed": seed, **figures.to_dict()}

    return {
        "format": CAPACITY_FORMAT, "scenario": "site.fleetsim.yaml::shift <a>", "planner": "p:P", "dispatcher": None,
        "seeds": [1, 2], "criteria": Criteria(0.1, None).to_dict(), "sustained": 60.0, "unsustained": 90.0,
        "capacity": 60.0, "runs": 4, "why": "resolution reached: the bracket is within 50%",
        "seed_brackets": [{"seed": 1, "sustained": 60.0, "unsustained": 90.0}, {"seed": 2, "sustained": 90.0, "unsustained": None}],
        "rates": [
            {"rate": 60.0, "step": 1, "sustained": True, "runs": [run(1, True, 58.0), run(2, True, 61.0)]},
            {"rate": 90.0, "step": 2, "sustained": False, "runs": [run(1, False, 70.0), run(2, True, 88.0)]},
        ],
    }  # fmt: skip


def test_the_summary_gives_the_capacity_its_bracket_the_spread_and_why_it_stopped() -> None:
    verdicts = judge_capacity((parse_gate("capacity < baseline - 5%"),), Baseline(100.0, "--baseline"), 60.0, 90.0)
    text = markdown(document(), verdicts)
    assert "**capacity 60 orders/h: sustained by every seed (1, 2) at 60, not at 90 orders/h**." in text
    assert "Stopped: resolution reached: the bracket is within 50%." in text
    assert "Per seed: seed 1 up to 60 (not 90); seed 2 up to 90." in text
    assert "| 90 | no | 1/2 | 79 | 60 | 100 | 200 | 1 | seed 1: overloaded: the backlog grew (+9.0 orders/h) |" in text
    assert "## Gate\n\n- FAIL  capacity < baseline - 5%" in text


class _Tags(HTMLParser):
    """Checks that every element the page opens is closed, in order (void elements aside)."""

    VOID = frozenset({"meta", "br", "hr", "img", "link", "input"})

    def __init__(self) -> None:
        super().__init__()
        self.open: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag not in self.VOID:
            self.open.append(tag)

    def handle_startendtag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        """A self-closing element (``<path ... />``) opens nothing that must be closed: not counted."""

    def handle_endtag(self, tag: str) -> None:
        assert self.open and self.open[-1] == tag, (tag, self.open[-3:])
        self.open.pop()


def check_page(page: str) -> list[ET.Element]:
    """The page is well formed, fetches nothing, and holds its two plots as well-formed SVG: those."""
    tags = _Tags()
    tags.feed(page)
    assert tags.open == []
    assert "default-src 'none'" in page
    assert "src=" not in page and "http" not in page.replace("http://www.w3.org/2000/svg", "").replace("http-equiv", "")
    start = 0
    plots = []
    while (start := page.find("<svg", start)) >= 0:
        end = page.index("</svg>", start) + len("</svg>")
        plots.append(ET.fromstring(page[start:end]))
        start = end
    assert [p.get("data-plot") for p in plots] == ["capacity-throughput", "capacity-service-time"]
    return plots


def test_the_page_is_well_formed_self_contained_and_holds_both_curves() -> None:
    page = html_page(document())
    plots = check_page(page)
    assert "site.fleetsim.yaml::shift &lt;a&gt;" in page
    circles = plots[0].findall(".//{http://www.w3.org/2000/svg}circle")
    assert len(circles) == 8  # throughput and arrivals of 2 seeds at 2 rates
