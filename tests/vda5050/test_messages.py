"""The VDA 5050 codec (fleetsim/vda5050/messages.py) against validators fleetsim did not write
(tests/vda5050/official.py): what fleetsim writes passes them, what they pass fleetsim reads, and what
is wrong is reported as validationErrors naming the key."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from collections.abc import Callable
from typing import Any, TypedDict

import official
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fleetsim.vda5050.messages import (
    KEY_REFERENCE,
    MessageInvalid,
    decode_connection,
    decode_instant_actions,
    decode_order,
    encode,
    to_document,
    topic,
)
from fleetsim.vda5050.model import BlockingType, ErrorLevel, ErrorReference, NodePosition, VdaError
from fleetsim.vda5050.state_model import (
    ActionState,
    ActionStatus,
    AgvAction,
    AgvActionParameter,
    AgvGeometry,
    AgvPosition,
    BatteryState,
    BoundingBoxReference,
    Connection,
    ConnectionState,
    EdgeState,
    Envelope2d,
    EStop,
    Factsheet,
    InfoLevel,
    InfoReference,
    Information,
    Load,
    LoadDimensions,
    LoadSpecification,
    MapState,
    MapStatus,
    NodeState,
    OperatingMode,
    OptionalParameter,
    PhysicalParameters,
    PolygonPoint,
    ProtocolFeatures,
    ProtocolLimits,
    SafetyState,
    State,
    Timing,
    TypeSpecification,
    VehicleConfig,
    Velocity,
    VersionInfo,
    Visualization,
)

VERSIONS = ("2.0", "2.1")


class HeaderFields(TypedDict):
    header_id: int
    timestamp: str
    manufacturer: str
    serial_number: str


HEADER: HeaderFields = {
    "header_id": 7,
    "timestamp": "2026-12-03T13:00:00.25Z",
    "manufacturer": "fleetsim",
    "serial_number": "v1",
}
TRAJECTORY = {
    "degree": 1,
    "knotVector": [0.0, 0.0, 1.0, 1.0],
    "controlPoints": [{"x": 0.0, "y": 0.0}, {"x": 2.0, "y": 0.0, "weight": 1.0}],
}
POSITION = AgvPosition(1.0, 2.0, 0.5, "hall", True, "the hall", 0.9, 0.05)


def full_state() -> State:
    return State(
        **HEADER,
        order_id="order-1",
        order_update_id=2,
        last_node_id="n1",
        last_node_sequence_id=0,
        driving=True,
        operating_mode=OperatingMode.AUTOMATIC,
        battery_state=BatteryState(80.0, False, 48.0, 97, 1200.0),
        safety_state=SafetyState(EStop.NONE, False),
        node_states=(NodeState("n2", 2, True, "second", NodePosition(2.0, 0.0, "hall", 0.0, 0.25, 0.1, "hall")),),
        edge_states=(EdgeState("e1", 1, True, "first edge", TRAJECTORY),),
        action_states=(
            ActionState("a1", ActionStatus.RUNNING, "pick", "lift", "ok"),
            ActionState("a2", ActionStatus.PAUSED, "startPause"),
        ),
        errors=(
            VdaError(
                "validationError",
                "nodes[0].nodeId: required key is missing",
                ErrorLevel.WARNING,
                (ErrorReference("headerId", "3"),),
                error_hint="send nodeId",
            ),
        ),
        information=(Information("battery", InfoLevel.INFO, "charged", (InfoReference("headerId", "1"),)),),
        maps=(MapState("hall", "1.0", MapStatus.ENABLED, "the hall"),),
        zone_set_id="zones",
        paused=False,
        new_base_request=False,
        distance_since_last_node=0.5,
        agv_position=POSITION,
        velocity=Velocity(0.5, 0.0, 0.1),
        loads=(
            Load(
                "l1", "pallet", "front", BoundingBoxReference(0.0, 0.0, 0.1, 0.0), LoadDimensions(1.2, 0.8, 1.0), 250.0
            ),
        ),
    )


def minimal_state() -> State:
    return State(
        **HEADER,
        order_id="",
        order_update_id=0,
        last_node_id="",
        last_node_sequence_id=0,
        driving=False,
        operating_mode=OperatingMode.AUTOMATIC,
        battery_state=BatteryState(100.0, False),
        safety_state=SafetyState(EStop.NONE, False),
    )


def full_factsheet() -> Factsheet:
    return Factsheet(
        **HEADER,
        type_specification=TypeSpecification(
            "fleetsim AGV", "DIFF", "CARRIER", 500.0, ("NATURAL",), ("AUTONOMOUS",), "simulated"
        ),
        physical_parameters=PhysicalParameters(0.0, 1.5, 0.5, 0.8, 1.8, 0.8, 1.2, 0.2),
        protocol_limits=ProtocolLimits(
            Timing(0.5, 0.1, 1.0, 0.2), {"idLen": 64, "idNumericalOnly": False}, {"order.nodes": 100}
        ),
        protocol_features=ProtocolFeatures(
            (OptionalParameter("order.edges.trajectory", "SUPPORTED", "NURBS edges"),),
            (
                AgvAction(
                    "startPause",
                    ("INSTANT",),
                    "pause",
                    (AgvActionParameter("reason", "STRING", "why", True),),
                    "paused",
                    ("HARD",),
                ),
            ),
        ),
        agv_geometry=AgvGeometry(
            (
                Envelope2d(
                    "default", tuple(PolygonPoint(x, y) for x, y in ((0.6, 0.4), (-0.6, 0.4), (-0.6, -0.4))), "outline"
                ),
            )
        ),
        load_specification=LoadSpecification(("front",)),
        vehicle_config=VehicleConfig((VersionInfo("fleetsim", "1.0"),)),
    )


def minimal_factsheet() -> Factsheet:
    return Factsheet(
        **HEADER,
        type_specification=TypeSpecification("fleetsim AGV", "DIFF", "CARRIER", 0.0, ("NATURAL",), ("AUTONOMOUS",)),
        physical_parameters=PhysicalParameters(0.0, 1.0, 0.5, 0.5, 1.0, 0.8, 1.2),
        protocol_limits=ProtocolLimits(Timing(0.5, 0.1)),
        protocol_features=ProtocolFeatures(),
    )


MESSAGES: dict[str, tuple[str, Callable[[], State | Connection | Visualization | Factsheet]]] = {
    "state-full": ("state", full_state),
    "state-required": ("state", minimal_state),
    "connection": ("connection", lambda: Connection(**HEADER, connection_state=ConnectionState.CONNECTIONBROKEN)),
    "visualization-full": (
        "visualization",
        lambda: Visualization(**HEADER, agv_position=POSITION, velocity=Velocity(0.1)),
    ),
    "visualization-required": ("visualization", lambda: Visualization(**HEADER)),
    "factsheet-full": ("factsheet", full_factsheet),
    "factsheet-required": ("factsheet", minimal_factsheet),
}


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("kind", MESSAGES)
def test_every_outgoing_message_passes_the_independent_validator(kind: str, version: str) -> None:
    name, build = MESSAGES[kind]
    document = to_document(build(), version)
    assert official.validate(version, name, document) == []
    assert json.loads(encode(build(), version)) == document
    broken = {**document, "headerId": "7"}
    assert official.validate(version, name, broken) != [], "the validator must reject a headerId that is a string"


def test_state_of_each_version_has_its_own_fields() -> None:
    old, new = to_document(full_state(), "2.0"), to_document(full_state(), "2.1")
    assert (old["version"], new["version"]) == ("2.0.0", "2.1.0")
    assert "maps" not in old and new["maps"] == [
        {"mapId": "hall", "mapVersion": "1.0", "mapStatus": "ENABLED", "mapDescription": "the hall"}
    ]
    assert "errorHint" not in old["errors"][0] and new["errors"][0]["errorHint"] == "send nodeId"
    assert list(new)[:5] == ["headerId", "timestamp", "version", "manufacturer", "serialNumber"]
    assert new["safetyState"] == {"eStop": "NONE", "fieldViolation": False}
    assert "loads" not in to_document(minimal_state(), "2.1") and "zoneSetId" not in to_document(minimal_state(), "2.1")
    factsheet = to_document(full_factsheet(), "2.0")
    assert "vehicleConfig" not in factsheet and "blockingTypes" not in factsheet["protocolFeatures"]["agvActions"][0]


def test_keys_the_text_spells_its_own_way_are_written_so() -> None:
    (node,) = to_document(full_state(), "2.1")["nodeStates"]
    assert node["nodePosition"]["allowedDeviationXY"] == 0.25 and "allowedDeviationXy" not in node["nodePosition"]


def test_vda_5050_lib_allowed_deviation_key_is_named() -> None:
    """vda-5050-lib 1.4.0 spells the node's tolerance ``allowedDeviationXy``; dropping it would be silent."""
    document = order_document("2.0")
    document["nodes"][1]["nodePosition"]["allowedDeviationXy"] = 0.5
    assert official.validate_20("order", document) == [], "vda-5050-lib itself accepts its spelling"
    with pytest.raises(MessageInvalid) as raised:
        decode_order(payload(document), "2.0")
    (error,) = raised.value.errors
    assert error.error_description == (
        "nodes[1].nodePosition.allowedDeviationXy: not a VDA 5050 2.x key; the text's key is 'allowedDeviationXY'"
    )
    assert ErrorReference("nodeId", "n2") in error.error_references


