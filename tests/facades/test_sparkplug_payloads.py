"""Sparkplug B payloads and topics alone (issue 35; Eclipse Sparkplug 3.0: ch. 4 the topic
namespace, ch. 6 the payloads, metric datatypes, ``seq`` and ``bdSeq``): :class:`SparkplugNode`,
:func:`decode_command`, :func:`metric_value` and :func:`command_request`, in-process, the bytes
read back with the Tahu binding's protobuf schema.  The facade on real brokers is in
test_mqtt_sparkplug.py."""

from __future__ import annotations

import functools
import json
import time
from typing import Any

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from tahutils.tahu import sparkplug_b as tahu

from devsim.core.clock import VirtualClock
from devsim.core.registry import device_class
from devsim.facades.mqtt_sparkplug import (
    DATATYPES,
    GROUP,
    NAMESPACE,
    SparkplugNode,
    birth_datatype,
    command_request,
    command_value,
    decode_command,
    metric_value,
)
from devsim.runtime import requests as rq

T = tahu.MetricDataType
#: Signed datatypes and their width (Sparkplug 3.0 §6.4.16: sent as their two's complement in the
#: unsigned ``int_value``/``long_value``).
SIGNED = {T.Int8: 8, T.Int16: 16, T.Int32: 32, T.Int64: 64}
UNSIGNED = {T.UInt8: 8, T.UInt16: 16, T.UInt32: 32, T.UInt64: 64}


@functools.cache
def sers() -> Any:
    return device_class("sers")(clock=VirtualClock(), config={})


def parse(data: bytes) -> Any:
    payload = tahu.Payload()
    payload.ParseFromString(data)
    return payload


def metrics(data: bytes) -> dict[str, Any]:
    return {m.name: m for m in parse(data).metrics}


def one_metric(datatype: int, value: Any) -> Any:
    payload = tahu.Payload()
    tahu.addMetric(payload, "m", None, datatype, value)
    return parse(payload.SerializeToString()).metrics[0]


@given(data=st.data(), datatype=st.sampled_from(sorted(SIGNED)))
def test_a_signed_metric_is_read_from_its_twos_complement(data: st.DataObject, datatype: int) -> None:
    bits = SIGNED[datatype]
    low, high = -(1 << bits - 1), (1 << bits - 1) - 1
    value = data.draw(st.one_of(st.sampled_from([low, low + 1, -1, 0, 1, high - 1, high]), st.integers(low, high)))
    assert metric_value(one_metric(datatype, value)) == value


@given(data=st.data(), datatype=st.sampled_from(sorted(UNSIGNED)))
def test_an_unsigned_metric_is_read_as_it_is(data: st.DataObject, datatype: int) -> None:
    high = (1 << UNSIGNED[datatype]) - 1
    value = data.draw(st.one_of(st.sampled_from([0, 1, high >> 1, (high >> 1) + 1, high]), st.integers(0, high)))
    assert metric_value(one_metric(datatype, value)) == value


@pytest.mark.parametrize(("datatype", "value"), [
    (T.Float, 0.5), (T.Double, -2.25), (T.Boolean, True), (T.Boolean, False), (T.String, "x y"), (T.Text, "t"),
    (T.UUID, "0a1b"), (T.DateTime, 1_700_000_000_000),
])
def test_each_supported_datatype_reads_its_field(datatype: int, value: Any) -> None:
    assert metric_value(one_metric(datatype, value)) == value


def test_a_null_metric_is_none_and_an_unsupported_datatype_is_refused() -> None:
    payload = tahu.Payload()
    tahu.addNullMetric(payload, "n", None, T.Int64)
    assert metric_value(parse(payload.SerializeToString()).metrics[0]) is None
    with pytest.raises(ValueError, match=r"metric 'b': datatype 17 is not supported"):
        payload = tahu.Payload()
        tahu.addMetric(payload, "b", None, T.Bytes, b"\1")
        metric_value(parse(payload.SerializeToString()).metrics[0])


def test_topics_of_the_namespace() -> None:
    """§4.1: namespace/group_id/message_type/edge_node_id[/device_id]."""
    node = SparkplugNode("plant1")
    assert (NAMESPACE, GROUP) == ("spBv1.0", "devsim")
    assert node.topic("NBIRTH") == "spBv1.0/devsim/NBIRTH/plant1"
    assert node.topic("DDATA", "x") == "spBv1.0/devsim/DDATA/plant1/x"
    assert node.topic("DDATA", "") == "spBv1.0/devsim/DDATA/plant1/"
    assert node.filters() == ["spBv1.0/devsim/NCMD/plant1", "spBv1.0/devsim/DCMD/plant1/+"]


