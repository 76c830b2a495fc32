"""The member's MQTT packets (devsim.facades.mqtt_wire) at the limits of OASIS MQTT 5.0 (and 3.1.1),
by property, against the standard's rules written here as small oracles:

* a variable byte integer (1.5.5) has one to four bytes, seven bits each, least significant
  first, bit 7 set when another byte follows: 0 … 268,435,455 (Table 1-1's boundaries);
* a UTF-8 string or binary data (1.5.4, 1.5.6) is a two-byte length and 0 … 65,535 bytes;
* a packet identifier (2.2.1) is 1 … 65,535; QoS (3.3.1.2) 0, 1 or 2, both bits set is malformed;
* every property (2.2.2.2, Table 2-4) has an identifier and a value of its type;
* a stream is cut into packets by the fixed header's remaining length (2.1.4), however it
  arrives.
"""

from __future__ import annotations

import struct

import hypothesis.strategies as hs
import pytest
from hypothesis import example, given

from devsim.facades import mqtt_wire as wire

MAX_VARINT = 268_435_455

#: Table 1-1: the boundaries of one, two, three and four bytes
VARINT_TABLE = [(0, "00"), (127, "7f"), (128, "80 01"), (16_383, "ff 7f"), (16_384, "80 80 01"),
                (2_097_151, "ff ff 7f"), (2_097_152, "80 80 80 01"), (268_435_455, "ff ff ff 7f")]


def _varint_oracle(value: int) -> bytes:
    """1.5.5, the standard's own encoding algorithm."""
    out = bytearray()
    while True:
        encoded, value = value % 128, value // 128
        if value > 0:
            encoded |= 128
        out.append(encoded)
        if value == 0:
            return bytes(out)


def _string_oracle(data: bytes) -> bytes:
    return len(data).to_bytes(2, "big") + data


# -- variable byte integers -------------------------------------------------------------------
@pytest.mark.parametrize("value, encoded", VARINT_TABLE)
def test_variable_byte_integers_of_table_1_1(value: int, encoded: str) -> None:
    assert wire._varint(value).hex(" ") == encoded
    assert wire._read_varint(bytes.fromhex(encoded) + b"\xaa", 0) == (value, len(bytes.fromhex(encoded)))


@given(hs.one_of(hs.integers(0, MAX_VARINT), hs.sampled_from([v + d for v, _ in VARINT_TABLE for d in (-1, 0, 1)
                                                                if 0 <= v + d <= MAX_VARINT])))
def test_a_variable_byte_integer_both_ways(value: int) -> None:
    encoded = wire._varint(value)
    assert encoded == _varint_oracle(value)
    assert wire._read_varint(b"\x01" + encoded, 1) == (value, 1 + len(encoded))


@pytest.mark.parametrize("value", [-1, MAX_VARINT + 1, 2**35])
def test_a_variable_byte_integer_beyond_four_bytes_is_refused(value: int) -> None:
    with pytest.raises(ValueError, match="variable byte integer"):
        wire._varint(value)


@pytest.mark.parametrize("data, message", [
    (b"", "cut short"), (b"\x80", "cut short"), (b"\xff\xff\xff", "cut short"),
    (b"\xff\xff\xff\xff", "longer than four"), (b"\x80\x80\x80\x80\x01", "longer than four"),
])
def test_a_variable_byte_integer_cut_short_or_of_five_bytes_is_malformed(data: bytes, message: str) -> None:
    with pytest.raises(wire.MalformedPacket, match=message):
        wire._read_varint(data, 0)


# -- strings, binary data, packet identifiers, QoS ----------------------------------------------
@given(hs.one_of(hs.text(max_size=20), hs.sampled_from(["", "ä/€/𝄞", "x" * 65_535, "ä" * 32_767])))
def test_a_utf8_string_is_its_byte_length_and_bytes(text: str) -> None:
    data = text.encode("utf-8")
    assert wire._string(text) == _string_oracle(data)
    assert wire._read_string(b"\x00" + _string_oracle(data) + b"\x00", 1) == (text, 3 + len(data))