def test_encode_writes_compact_utf8_and_refuses_what_json_cannot_say() -> None:
    payload = encode(
        Connection(7, "2026-12-03T13:00:00Z", "fleetsim", "Fahrzeug-ä", connection_state=ConnectionState.ONLINE), "2.1"
    )
    assert b", " not in payload and "Fahrzeug-ä".encode() in payload
    bad = Visualization(**HEADER, velocity=Velocity(vx=math.nan))
    with pytest.raises(ValueError, match=r"visualization\.velocity\.vx=nan must be a finite number"):
        encode(bad, "2.0")
    spec = minimal_factsheet()
    wrong_word = Factsheet(
        **HEADER,
        type_specification=TypeSpecification("s", "TANK", "CARRIER", 0.0, (), ()),
        physical_parameters=spec.physical_parameters,
        protocol_limits=spec.protocol_limits,
        protocol_features=spec.protocol_features,
    )
    with pytest.raises(ValueError, match=r"agvKinematic='TANK' must be one of"):
        encode(wrong_word, "2.1")
    with pytest.raises(ValueError, match=r"version='3.0' must be one of"):
        encode(minimal_state(), "3.0")


def test_encode_holds_numbers_and_timestamps_to_the_text() -> None:
    over = dataclasses.replace(minimal_state(), battery_state=BatteryState(90.0, False, battery_health=101))
    with pytest.raises(ValueError, match=r"state\.batteryState\.batteryHealth=101 must be in 0\.0\.\.100\.0"):
        encode(over, "2.1")
    fractional = dataclasses.replace(over, battery_state=BatteryState(50.0, False, battery_health=97.5))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"batteryHealth=97\.5 must be an integer"):
        encode(fractional, "2.0")
    lost = Visualization(**HEADER, agv_position=AgvPosition(0.0, 0.0, 0.0, "hall", False, localization_score=-0.1))
    with pytest.raises(ValueError, match=r"localizationScore=-0\.1 must be in 0\.0\.\.1\.0"):
        encode(lost, "2.0")
    late = Connection(7, "13:00 yesterday", "fleetsim", "v1", ConnectionState.OFFLINE)
    with pytest.raises(ValueError, match=r"connection\.timestamp='13:00 yesterday' must be an ISO 8601 date-time"):
        encode(late, "2.1")