@pytest.mark.parametrize(("topic", "target"), [
    ("spBv1.0/devsim/DCMD/p/x", "x"),
    ("spBv1.0/devsim/NCMD/p", None),
])
def test_a_command_topic_names_its_target(topic: str, target: str | None) -> None:
    assert SparkplugNode("p").command_target(topic) == target


@pytest.mark.parametrize("topic", [
    "spBv1.0/devsim/DCMD/p", "spBv1.0/devsim/DCMD/p/x/y", "spBv1.0/devsim/DCMD/q/x", "spBv1.0/other/DCMD/p/x",
    "spBv2.0/devsim/DCMD/p/x", "spBv1.0/devsim/DDATA/p/x", "spBv1.0/devsim/NCMD/p/x", "spBv1.0/devsim/NCMD/q",
    "spBv1.0/devsim/NDATA/p", "other/devsim/NCMD/p", "spBv1.0/x/NCMD/p",
])
def test_any_other_topic_is_no_command(topic: str) -> None:
    with pytest.raises(ValueError, match="not a command topic of node 'p'"):
        SparkplugNode("p").command_target(topic)


def test_a_session_bdseq_and_seq_from_birth_to_death() -> None:
    """§6.4.5 … 6.4.7: NDEATH (the last will) carries bdSeq and no seq; NBIRTH the same bdSeq and
    seq 0; every later payload the next seq."""
    node = SparkplugNode("p")
    topic, will = node.new_session()
    death = parse(will)
    assert topic == "spBv1.0/devsim/NDEATH/p" and not death.HasField("seq")
    assert [(m.name, m.datatype, m.long_value) for m in death.metrics] == [("bdSeq", T.Int64, 0)]
    assert death.timestamp > 0
    topic, birth = node.node_birth()
    nbirth = parse(birth)
    assert topic == "spBv1.0/devsim/NBIRTH/p" and nbirth.seq == 0 and nbirth.timestamp > 0
    assert [(m.name, m.datatype) for m in nbirth.metrics] == [("bdSeq", T.Int64), ("Node Control/Rebirth", T.Boolean)]
    assert nbirth.metrics[0].long_value == 0 and nbirth.metrics[1].boolean_value is False
    device = sers()
    topic, dbirth = node.device_birth(device, {})
    assert topic == "spBv1.0/devsim/DBIRTH/p/sers" and parse(dbirth).seq == 1
    topic, ddeath = node.device_death(device)
    assert topic == "spBv1.0/devsim/DDEATH/p/sers" and parse(ddeath).seq == 2 and not parse(ddeath).metrics
    topic, final = node.death()  # the session's NDEATH as its will said: bdSeq, no seq
    last = parse(final)
    assert topic == "spBv1.0/devsim/NDEATH/p" and not last.HasField("seq")
    assert [(m.name, m.datatype, m.long_value) for m in last.metrics] == [("bdSeq", T.Int64, 0)]
    assert parse(node.device_birth(device, {})[1]).seq == 3  # an NDEATH takes no seq


@settings(deadline=None)  # (the first example may build the module's cached device)
@given(births=st.integers(1, 600))
@example(births=256)
@example(births=257)
def test_seq_wraps_after_255_and_a_node_birth_starts_it_at_0(births: int) -> None:
    node = SparkplugNode("p")
    node.new_session()
    node.node_birth()
    device = sers()
    seqs = [parse(node.device_data(device, {})[1]).seq for _ in range(births)]
    assert seqs == [(n + 1) % 256 for n in range(births)]
    assert parse(node.node_birth()[1]).seq == 0
    assert parse(node.device_data(device, {})[1]).seq == 1


@settings(deadline=None)  # (the first example may build the module's cached device)
@given(sessions=st.integers(1, 600))
@example(sessions=256)
@example(sessions=257)
def test_bdseq_counts_sessions_and_wraps_after_255(sessions: int) -> None:
    node = SparkplugNode("p")
    for _ in range(sessions):
        will = parse(node.new_session()[1])
    expected = (sessions - 1) % 256
    assert will.metrics[0].long_value == expected == node.bd_seq
    assert parse(node.node_birth()[1]).metrics[0].long_value == expected


def test_a_new_session_starts_seq_again() -> None:
    node = SparkplugNode("p")
    node.new_session()
    node.node_birth()
    node.device_data(sers(), {})
    node.new_session()
    assert parse(node.device_data(sers(), {})[1]).seq == 0