@pytest.mark.parametrize("text", ["x" * 65_536, "ä" * 32_768])
def test_a_string_of_more_than_65535_bytes_is_refused(text: str) -> None:
    with pytest.raises(ValueError, match="at most 65535 bytes"):
        wire._string(text)
    with pytest.raises(ValueError, match="at most 65535 bytes"):
        wire.publish(text, b"")
    with pytest.raises(ValueError, match="at most 65535 bytes"):
        wire.properties(correlation=text.encode())


def test_binary_data_at_its_limit() -> None:
    assert wire._binary(b"\x00" * 65_535)[:2] == b"\xff\xff"
    with pytest.raises(ValueError):
        wire._binary(b"\x00" * 65_536)
    assert wire._read_binary(b"\x00\x03abc", 0) == (b"abc", 5)  # exactly to the end
    with pytest.raises(wire.MalformedPacket, match="cut short"):
        wire._read_binary(b"\x00\x03ab", 0)
    with pytest.raises(wire.MalformedPacket, match="two-byte integer cut short"):
        wire._read_binary(b"\x00", 0)
    with pytest.raises(wire.MalformedPacket, match="not UTF-8"):
        wire._read_string(b"\x00\x02\xc3\x28", 0)


@pytest.mark.parametrize("packet_id", [1, 2, 255, 256, 65_534, 65_535])
def test_packet_identifiers_from_1_to_65535(packet_id: int) -> None:
    high_low = packet_id.to_bytes(2, "big")
    assert wire.puback(packet_id) == b"\x40\x02" + high_low
    assert wire.subscribe(packet_id, "t", 1) == b"\x82\x07" + high_low + b"\x00\x00\x01t\x01"
    assert wire.subscribe(packet_id, "t", 2, v5=False) == b"\x82\x06" + high_low + b"\x00\x01t\x02"
    assert wire.unsubscribe(packet_id, "t") == b"\xa2\x06" + high_low + b"\x00\x00\x01t"
    assert wire.unsubscribe(packet_id, "t", v5=False) == b"\xa2\x05" + high_low + b"\x00\x01t"
    packet = wire.publish("t", b"p", qos=1, packet_id=packet_id)
    assert packet == b"\x32\x07\x00\x01t" + high_low + b"\x00p"
    [(_kind, flags, body)] = wire.PacketReader().feed(packet)
    assert wire.parse_publish(flags, body).packet_id == packet_id


@pytest.mark.parametrize("packet_id", [0, -1, 65_536])
def test_a_packet_identifier_outside_1_to_65535_is_refused(packet_id: int) -> None:
    for build in (lambda: wire.puback(packet_id), lambda: wire.subscribe(packet_id, "t", 0),
                  lambda: wire.unsubscribe(packet_id, "t"), lambda: wire.publish("t", b"", 1, packet_id=packet_id)):
        with pytest.raises(ValueError, match="packet identifier"):
            build()
    assert wire.publish("t", b"", 0, packet_id=packet_id) == b"\x30\x04\x00\x01t\x00"  # QoS 0 has none


def test_a_publish_at_qos_1_needs_its_packet_identifier() -> None:
    with pytest.raises(ValueError, match="packet identifier"):
        wire.publish("t", b"", qos=1)


@pytest.mark.parametrize("qos", [-1, 3, 4])
def test_a_qos_outside_0_to_2_is_refused(qos: int) -> None:
    with pytest.raises(ValueError, match="QoS"):
        wire.publish("t", b"", qos, packet_id=1)
    with pytest.raises(ValueError, match="QoS"):
        wire.subscribe(1, "t", qos)
    with pytest.raises(ValueError, match="QoS"):
        wire.connect("c", 0, will=wire.Will("w", b"", qos=qos))


@given(topic=hs.text(max_size=8), payload=hs.binary(max_size=20), qos=hs.sampled_from([0, 1, 2]), retain=hs.booleans(),
       packet_id=hs.integers(1, 65_535), v5=hs.booleans())
def test_publish_round_trips_at_every_qos(topic: str, payload: bytes, qos: int, retain: bool, packet_id: int,
                                          v5: bool) -> None:
    packet = wire.publish(topic, payload, qos, retain, packet_id, props=b"\x00" if v5 else b"")
    body = _string_oracle(topic.encode()) + (packet_id.to_bytes(2, "big") if qos else b"") + (b"\x00" if v5 else b"")
    assert packet == bytes((0x30 | qos << 1 | retain,)) + _varint_oracle(len(body) + len(payload)) + body + payload
    message = wire.parse_publish(packet[0] & 0x0F, packet[len(packet) - len(body) - len(payload):], v5)
    assert (message.topic, message.payload, message.qos, message.retain) == (topic, payload, qos, retain)
    assert message.packet_id == (packet_id if qos else 0)
    assert (message.response_topic, message.correlation) == (None, None)


