"""A member's fast path of reads and sets (devsim.fleet.answers) answers every request byte for
byte as the generic way (the control API's answer_parsed) does, and sees a device replaced, a
power cycle and the passing of time.  In process: two runtimes with the same devices, one member
each (not connected), the second one's fast path switched off."""

from __future__ import annotations

import json
import socket
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from devsim.facades.mqtt_link import MqttLink
from devsim.facades.mqtt_wire import PacketReader, parse_publish
from devsim.fleet.member import FleetMember
from devsim.fleet.topics import parse_fleet_url
from devsim.runtime import Runtime

URL = parse_fleet_url("mqtt://127.0.0.1:1883/answers")
REPLY = "devsim-fleet/answers/client/c1/reply"


def _runtime() -> Runtime:
    rt = Runtime(virtual=True).start()
    rt.add_device("sers", "d0")
    rt.add_device("sers", "d1")
    rt.add_device("gms96", "g0")
    return rt


@pytest.fixture
def pair(monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[Runtime, FleetMember, Runtime, FleetMember, list[bytes]]]:
    """(fast runtime, its member, generic runtime, its member, the requests the fast path took)."""
    fast_rt, generic_rt = _runtime(), _runtime()
    try:
        fast = fast_rt.call(lambda: FleetMember(fast_rt, URL, process="p0"))
        generic = generic_rt.call(lambda: FleetMember(generic_rt, URL, process="p0"))
        monkeypatch.setattr(generic.resolved, "answer", lambda raw: None)
        taken: list[bytes] = []
        answer = fast.resolved.answer

        def counted(raw: bytes) -> Any:
            found = answer(raw)
            if found is not None:
                taken.append(raw)
            return found

        monkeypatch.setattr(fast.resolved, "answer", counted)
        yield fast_rt, fast, generic_rt, generic, taken
    finally:
        fast_rt.stop()
        generic_rt.stop()


def ask(rt: Runtime, member: FleetMember, raw: bytes, reply_to: str | None = None,
        correlation: bytes | None = None) -> Any:
    """The member's answer to one request, in its runtime's loop (where it takes requests)."""
    return rt.call(member.answer, raw, reply_to, correlation)


def request(**fields: Any) -> bytes:
    return json.dumps({"reply_to": REPLY, **fields}).encode()


READ = {"op": "read", "device": "d0", "name": "input.I1"}
SET = {"op": "set", "device": "d0", "name": "quantity.adc_volts"}

#: Requests the fast path takes (a read or a set of a point that resolves), in order: sets change
#: what later reads see, errors of the op's own (a bad value) are answered by the fast path too.
TAKEN = [
    request(id="c1-1", **READ),
    request(id=7, **READ),
    request(id=None, **READ),
    request(**READ),
    request(id=2**70, **READ),
    request(id="ä-ünïcode", **READ),
    json.dumps({"id": "ä-ünïcode", **READ, "reply_to": REPLY}, ensure_ascii=False).encode(),
    request(id="s1", op="set", device="d0", name="input.I1", value=True),
    request(id="s2", **READ),
    request(id="s3", **SET, value=2.5),
    request(id="s4", op="read", device="d0", name="quantity.adc_volts"),
    request(id="s5", **SET, value="1.25"),
    request(id="s6", op="read", device="d0", name="quantity.adc_volts"),
    request(id="b1", **SET, value=9.9),
    request(id="b2", **SET, value=-1),
    request(id="b3", **SET, value="many"),
    request(id="b4", **SET, value=None),
    request(id="b5", **SET, value=True),
    request(id="b6", op="set", device="d0", name="input.I2", value="maybe"),
    request(id="b7", op="set", device="d0", name="input.I2", value=2),
    request(id="r1", op="read", device="d0", name="axis.position"),
    request(id="r2", op="read", device="d1", name="display"),
    request(id="r3", op="read", device="d1", name="param.P41"),
    request(id="r4", op="set", device="d1", name="param.P41", value=1000),
    request(id="r5", op="read", device="d1", name="param.P41"),
    request(id="r6", op="read", device="g0", name="ready"),
    request(id="r7", op="read", device="d0", name="program"),
    json.dumps({"op": "read", "device": "d0", "name": "input.I1", "id": "spaced", "reply_to": REPLY},
               indent=2).encode(),
]

#: Requests the fast path declines: the generic way answers them (errors, other ops, other shapes).
DECLINED = [
    request(id="e1", op="read", device="nope", name="input.I1"),
    request(id="e2", op="read", device="d0", name="input.I99"),
    request(id="e3", op="read", device="d0", name="encoder.pulses"),
    request(id="e4", op="set", device="d0", name="axis.position", value=1.0),
    request(id="e5", op="read", device="", name="input.I1"),
    request(id="e6", op="read", device="d0", name=""),
    request(id="e7", op="read", device=3, name="input.I1"),
    request(id=True, **READ),
    request(id=1.5, **READ),
    request(id=[1], **READ),
    request(id="e8", **READ, value=1),
    request(id="e9", **READ, extra=1),
    request(id="e10", **SET),
    request(id="e11", **SET, value=[1, 2]),
    request(id="e12", **SET, value={"v": 1}),
    request(id="e13", op="set", device="d0", name="program", value=["VA1000"]),
    request(id="e14", op="read", device="d0", name="line.settings"),
    request(id="e15", op="state", device="d0"),
    request(id="e16", op="nope", device="d0", name="input.I1"),
    request(id="e17", op="read", device="d0"),
    request(id="e18", op="read", name="input.I1"),
    json.dumps({"id": "e19", "op": "read", "device": "d0", "name": "input.I1", "stream_to": REPLY,
                "reply_to": REPLY}).encode(),
    b'{"id": "e20", "op": "read", "device": "d0", "name": "input.I1", "reply_to": "' + REPLY.encode() + b'", "x": NaN}',
    b'{"id": "e21", "op": "read", "device": "d0", "name": "input.I1"',
    b"[" * 100 + b"]" * 100,
    b"",
    b"not json",
]