@pytest.mark.parametrize("version", VERSIONS)
def test_the_validation_errors_of_a_rejected_order_go_into_a_valid_state(version: str) -> None:
    document = order_document(version)
    del document["nodes"][0]["released"]
    document["edges"][1]["actions"] = [action("x1", blocking="SOMETIMES")]
    with pytest.raises(MessageInvalid) as raised:
        decode_order(payload(document), version)
    written = to_document(dataclasses.replace(minimal_state(), errors=raised.value.errors), version)
    assert official.validate(version, "state", written) == []
    assert [e["errorType"] for e in written["errors"]] == ["validationError", "validationError"]
    assert {"referenceKey": "edgeId", "referenceValue": "e2"} in written["errors"][1]["errorReferences"]


def test_a_decoder_asked_for_an_unknown_version_says_which_exist() -> None:
    with pytest.raises(ValueError, match=r"version='2\.2' must be one of \['2\.0', '2\.1'\]"):
        decode_order(payload(order_document("2.1")), "2.2")


def test_unknown_keys_are_ignored_and_2_1_keys_are_not_checked_in_2_0() -> None:
    document = order_document("2.0")
    document["vendorExtension"] = {"anything": True}
    document["edges"][0]["corridor"] = {"leftWidth": "wide"}
    assert decode_order(payload(document), "2.0").order_id == "order-1"
    with pytest.raises(MessageInvalid, match=r"edges\[0\]\.corridor\.leftWidth: expected a number, got 'wide'"):
        decode_order(payload({**document, "version": "2.1.0"}), "2.1")


def action(action_id: str, action_type: str = "pick", blocking: str = "HARD", **extra: Any) -> dict[str, Any]:
    return {"actionId": action_id, "actionType": action_type, "blockingType": blocking, **extra}


def order_document(version: str) -> dict[str, Any]:
    """A 3-node order as the text describes one: n1 and n2 released (the base), n3 the horizon."""
    nodes = [
        {
            "nodeId": "n1",
            "sequenceId": 0,
            "released": True,
            "actions": [],
            "nodePosition": {"x": 0.0, "y": 0.0, "mapId": "hall", "theta": 0.0, "allowedDeviationXY": 0.1},
        },
        {
            "nodeId": "n2",
            "sequenceId": 2,
            "released": True,
            "actions": [action("a1", actionParameters=[{"key": "height", "value": 0.5}], actionDescription="lift")],
            "nodePosition": {"x": 2.0, "y": 0.0, "mapId": "hall"},
        },
        {"nodeId": "n3", "sequenceId": 4, "released": False, "actions": []},
    ]
    edges = [
        {
            "edgeId": "e1",
            "sequenceId": 1,
            "released": True,
            "startNodeId": "n1",
            "endNodeId": "n2",
            "actions": [],
            "maxSpeed": 1.0,
            "orientation": 3.14159,
            "orientationType": "TANGENTIAL",
            "trajectory": TRAJECTORY,
        },
        {"edgeId": "e2", "sequenceId": 3, "released": False, "startNodeId": "n2", "endNodeId": "n3", "actions": []},
    ]
    return {
        "headerId": 3,
        "timestamp": "2026-12-03T13:00:00.00Z",
        "version": f"{version}.0",
        "manufacturer": "fleetsim",
        "serialNumber": "v1",
        "orderId": "order-1",
        "orderUpdateId": 0,
        "nodes": nodes,
        "edges": edges,
    }


def payload(document: Any) -> bytes:
    return json.dumps(document).encode()


