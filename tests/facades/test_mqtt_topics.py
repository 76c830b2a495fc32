"""The MQTT facade's pure parts (issue 14): broker URLs, command topics, payload reading, and the
Sparkplug metric values (signed integers travel as two's complement)."""

from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tahutils.tahu import sparkplug_b as tahu

from devsim.core.clock import VirtualClock
from devsim.core.registry import device_class
from devsim.facades.mqtt_sparkplug import SparkplugNode, metric_value
from devsim.facades.mqtt_topics import (
    COMMANDS,
    DEFAULT_PORT,
    birth,
    check_name,
    command_filters,
    decode_value,
    encode,
    error_payload,
    parse_command,
    parse_url,
    prefix,
    state_topic,
)
from devsim.runtime import requests as rq


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
    for topic in ("devsim/q/x/set/a", "devsim/p/x/state/a", "other/p/x/set/a", "devsim/p/x"):
        assert parse_command(topic, "p") is None, topic


@pytest.mark.parametrize(("topic", "shape"), [
    ("devsim/p/x/set", "set/<point>"), ("devsim/p/x/set/", "set/<point>"), ("devsim/p/x/set/input/I1", "set/<point>"),
    ("devsim/p/x/fault/a/b", "fault/<kind>"), ("devsim/p/x/power_cycle/now", "power_cycle"),
])
def test_a_command_with_levels_too_many_or_too_few_is_refused(topic: str, shape: str) -> None:
    found = parse_command(topic, "p")
    assert found is not None and found[0] == "x"
    with pytest.raises(ValueError, match=f"topic ends in {shape}$"):
        found[1](None, found[2], b"true")  # type: ignore[arg-type]


def test_payloads_are_json_or_plain_text() -> None:
    assert decode_value(b"true") is True
    assert decode_value(b" 12.5 ") == 12.5
    assert decode_value(b'{"a": [1, 2]}') == {"a": [1, 2]}
    assert decode_value(b"hello") == "hello"
    assert decode_value(b"42", "str") == "42"  # a text point gets the text it was sent
    assert decode_value(b'"42"', "str") == "42"
    assert decode_value(b"[" * 100_000) == "[" * 100_000  # (a RecursionError went to the error topic)
    # blanks are JSON's four: a number between other spaces is text (which a number point refuses)
    assert decode_value("\u00a012.5".encode()) == "\u00a012.5"
    assert decode_value(b"\x1c12\x1f") == "\x1c12\x1f"
    assert decode_value("\u3000true\u0085".encode()) == "\u3000true\u0085"


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


# -- the rest of the convention, by value (issue 35: mutation run) --------------------------------

#: No deadline, no speed health check: a loaded machine (or a mutation run) must not fail these.
BOUNDARY = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])


def test_more_broker_urls() -> None:
    assert DEFAULT_PORT == 1883
    assert parse_url("tcp://h:1") == ("h", 1)
    assert parse_url("mqtt://h/") == ("h", 1883)
    for url in ("mqtt://h:x", "ftp://h", "mqtt://:5"):
        with pytest.raises(ValueError) as err:
            parse_url(url)
        assert str(err.value) == f"expected mqtt://HOST[:PORT], not {url!r}"


@BOUNDARY
@given(st.text(max_size=6))
def test_names_are_one_topic_level(name: str) -> None:
    """Oracle (MQTT 3.1.1 §4.7: '/' separates levels, '+' and '#' are wildcards; NUL is not
    allowed): a name is taken when it is not empty and has none of them."""
    ok = bool(name) and not any(c in name for c in "/+#\0")
    if ok:
        assert check_name("device", name) == name
    else:
        with pytest.raises(ValueError) as err:
            check_name("device", name)
        assert str(err.value) == f"an MQTT device name is one topic level (no '/', '+', '#'), not {name!r}"


