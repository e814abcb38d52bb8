"""A run with transport orders recorded as MCAP and read back by two independent readers (mcap + mcap_ros2,
and rosbags): the waiting stations and each vehicle's order as markers, the orders' life and the stalls
as log lines, when the trace says they happened."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from orders_support import stall_run, warehouse_run
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from fleetsim.recording.orders import followed
from fleetsim.recording.recorder import record_mcap


def _decoded(path: Path, topics: list[str]) -> list[tuple[str, int, Any]]:
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        return [(c.topic, msg.log_time, value) for _, c, msg, value in reader.iter_decoded_messages(topics=topics)]


@pytest.fixture(scope="module")
def warehouse(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Any, Path]:
    scenario, result = warehouse_run()
    assert result.trace is not None
    path = tmp_path_factory.mktemp("orders") / "run.mcap"
    record_mcap(path, scenario, result.trace.lines, every=10)
    return scenario, result, path


def test_order_markers_show_each_station_and_vehicle_as_the_trace_has_them(warehouse: Any) -> None:
    scenario, result, path = warehouse
    markers = {time: value for topic, time, value in _decoded(path, ["/fleetsim/orders"])}
    expected = {}
    for frame, tracker, changes in followed(scenario, result.trace.lines):
        if frame.step == 0 or changes.vehicles or changes.stations:
            expected[round(frame.time * 1e9)] = tracker.state()
    assert sorted(markers) == sorted(expected) and len(markers) > 20
    for time, array in markers.items():
        state = expected[time]
        assert array.markers[0].action == 3  # DELETEALL first: the orders replace what was shown
        texts = {(mk.ns, mk.id): mk.text for mk in array.markers[1:]}
        waiting = [text for (ns, _), text in sorted(texts.items()) if ns == "waiting_text"]
        assert sorted(waiting) == sorted(
            f"{len(o)} waiting: {' '.join(o[:5])}" + (" ..." if len(o) > 5 else "") for o in state.waiting.values()
        )
        labels = {i: text for (ns, i), text in texts.items() if ns == "order_labels"}
        assert set(labels) == set(state.carry)
        for vehicle, carry in state.carry.items():
            assert labels[vehicle].startswith(f"{carry.orders[0]} {carry.stop + 1}/2")
            assert ("loaded" in labels[vehicle]) == carry.loaded
            assert ("dwell" in labels[vehicle]) == (carry.dwell is not None)
        for marker in array.markers[1:]:
            assert marker.color.a > 0 and marker.header.stamp.sec * 10**9 + marker.header.stamp.nanosec == time
            if marker.ns == "order_labels":
                assert marker.header.frame_id == f"vehicle_{marker.id}" and marker.frame_locked


def test_the_orders_life_is_logged_when_it_happened_and_rosbags_reads_it_too(warehouse: Any) -> None:
    _, result, path = warehouse
    logs = [(time, value.msg) for _, time, value in _decoded(path, ["/rosout"])]
    first = result.orders[0]
    release = round((round(first["release"] / 0.1)) * 0.1 * 1e9)  # released at the step's start,
    assert (release + 100_000_000, f"order {first['id']} released") in logs  # logged at the step's end
    assert any(text == f"vehicle {first['vehicle']} assigned orders: {first['id']}" for _, text in logs)
    done = [t for t, text in logs if text == f"order {first['id']} completed"]
    assert done == [round((first["completed"] + 0.1) * 1e9)]
    served = [text for _, text in logs if text.startswith(f"vehicle {first['vehicle']} served stop")]
    assert f"vehicle {first['vehicle']} served stop 2 of order {first['id']}" in served
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        connections = [c for c in reader.connections if c.topic in ("/fleetsim/orders", "/rosout")]
        seen = [(c.topic, reader.deserialize(raw, c.msgtype)) for c, _, raw in reader.messages(connections=connections)]
    assert sum(1 for topic, _ in seen if topic == "/fleetsim/orders") == len(_decoded(path, ["/fleetsim/orders"]))
    assert [m.msg for topic, m in seen if topic == "/rosout"] == [text for _, text in logs]


def test_a_stall_is_a_warning_naming_the_orders_held_up_and_the_vehicle_is_labelled(tmp_path: Path) -> None:
    scenario, result = stall_run("end")
    assert result.trace is not None
    path = tmp_path / "run.mcap"
    record_mcap(path, scenario, result.trace.lines)
    logs = [(time, value.level, value.msg) for _, time, value in _decoded(path, ["/rosout"])]
    stall = [entry for entry in logs if "stalled" in entry[2]]
    assert stall == [(16_100_000_000, 30, "vehicle 2 stalled: it has work and has not moved; orders held up: b")]
    last = _decoded(path, ["/fleetsim/orders"])[-1]
    assert last[1] == 16_100_000_000
    labels = {mk.id: mk.text for mk in last[2].markers if mk.ns == "order_labels"}
    assert labels[2] == "b 1/2 STALLED" and labels[1] == "a 1/2"
