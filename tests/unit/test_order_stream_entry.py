"""A suite entry's order keys (issue 45): ``order_stream``, ``shift``, ``stations``, ``dispatcher`` and
``orders``, merged over ``defaults``, every mistake located at its YAML path and line."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from fleetsim.enums import Direction, Progress, Shape
from fleetsim.errors import LoadErrors, ScenarioFileError, SuiteError
from fleetsim.layout.segment import Segment
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.load.tiled.writer import write_map
from fleetsim.orders import Arrivals, Order, OrderStream, Shift, Station, Stop, StopDraw
from fleetsim.scenario import Scenario

# A one-way row 1 → 2 → 3 → 4; the map marks 1 and 2 as pick stations, 4 as a drop station.
ROW = tuple(Segment(n, Shape.STRAIGHT, Direction.FORWARD, ((4.0 * (n - 1), 0.0), (4.0 * n, 0.0))) for n in range(1, 5))
MAP_STATIONS = {"pick": [Station(1), Station(2, 2.0)], "drop": [Station(4)]}
HEAD = """\
fleetsim: 1
name: orders
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
  tugger: {length: 2.0, width: 1.0, height: 1.0, max_speed: 1.0, acceleration: 0.5, turn_capability: curve}
"""


def write_suite(tmp_path: Path, entries: str, defaults: str = "", vehicles: str = "1,1,forward,forward,agv\n") -> Path:
    site = tmp_path / "site"
    site.mkdir(exist_ok=True)
    write_map(site / "map.json", ROW, stations=MAP_STATIONS)
    (site / "vehicles.csv").write_text(
        "vehicle_id,start_segment_id,segment_orientation,progress_direction,type\n" + vehicles, encoding="utf-8"
    )
    (site / "tasks.csv").write_text("vehicle_id,goal_segment_id\n", encoding="utf-8")
    text = HEAD
    if defaults:
        text += "defaults:\n" + textwrap.indent(textwrap.dedent(defaults), "  ")
    text += "scenarios:\n" + textwrap.indent(textwrap.dedent(entries), "  ")
    path = tmp_path / "orders.fleetsim.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def entry(body: str, name: str = "a") -> str:
    """One scenario entry on the site, with ``body`` (YAML lines) added."""
    return f"- name: {name}\n  dir: site/\n" + textwrap.indent(textwrap.dedent(body), "  ")


def loaded(tmp_path: Path, entries: str, defaults: str = "", **kwargs: str) -> list[Scenario]:
    suite = load_suite(write_suite(tmp_path, entries, defaults, **kwargs))
    return [load_scenario(spec, suite) for spec in suite.scenarios]


def suite_error(tmp_path: Path, entries: str, defaults: str = "") -> SuiteError:
    """The one error of the suite, or of loading its first scenario."""
    with pytest.raises(SuiteError) as info:
        loaded(tmp_path, entries, defaults)
    assert not isinstance(info.value, LoadErrors), str(info.value)
    return info.value


# -- what the keys give -----------------------------------------------------------------------------


def test_the_order_keys_become_the_scenarios_stream_shift_stations_and_dispatcher(tmp_path: Path) -> None:
    (scenario,) = loaded(
        tmp_path,
        entry("""\
            order_stream:
              seed: 7
              arrivals: {poisson: 120, start: 1min, until: 8h}
              stops:
                - {from: pick, dwell: 20}
                - {from: [drop, buffer], dwell: [10, 30s], weighted: true, count: [1, 2], progress: reverse}
              deadline: 15min
              vehicle_types: [AGV]
              priority: 2
              limit: 1000
            stations: {buffer: [3, {segment: 2, weight: 0.5}]}
            shift: {duration: 8h, warmup: 15min, dispatch_period: 10, stall_after: "1h30min", on_stall: end}
            dispatcher: mypkg.dispatch:Nearest
            """),
    )
    assert scenario.order_stream == OrderStream(
        seed=7,
        arrivals=Arrivals("poisson", rate=120.0, start=60.0, until=28800.0),
        stops=(
            StopDraw(("pick",), False, (20.0, 20.0), (1, 1), None),
            StopDraw(("drop", "buffer"), True, (10.0, 30.0), (1, 2), Progress.REVERSE),
        ),
        deadline=900.0,
        vehicle_types=("agv",),
        priority=2,
        limit=1000,
    )
    assert scenario.shift == Shift(28800.0, 900.0, 10.0, 5400.0, "end")
    assert scenario.dispatcher == "mypkg.dispatch:Nearest"
    assert dict(scenario.stations) == {
        "buffer": (Station(2, 0.5), Station(3)),
        "drop": (Station(4),),
        "pick": (Station(1), Station(2, 2.0)),
    }
    assert list(scenario.stations) == ["buffer", "drop", "pick"]


def test_an_entry_without_order_keys_has_none_but_the_maps_stations(tmp_path: Path) -> None:
    (scenario,) = loaded(tmp_path, entry(""))
    assert scenario.order_stream is None and scenario.shift is None and scenario.dispatcher is None
    assert scenario.orders == () and dict(scenario.stations) == {
        "drop": (Station(4),),
        "pick": (Station(1), Station(2, 2.0)),
    }


@pytest.mark.parametrize(
    ("written", "seconds"),
    [("90", 90.0), ("1.5", 1.5), ("90s", 90.0), ("15min", 900.0), ("8h", 28800.0), ("1h30min", 5400.0),
     ("'2h 15min 30s'", 8130.0), ("0.5h", 1800.0)],
)  # fmt: skip
def test_durations_are_seconds_or_numbers_with_units(tmp_path: Path, written: str, seconds: float) -> None:
    (scenario,) = loaded(tmp_path, entry(f"shift: {{duration: {written}}}\n"))
    assert scenario.shift is not None and scenario.shift.duration == seconds


def test_a_suites_set_replaces_the_maps_set_of_its_name(tmp_path: Path) -> None:
    (scenario,) = loaded(tmp_path, entry("stations: {pick: [3]}\n"))
    assert dict(scenario.stations) == {"drop": (Station(4),), "pick": (Station(3),)}


def test_an_entry_replaces_the_defaults_key_by_key_and_set_by_set(tmp_path: Path) -> None:
    defaults = """\
        order_stream: {seed: 3, arrivals: {interval: 30}, stops: [{from: pick}], priority: 1}
        shift: {duration: 2h, warmup: 10min}
        stations: {buffer: [3], dock: [4]}
        dispatcher: base:Dispatcher
        """
    entries = entry("") + entry(
        """\
        order_stream: {arrivals: {pool: 4}}
        shift: {warmup: 0}
        stations: {dock: [1]}
        dispatcher: own:Dispatcher
        """,
        name="b",
    )
    first, second = loaded(tmp_path, entries, defaults)
    assert first.order_stream == OrderStream(3, Arrivals("interval", interval=30.0), (StopDraw(("pick",)),), priority=1)
    assert second.order_stream == OrderStream(3, Arrivals("pool", open=4), (StopDraw(("pick",)),), priority=1)
    assert (first.shift, second.shift) == (Shift(7200.0, 600.0), Shift(7200.0, 0.0))
    assert (first.dispatcher, second.dispatcher) == ("base:Dispatcher", "own:Dispatcher")
    assert [s.segment for s in first.stations["dock"]] == [4] and [s.segment for s in second.stations["dock"]] == [1]
    assert [s.segment for s in second.stations["buffer"]] == [3]


# -- orders.csv ---------------------------------------------------------------------------------------


def test_orders_are_read_from_the_entrys_path_or_else_its_dirs_orders_csv(tmp_path: Path) -> None:
    path = write_suite(tmp_path, entry("") + entry("orders: elsewhere/rush.csv\n", name="b"))
    header = "order_id,stops\n"
    (tmp_path / "site" / "orders.csv").write_text(header + "o1,2>4\n", encoding="utf-8")
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "elsewhere" / "rush.csv").write_text(header + "r1,3\n", encoding="utf-8")
    suite = load_suite(path)
    first, second = (load_scenario(spec, suite) for spec in suite.scenarios)
    assert first.orders == (Order("o1", (Stop(2), Stop(4))),) and first.orders_path == tmp_path / "site" / "orders.csv"
    assert second.orders == (Order("r1", (Stop(3),)),)


def test_orders_csv_is_checked_against_the_suites_vehicle_types(tmp_path: Path) -> None:
    path = write_suite(tmp_path, entry(""))
    (tmp_path / "site" / "orders.csv").write_text("order_id,stops,vehicle_types\no1,2,tugger agvv\n", encoding="utf-8")
    suite = load_suite(path)
    with pytest.raises(ScenarioFileError, match=r"vehicle type 'agvv' is not defined; did you mean 'agv'\?"):
        load_scenario(suite.scenarios[0], suite)


def test_an_orders_file_that_does_not_exist_is_an_error(tmp_path: Path) -> None:
    found = suite_error(tmp_path, entry("orders: nope.csv\n"))
    assert found.problem == f"scenarios[0].orders: no such file: {str(tmp_path / 'nope.csv')!r}"
    assert found.location is not None and found.location.line == 9


def test_a_generated_scenario_cannot_also_name_an_orders_file(tmp_path: Path) -> None:
    found = suite_error(tmp_path, "- name: g\n  generate: {}\n  orders: o.csv\n")
    assert found.problem == "scenarios[0]: 'generate' makes the scenario, so it cannot also name files ('orders')"


# -- mistakes, each with the value next to it that passes -------------------------------------------

STREAM = "order_stream: {{arrivals: {arrivals}, stops: [{stop}]{more}}}\n"


def stream(arrivals: str = "{poisson: 60}", stop: str = "{from: pick}", more: str = "") -> str:
    return entry(STREAM.format(arrivals=arrivals, stop=stop, more=more))


@pytest.mark.parametrize(
    ("entries", "message", "line"),
    [
        (stream("{poisson: 0}"), "scenarios[0].order_stream.arrivals.poisson: 0 must be > 0", 9),
        (stream("{poisson: -5}"), "scenarios[0].order_stream.arrivals.poisson: -5 must be > 0", 9),
        (stream("{interval: 0}"), "scenarios[0].order_stream.arrivals.interval: 0 must be more than 0 seconds", 9),
        (stream("{interval: 0s}"), "scenarios[0].order_stream.arrivals.interval: '0s' must be more than 0 seconds", 9),
        (stream("{interval: -3}"), "scenarios[0].order_stream.arrivals.interval: -3 must be >= 0", 9),
        (stream("{pool: 0}"), "scenarios[0].order_stream.arrivals.pool: 0 must be >= 1", 9),
        (stream("{pool: 2, poisson: 5}"), "scenarios[0].order_stream.arrivals: give exactly one of 'poisson' "
         "(orders per hour), 'interval' (time between releases) or 'pool' (orders open at once); it has 'poisson' and 'pool'", 9),
        (stream("{start: 10}"), "scenarios[0].order_stream.arrivals: give exactly one of 'poisson' (orders per hour), "
         "'interval' (time between releases) or 'pool' (orders open at once); it has none", 9),
        (stream("{poisson: 5, start: 1h, until: 60min}"),
         "scenarios[0].order_stream.arrivals.until: '60min' (3600 s) must be after start (3600 s)", 9),
        (stream(stop="{from: pick, dwell: [30, 10]}"),
         "scenarios[0].order_stream.stops[0].dwell: [30, 10] must be [min, max] with min <= max", 9),
        (stream(stop="{from: pick, count: [3, 1]}"),
         "scenarios[0].order_stream.stops[0].count: [3, 1] must be [min, max] with min <= max", 9),
        (stream(stop="{from: pick, count: 0}"), "scenarios[0].order_stream.stops[0].count: 0 is not a whole number "
         ">= 1 or [min, max] whole numbers >= 1", 9),
        (stream(stop="{from: pick, dwell: 2 hours}"), "scenarios[0].order_stream.stops[0].dwell: '2 hours' is not a "
         "duration: seconds, or a number with a unit ('90s', '15min', '8h', '1h30min'), or a [min, max] pair of them", 9),
        (stream(more=", vehicle_types: [agx]"), "scenarios[0].order_stream.vehicle_types[0]: 'agx' is not a vehicle "
         "type of this suite (agv, tugger); did you mean 'agv'?", 9),
        (stream(more=", deadline: 0s"), "scenarios[0].order_stream.deadline: '0s' must be more than 0 seconds", 9),
        (entry("order_stream: {arrivals: {pool: 3}}\n"),
         "scenarios[0].order_stream: an order stream needs 'stops' (when orders are released, where their stops are)", 9),
        (entry("shift: {duration: 8 hours}\n"), "scenarios[0].shift.duration: '8 hours' is not a duration: seconds, "
         "or a number with a unit ('90s', '15min', '8h', '1h30min')", 9),
        (entry("shift: {duration: 1h, warmup: 60min}\n"),
         "scenarios[0].shift.warmup: '60min' (3600 s) must be shorter than the shift's duration (3600 s)", 9),
        (entry("shift: {warmup: 10min}\n"), "scenarios[0].shift: a shift needs a duration (e.g. duration: 8h)", 9),
        (entry("shift: {duration: 0}\n"), "scenarios[0].shift.duration: 0 must be more than 0 seconds", 9),
        (entry("shift: {duration: 1h, stall_after: 0s}\n"),
         "scenarios[0].shift.stall_after: '0s' must be more than 0 seconds", 9),
        (entry("shift: {duration: 1h, on_stall: stop}\n"),
         "scenarios[0].shift.on_stall: 'stop' is not one of 'count' or 'end'", 9),
        (entry("stations: {pick: []}\n"), "scenarios[0].stations.pick: must not be empty", 9),
        (entry("stations: {pick: [1, {segment: 1}]}\n"),
         "scenarios[0].stations.pick[1]: segment 1 is listed twice in station set 'pick' (first as item 0)", 9),
        (entry("stations: {pick: [{segment: 1, weight: 0}]}\n"),
         "scenarios[0].stations.pick[0].weight: 0 must be > 0", 9),
        (entry("dispatcher: my_dispatcher.py\n"), "scenarios[0].dispatcher: 'my_dispatcher.py' is not a dispatcher "
         "spec module:attr (e.g. mypkg.dispatch:Nearest)", 9),
    ],
)  # fmt: skip
def test_a_mistake_in_an_order_key_is_an_error_at_its_line(
    tmp_path: Path, entries: str, message: str, line: int
) -> None:
    found = suite_error(tmp_path, entries)
    assert found.problem == message
    assert found.location is not None and found.location.line == line


@pytest.mark.parametrize(
    "entries",
    [
        stream("{poisson: 0.01}"),
        stream("{interval: 0.1s}"),
        stream("{pool: 1}"),
        stream("{poisson: 5, start: 1h, until: 61min}"),
        stream(stop="{from: pick, dwell: [10, 10], count: [2, 2]}"),
        stream(more=", vehicle_types: [Tugger, agv]"),
        entry("shift: {duration: 1h, warmup: 59min 59s}\n"),
        entry("stations: {pick: [{segment: 1, weight: 0.01}]}\n"),
        entry("dispatcher: my_dispatcher:Mine\n"),
    ],
)
def test_the_value_next_to_each_mistake_is_accepted(tmp_path: Path, entries: str) -> None:
    assert loaded(tmp_path, entries)


def test_every_mistake_of_the_order_keys_is_reported_at_once(tmp_path: Path) -> None:
    entries = entry(
        """\
        order_stream: {arrivals: {pool: 2, interval: 3}, stops: [{from: pick, dwell: [2, 1]}], vehicle_types: [x]}
        shift: {duration: 1h, warmup: 2h}
        stations: {a: [1, 1]}
        dispatcher: nope
        """
    )
    with pytest.raises(LoadErrors) as info:
        loaded(tmp_path, entries)
    assert [error.problem.split(":")[0] for error in info.value.errors] == [
        "scenarios[0].order_stream.arrivals",
        "scenarios[0].order_stream.stops[0].dwell",
        "scenarios[0].order_stream.vehicle_types[0]",
        "scenarios[0].shift.warmup",
        "scenarios[0].stations.a[1]",
        "scenarios[0].dispatcher",
    ]


def test_a_broken_default_inherited_by_several_entries_is_reported_once(tmp_path: Path) -> None:
    with pytest.raises(SuiteError) as info:
        loaded(tmp_path, entry("") + entry("", name="b"), defaults="shift: {warmup: 5min}\n")
    assert not isinstance(info.value, LoadErrors)
    assert info.value.problem == "defaults.shift: a shift needs a duration (e.g. duration: 8h)"


# -- checked against the map ------------------------------------------------------------------------


def test_a_stream_drawing_from_a_set_nobody_defines_is_an_error_at_its_from(tmp_path: Path) -> None:
    found = suite_error(tmp_path, stream(stop="{from: [drop, pik]}"))
    assert found.problem == (
        "scenarios[0].order_stream.stops[0].from: station set 'pik' is defined neither by the map nor by the "
        "suite's 'stations' (sets: drop, pick); did you mean 'pick'?"
    )
    assert found.location is not None and found.location.line == 9


def test_a_suites_station_set_on_a_segment_the_map_lacks_is_an_error_at_its_item(tmp_path: Path) -> None:
    found = suite_error(tmp_path, entry("stations:\n  dock:\n    - 4\n    - {segment: 7}\n"))
    assert (
        found.problem
        == "scenarios[0].stations.dock[1]: station set 'dock': segment 7, which is not in the map (segments 1–4)"
    )
    assert found.location is not None and found.location.line == 12


def test_a_station_no_vehicle_the_stream_allows_can_reach_is_a_warning(tmp_path: Path) -> None:
    # The vehicle starts on segment 3 of the one-way row: pick stations 1 and 2 lie behind it.
    vehicles = "1,3,forward,forward,agv\n"
    (scenario,) = loaded(tmp_path, stream(stop="{from: [pick, drop]}"), vehicles=vehicles)
    assert scenario.warnings == tuple(
        f"{tmp_path / 'orders.fleetsim.yaml'}:9:60: warning unreachable-station: station set 'pick': segment "
        f"{segment} cannot be reached by vehicle 1 from its start; no vehicle the stream allows can serve a stop there"
        for segment in (1, 2)
    )
    # With a second vehicle behind them, the stations wait for that one.
    vehicles += "2,1,forward,forward,agv\n"
    (scenario,) = loaded(tmp_path, stream(stop="{from: [pick, drop]}"), vehicles=vehicles)
    assert [w.split("warning ")[1] for w in scenario.warnings] == [
        f"unreachable-station: station set 'pick': segment {segment} cannot be reached by vehicle 1 from its "
        "start; a stop drawn there waits for another vehicle"
        for segment in (1, 2)
    ]
    # Stations every vehicle reaches (drop, on segment 4) give no warning.
    (scenario,) = loaded(tmp_path, stream(stop="{from: drop}"), vehicles=vehicles)
    assert scenario.warnings == ()


def test_vehicles_the_stream_does_not_allow_are_not_asked(tmp_path: Path) -> None:
    vehicles = "1,3,forward,forward,agv\n2,1,forward,forward,tugger\n"
    (scenario,) = loaded(tmp_path, stream(more=", vehicle_types: [tugger]"), vehicles=vehicles)
    assert scenario.warnings == ()
