"""The capacity search with a fake evaluator: bracketing, bisection, stop reasons, the seed rule, determinism."""

from __future__ import annotations

from collections.abc import Mapping

import pytest

from fleetsim.capacity.criteria import Judgement
from fleetsim.capacity.search import (
    Resolution,
    SearchError,
    SearchResult,
    SearchSettings,
    rate_value,
    search,
)


class Fleet:
    """A fake fleet: seed S sustains every rate up to capacities[S]; it records the rates asked for."""

    def __init__(self, capacities: Mapping[int, float]) -> None:
        self.capacities = capacities
        self.asked: list[float] = []

    def __call__(self, rate: float) -> dict[int, Judgement]:
        self.asked.append(rate)
        return {
            seed: Judgement(rate <= cap, "" if rate <= cap else "overloaded") for seed, cap in self.capacities.items()
        }


def settings(start: float = 30.0, seeds: tuple[int, ...] = (1, 2, 3), **changes: object) -> SearchSettings:
    values: dict[str, object] = {
        "resolution": Resolution(2, relative=True), "min_rate": 1.0, "max_rate": 10_000.0, "max_runs": 300,
    }  # fmt: skip
    values.update(changes)
    return SearchSettings(start, seeds, **values)  # type: ignore[arg-type]


def test_a_sustained_start_is_doubled_until_a_rate_is_not_sustained_then_bisected_to_the_resolution() -> None:
    fleet = Fleet({1: 100.0, 2: 100.0, 3: 100.0})
    result = search(settings(), fleet)
    assert fleet.asked[:3] == [30.0, 60.0, 120.0]
    assert result.stop == "resolution"
    assert result.sustained is not None and result.unsustained is not None
    assert result.sustained <= 100.0 < result.unsustained
    assert result.unsustained - result.sustained <= 0.02 * result.sustained
    assert result.capacity == result.sustained
    assert result.runs == 3 * len(fleet.asked)


def test_an_unsustained_start_is_halved_until_a_rate_is_sustained() -> None:
    fleet = Fleet({1: 70.0})
    result = search(settings(start=400.0, seeds=(1,)), fleet)
    assert fleet.asked[:4] == [400.0, 200.0, 100.0, 50.0]
    assert result.sustained is not None and 68.6 <= result.sustained <= 70.0
    assert result.stop == "resolution"


def test_an_absolute_resolution_stops_when_the_bracket_is_that_many_orders_per_hour() -> None:
    result = search(settings(seeds=(1,), resolution=Resolution(5, relative=False)), Fleet({1: 100.0}))
    assert result.sustained is not None and result.unsustained is not None
    assert result.unsustained - result.sustained <= 5
    assert result.unsustained - result.sustained > 2.5  # one halving fewer would have been too wide


def test_every_rate_below_the_bracket_was_sustained_and_every_rate_above_it_was_not() -> None:
    result = search(settings(), Fleet({1: 100.0, 2: 83.0, 3: 140.0}))
    assert result.sustained is not None and result.unsustained is not None
    for outcome in result.tried:
        assert outcome.sustained == (outcome.rate <= result.sustained)
        assert outcome.sustained != (outcome.rate >= result.unsustained)


def test_a_rate_is_sustained_only_when_every_seed_sustains_it_and_each_seed_has_its_own_bracket() -> None:
    result = search(settings(), Fleet({1: 100.0, 2: 83.0, 3: 140.0}))
    assert result.sustained is not None and result.sustained <= 83.0
    brackets = {b.seed: b for b in result.seed_brackets()}
    assert brackets[2].sustained == result.sustained
    assert brackets[3].sustained is not None and brackets[3].sustained > brackets[1].sustained > 83.0  # type: ignore[operator]
    for bracket in brackets.values():
        assert bracket.unsustained is None or bracket.sustained is None or bracket.sustained < bracket.unsustained


def test_a_fleet_that_sustains_every_rate_stops_at_the_maximum_rate() -> None:
    fleet = Fleet({1: 1e9})
    result = search(settings(seeds=(1,), max_rate=200.0), fleet)
    assert fleet.asked == [30.0, 60.0, 120.0, 200.0]
    assert (result.stop, result.sustained, result.unsustained) == ("max-rate", 200.0, None)
    assert "at least" in result.why()