@given(topic=hs.text(max_size=8), payload=hs.binary(max_size=300), v5=hs.booleans())
@example(topic="t", payload=b"p" * (127 - 4), v5=True)  # a remaining length of 127, the last of one byte
@example(topic="t", payload=b"p" * (128 - 4), v5=True)  # 128, the first of two
def test_a_publish_on_a_head_is_the_plain_publish(topic: str, payload: bytes, v5: bool) -> None:
    head = wire.publish_head(topic, v5)
    assert head == _string_oracle(topic.encode()) + (b"\x00" if v5 else b"")
    assert wire.publish_headed(head, payload) == wire.publish(topic, payload, props=b"\x00" if v5 else b"")
    assert wire.publish_headed(head, payload) == b"\x30" + _varint_oracle(len(head) + len(payload)) + head + payload


def test_a_head_is_of_mqtt_5_unless_told() -> None:
    assert wire.publish_head("t") == b"\x00\x01t\x00"  # (the member speaks MQTT 5)


def test_a_publish_with_both_qos_bits_or_identifier_0_is_malformed() -> None:
    with pytest.raises(wire.MalformedPacket, match="both QoS bits"):
        wire.parse_publish(0b0110, b"\x00\x01t\x00\x01\x00")
    for qos_flags in (0b0010, 0b0100):
        with pytest.raises(wire.MalformedPacket, match="identifier 0"):
            wire.parse_publish(qos_flags, b"\x00\x01t\x00\x00\x00")
    assert wire.parse_publish(0b0001, b"\x00\x01t\x00\x00\x00").payload == b"\x00\x00"  # QoS 0: no identifier


# -- properties (2.2.2.2) ---------------------------------------------------------------------
#: Table 2-4: identifier -> the type of its value
PROPERTY_TYPES = {
    0x01: "byte", 0x02: "u32", 0x03: "string", 0x08: "string", 0x09: "binary", 0x0B: "varint", 0x11: "u32",
    0x12: "string", 0x13: "u16", 0x15: "string", 0x16: "binary", 0x17: "byte", 0x18: "u32", 0x19: "byte",
    0x1A: "string", 0x1C: "string", 0x1F: "string", 0x21: "u16", 0x22: "u16", 0x23: "u16", 0x24: "byte",
    0x25: "byte", 0x26: "pair", 0x27: "u32", 0x28: "byte", 0x29: "byte", 0x2A: "byte",
}
VALUES = {
    "byte": hs.integers(0, 255), "u16": hs.integers(0, 0xFFFF), "u32": hs.integers(0, 0xFFFF_FFFF),
    "varint": hs.integers(0, MAX_VARINT), "string": hs.text(max_size=6), "binary": hs.binary(max_size=6),
    "pair": hs.tuples(hs.text(max_size=4), hs.text(max_size=4)),
}


def _value_bytes(kind: str, value: object) -> bytes:
    if kind == "byte":
        return bytes((value,))  # type: ignore[arg-type]
    if kind in ("u16", "u32"):
        return int(value).to_bytes(2 if kind == "u16" else 4, "big")  # type: ignore[call-overload]
    if kind == "varint":
        return _varint_oracle(int(value))  # type: ignore[call-overload]
    if kind == "string":
        return _string_oracle(str(value).encode())
    if kind == "binary":
        return _string_oracle(bytes(value))  # type: ignore[call-overload]
    key, val = value  # type: ignore[misc]
    return _string_oracle(key.encode()) + _string_oracle(val.encode())


@hs.composite
def property_lists(draw: hs.DrawFn) -> tuple[bytes, dict[int, object]]:
    """A property list (its varint length first) and what it says, the last of a repeated one."""
    identifiers = draw(hs.lists(hs.sampled_from(sorted(PROPERTY_TYPES)), max_size=6))
    out, found = b"", {}
    for identifier in identifiers:
        kind = PROPERTY_TYPES[identifier]
        value = draw(VALUES[kind])
        out += bytes((identifier,)) + _value_bytes(kind, value)
        found[identifier] = None if kind == "pair" else value
    return _varint_oracle(len(out)) + out, found