@pytest.mark.parametrize("version", VERSIONS)
def test_a_valid_order_reads_into_the_model(version: str) -> None:
    document = order_document(version)
    assert official.validate(version, "order", document) == []
    order = decode_order(payload(document), version)
    assert (order.header.header_id, order.header.version, order.order_id, order.zone_set_id) == (
        3,
        f"{version}.0",
        "order-1",
        None,
    )
    assert [n.node_id for n in order.nodes] == ["n1", "n2", "n3"] and [e.sequence_id for e in order.edges] == [1, 3]
    base_nodes, base_edges = order.base
    assert [n.node_id for n in base_nodes] == ["n1", "n2"] and [e.edge_id for e in base_edges] == ["e1"]
    (lift,) = order.nodes[1].actions
    assert (lift.action_type, lift.blocking_type, lift.parameter("height"), lift.action_description) == (
        "pick",
        BlockingType.HARD,
        0.5,
        "lift",
    )
    assert order.nodes[0].node_position == NodePosition(0.0, 0.0, "hall", 0.0, 0.1)
    assert order.edges[0].orientation == 3.14159 and order.edges[0].trajectory == TRAJECTORY
    assert order.edges[1].max_speed is None and order.nodes[2].node_position is None


@pytest.mark.parametrize("version", VERSIONS)
def test_valid_instant_actions_read_into_the_model(version: str) -> None:
    document = {
        "headerId": 9,
        "timestamp": "2026-12-03T13:00:00Z",
        "version": f"{version}.0",
        "manufacturer": "m",
        "serialNumber": "v1",
        "actions": [action("p1", "startPause", "HARD"), action("s1", "stateRequest", "NONE")],
    }
    assert official.validate(version, "instantActions", document) == []
    message = decode_instant_actions(payload(document), version)
    assert [(a.action_id, a.action_type, a.blocking_type) for a in message.actions] == [
        ("p1", "startPause", BlockingType.HARD),
        ("s1", "stateRequest", BlockingType.NONE),
    ]


def problems(raised: pytest.ExceptionInfo[MessageInvalid]) -> dict[str, VdaError]:
    """The errors by the key path they name."""
    errors = raised.value.errors
    assert all(e.error_type == "validationError" and e.error_level is ErrorLevel.WARNING for e in errors)
    return {
        next((r.reference_value for r in e.error_references if r.reference_key == KEY_REFERENCE), ""): e for e in errors
    }


def test_every_problem_of_an_order_is_reported_at_once_with_its_references() -> None:
    document = order_document("2.1")
    del document["nodes"][2]["sequenceId"]
    document["nodes"][1]["released"] = "yes"
    document["nodes"][1]["actions"][0]["blockingType"] = "MEDIUM"
    document["edges"][0]["orientationType"] = "SIDEWAYS"
    document["edges"][1]["sequenceId"] = -1
    document["orderUpdateId"] = "0"
    with pytest.raises(MessageInvalid) as raised:
        decode_order(payload(document), "2.1")
    found = problems(raised)
    assert set(found) == {
        "nodes[2].sequenceId",
        "nodes[1].released",
        "nodes[1].actions[0].blockingType",
        "edges[0].orientationType",
        "edges[1].sequenceId",
        "orderUpdateId",
    }
    missing = found["nodes[2].sequenceId"]
    assert missing.error_description == "nodes[2].sequenceId: required key is missing"
    assert missing.error_references == (
        ErrorReference("headerId", "3"),
        ErrorReference("orderId", "order-1"),
        ErrorReference("nodeId", "n3"),
        ErrorReference(KEY_REFERENCE, "nodes[2].sequenceId"),
    )
    assert "'yes' (a string)" in found["nodes[1].released"].error_description
    assert ErrorReference("actionId", "a1") in found["nodes[1].actions[0].blockingType"].error_references
    assert "'MEDIUM' is not one of NONE, SOFT, HARD" in found["nodes[1].actions[0].blockingType"].error_description
    assert "'SIDEWAYS' is not one of GLOBAL, TANGENTIAL" in found["edges[0].orientationType"].error_description
    assert ErrorReference("edgeId", "e2") in found["edges[1].sequenceId"].error_references
    assert "6 problems" in str(raised.value)


def test_an_order_missing_every_required_key_names_each() -> None:
    with pytest.raises(MessageInvalid) as raised:
        decode_order(b"{}", "2.0")
    assert set(problems(raised)) == {
        "headerId",
        "timestamp",
        "version",
        "manufacturer",
        "serialNumber",
        "orderId",
        "orderUpdateId",
        "nodes",
        "edges",
    }
    assert all(len(e.error_references) == 1 for e in raised.value.errors), "no headerId or orderId to refer to"


def test_malformed_json_names_the_byte_offset() -> None:
    text = '{"orderId": "ä", "nodes": [}'
    with pytest.raises(MessageInvalid) as raised:
        decode_order(text.encode(), "2.0")
    (error,) = raised.value.errors
    offset = len(text[: text.index("}")].encode())
    assert offset != text.index("}"), "the test needs a multi-byte character before the fault"
    assert error.error_description.startswith(f"payload is not JSON: Expecting value at byte {offset} (line 1, column")
    with pytest.raises(MessageInvalid, match=r"payload is not UTF-8: byte 2"):
        decode_order(b'{"\xff": 1}', "2.0")


@pytest.mark.parametrize(("text", "kind"), [("[]", "an array"), ('"order"', "a string"), ("null", "null")])
def test_a_payload_that_is_not_an_object_is_a_validation_error(text: str, kind: str) -> None:
    with pytest.raises(MessageInvalid) as raised:
        decode_instant_actions(text.encode(), "2.1")
    assert [e.error_description for e in raised.value.errors] == [f"payload must be a JSON object, got {kind}"]


