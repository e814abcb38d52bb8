"""``orders.csv`` (issue 45): every column read, every mistake located at its row and column, the file
loaded with the scenario's other CSV files, and every order checked for a vehicle that can serve it."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from scenario_factory import make_scenario

from fleetsim.enums import Direction, Progress, Shape
from fleetsim.errors import LoadErrors, ScenarioError, ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.tables.orders import read_orders
from fleetsim.orders import Order, Station, Stop

HEADER = "order_id,release,deadline,stops,dwell,vehicle_types,priority\n"
# A one-way row of three segments: 1 → 2 → 3, and a two-way spur 4 off the end of 3.
ONE_WAY = (
    Segment(1, Shape.STRAIGHT, Direction.FORWARD, ((0.0, 0.0), (4.0, 0.0))),
    Segment(2, Shape.STRAIGHT, Direction.FORWARD, ((4.0, 0.0), (8.0, 0.0))),
    Segment(3, Shape.STRAIGHT, Direction.FORWARD, ((8.0, 0.0), (12.0, 0.0))),
    Segment(4, Shape.STRAIGHT, Direction.BOTH, ((12.0, 0.0), (12.0, 4.0))),
)
SEGMENTS = {segment.id: segment for segment in ONE_WAY}
TYPES = ("agv", "tugger")  # the vehicle types of scenario_factory


def orders_file(tmp_path: Path, rows: str, header: str = HEADER) -> Path:
    path = tmp_path / "orders.csv"
    path.write_text(header + rows, encoding="utf-8")
    return path


def read(tmp_path: Path, rows: str, header: str = HEADER) -> tuple[Order, ...]:
    return read_orders(orders_file(tmp_path, rows, header), SEGMENTS, TYPES)


def error(tmp_path: Path, rows: str, header: str = HEADER) -> ScenarioFileError:
    with pytest.raises(ScenarioFileError) as info:
        read(tmp_path, rows, header)
    assert not isinstance(info.value, LoadErrors), str(info.value)
    return info.value


# -- reading --------------------------------------------------------------------------------------


def test_every_column_is_read(tmp_path: Path) -> None:
    orders = read(
        tmp_path,
        "o1,0,900,1>3,20>10,,\n"
        "# a comment row keeps its line\n"
        "o2,00:05:00,01:00:00.5,1>3:reverse>4:FORWARD,15,AGV tugger,2\n"
        "o3,300.5,,2,,agv;Tugger;agv,-1\n",
    )
    assert orders == (
        Order("o1", (Stop(1, None, 20.0), Stop(3, None, 10.0)), 0.0, 900.0, None, 0),
        Order(
            "o2",
            (Stop(1, None, 15.0), Stop(3, Progress.REVERSE, 15.0), Stop(4, Progress.FORWARD, 15.0)),
            300.0,
            3600.5,
            ("agv", "tugger"),
            2,
        ),
        Order("o3", (Stop(2),), 300.5, None, ("agv", "tugger"), -1),
    )
    assert [order.line for order in orders] == [2, 4, 5]


def test_only_order_id_and_stops_are_required_in_any_column_order(tmp_path: Path) -> None:
    (order,) = read(tmp_path, "4> 1 ,o1\n", header="Stops,ORDER_ID\n")
    assert order == Order("o1", (Stop(4), Stop(1)))
    assert order.release == 0.0 and order.deadline is None and order.vehicle_types is None and order.priority == 0


def test_a_file_with_a_header_and_no_rows_has_no_orders(tmp_path: Path) -> None:
    assert read(tmp_path, "") == ()


# -- one mistake each, and the value that narrowly passes -------------------------------------------


@pytest.mark.parametrize(
    ("rows", "field", "message"),
    [
        ("o1,0,,1,,,\no1,0,,2,,,\n", "order_id", "order id 'o1' is already used on line 2"),
        (",0,,1,,,\n", "order_id", "missing: every order needs an id"),
        ("o1,0,,,,,\n", "stops", "missing: an order needs at least one stop"),
        ("o1,0,,1>x,,,\n", "stops", "stop 2 of '1>x' is 'x': a stop is a segment id, optionally with"),
        ("o1,0,,1>,,,\n", "stops", "stop 2 of '1>' is ''"),
        (
            "o1,0,,1:sideways,,,\n",
            "stops",
            "stop 1 of '1:sideways' arrives 'sideways'; it must be ':forward' or ':reverse'",
        ),
        ("o1,0,,1>99,,,\n", "stops", "stop 2 of '1>99' is on segment 99, which is not in the map (segments 1–4)"),
        (
            "o1,0,,1>2,1>2>3,,\n",
            "dwell",
            "'1>2>3' gives 3 dwell times for 2 stops; give one for every stop, or one per stop",
        ),
        ("o1,0,,1>2,5>-1,,\n", "dwell", "dwell '-1' is negative; a vehicle stands 0 seconds or more"),
        ("o1,0,,1,soon,,\n", "dwell", "dwell 'soon' of 'soon' is not a number of seconds"),
        ("o1,-3,,1,,,\n", "release", "release '-3' is negative; times count from the start of the run (0)"),
        ("o1,5:00,,1,,,\n", "release", "release '5:00' is not a time: give seconds (300) or hh:mm:ss (00:05:00)"),
        (
            "o1,00:05:00,,1,,,\no2,60,,1,,,\n",
            "release",
            "release '60' (60 s) is before the release '00:05:00' (300 s) of order 'o1' on line 2; rows must be in release order",
        ),
        ("o1,100,100,1,,,\n", "deadline", "deadline '100' (100 s) is not after the release (100 s)"),
        ("o1,100,00:01:00,1,,,\n", "deadline", "deadline '00:01:00' (60 s) is not after the release (100 s)"),
        (
            "o1,0,,1,,agx,\n",
            "vehicle_types",
            "vehicle type 'agx' is not defined; did you mean 'agv'? (known: agv, tugger)",
        ),
        ("o1,0,,1,,,high\n", "priority", "priority 'high' is not a whole number"),
        ("o1,0,,1,,,1.5\n", "priority", "priority '1.5' is not a whole number"),
    ],
)
def test_a_bad_cell_is_an_error_at_its_row_and_column(tmp_path: Path, rows: str, field: str, message: str) -> None:
    found = error(tmp_path, rows)
    assert found.location is not None and found.location.field == field
    assert found.location.line == rows.count("\n") + 1
    assert found.problem == message or found.problem.startswith(message), found.problem
    assert str(found).startswith(f"{tmp_path / 'orders.csv'}:{found.location.line}: field {field!r}: ")


@pytest.mark.parametrize(
    "rows",
    [
        "o1,0,,1,,,\nO1,0,,2,,,\n",  # ids are case-sensitive
        "o1,0,,1:REVERSE > 4,,,\n",  # words in any case, spaces around '>'
        "o1,0,,1>4,1>2,,\n",  # one dwell per stop
        "o1,0,,1>4,0,,\n",  # a dwell of 0
        "o1,60,,1,,,\no2,60,,2,,,\no3,00:01:00,,3,,,\n",  # equal releases keep the order
        "o1,100,100.5,1,,,\n",  # a deadline just after the release
        "o1,0,,1,,AGV,-2\n",  # a type in another case; a negative priority
    ],
)
def test_the_value_next_to_each_mistake_is_accepted(tmp_path: Path, rows: str) -> None:
    assert read(tmp_path, rows)


def test_a_misspelt_header_column_is_named_with_the_column_meant(tmp_path: Path) -> None:
    found = error(tmp_path, "o1,0\n", header="order_id,release,stop\n")
    assert found.problem == (
        "unknown column 'stop'; did you mean 'stops'? (the header is "
        "order_id,stops[,release][,deadline][,dwell][,vehicle_types][,priority])"
    )


def test_a_missing_required_column_is_an_error(tmp_path: Path) -> None:
    found = error(tmp_path, "o1,0\n", header="order_id,release\n")
    assert found.problem.startswith("missing required column 'stops'")


def test_every_mistake_of_a_file_is_reported_at_once_in_file_order(tmp_path: Path) -> None:
    with pytest.raises(LoadErrors) as info:
        read(tmp_path, "o1,10,5,1>99,,,\no1,0,,1,,agx,\no3,20,,1,,,x\n")
    assert [(e.location.line, e.location.field) for e in info.value.errors if e.location] == [
        (2, "stops"),
        (2, "deadline"),
        (3, "order_id"),
        (3, "release"),
        (3, "vehicle_types"),
        (4, "priority"),
    ]


# -- as part of a scenario --------------------------------------------------------------------------


def scenario_with_orders(tmp_path: Path, orders: str, vehicles: str = "1,1,forward,forward,agv\n") -> object:
    folder = tmp_path / "scenario"
    folder.mkdir(exist_ok=True)
    orders_file(folder, orders)
    return make_scenario(folder, ONE_WAY, vehicles)


def test_a_scenario_folder_reads_its_orders_csv(tmp_path: Path) -> None:
    scenario = scenario_with_orders(tmp_path, "o1,0,,2>4:reverse,30,,\n")
    assert scenario.orders == (Order("o1", (Stop(2, None, 30.0), Stop(4, Progress.REVERSE, 30.0))),)  # type: ignore[attr-defined]
    assert scenario.orders_path == tmp_path / "scenario" / "orders.csv"  # type: ignore[attr-defined]


def test_a_scenario_folder_without_orders_csv_has_no_orders(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path / "plain", ONE_WAY, "1,1,forward,forward,agv\n")
    assert scenario.orders == () and scenario.orders_path is None


def test_orders_csv_errors_come_with_the_other_csv_files_errors(tmp_path: Path) -> None:
    with pytest.raises(LoadErrors) as info:
        scenario_with_orders(tmp_path, "o1,0,,9,,,\n", vehicles="1,1,sideways,forward,agv\n")
    assert [(Path(e.location.path).name, e.location.field) for e in info.value.errors if e.location] == [
        ("vehicles.csv", "segment_orientation"),
        ("orders.csv", "stops"),
    ]


def test_an_order_whose_stop_no_vehicle_can_reach_is_an_error_at_its_row(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError) as info:
        scenario_with_orders(tmp_path, "o1,0,,2>3,,,\no2,0,,3>1,,,\n")
    assert info.value.location is not None
    assert (info.value.location.line, info.value.location.field) == (3, "stops")
    assert info.value.problem.startswith(
        "order 'o2': no vehicle it may go to (1) can reach segment 1, its stop 2, from its stop 1 (segment 3): "
    )


def test_an_order_no_vehicle_of_the_scenario_may_carry_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError) as info:
        scenario_with_orders(tmp_path, "o1,0,,2,,tugger,\n")
    assert info.value.problem == "order 'o1': no vehicle is of a type it allows (tugger; the vehicles' types: agv)"


def test_an_order_is_served_when_one_vehicle_it_allows_can_reach_every_stop(tmp_path: Path) -> None:
    # Vehicle 1 (agv) starts past segment 2; vehicle 2 (tugger) before it: only the tugger can serve o1.
    vehicles = "1,3,forward,forward,agv\n2,1,forward,forward,tugger\n"
    scenario = scenario_with_orders(tmp_path, "o1,0,,2>3,,,\n", vehicles)
    assert len(scenario.orders) == 1  # type: ignore[attr-defined]
    with pytest.raises(ScenarioFileError, match=r"order 'o1': no vehicle it may go to \(1\) can reach segment 2"):
        scenario_with_orders(tmp_path, "o1,0,,2>3,,agv,\n", vehicles)


# -- a scenario made in code ------------------------------------------------------------------------


def test_a_scenario_made_in_code_refuses_orders_and_stations_on_missing_segments(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path / "plain", ONE_WAY, "1,1,forward,forward,agv\n")
    with pytest.raises(ScenarioError) as info:
        replace(scenario, orders=(Order("o1", (Stop(2), Stop(9))),), stations={"pick": (Station(8),)})
    assert info.value.problems == (
        "order 'o1' has its stop 2 on segment 9, which is not in the map (segments 1–4)",
        "station set 'pick' has a station on segment 8, which is not in the map (segments 1–4)",
    )
    assert replace(scenario, orders=(Order("o1", (Stop(4),)),), stations={"pick": (Station(1),)}).orders