@given(property_lists(), hs.binary(max_size=3))
def test_every_property_a_broker_may_send_is_read(listed: tuple[bytes, dict[int, object]], after: bytes) -> None:
    data, found = listed
    assert wire.parse_properties(b"\xaa" + data + after, 1) == (found, 1 + len(data))


@pytest.mark.parametrize("identifier", sorted(PROPERTY_TYPES))
def test_each_property_cut_short_by_its_list_is_malformed(identifier: int) -> None:
    kind = PROPERTY_TYPES[identifier]
    value = _value_bytes(kind, {"byte": 7, "u16": 7, "u32": 7, "varint": 200, "string": "ab", "binary": b"ab",
                                "pair": ("k", "v")}[kind])
    whole = bytes((identifier,)) + value
    assert wire.parse_properties(bytes((len(whole),)) + whole, 0)[1] == 1 + len(whole)
    with pytest.raises(wire.MalformedPacket):  # the list's length ends inside the value
        wire.parse_properties(bytes((len(whole) - 1,)) + whole, 0)
    with pytest.raises(wire.MalformedPacket):  # the packet ends inside the value
        wire.parse_properties(bytes((len(whole),)) + whole[:-1], 0)


@pytest.mark.parametrize("identifier", [0x00, 0x04, 0x14, 0x20, 0x2B, 0xFF])
def test_an_unknown_property_is_malformed(identifier: int) -> None:
    with pytest.raises(wire.MalformedPacket, match=f"unknown property 0x{identifier:02x}"):
        wire.parse_properties(bytes((2, identifier, 0)), 0)


@given(expiry=hs.one_of(hs.none(), hs.integers(0, 0xFFFF_FFFF)), response=hs.one_of(hs.none(), hs.text(max_size=6)),
       correlation=hs.one_of(hs.none(), hs.binary(max_size=6)))
@example(expiry=0xFFFF_FFFF, response="", correlation=b"")
def test_the_properties_devsim_writes(expiry: int | None, response: str | None, correlation: bytes | None) -> None:
    data = wire.properties(expiry, response, correlation)
    body = b""
    if expiry is not None:
        body += b"\x02" + expiry.to_bytes(4, "big")
    if response is not None:
        body += b"\x08" + _string_oracle(response.encode())
    if correlation is not None:
        body += b"\x09" + _string_oracle(correlation)
    assert data == _varint_oracle(len(body)) + body
    kept = {k: v for k, v in ((2, expiry), (8, response), (9, correlation)) if v is not None}
    assert wire.parse_properties(data, 0) == (kept, len(data))
    for retain in (False, True):
        packet = wire.publish("t", b"p", retain=retain, props=data)
        [(_kind, flags, rest)] = wire.PacketReader().feed(packet)
        message = wire.parse_publish(flags, rest)
        assert (message.payload, message.response_topic, message.correlation) == (b"p", response, correlation)
        assert message.retain is retain


@pytest.mark.parametrize("expiry", [-1, 0x1_0000_0000])
def test_an_expiry_that_does_not_fit_four_bytes_is_refused(expiry: int) -> None:
    with pytest.raises(ValueError, match=f"^a message expiry interval is 0 … 4294967295 s, not {expiry}$"):
        wire.properties(expiry=expiry)


def test_other_properties_of_a_publish_are_not_taken_for_the_response() -> None:
    # payload format, topic alias, subscription identifier, message expiry, content type, authentication data
    items = b"\x01\x01" + b"\x23\x00\x05" + b"\x0b\x80\x01" + b"\x02\x00\x00\x00\x3c" + b"\x03\x00\x01j" + b"\x16\x00\x00"
    message = wire.parse_publish(0, b"\x00\x01t" + bytes((len(items),)) + items + b"p")
    assert (message.payload, message.response_topic, message.correlation) == (b"p", None, None)


# -- CONNECT, CONNACK, SUBACK -----------------------------------------------------------------
@given(qos=hs.sampled_from([0, 1, 2]), retain=hs.booleans(), user=hs.booleans(), password=hs.booleans(),
       keepalive=hs.sampled_from([0, 1, 255, 256, 65_535]), v5=hs.booleans(), with_will=hs.booleans())