def test_dbirth_every_point_with_its_datatype_and_the_command_metrics() -> None:
    """§6.4.9: every declared point (bool → Boolean, int → Int64, float → Double, str and json →
    String), a write-only one or one without a value as null; the writable command metrics."""
    assert DATATYPES == {"bool": T.Boolean, "int": T.Int64, "float": T.Double, "str": T.String, "json": T.String}
    device = sers()
    values = {p.name: device.read(p.name) for p in device.points if p.readable}
    by_name = metrics(device_birth(device, values))
    for point in device.points:
        metric = by_name[point.name]
        assert metric.datatype == DATATYPES[point.type], point.name
        value = values.get(point.name)
        assert metric.is_null == (value is None), point.name
        if value is not None:
            shown = metric_value(metric)
            assert (json.loads(shown) if point.type == "json" else shown) == pytest.approx(value), point.name
    commands = ["Device Control/Power Cycle"] + [f"Device Control/Fault/{k}" for k in device.faults.names()]
    assert list(by_name)[-len(commands):] == commands
    for name in commands:
        assert by_name[name].datatype == T.Boolean and by_name[name].boolean_value is False
    assert len(by_name) == len(list(device.points)) + len(commands)


def device_birth(device: Any, values: dict[str, Any]) -> bytes:
    return SparkplugNode("p").device_birth(device, values)[1]


def test_ddata_carries_what_changed_a_str_that_is_none_or_not_text_as_json() -> None:
    device = sers()
    str_point = next(p.name for p in device.points if p.type == "str")
    json_point = next(p.name for p in device.points if p.type == "json")
    changes = {"axis.position": 1.5, "motion": True, "P11": -3, str_point: 7, json_point: {"a": [1, "b"]}}
    topic, data = SparkplugNode("p").device_data(device, changes)
    assert topic == "spBv1.0/devsim/DDATA/p/sers"
    got = metrics(data)
    assert list(got) == list(changes)
    assert got["axis.position"].double_value == 1.5 and got["motion"].boolean_value is True
    assert metric_value(got["P11"]) == -3
    assert got[str_point].string_value == "7" and json.loads(got[json_point].string_value) == {"a": [1, "b"]}
    assert all(m.timestamp > 0 for m in got.values())
    text = SparkplugNode("p").device_data(device, {str_point: "plain", "motion": None})[1]
    got = metrics(text)
    assert got[str_point].string_value == "plain" and got["motion"].is_null and got["motion"].datatype == T.Boolean


def command(*items: tuple[str, int, Any]) -> bytes:
    payload = tahu.Payload()
    for name, datatype, value in items:
        tahu.addMetric(payload, name, None, datatype, value)
    return bytes(payload.SerializeToString())


def test_a_command_payload_decodes_to_its_metrics() -> None:
    data = command(("input.I1", T.Boolean, True), ("P11", T.Int32, -5), ("param.P0", T.Double, 2.5))
    assert decode_command(data) == [("input.I1", True), ("P11", -5), ("param.P0", 2.5)]


@pytest.mark.parametrize(("data", "why"), [
    (b"\xff\xff\xff", "not a Sparkplug B payload: "),
    (b"\x08", "not a Sparkplug B payload: "),
    (b"\xa2\x06\x01x", "not a Sparkplug B payload: fields its schema does not have"),  # field 100
    (b"", "a Sparkplug B command without metrics"),
    (b"\x08\x01\x18\x02", "a Sparkplug B command without metrics"),  # timestamp and seq only
])
def test_bytes_that_are_no_command_are_refused(data: bytes, why: str) -> None:
    with pytest.raises(ValueError) as refused:
        decode_command(data)
    assert str(refused.value).startswith(why)
    assert refused.value.__cause__ is None
    assert refused.value.__suppress_context__ == (why == "not a Sparkplug B payload: ")  # (protobuf's error hidden)


def test_command_requests() -> None:
    device = sers()
    assert command_request(device, "Device Control/Power Cycle", True) == rq.PowerCycle("sers")
    assert command_request(device, "Device Control/Power Cycle", False) is None
    assert command_request(device, "Device Control/Fault/power", True) == rq.SwitchFault("sers", "power", True)
    assert command_request(device, "Device Control/Fault/power", False) == rq.SwitchFault("sers", "power", False)
    assert command_request(device, "input.I1", True) == rq.Set("sers", "input.I1", True)
    assert command_request(device, "Device Control/Faultx", 1) == rq.Set("sers", "Device Control/Faultx", 1)