def test_topics_and_values() -> None:
    assert prefix("p", "d") == "devsim/p/d"
    assert state_topic("p", "d", "axis.position") == "devsim/p/d/state/axis.position"
    assert encode({"a": [1, 2.5, None, True]}) == b'{"a":[1,2.5,null,true]}'
    assert decode_value(b"\xff") == "\ufffd"  # broken UTF-8 is replaced, not refused
    assert command_filters("p", ["a", "b"]) == [
        "devsim/p/a/set/#", "devsim/p/a/fault/#", "devsim/p/a/power_cycle/#",
        "devsim/p/b/set/#", "devsim/p/b/fault/#", "devsim/p/b/power_cycle/#",
    ]


@BOUNDARY
@given(st.integers(495, 505), st.sampled_from(["value", "key"]))
def test_error_payloads_cut_at_500_characters(length: int, kind: str) -> None:
    message = "m" * length
    exc: BaseException = KeyError(message) if kind == "key" else ValueError(message)
    data = json.loads(error_payload("devsim/p/d/set/x", exc))
    assert data == {"topic": "devsim/p/d/set/x", "error": message[:500], "type": type(exc).__name__}


def test_error_payload_of_a_key_error_with_more_arguments() -> None:
    data = json.loads(error_payload("t", KeyError("a", "b")))
    assert data["error"] == "('a', 'b')"


@pytest.fixture
def sers():  # type: ignore[no-untyped-def]
    device = device_class("sers")(clock=VirtualClock(), name="x")
    yield device
    device.close()


def test_birth_lists_points_and_faults(sers) -> None:  # type: ignore[no-untyped-def]
    data = birth(sers, 0.5)
    assert (data["device"], data["kind"], data["rate"]) == ("x", "sers", 0.5)
    assert data["faults"] == list(sers.faults.names()) and data["faults"]
    first = next(iter(sers.points))
    assert data["points"][0] == {"name": first.name, "type": first.type, "unit": first.unit,
                                 "access": first.access, "doc": first.doc}
    assert len(data["points"]) == len(sers.points)


def test_commands_become_requests(sers) -> None:  # type: ignore[no-untyped-def]
    set_, fault, power = (COMMANDS[v][0] for v in ("set", "fault", "power_cycle"))
    assert [COMMANDS[v][1] for v in ("set", "fault", "power_cycle")] == [True, True, False]
    assert set_(sers, "input.I1", b"true") == rq.Set("x", "input.I1", True)
    assert set_(sers, "nothing", b"42") == rq.Set("x", "nothing", 42)  # unknown: refused later, by the op
    text_point = next(p for p in sers.points if p.type == "str")
    assert set_(sers, text_point.name, b"42") == rq.Set("x", text_point.name, "42")
    assert fault(sers, "power", b"on") == rq.SwitchFault("x", "power", True)
    assert fault(sers, "power", b"0") == rq.SwitchFault("x", "power", False)
    assert power(sers, "", b"") == rq.PowerCycle("x", False)
    assert power(sers, "", b"  ") == rq.PowerCycle("x", False)
    assert power(sers, "", b'{"wipe": true}') == rq.PowerCycle("x", True)
    assert power(sers, "", b"{}") == rq.PowerCycle("x", False)
    for payload in (b'{"wipe": true, "x": 1}', b"[1]", b"true"):
        with pytest.raises(ValueError) as err:
            power(sers, "", payload)
        assert str(err.value) == 'power_cycle takes an empty payload or {"wipe": true}'


def test_command_topic_parts() -> None:
    found = parse_command("devsim/p/x/set/input.I1", "p")
    assert found is not None and found[1] is COMMANDS["set"][0]
    assert parse_command("devsim/p/x/fault/power", "p")[1:] == (COMMANDS["fault"][0], "power")  # type: ignore[index]
    assert parse_command("devsim/p/x/power_cycle", "p") == ("x", COMMANDS["power_cycle"][0], "")
    for topic in ("devsim/p/x", "devsim/p/x/nothing/a", "Devsim/p/x/set/a"):
        assert parse_command(topic, "p") is None, topic
    misshapen = parse_command("devsim/p/x/fault/a/b", "p")  # (refused: test above)
    assert misshapen is not None and misshapen[1] is not COMMANDS["fault"][0]