def test_numbers_must_be_finite_and_in_range() -> None:
    document = order_document("2.0")
    text = json.dumps(document).replace('"x": 2.0', '"x": NaN').replace('"theta": 0.0', '"theta": 4.0')
    with pytest.raises(MessageInvalid) as raised:
        decode_order(text.encode(), "2.0")
    found = problems(raised)
    assert found["nodes[1].nodePosition.x"].error_description.endswith("expected a finite number, got nan")
    assert found["nodes[0].nodePosition.theta"].error_description.endswith(
        "4.0 must be in -3.14159265359..3.14159265359"
    )


def test_vda_5050_lib_instant_actions_key_is_named() -> None:
    """vda-5050-lib 1.4.0's master controller sends the actions under ``instantActions``."""
    document = {
        "headerId": 1,
        "timestamp": "2026-12-03T13:00:00Z",
        "version": "2.0.0",
        "manufacturer": "m",
        "serialNumber": "v1",
        "instantActions": [action("p1", "startPause")],
    }
    with pytest.raises(MessageInvalid) as raised:
        decode_instant_actions(payload(document), "2.0")
    (error,) = raised.value.errors
    assert (
        error.error_description
        == "instantActions: expected key 'actions' (VDA 5050 2.x); 'instantActions' is not a 2.x key"
    )
    assert error.error_references == (ErrorReference("headerId", "1"), ErrorReference(KEY_REFERENCE, "instantActions"))


@pytest.mark.parametrize("version", VERSIONS)
def test_action_name_is_accepted_nowhere(version: str) -> None:
    named = {"actionId": "p1", "actionName": "startPause", "blockingType": "HARD"}
    document = {
        "headerId": 1,
        "timestamp": "2026-12-03T13:00:00Z",
        "version": f"{version}.0",
        "manufacturer": "m",
        "serialNumber": "v1",
        "actions": [named],
    }
    with pytest.raises(MessageInvalid) as raised:
        decode_instant_actions(payload(document), version)
    assert set(problems(raised)) == {"actions[0].actionName", "actions[0].actionType"}
    order = order_document(version)
    order["nodes"][0]["actions"] = [{**action("a9"), "actionName": "pick"}]
    with pytest.raises(MessageInvalid, match=r"nodes\[0\]\.actions\[0\]\.actionName: not a VDA 5050 2.x key"):
        decode_order(payload(order), version)


def test_known_defects_of_the_independent_validators_still_exist() -> None:
    """Each allow-list entry is a finding its validator really makes (else the entry is stale), and only it."""
    instant = {
        "headerId": 1,
        "timestamp": "2026-12-03T13:00:00Z",
        "version": "2.0.0",
        "manufacturer": "m",
        "serialNumber": "v1",
        "actions": [action("p1", "startPause")],
    }
    documents = {
        "state": to_document(full_state(), "2.1"),
        "factsheet": to_document(full_factsheet(), "2.1"),
        "instantActions": instant,
    }
    for defect in official.KNOWN_DEFECTS:
        document = documents[defect.topic]
        if defect.version == "2.0":
            raw = official.validate_20(defect.topic, document, adapt_known_defects=False)
            assert raw == [f"#/{defect.path}: #/allOf/1/{defect.keyword}"], (defect.name, raw)
            assert official.validate_20(defect.topic, document) == []
        else:
            raw = official.validate_21(defect.topic, document, forgive_known_defects=False)
            assert len(raw) == 1 and re.match(defect.path, raw[0].split(":")[0]), (defect.name, raw)
            assert official.validate_21(defect.topic, document) == []
    stopped = {**documents["state"], "actionStates": [{"actionId": "a", "actionStatus": "STOPPED"}]}
    assert official.validate_21("state", stopped) != [], "forgiving PAUSED must not forgive any other status"
    assert official.validate_20("instantActions", {**instant, "actions": [{"actionId": "p1"}]}) != []


def test_vda_5050_lib_20_validators_follow_the_text_on_action_type_and_paused() -> None:
    """The 2.0.0 instantActions.schema file requires actionName; vda-5050-lib's compiled validator requires
    actionType (in orders and instant actions) and knows PAUSED."""
    base = {
        "headerId": 1,
        "timestamp": "2026-12-03T13:00:00Z",
        "version": "2.0.0",
        "manufacturer": "m",
        "serialNumber": "v1",
    }
    named = {**base, "actions": [{"actionId": "p1", "actionName": "startPause", "blockingType": "HARD"}]}
    assert official.validate_20("instantActions", named) == [
        "#/instantActions/0/actionType: #/allOf/1/properties/instantActions/items/$ref/required"
    ]
    order = order_document("2.0")
    order["nodes"][1]["actions"] = [{"actionId": "a1", "actionName": "pick", "blockingType": "HARD"}]
    assert official.validate_20("order", order) != []
    assert official.validate_20("state", to_document(full_state(), "2.0")) == []  # it holds a PAUSED action