def test_a_fleet_that_sustains_nothing_stops_at_the_minimum_rate_with_capacity_zero() -> None:
    fleet = Fleet({1: 0.0})
    result = search(settings(seeds=(1,), min_rate=5.0), fleet)
    assert fleet.asked == [30.0, 15.0, 7.5, 5.0]
    assert (result.stop, result.sustained, result.unsustained, result.capacity) == ("nothing-sustained", None, 5.0, 0.0)


def test_the_search_stops_before_a_rate_whose_runs_would_exceed_max_runs() -> None:
    fleet = Fleet({1: 100.0, 2: 100.0, 3: 100.0})
    result = search(settings(max_runs=8), fleet)
    assert fleet.asked == [30.0, 60.0]  # a third rate would take runs 7 to 9
    assert (result.stop, result.sustained, result.unsustained, result.runs) == ("max-runs", 60.0, None, 6)
    assert "--max-runs 8" in result.why()


def test_max_runs_also_stops_the_bisection() -> None:
    result = search(settings(seeds=(1,), max_runs=5), Fleet({1: 100.0}))
    assert result.stop == "max-runs"
    assert [o.rate for o in result.tried] == [30.0, 60.0, 120.0, 90.0, 105.0]
    assert (result.sustained, result.unsustained) == (90.0, 105.0)


def test_the_same_answers_give_the_same_search_whatever_order_the_seeds_answer_in() -> None:
    forward = Fleet({1: 100.0, 2: 83.0, 3: 140.0})
    backward = Fleet({3: 140.0, 2: 83.0, 1: 100.0})
    first, second = search(settings(), forward), search(settings(), backward)
    assert forward.asked == backward.asked
    assert _summary(first) == _summary(second)


def _summary(result: SearchResult) -> object:
    return (
        [(o.rate, sorted((s, j.sustained) for s, j in o.runs.items())) for o in result.tried],
        result.sustained, result.unsustained, result.stop, result.seed_brackets(),
    )  # fmt: skip


def test_rates_are_tried_rounded_to_hundredths_and_a_bracket_that_cannot_be_split_ends_the_search() -> None:
    result = search(
        settings(start=0.03, seeds=(1,), min_rate=0.01, resolution=Resolution(0.1, relative=True)), Fleet({1: 0.05})
    )
    assert all(round(o.rate, 2) == o.rate for o in result.tried)
    assert (result.sustained, result.unsustained, result.stop) == (0.05, 0.06, "resolution")


def test_an_evaluator_that_leaves_a_seed_out_is_a_programming_error() -> None:
    with pytest.raises(ValueError, match="seeds \\[3\\]"):
        search(settings(), lambda rate: {1: Judgement(True), 2: Judgement(True)})


@pytest.mark.parametrize(("text", "amount", "relative"), [("2%", 2.0, True), (" 5 ", 5.0, False), ("0.5%", 0.5, True)])
def test_a_resolution_is_a_percentage_or_orders_per_hour(text: str, amount: float, relative: bool) -> None:
    assert Resolution.parse(text) == Resolution(amount, relative)


@pytest.mark.parametrize("text", ["", "abc", "0", "0%", "100%", "-2%", "2 %%"])
def test_a_resolution_that_is_not_one_is_refused_with_its_value(text: str) -> None:
    with pytest.raises(SearchError, match=f"--resolution={text!r}"):
        Resolution.parse(text)


@pytest.mark.parametrize("text", ["x", "-3", "0", "inf", "nan"])
def test_a_rate_must_be_a_positive_number(text: str) -> None:
    with pytest.raises(SearchError, match=f"--max-rate={text!r} must be a positive number"):
        rate_value("--max-rate", text)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"seeds": ()}, "at least one order stream seed"),
        ({"seeds": (1, 1)}, "a seed is named twice"),
        ({"max_rate": 20.0}, "between --min-rate=1 and --max-rate=20 orders/h; it starts at the entry's rate, 30"),
        ({"min_rate": 40.0}, "between --min-rate=40"),
        ({"min_rate": 0.001}, "--min-rate=0.001 must be at least 0.01"),
        ({"max_runs": 2}, "--max-runs=2 must allow one rate: at least one run per seed \\(3\\)"),
    ],
)
def test_settings_a_search_cannot_start_from_are_refused(changes: dict[str, object], message: str) -> None:
    with pytest.raises(SearchError, match=message):
        settings(**changes)  # type: ignore[arg-type]