def test_connect_flags_and_fields(qos: int, retain: bool, user: bool, password: bool, keepalive: int, v5: bool,
                                  with_will: bool) -> None:
    will = wire.Will("w/t", b"bye", qos=qos, retain=retain, expiry=None) if with_will else None
    packet = wire.connect("me", keepalive, will=will, username="u" if user else None,
                          password="pw" if password else None, v5=v5)
    flags = 0x02 | (0x80 if user else 0) | (0x40 if password else 0)  # 3.1.2.3
    if with_will:
        flags |= 0x04 | qos << 3 | (0x20 if retain else 0)
    header = b"\x00\x04MQTT" + bytes((5 if v5 else 4, flags)) + keepalive.to_bytes(2, "big") + (b"\x00" if v5 else b"")
    payload = b"\x00\x02me"
    if with_will:
        payload += (b"\x00" if v5 else b"") + b"\x00\x03w/t\x00\x03bye"
    payload += (b"\x00\x01u" if user else b"") + (b"\x00\x02pw" if password else b"")
    assert packet == b"\x10" + _varint_oracle(len(header) + len(payload)) + header + payload


@pytest.mark.parametrize("keepalive", [-1, 65_536])
def test_a_keep_alive_that_does_not_fit_two_bytes_is_refused(keepalive: int) -> None:
    with pytest.raises(ValueError, match="keep alive"):
        wire.connect("me", keepalive)


@pytest.mark.parametrize("body, v5, expected", [
    (b"\x00\x00", True, (0, {})),  # no property length at all
    (b"\x01\x00\x00", True, (0, {})),
    (b"\x00\x87\x00", True, (0x87, {})),
    (b"\x00\x00\x03\x21\x00\x0a", True, (0, {0x21: 10})),  # receive maximum
    (b"\x00\x00", False, (0, {})),
    (b"\x00\x01", False, (0x81, {})),  # 3.1.1: return code 1, unacceptable protocol version
    (b"\x00\x02", False, (0x82, {})),
    (b"\x00\x04", False, (0x84, {})),
    (b"\x00\x05", False, (0x85, {})),
    (b"\x00\x00\x03\x13\x00\x3c", False, (0, {})),  # 3.1.1 has no properties
])
def test_connack(body: bytes, v5: bool, expected: tuple[int, dict[int, object]]) -> None:
    reason, props = wire.parse_connack(body, v5)
    assert (reason, {k: v for k, v in props.items() if v is not None}) == expected


@pytest.mark.parametrize("body", [b"", b"\x00"])
def test_a_connack_of_less_than_two_bytes_is_malformed(body: bytes) -> None:
    for v5 in (True, False):
        with pytest.raises(wire.MalformedPacket, match="CONNACK"):
            wire.parse_connack(body, v5)


@pytest.mark.parametrize("code, refused", [(0x00, None), (0x01, None), (0x02, None), (0x7F, None), (0x80, 0x80),
                                           (0x87, 0x87), (0xA2, 0xA2)])
def test_a_suback_refuses_with_a_code_from_80h(code: int, refused: int | None) -> None:
    assert wire.suback_refused(b"\x00\x01\x00" + bytes((code,))) == refused
    assert wire.suback_refused(b"\x00\x01\x03\x1f\x00\x00" + bytes((code, 0x80))) == refused  # a reason string first
    assert wire.suback_refused(b"\x00\x01" + bytes((code,)), v5=False) == refused


@pytest.mark.parametrize("body, v5", [(b"\x00\x01\x00", True), (b"\x00\x01", False)])
def test_a_suback_without_a_reason_code_is_malformed(body: bytes, v5: bool) -> None:
    with pytest.raises(wire.MalformedPacket, match="without a reason code"):
        wire.suback_refused(body, v5)