def test_topic_names_the_interface_major_version_vehicle_and_message() -> None:
    assert topic("uagv", "2.1", "fleetsim", "v1", "state") == "uagv/v2/fleetsim/v1/state"
    assert topic("uagv", "2.0", "fleetsim", "v1", "order") == "uagv/v2/fleetsim/v1/order"
    with pytest.raises(ValueError, match=r"serial_number='a/b' must be a non-empty topic level"):
        topic("uagv", "2.0", "fleetsim", "a/b", "order")
    with pytest.raises(ValueError, match=r"name='orders' must be one of"):
        topic("uagv", "2.0", "fleetsim", "v1", "orders")


ids = st.text(st.characters(codec="ascii", categories=("L", "N")), min_size=1, max_size=8)
numbers = st.floats(-1e6, 1e6, allow_nan=False)
angles = st.floats(-3.14, 3.14)


@st.composite
def trajectories(draw: st.DrawFn) -> dict[str, Any]:
    """A NURBS as the text describes it: the knot vector has control points + degree + 1 entries in 0..1."""
    degree = draw(st.integers(1, 3))
    points = draw(st.integers(degree + 1, 4))
    knots = sorted(draw(st.lists(st.floats(0, 1), min_size=points + degree + 1, max_size=points + degree + 1)))
    control = st.fixed_dictionaries({"x": numbers, "y": numbers}, optional={"weight": st.floats(0, 2)})
    return {
        "degree": degree,
        "knotVector": knots,
        "controlPoints": draw(st.lists(control, min_size=points, max_size=points)),
    }


@st.composite
def orders(draw: st.DrawFn) -> tuple[str, dict[str, Any]]:
    """A version and an order valid per the text: alternating nodes and edges, optional keys or not."""
    version = draw(st.sampled_from(VERSIONS))
    count = draw(st.integers(1, 5))
    released = draw(st.integers(1, count))

    def optional(**choices: st.SearchStrategy[Any]) -> dict[str, Any]:
        return {key: draw(value) for key, value in choices.items() if draw(st.booleans())}

    values = [numbers, ids, st.booleans(), st.lists(ids, max_size=2)]
    if version == "2.1":
        values.append(st.dictionaries(ids, numbers, max_size=2))

    def actions() -> list[dict[str, Any]]:
        return [
            {
                "actionId": draw(ids),
                "actionType": draw(ids),
                "blockingType": draw(st.sampled_from(["NONE", "SOFT", "HARD"])),
                **optional(
                    actionDescription=ids,
                    actionParameters=st.lists(
                        st.fixed_dictionaries({"key": ids, "value": st.one_of(values)}), max_size=2
                    ),
                ),
            }
            for _ in range(draw(st.integers(0, 2)))
        ]

    nodes = [
        {
            "nodeId": f"n{i}",
            "sequenceId": 2 * i,
            "released": i < released,
            "actions": actions(),
            **optional(
                nodeDescription=ids,
                nodePosition=st.fixed_dictionaries(
                    {"x": numbers, "y": numbers, "mapId": ids},
                    optional={"theta": angles, "allowedDeviationXY": st.floats(0, 5)},
                ),
            ),
        }
        for i in range(count)
    ]
    edges = [
        {
            "edgeId": f"e{i}",
            "sequenceId": 2 * i + 1,
            "released": i + 1 < released,
            "startNodeId": f"n{i}",
            "endNodeId": f"n{i + 1}",
            "actions": actions(),
            **optional(
                maxSpeed=st.floats(0, 3),
                orientation=angles,
                orientationType=st.sampled_from(["GLOBAL", "TANGENTIAL"]),
                rotationAllowed=st.booleans(),
                length=st.floats(0, 100),
                direction=ids,
                trajectory=trajectories(),
                **(
                    {
                        "corridor": st.fixed_dictionaries(
                            {"leftWidth": st.floats(0, 2), "rightWidth": st.floats(0, 2)},
                            optional={"corridorRefPoint": st.sampled_from(["KINEMATICCENTER", "CONTOUR"])},
                        )
                    }
                    if version == "2.1"
                    else {}
                ),
            ),
        }
        for i in range(count - 1)
    ]
    document = {
        "headerId": draw(st.integers(0, 2**31)),
        "timestamp": "2026-12-03T13:00:00.5Z",
        "version": f"{version}.0",
        "manufacturer": draw(ids),
        "serialNumber": draw(ids),
        "orderId": draw(ids),
        "orderUpdateId": draw(st.integers(0, 100)),
        "nodes": nodes,
        "edges": edges,
        **optional(zoneSetId=ids),
    }
    return version, document


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(orders())
def test_orders_valid_per_the_independent_schema_are_accepted(case: tuple[str, dict[str, Any]]) -> None:
    version, document = case
    assert official.validate(version, "order", document) == []
    order = decode_order(payload(document), version)
    assert [n.node_id for n in order.nodes] == [n["nodeId"] for n in document["nodes"]]
    assert len(order.base[0]) == sum(n["released"] for n in document["nodes"])


