"""The MQTT facade's pure parts (issue 14): broker URLs, command topics, payload reading, and the
Sparkplug metric values (signed integers travel as two's complement)."""

from __future__ import annotations

import pytest
from tahutils.tahu import sparkplug_b as tahu

from devsim.core.clock import VirtualClock
from devsim.core.registry import device_class
from devsim.facades.mqtt_sparkplug import SparkplugNode, metric_value
from devsim.facades.mqtt_topics import decode_value, parse_command, parse_url


@pytest.mark.parametrize(("url", "where"), [
    ("mqtt://127.0.0.1:1884", ("127.0.0.1", 1884)),
    ("mqtt://broker.local", ("broker.local", 1883)),
    ("10.0.0.5:2000", ("10.0.0.5", 2000)),
])
def test_broker_urls(url: str, where: tuple[str, int]) -> None:
    assert parse_url(url) == where


@pytest.mark.parametrize("url", ["http://x", "mqtt://", "mqtt://x:99999", "mqtt://x/y"])
def test_bad_broker_urls(url: str) -> None:
    with pytest.raises(ValueError, match="expected mqtt://HOST"):
        parse_url(url)


def test_command_topics() -> None:
    device, _handler, arg = parse_command("devsim/p/x/set/input.I1", "p") or ("", None, "")
    assert (device, arg) == ("x", "input.I1")
    assert parse_command("devsim/p/x/power_cycle", "p") is not None
    for topic in ("devsim/q/x/set/a", "devsim/p/x/set", "devsim/p/x/power_cycle/now", "devsim/p/x/state/a",
                  "other/p/x/set/a"):
        assert parse_command(topic, "p") is None, topic


def test_payloads_are_json_or_plain_text() -> None:
    assert decode_value(b"true") is True
    assert decode_value(b" 12.5 ") == 12.5
    assert decode_value(b'{"a": [1, 2]}') == {"a": [1, 2]}
    assert decode_value(b"hello") == "hello"
    assert decode_value(b"42", "str") == "42"  # a text point gets the text it was sent
    assert decode_value(b'"42"', "str") == "42"


@pytest.mark.parametrize(("datatype", "value"), [
    (tahu.MetricDataType.Int64, -5), (tahu.MetricDataType.Int32, -70000), (tahu.MetricDataType.Int16, -2),
    (tahu.MetricDataType.Int8, -128), (tahu.MetricDataType.UInt32, 4_000_000_000),
    (tahu.MetricDataType.Double, -0.25), (tahu.MetricDataType.String, "ON"),
])
def test_sparkplug_metric_values_round_trip(datatype: int, value: object) -> None:
    payload = tahu.Payload()
    tahu.addMetric(payload, "m", None, datatype, value)
    decoded = tahu.Payload.FromString(payload.SerializeToString())
    assert metric_value(decoded.metrics[0]) == value


def test_sparkplug_sequence_numbers_wrap_and_bdseq_counts_sessions() -> None:
    device = device_class("sers")(clock=VirtualClock(), name="x")
    node = SparkplugNode("p")
    node.new_session()
    assert node.bd_seq == 0
    seqs = [tahu.Payload.FromString(node.node_birth()[1]).seq]
    for _ in range(300):
        topic, data = node.device_data(device, {"input.I1": True})
        seqs.append(tahu.Payload.FromString(data).seq)
    assert topic == "spBv1.0/devsim/DDATA/p/x"
    assert seqs[:3] == [0, 1, 2] and seqs[256] == 0 and max(seqs) == 255
    death = tahu.Payload.FromString(node.new_session()[1])
    assert node.bd_seq == 1 and metric_value(death.metrics[0]) == 1
    device.close()