# -- the stream -------------------------------------------------------------------------------
@pytest.mark.parametrize("size", [0, 1, 127, 128, 16_383, 16_384])
def test_a_packet_of_each_remaining_length_boundary_however_it_arrives(size: int) -> None:
    body = bytes(i % 251 for i in range(size))
    packet = b"\x30" + _varint_oracle(size) + body
    cuts = sorted({0, 1, 2, 3, 4, len(packet) - 1, len(packet)} & set(range(len(packet) + 1)))
    for cut in cuts:
        reader = wire.PacketReader()
        assert reader.feed(packet[:cut]) + reader.feed(packet[cut:] + b"\xd0") + reader.feed(b"\x00") == [
            (3, 0, body), (13, 0, b"")]


def test_a_remaining_length_still_arriving_waits_and_one_of_five_bytes_is_malformed() -> None:
    reader = wire.PacketReader()
    assert reader.feed(b"\x30\xff\xff\xff") == []  # four bytes: the length may still come
    assert reader.feed(b"\x7f") == []  # 268,435,455: the body may still come
    with pytest.raises(wire.MalformedPacket, match="longer than four"):
        wire.PacketReader().feed(b"\x30\xff\xff\xff\xff")
    with pytest.raises(wire.MalformedPacket, match="longer than four"):
        wire.PacketReader().feed(b"\xd0\x00" + b"\x30\x80\x80\x80\x80")  # after a whole packet
    reader = wire.PacketReader()
    assert reader.feed(b"\xd0\x00" + b"\x30\x80\x80\x80") == [(13, 0, b"")]  # and one still arriving
    assert reader.feed(b"\x01") == []


def test_a_two_byte_remaining_length_cut_after_its_first_byte_waits_after_a_whole_packet() -> None:
    body = bytes(range(128))
    reader = wire.PacketReader()
    assert reader.feed(b"\xd0\x00" + b"\x30\x80") == [(13, 0, b"")]  # 128: 0x80 0x01, the 0x01 still to come
    assert reader.feed(b"\x01" + body) == [(3, 0, body)]


@given(hs.lists(hs.tuples(hs.sampled_from([0x30, 0x31, 0x40, 0x90, 0xB0, 0xD0, 0xE0]), hs.binary(max_size=200)),
                max_size=5), hs.lists(hs.integers(0, 1200), max_size=4))
def test_a_stream_cut_anywhere_gives_its_packets(packets: list[tuple[int, bytes]], cuts: list[int]) -> None:
    stream = b"".join(bytes((first,)) + _varint_oracle(len(body)) + body for first, body in packets)
    reader = wire.PacketReader()
    got: list[tuple[int, int, bytes]] = []
    last = 0
    for cut in [*sorted(c for c in cuts if c <= len(stream)), len(stream)]:
        got += reader.feed(stream[last:cut])
        last = cut
    assert got == [(first >> 4, first & 0x0F, body) for first, body in packets]
    assert reader.feed(b"") == []


def test_a_varint_packed_struct_agrees() -> None:
    """The two-byte fields written with struct are big-endian (1.5.2)."""
    assert struct.pack("!H", 258) == b"\x01\x02" == wire.puback(258)[2:]


# -- what the user reads: "malformed packet from the broker: <this>" ----------------------------
@pytest.mark.parametrize("parse, message", [
    (lambda: wire._read_varint(b"\x80", 0), "variable byte integer cut short"),
    (lambda: wire._read_varint(b"\x80\x80\x80\x80\x00", 0), "variable byte integer longer than four bytes"),
    (lambda: wire._read_byte(b"\x01", 1), "byte cut short"),
    (lambda: wire._read_u16(b"\x01", 0), "two-byte integer cut short"),
    (lambda: wire._read_u32(b"\x00\x00\x00", 0), "four-byte integer cut short"),
    (lambda: wire._read_u32(b"\x00\x00\x00\x00\x00", 2), "four-byte integer cut short"),
    (lambda: wire._read_binary(b"\x00\x02a", 0), "string or binary data cut short"),
    (lambda: wire._read_binary(b"\x00", 0), "two-byte integer cut short"),  # its length cut short
    (lambda: wire._read_string(b"\x00\x01\xff", 0), "a string that is not UTF-8"),
    (lambda: wire.parse_properties(b"\x02\x01", 0), "property list cut short"),
    (lambda: wire.parse_properties(b"\x01\x02\x00\x00\x00\x00", 0), "property list overruns its length"),
    (lambda: wire.parse_properties(b"\x01\x02\x00", 0), "four-byte integer cut short"),
    (lambda: wire.parse_properties(b"\x02\x04\x00", 0), "unknown property 0x04"),
    (lambda: wire.parse_publish(0b0110, b"\x00\x01t\x00\x01"), "a PUBLISH with both QoS bits set"),
    (lambda: wire.parse_publish(0b0010, b"\x00\x01t\x00\x00"), "a PUBLISH at QoS 1 or 2 with packet identifier 0"),
    (lambda: wire.parse_connack(b"\x00"), "CONNACK cut short"),
    (lambda: wire.parse_connack(b"\x00\x00\x05"), "property list cut short"),  # three bytes, properties promised
    (lambda: wire.suback_refused(b"\x00\x01\x00"), "SUBACK without a reason code"),
])
def test_each_malformed_packet_says_what_is_wrong(parse: object, message: str) -> None:
    with pytest.raises(wire.MalformedPacket) as raised:
        parse()  # type: ignore[operator]
    assert str(raised.value) == message