def required_places(document: dict[str, Any]) -> list[tuple[dict[str, Any], str, str]]:
    """Every required key of an order with the object holding it and its key path."""
    places = [(document, key, key) for key in ("headerId", "timestamp", "version", "manufacturer", "serialNumber")]
    places += [(document, key, key) for key in ("orderId", "orderUpdateId", "nodes", "edges")]
    for kind, keys in (
        ("nodes", ("nodeId", "sequenceId", "released", "actions")),
        ("edges", ("edgeId", "sequenceId", "released", "startNodeId", "endNodeId", "actions")),
    ):
        for index, item in enumerate(document[kind]):
            places += [(item, key, f"{kind}[{index}].{key}") for key in keys]
            for number, act in enumerate(item["actions"]):
                at = f"{kind}[{index}].actions[{number}]"
                places += [(act, key, f"{at}.{key}") for key in ("actionId", "actionType", "blockingType")]
    return places


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(orders(), st.data())
def test_an_order_missing_or_mistyping_a_required_key_is_rejected_by_both(
    case: tuple[str, dict[str, Any]], data: st.DataObject
) -> None:
    """One required key deleted or given a value of another JSON type: the independent validator and
    decode_order both reject the order, and decode_order names exactly that key."""
    version, document = case
    holder, key, path = data.draw(st.sampled_from(required_places(document)))
    if data.draw(st.booleans()):
        del holder[key]
    else:
        holder[key] = "x" if isinstance(holder[key], (list, bool, int, float)) else [1]
    assert official.validate(version, "order", document) != []
    with pytest.raises(MessageInvalid) as raised:
        decode_order(payload(document), version)
    assert list(problems(raised)) == [path]


finite = st.floats(-1e4, 1e4)


@st.composite
def states(draw: st.DrawFn) -> State:
    """A state with any of its optional parts, values within the text's bounds."""

    def maybe(strategy: st.SearchStrategy[Any]) -> Any:
        return draw(st.none() | strategy)

    position = st.builds(
        AgvPosition,
        finite,
        finite,
        angles,
        ids,
        st.booleans(),
        st.none() | ids,
        st.none() | st.floats(0, 1),
        st.none() | st.floats(0, 5),
    )
    node_position = st.builds(NodePosition, finite, finite, ids, st.none() | angles)
    return State(
        **HEADER,
        order_id=draw(ids | st.just("")),
        order_update_id=draw(st.integers(0, 1000)),
        last_node_id=draw(ids | st.just("")),
        last_node_sequence_id=draw(st.integers(0, 1000)),
        driving=draw(st.booleans()),
        operating_mode=draw(st.sampled_from(OperatingMode)),
        battery_state=draw(
            st.builds(
                BatteryState,
                st.floats(0, 100),
                st.booleans(),
                st.none() | st.floats(0, 60),
                st.none() | st.integers(0, 100),
                st.none() | st.floats(0, 1e5),
            )
        ),
        safety_state=draw(st.builds(SafetyState, st.sampled_from(EStop), st.booleans())),
        node_states=tuple(
            draw(
                st.lists(
                    st.builds(
                        NodeState, ids, st.integers(0, 99), st.booleans(), st.none() | ids, st.none() | node_position
                    ),
                    max_size=3,
                )
            )
        ),
        edge_states=tuple(
            draw(
                st.lists(
                    st.builds(
                        EdgeState, ids, st.integers(0, 99), st.booleans(), st.none() | ids, st.none() | trajectories()
                    ),
                    max_size=3,
                )
            )
        ),
        action_states=tuple(
            draw(
                st.lists(
                    st.builds(
                        ActionState,
                        ids,
                        st.sampled_from(ActionStatus),
                        st.none() | ids,
                        st.none() | ids,
                        st.none() | ids,
                    ),
                    max_size=3,
                )
            )
        ),
        errors=tuple(
            draw(
                st.lists(
                    st.builds(
                        VdaError,
                        ids,
                        ids,
                        st.sampled_from(ErrorLevel),
                        st.lists(st.builds(ErrorReference, ids, ids), max_size=2).map(tuple),
                        st.none() | ids,
                    ),
                    max_size=2,
                )
            )
        ),
        information=tuple(draw(st.lists(st.builds(Information, ids, st.sampled_from(InfoLevel)), max_size=2))),
        maps=tuple(draw(st.lists(st.builds(MapState, ids, ids, st.sampled_from(MapStatus)), max_size=2))),
        zone_set_id=maybe(ids),
        paused=maybe(st.booleans()),
        new_base_request=maybe(st.booleans()),
        distance_since_last_node=maybe(st.floats(0, 100)),
        agv_position=maybe(position),
        velocity=maybe(st.builds(Velocity, st.none() | finite, st.none() | finite, st.none() | finite)),
        loads=maybe(
            st.lists(
                st.builds(
                    Load, st.none() | ids, st.none() | ids, st.none() | ids, weight=st.none() | st.floats(0, 1000)
                ),
                max_size=2,
            ).map(tuple)
        ),
    )


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(states())
def test_any_state_fleetsim_can_hold_passes_the_independent_validators(state: State) -> None:
    for version in VERSIONS:
        assert official.validate(version, "state", to_document(state, version)) == []


def test_a_payload_that_is_not_bytes_is_a_type_error() -> None:
    with pytest.raises(TypeError, match=r"payload='\{\}' must be bytes"):
        decode_order("{}", "2.0")  # type: ignore[arg-type]