def test_timestamps_are_utc_milliseconds_since_the_epoch() -> None:
    """§6.4.1: a payload's and a metric's timestamp, UTC, in milliseconds since the epoch."""
    node = SparkplugNode("p")
    before = int(time.time() * 1000)
    stamps = [parse(node.new_session()[1]).timestamp, parse(node.node_birth()[1]).timestamp]
    data = parse(node.device_data(sers(), {"axis.position": 1.0})[1])
    stamps += [data.timestamp, data.metrics[0].timestamp]
    after = int(time.time() * 1000)
    assert all(before <= stamp <= after for stamp in stamps), (before, stamps, after)


def test_a_command_metrics_birth_datatype() -> None:
    device = sers()
    int_point = next(p.name for p in device.points if p.type == "int")
    assert [birth_datatype(device, name) for name in ("input.I1", "param.P0", int_point, "program",
                                                       "Device Control/Power Cycle", "Device Control/Fault/power")] \
        == [T.Boolean, T.Double, T.Int64, T.String, T.Boolean, T.Boolean]
    assert birth_datatype(device, "Device Control/Fault/nothing") is None and birth_datatype(device, "nothing") is None


def bare_metric(field: str, value: Any) -> Any:
    payload = tahu.Payload()
    metric = payload.metrics.add()
    metric.name = "m"
    setattr(metric, field, value)
    return parse(payload.SerializeToString()).metrics[0]


@pytest.mark.parametrize(("metric", "birth", "value"), [
    (bare_metric("boolean_value", True), T.Boolean, True),  # §6.4.6: no datatype in a DCMD
    (bare_metric("long_value", (1 << 64) - 5), T.Int64, -5),
    (bare_metric("double_value", 2.5), T.Double, 2.5),
    (bare_metric("string_value", "x"), T.String, "x"),
    (one_metric(T.Int32, -5), T.Int64, -5),  # an integer of another width for an Int64
    (one_metric(T.UInt8, 200), T.Int64, 200),
    (one_metric(T.Float, 0.5), T.Double, 0.5),
    (one_metric(T.Text, "t"), T.String, "t"),
    (one_metric(T.Double, 1.5), None, 1.5),  # a name no birth has: as its own datatype
])
def test_a_command_value_is_read_as_its_datatype_or_its_births(metric: Any, birth: int | None, value: Any) -> None:
    assert command_value(metric, birth) == value


@pytest.mark.parametrize(("metric", "birth", "why"), [
    (one_metric(T.Double, 1.0), T.Boolean, "metric 'm': datatype Double, but its DBIRTH's is Boolean"),
    (one_metric(T.String, "true"), T.Boolean, "metric 'm': datatype String, but its DBIRTH's is Boolean"),
    (one_metric(T.Int64, 1), T.Boolean, "metric 'm': datatype Int64, but its DBIRTH's is Boolean"),
    (one_metric(T.Double, 3.0), T.Int64, "metric 'm': datatype Double, but its DBIRTH's is Int64"),
    (one_metric(T.Int64, 3), T.Double, "metric 'm': datatype Int64, but its DBIRTH's is Double"),
    (one_metric(T.Boolean, True), T.String, "metric 'm': datatype Boolean, but its DBIRTH's is String"),
    (bare_metric("double_value", 1.0), T.Boolean, "metric 'm': datatype Boolean, but its value is a double_value"),
    (bare_metric("long_value", 1), None, "metric 'm': no datatype, and no birth names one"),
])
def test_a_command_value_of_another_kind_than_its_births_is_refused(metric: Any, birth: int | None, why: str) -> None:
    """§5, tck-id-operational-behavior-data-commands-dcmd-metric-value: a compatible value only."""
    with pytest.raises(ValueError) as refused:
        command_value(metric, birth)
    assert str(refused.value) == why


def test_a_value_outside_its_datatypes_field_is_refused() -> None:
    payload = tahu.Payload()
    metric = payload.metrics.add()
    metric.name, metric.datatype, metric.long_value = "m", T.Int32, 1  # Int32 lives in int_value
    with pytest.raises(ValueError, match=r"^metric 'm': datatype Int32, but its value is a long_value$"):
        metric_value(parse(payload.SerializeToString()).metrics[0])
    metric.ClearField("long_value")
    with pytest.raises(ValueError, match=r"^metric 'm': datatype Int32, but its value is missing$"):
        metric_value(parse(payload.SerializeToString()).metrics[0])