HEAD = wire.publish_head("f/p1/request")


@pytest.mark.parametrize("payload", [b"", b"x", bytes(128 - len(HEAD) - 1), bytes(128 - len(HEAD)),
                                     bytes(200), bytes(16383 - len(HEAD))],
                         ids=["empty", "one byte", "remaining 127", "remaining 128", "200 bytes", "remaining 16383"])
def test_a_single_publish_on_a_head_gives_its_payload_as_feed_does(payload: bytes) -> None:
    packet = wire.publish_headed(HEAD, payload)
    assert wire.PacketReader().single_publish(packet, HEAD) == payload
    [(kind, flags, body)] = wire.PacketReader().feed(packet)
    assert (kind, flags, body[len(HEAD):]) == (wire.PUBLISH, 0, payload)


@pytest.mark.parametrize("data", [
    b"", b"\x30", b"\x30\x80",  # cut short: a header, a length still arriving
    wire.publish_headed(HEAD, bytes(16384 - len(HEAD))),  # a remaining length of three bytes
    wire.publish_headed(HEAD, bytes(2_097_152 - len(HEAD))),  # of four
    wire.publish_headed(HEAD, b"req")[:-1],  # the payload cut short
    wire.publish_headed(HEAD, b"req") + b"\xc0",  # more than the one packet
    wire.publish_headed(HEAD, b"req") * 2,
    b"\x31" + wire.publish_headed(HEAD, b"req")[1:],  # retained
    b"\x32" + wire.publish_headed(HEAD, b"req")[1:],  # QoS 1
    b"\x20" + wire.publish_headed(HEAD, b"req")[1:],  # a CONNACK's type
    wire.publish_headed(wire.publish_head("f/p1/requesT"), b"req"),  # another topic
    wire.publish_headed(wire.publish_head("f/p1/request/x"), b"req"),
    wire.publish("f/p1/request", b"req", props=wire.properties(correlation=b"c")),  # with properties
], ids=["empty", "header", "length cut", "three-byte length", "four-byte length", "payload cut", "and a byte", "two packets",
        "retained", "qos 1", "connack", "another topic", "a longer topic", "properties"])
def test_anything_else_is_not_a_single_publish(data: bytes) -> None:
    assert wire.PacketReader().single_publish(data, HEAD) is None


def test_a_single_publish_after_bytes_held_from_a_read_is_not_taken() -> None:
    packet = wire.publish_headed(HEAD, b"req")
    reader = wire.PacketReader()
    assert reader.feed(packet[:1]) == []
    assert reader.single_publish(packet, HEAD) is None  # (it is the rest of the held packet's)
    assert reader.feed(packet[1:]) == [(wire.PUBLISH, 0, packet[2:])]
    assert reader.single_publish(packet, HEAD) == b"req"


@given(hs.binary(max_size=300), hs.integers(-3, 3), hs.booleans())
def test_a_single_publish_is_what_feed_cuts(payload: bytes, trim: int, headed: bool) -> None:
    data = wire.publish_headed(HEAD, payload) if headed else payload
    data = data[:len(data) + trim] if trim < 0 else data + bytes(trim)
    taken = wire.PacketReader().single_publish(data, HEAD)
    if taken is not None:
        assert wire.PacketReader().feed(data) == [(wire.PUBLISH, 0, HEAD + taken)]
    assert (taken == payload) == (headed and not trim)