def test_without_node_the_20_checks_skip_or_fail_when_tools_are_required(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(official, "_node_validator", None)
    monkeypatch.setattr("shutil.which", lambda _program: None)
    monkeypatch.delenv("FLEETSIM_REQUIRE_TOOLS", raising=False)
    with pytest.raises(pytest.skip.Exception, match=r"Node.js 'node' is not on PATH"):
        official.validate_20("connection", {})
    monkeypatch.setenv("FLEETSIM_REQUIRE_TOOLS", "1")
    with pytest.raises(pytest.fail.Exception, match=r"FLEETSIM_REQUIRE_TOOLS=1 requires it"):
        official.validate_20("connection", {})


@st.composite
def factsheets(draw: st.DrawFn) -> Factsheet:
    """A factsheet with any of its optional parts."""
    some = st.none() | ids

    def words(*choices: str) -> st.SearchStrategy[tuple[str, ...]]:
        return st.lists(st.sampled_from(choices), min_size=1, max_size=3, unique=True).map(tuple)

    parameter = st.builds(
        AgvActionParameter,
        ids,
        st.sampled_from(["BOOL", "NUMBER", "STRING", "OBJECT"]),
        some,
        st.none() | st.booleans(),
    )
    agv_action = st.builds(
        AgvAction,
        ids,
        words("INSTANT", "NODE", "EDGE"),
        some,
        st.none() | st.lists(parameter, max_size=2).map(tuple),
        some,
        st.none() | words("NONE", "SOFT", "HARD"),
    )
    outline = st.lists(st.builds(PolygonPoint, finite, finite), min_size=3, max_size=5).map(tuple)
    return Factsheet(
        **HEADER,
        type_specification=draw(
            st.builds(
                TypeSpecification,
                ids,
                st.sampled_from(["DIFF", "OMNI", "THREEWHEEL"]),
                st.sampled_from(["FORKLIFT", "CONVEYOR", "TUGGER", "CARRIER"]),
                st.floats(0, 2000),
                words("NATURAL", "SPOT", "GRID"),
                words("AUTONOMOUS", "VIRTUAL_LINE_GUIDED"),
                some,
            )
        ),
        physical_parameters=draw(st.builds(PhysicalParameters, *[st.floats(0, 10)] * 7, st.none() | st.floats(0, 1))),
        protocol_limits=draw(
            st.builds(
                ProtocolLimits,
                st.builds(
                    Timing, st.floats(0, 5), st.floats(0, 5), st.none() | st.floats(0, 5), st.none() | st.floats(0, 5)
                ),
                st.dictionaries(st.sampled_from(["msgLen", "idLen", "enumLen"]), st.integers(1, 999)),
                st.dictionaries(st.sampled_from(["order.nodes", "order.edges"]), st.integers(1, 999)),
            )
        ),
        protocol_features=draw(
            st.builds(
                ProtocolFeatures,
                st.lists(
                    st.builds(OptionalParameter, ids, st.sampled_from(["SUPPORTED", "REQUIRED"]), some), max_size=2
                ).map(tuple),
                st.lists(agv_action, max_size=3).map(tuple),
            )
        ),
        agv_geometry=AgvGeometry(
            draw(st.none() | st.lists(st.builds(Envelope2d, ids, outline, some), max_size=2).map(tuple))
        ),
        load_specification=LoadSpecification(draw(st.none() | st.lists(ids, max_size=2).map(tuple))),
        vehicle_config=draw(
            st.none()
            | st.builds(VehicleConfig, st.none() | st.lists(st.builds(VersionInfo, ids, ids), max_size=2).map(tuple))
        ),
    )


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(factsheets())
def test_any_factsheet_fleetsim_can_hold_passes_the_independent_validators(factsheet: Factsheet) -> None:
    for version in VERSIONS:
        assert official.validate(version, "factsheet", to_document(factsheet, version)) == []


def test_a_header_with_a_bad_timestamp_or_a_foreign_major_version_is_named() -> None:
    document = {**order_document("2.0"), "timestamp": "yesterday", "version": "1.1.0"}
    with pytest.raises(MessageInvalid) as raised:
        decode_order(payload(document), "2.0")
    found = problems(raised)
    assert set(found) == {"timestamp", "version"}
    assert (
        found["timestamp"].error_description
        == "timestamp: 'yesterday' is not an ISO 8601 date-time (YYYY-MM-DDTHH:mm:ss.ffZ)"
    )
    assert found["version"].error_description.startswith("version: '1.1.0' is not a VDA 5050 2.x version")
    assert decode_order(payload({**document, "timestamp": "2026-12-03T13:00:00+02:00", "version": "2.1.0"}), "2.0")


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("state", list(ConnectionState))
def test_a_connection_reads_back_what_was_written(version: str, state: ConnectionState) -> None:
    written = Connection(**HEADER, connection_state=state)
    assert decode_connection(encode(written, version), version) == written


def test_a_connection_state_outside_the_standards_words_is_a_validation_error_naming_it() -> None:
    document = json.loads(encode(Connection(**HEADER, connection_state=ConnectionState.ONLINE), "2.0"))
    document["connectionState"] = "GONE"
    with pytest.raises(MessageInvalid) as raised:
        decode_connection(payload(document), "2.0")
    [error] = raised.value.errors
    assert "'GONE' is not one of ONLINE, OFFLINE, CONNECTIONBROKEN" in error.error_description
    with pytest.raises(MessageInvalid, match="not JSON"):
        decode_connection(b"{", "2.0")
