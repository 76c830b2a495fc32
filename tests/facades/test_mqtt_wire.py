"""The member's MQTT 5 packets (devsim.facades.mqtt_wire) against the bytes of OASIS MQTT 5.0 and a
stream cut at every byte; the exchange with a real broker is what tests/fleet's other tests do."""

from __future__ import annotations

import pytest

from devsim.facades import mqtt_wire as wire


def test_connect_with_a_will_and_credentials() -> None:
    will = wire.Will("t/w", b"gone", qos=1, retain=True, expiry=86400)
    packet = wire.connect("id", 15, will=will, username="u", password="p")
    assert packet[0] == 0x10 and packet[1] == len(packet) - 2
    body = packet[2:]
    assert body[:7] == b"\x00\x04MQTT\x05"
    assert body[7] == 0x80 | 0x40 | 0x20 | 0x08 | 0x04 | 0x02  # user, password, will retain, QoS 1, will, clean
    assert body[8:10] == b"\x00\x0f" and body[10] == 0  # keep alive 15, no properties
    assert body[11:15] == b"\x00\x02id"
    assert body[15:21] == b"\x05\x02\x00\x01\x51\x80"  # will properties: message expiry 86400
    assert body[21:] == b"\x00\x03t/w\x00\x04gone\x00\x01u\x00\x01p"


def test_publish_round_trip_with_properties() -> None:
    props = wire.properties(correlation=b"c-7", response_topic="r/t")
    packet = wire.publish("a/b", b"{}", qos=1, retain=True, packet_id=258, props=props)
    assert packet[0] == 0x33
    [(kind, flags, body)] = wire.PacketReader().feed(packet)
    message = wire.parse_publish(flags, body)
    assert kind == wire.PUBLISH
    assert (message.topic, message.payload, message.qos, message.retain, message.packet_id) == ("a/b", b"{}", 1, True, 258)
    assert (message.response_topic, message.correlation) == ("r/t", b"c-7")
    assert wire.publish("a", b"x") == b"\x30\x05\x00\x01a\x00x"


def test_a_stream_cut_anywhere_gives_the_same_packets() -> None:
    big = b"x" * 300  # a two-byte remaining length
    stream = wire.publish("t", big) + wire.puback(5) + wire.PINGREQ + wire.publish("u", b"")
    whole = wire.PacketReader().feed(stream)
    assert [(k, f) for k, f, _b in whole] == [(3, 0), (4, 0), (12, 0), (3, 0)]
    for cut in range(len(stream) + 1):
        reader = wire.PacketReader()
        assert reader.feed(stream[:cut]) + reader.feed(stream[cut:]) == whole


def test_connack_and_malformed_input() -> None:
    reason, props = wire.parse_connack(b"\x00\x00\x03\x13\x00\x3c")
    assert reason == 0 and props == {wire.SERVER_KEEP_ALIVE: 60}
    assert wire.parse_connack(b"\x00\x87")[0] == 0x87  # not authorized
    with pytest.raises(wire.MalformedPacket):
        wire.PacketReader().feed(b"\x30\xff\xff\xff\xff\x01")  # a length of five bytes
    with pytest.raises(wire.MalformedPacket):
        wire.parse_publish(0, b"\x00\x05ab")  # a topic cut short
    with pytest.raises(wire.MalformedPacket):
        wire.parse_publish(0, b"\x00\x01a\x02\x7f\x00")  # an unknown property