def test_the_fast_path_answers_as_the_generic_way(pair: Any) -> None:
    fast_rt, fast, generic_rt, generic, taken = pair
    for raw in TAKEN + DECLINED:
        assert ask(fast_rt, fast, raw) == ask(generic_rt, generic, raw), raw
    assert taken == TAKEN  # (else the comparison above compared the generic way with itself)
    assert ask(fast_rt, fast, TAKEN[0]) == (REPLY, b'{"id":"c1-1","ok":true,"result":true}\n', None)
    assert ask(fast_rt, fast, request(id="b1", **SET, value=9.9))[1] == (
        b'{"id":"b1","ok":false,"error":"quantity.adc_volts: 9.9 is above the maximum 5 V","type":"BadValue"}\n')


def routed(rt: Runtime, member: FleetMember, raw: bytes) -> list[tuple[str, bytes]]:
    """(topic, payload) of what the member publishes for a request its link hands over straight
    from a read (no MQTT 5 properties: ``FleetMember._requested``), read back from the link's
    socket (a real MqttLink on a socket pair, in the runtime's loop)."""
    def run() -> list[tuple[str, bytes]]:
        ours, theirs = socket.socketpair()
        link = MqttLink(ours, 15)
        try:
            member._requested(link, raw)
            link.flush()
            theirs.setblocking(False)
            try:
                data = theirs.recv(1 << 20)
            except BlockingIOError:
                data = b""
        finally:
            link.abort()
            theirs.close()
        messages = [parse_publish(flags, body) for kind, flags, body in PacketReader().feed(data)]
        return [(message.topic, message.payload) for message in messages]

    return rt.call(run)


def test_a_request_handed_over_by_the_link_is_answered_as_answer_answers_it(pair: Any) -> None:
    fast_rt, fast, generic_rt, generic, taken = pair
    for raw in TAKEN + DECLINED:
        answer = ask(generic_rt, generic, raw)
        assert routed(fast_rt, fast, raw) == ([] if answer is None else [answer[:2]]), raw
    assert taken == TAKEN
    assert fast.served == len(TAKEN + DECLINED)


@pytest.mark.parametrize(("raw", "reply_to", "correlation"), [
    (request(id="t1", **READ), None, None),
    (json.dumps({"id": "t2", **READ}).encode(), REPLY, b"\x00corr"),  # MQTT 5 response topic, correlation data
    (json.dumps({"id": "t3", **READ}).encode(), None, None),  # no reply topic: executed, not answered
    (json.dumps({"id": "t4", **READ, "reply_to": None}).encode(), REPLY, None),  # the JSON's wins
    (json.dumps({"id": "t5", **READ, "reply_to": "elsewhere/x"}).encode(), REPLY, None),  # outside client/
    (json.dumps({"id": "t6", **READ, "reply_to": ["a"]}).encode(), REPLY, None),
    (json.dumps({"id": "t7", **READ, "reply_to": "devsim-fleet/answers/client/#"}).encode(), None, None),
])
def test_reply_topics_as_the_generic_way(pair: Any, raw: bytes, reply_to: str | None, correlation: bytes | None) -> None:
    fast_rt, fast, generic_rt, generic, taken = pair
    assert ask(fast_rt, fast, raw, reply_to, correlation) == ask(generic_rt, generic, raw, reply_to, correlation)
    assert taken == [raw]


def _replace_d0(kind: str) -> Callable[[Runtime], Any]:
    def replace(rt: Runtime) -> None:
        rt.devices.pop("d0").close()
        rt.add_device(kind, "d0")

    return replace


def _advance(rt: Runtime) -> Any:
    return rt.advance(5.0)


def _power_cycle(rt: Runtime) -> None:
    rt.devices["d0"].power_cycle()


def _remove(rt: Runtime) -> None:
    rt.devices.pop("d0").close()


def _result(answer: Any) -> Any:
    body = json.loads(answer[1])
    return body["result"] if body["ok"] else body["type"]


@pytest.mark.parametrize(("setup", "change", "name", "before", "after"), [
    (_advance, _power_cycle, "booting", False, True),
    (None, _advance, "booting", True, False),
    (None, _replace_d0("sers"), "quantity.adc_volts", 3.0, 0.0),  # the same points, another device
    (None, _replace_d0("gms96"), "quantity.adc_volts", 3.0, "UnknownName"),
    (None, _remove, "quantity.adc_volts", 3.0, "UnknownDevice"),
], ids=["power cycle", "time", "replaced", "replaced by another kind", "removed"])
def test_a_change_is_seen(pair: Any, setup: Callable[[Runtime], Any] | None, change: Callable[[Runtime], Any],
                          name: str, before: Any, after: Any) -> None:
    fast_rt, fast, generic_rt, generic, taken = pair
    read = request(id="m", op="read", device="d0", name=name)
    for raw in [request(id="s", op="set", device="d0", name="quantity.adc_volts", value=3.0), read]:
        assert ask(fast_rt, fast, raw) == ask(generic_rt, generic, raw)
    for rt in (fast_rt, generic_rt):
        if setup is not None:
            rt.call(setup, rt)
    answer = ask(fast_rt, fast, read)
    assert (_result(answer), answer) == (before, ask(generic_rt, generic, read))
    for rt in (fast_rt, generic_rt):
        rt.call(change, rt)
    answer = ask(fast_rt, fast, read)
    assert (_result(answer), answer) == (after, ask(generic_rt, generic, read))
