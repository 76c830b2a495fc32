"""The MQTT packets devsim's own client sends and takes (OASIS MQTT Version 5.0, section 3; with
``v5=False`` the same packets of MQTT 3.1.1, which has no properties), pure: bytes in, records
out, no I/O.

Only what a member needs: CONNECT with a will (3.1), CONNACK (3.2), PUBLISH at QoS 0 and 1 (3.3)
and its PUBACK (3.4), SUBSCRIBE/SUBACK (3.8, 3.9), UNSUBSCRIBE/UNSUBACK (3.10, 3.11), PINGREQ and
PINGRESP (3.12, 3.13) and DISCONNECT (3.14).  Of the properties (2.2.2.2) it writes the message
expiry interval, the response topic and the correlation data, and reads every property a broker
may send, keeping those three and the server keep alive.

:class:`PacketReader` cuts a byte stream into packets (fixed header, 2.1); :func:`parse_publish`
reads a PUBLISH.  A malformed stream raises :class:`MalformedPacket`; a packet that cannot be
written (a string or binary of more than 65,535 bytes, a packet identifier outside 1 … 65,535, a
QoS outside 0 … 2, a keep alive or expiry interval that does not fit its field, a remaining
length beyond 268,435,455) raises ``ValueError`` instead of going out malformed.
"""

from __future__ import annotations

import functools
import struct
from collections.abc import Callable

import msgspec

__all__ = ["DISCONNECT", "PINGREQ", "MalformedPacket", "PacketReader", "Publish", "Will", "connect", "parse_connack",
           "parse_properties", "parse_publish", "properties", "puback", "publish", "publish_head", "publish_headed",
           "suback_refused", "subscribe",
           "unsubscribe"]

# packet types (2.1.2)
CONNACK, PUBLISH, PUBACK, SUBACK, UNSUBACK, PINGRESP, SERVER_DISCONNECT = 2, 3, 4, 9, 11, 13, 14
PINGREQ = b"\xc0\x00"
DISCONNECT = b"\xe0\x00"  # reason 0, normal disconnection: the broker does not send the will (3.14.2.1)
MAX_REMAINING = 268_435_455  # the largest remaining length (2.1.4)
MAX_TWO_BYTE = 0xFFFF  # the longest string or binary data (1.5.4, 1.5.6), the largest packet identifier (2.2.1)

# properties (2.2.2.2)
MESSAGE_EXPIRY, RESPONSE_TOPIC, CORRELATION_DATA, SERVER_KEEP_ALIVE = 0x02, 0x08, 0x09, 0x13


class MalformedPacket(ValueError):
    """Bytes that are not an MQTT 5 packet (the connection must be closed, 4.13)."""


class Will(msgspec.Struct, frozen=True):
    """The will message of a CONNECT (3.1.2.5, 3.1.3.2)."""

    topic: str
    payload: bytes
    qos: int = 1
    retain: bool = True
    expiry: int | None = None  # message expiry interval, seconds


class Publish(msgspec.Struct):
    """A PUBLISH as received (3.3)."""

    topic: str
    payload: bytes
    qos: int = 0
    retain: bool = False
    packet_id: int = 0
    response_topic: str | None = None
    correlation: bytes | None = None


# -- encoding ---------------------------------------------------------------------------------
def _varint(value: int) -> bytes:
    """A variable byte integer (1.5.5): 0 … 268,435,455 in one to four bytes."""
    if not 0 <= value <= MAX_REMAINING:
        raise ValueError(f"a variable byte integer is 0 … {MAX_REMAINING}, not {value}")
    if value < 128:  # (one byte: a short packet's length, a property list's)
        return _ONE_BYTE[value]
    out = bytearray()
    while True:
        value, byte = divmod(value, 128)
        out.append(byte | (128 if value else 0))
        if not value:
            return bytes(out)


_ONE_BYTE = [bytes((value,)) for value in range(128)]


def _string(text: str) -> bytes:
    return _binary(text.encode("utf-8"))


def _binary(data: bytes) -> bytes:
    if len(data) > MAX_TWO_BYTE:
        raise ValueError(f"a string or binary data holds at most {MAX_TWO_BYTE} bytes, not {len(data)}")
    return struct.pack("!H", len(data)) + data


def _packet_id(value: int) -> bytes:
    if not 1 <= value <= MAX_TWO_BYTE:
        raise ValueError(f"a packet identifier is 1 … {MAX_TWO_BYTE}, not {value}")
    return struct.pack("!H", value)


def _qos(value: int) -> int:
    if value not in (0, 1, 2):
        raise ValueError(f"QoS is 0, 1 or 2, not {value}")
    return value


def _packet(first: int, body: bytes) -> bytes:
    return bytes((first,)) + _varint(len(body)) + body


def properties(expiry: int | None = None, response_topic: str | None = None, correlation: bytes | None = None) -> bytes:
    """A property list with its length (2.2.2.1)."""
    out = b""
    if expiry is not None:
        if not 0 <= expiry <= 0xFFFF_FFFF:
            raise ValueError(f"a message expiry interval is 0 … {0xFFFF_FFFF} s, not {expiry}")
        out += bytes((MESSAGE_EXPIRY,)) + struct.pack("!I", expiry)
    if response_topic is not None:
        out += bytes((RESPONSE_TOPIC,)) + _string(response_topic)
    if correlation is not None:
        out += bytes((CORRELATION_DATA,)) + _binary(correlation)
    return _varint(len(out)) + out


def connect(identifier: str, keepalive: int, *, will: Will | None = None, username: str | None = None,
            password: str | None = None, v5: bool = True) -> bytes:
    """CONNECT with clean start (3.1; MQTT 3.1.1's clean session)."""
    if not 0 <= keepalive <= MAX_TWO_BYTE:
        raise ValueError(f"a keep alive is 0 … {MAX_TWO_BYTE} s, not {keepalive}")
    flags = 0x02
    payload = _string(identifier)
    if will is not None:
        flags |= 0x04 | (_qos(will.qos) << 3) | (0x20 if will.retain else 0)
        payload += (properties(expiry=will.expiry) if v5 else b"") + _string(will.topic) + _binary(will.payload)
    if username is not None:
        flags |= 0x80
        payload += _string(username)
    if password is not None:
        flags |= 0x40
        payload += _binary(password.encode("utf-8"))
    header = _string("MQTT") + bytes((5 if v5 else 4, flags)) + struct.pack("!H", keepalive) + (b"\x00" if v5 else b"")
    return _packet(0x10, header + payload)


_NO_PROPERTIES = b"\x00"


def publish(topic: str, payload: bytes, qos: int = 0, retain: bool = False, packet_id: int = 0,
            props: bytes = _NO_PROPERTIES) -> bytes:
    """PUBLISH (3.3); ``props`` from :func:`properties` (``b""`` for MQTT 3.1.1)."""
    head = _topic(topic) + (_packet_id(packet_id) if qos and _qos(qos) else b"") + props  # (QoS 0: nothing to check)
    body = len(head) + len(payload)
    return b"".join((_ONE_BYTE[0x30 | (qos << 1) | (1 if retain else 0)], _varint(body), head, payload))


def publish_head(topic: str, v5: bool = True) -> bytes:
    """What a PUBLISH at QoS 0 without properties carries before its payload (3.3.2): the topic
    name and, in MQTT 5, an empty property list.  A member's replies are built on it
    (:func:`publish_headed`), its requests recognised by it."""
    return _string(topic) + (_NO_PROPERTIES if v5 else b"")


def publish_headed(head: bytes, payload: bytes) -> bytes:
    """A PUBLISH at QoS 0, not retained, of ``payload`` after a ``head`` from :func:`publish_head`."""
    size = len(head) + len(payload)
    return b"".join((b"\x30", _ONE_BYTE[size] if size < 128 else _varint(size), head, payload))


@functools.lru_cache(maxsize=1024)
def _topic(topic: str) -> bytes:
    """A topic name as a PUBLISH carries it (a member answers on the same few reply topics)."""
    return _string(topic)


def puback(packet_id: int) -> bytes:
    """PUBACK, success (3.4.2.1: the reason code may be left out)."""
    return b"\x40\x02" + _packet_id(packet_id)


def subscribe(packet_id: int, topic: str, qos: int, v5: bool = True) -> bytes:
    """SUBSCRIBE to one filter (3.8)."""
    return _packet(0x82, _packet_id(packet_id) + (b"\x00" if v5 else b"") + _string(topic) + bytes((_qos(qos),)))


def unsubscribe(packet_id: int, topic: str, v5: bool = True) -> bytes:
    """UNSUBSCRIBE from one filter (3.10)."""
    return _packet(0xA2, _packet_id(packet_id) + (b"\x00" if v5 else b"") + _string(topic))


# -- decoding ---------------------------------------------------------------------------------
def _read_varint(data: bytes | memoryview, at: int) -> tuple[int, int]:
    value = shift = 0
    for _ in range(4):
        if at >= len(data):
            raise MalformedPacket("variable byte integer cut short")
        byte = data[at]
        at += 1
        value |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return value, at
        shift += 7
    raise MalformedPacket("variable byte integer longer than four bytes")


def _read_u16(data: bytes, at: int) -> tuple[int, int]:
    if at + 2 > len(data):
        raise MalformedPacket("two-byte integer cut short")
    return (data[at] << 8) | data[at + 1], at + 2


def _binary_end(data: bytes, at: int) -> int:
    """Where the string or binary data at ``at`` (its two-byte length, then its bytes) ends."""
    if at + 2 > len(data):
        raise MalformedPacket("two-byte integer cut short")
    end = at + 2 + ((data[at] << 8) | data[at + 1])
    if end > len(data):
        raise MalformedPacket("string or binary data cut short")
    return end


def _read_binary(data: bytes, at: int) -> tuple[bytes, int]:
    end = _binary_end(data, at)
    return data[at + 2:end], end


def _read_string(data: bytes, at: int) -> tuple[str, int]:
    end = _binary_end(data, at)
    try:
        return str(data[at + 2:end], "utf-8"), end
    except UnicodeDecodeError:
        raise MalformedPacket("a string that is not UTF-8") from None


def _read_byte(data: bytes, at: int) -> tuple[int, int]:
    if at >= len(data):
        raise MalformedPacket("byte cut short")
    return data[at], at + 1


def _read_u32(data: bytes, at: int) -> tuple[int, int]:
    if at + 4 > len(data):
        raise MalformedPacket("four-byte integer cut short")
    return int.from_bytes(data[at:at + 4], "big"), at + 4


def _read_pair(data: bytes, at: int) -> tuple[None, int]:
    _key, at = _read_binary(data, at)
    _value, at = _read_binary(data, at)
    return None, at


#: property identifier -> reader of its value (2.2.2.2)
_PROPERTY_READERS: dict[int, Callable[[bytes, int], tuple[object, int]]] = {
    0x01: _read_byte, MESSAGE_EXPIRY: _read_u32, 0x03: _read_string, RESPONSE_TOPIC: _read_string,
    CORRELATION_DATA: _read_binary, 0x0B: _read_varint, 0x11: _read_u32, 0x12: _read_string,
    SERVER_KEEP_ALIVE: _read_u16, 0x15: _read_string, 0x16: _read_binary, 0x17: _read_byte, 0x18: _read_u32,
    0x19: _read_byte, 0x1A: _read_string, 0x1C: _read_string, 0x1F: _read_string, 0x21: _read_u16,
    0x22: _read_u16, 0x23: _read_u16, 0x24: _read_byte, 0x25: _read_byte, 0x26: _read_pair, 0x27: _read_u32,
    0x28: _read_byte, 0x29: _read_byte, 0x2A: _read_byte,
}


def parse_properties(data: bytes, at: int) -> tuple[dict[int, object], int]:
    """The property list at ``at``: identifier -> value (the last of a repeated one), and where
    the list ends."""
    length, at = _read_varint(data, at)
    end = at + length
    if end > len(data):
        raise MalformedPacket("property list cut short")
    found: dict[int, object] = {}
    while at < end:
        identifier = data[at]
        reader = _PROPERTY_READERS.get(identifier)
        if reader is None:
            raise MalformedPacket(f"unknown property 0x{identifier:02x}")
        found[identifier], at = reader(data, at + 1)
    if at != end:
        raise MalformedPacket("property list overruns its length")
    return found, end


def parse_publish(flags: int, body: bytes, v5: bool = True) -> Publish:
    """A PUBLISH's variable header and payload (3.3.2, 3.3.3); both QoS bits set (3.3.1.2) or a
    packet identifier of 0 (2.2.1) is malformed."""
    qos = (flags >> 1) & 3
    if qos == 3:
        raise MalformedPacket("a PUBLISH with both QoS bits set")
    topic, at = _read_string(body, 0)
    packet_id = 0
    if qos:
        packet_id, at = _read_u16(body, at)
        if not packet_id:
            raise MalformedPacket("a PUBLISH at QoS 1 or 2 with packet identifier 0")
    if not v5:
        return Publish(topic, body[at:], qos, bool(flags & 1), packet_id)
    if body[at:at + 1] == b"\x00":  # no properties: the common case
        return Publish(topic, body[at + 1:], qos, bool(flags & 1), packet_id)
    props, at = parse_properties(body, at)
    response = props.get(RESPONSE_TOPIC)
    correlation = props.get(CORRELATION_DATA)
    return Publish(topic, body[at:], qos, bool(flags & 1), packet_id,
                   response if isinstance(response, str) else None,
                   correlation if isinstance(correlation, bytes) else None)


def parse_connack(body: bytes, v5: bool = True) -> tuple[int, dict[int, object]]:
    """A CONNACK's reason code (0 = success, 3.2.2.2; MQTT 3.1.1: return codes 1-5 refuse) and
    properties."""
    if len(body) < 2:
        raise MalformedPacket("CONNACK cut short")
    props, _end = parse_properties(body, 2) if v5 and len(body) > 2 else ({}, 2)
    return body[1] if v5 or body[1] == 0 else 0x80 | body[1], props


def suback_refused(body: bytes, v5: bool = True) -> int | None:
    """The failure code of a SUBACK for one filter (3.9.3), or None when granted."""
    at = parse_properties(body, 2)[1] if v5 else 2
    if at >= len(body):
        raise MalformedPacket("SUBACK without a reason code")
    return body[at] if body[at] >= 0x80 else None


class PacketReader:
    """Cuts a byte stream into packets: :meth:`feed` returns each whole one as (type, flags,
    body) and keeps the rest for the next call."""

    def __init__(self) -> None:
        self._buffer = b""

    def single_publish(self, data: bytes, head: bytes) -> bytes | None:
        """The payload of ``data`` when it is one whole PUBLISH at QoS 0, not retained, on
        ``head`` (:func:`publish_head`: the topic without properties), of a remaining length in
        one or two bytes, and nothing is held from earlier reads; else None, nothing taken
        (:meth:`feed` it).  A member's request, read in one piece, recognised in one step."""
        if self._buffer:
            return None
        try:
            if data[0] != 0x30:
                return None
            length = data[1]
            start = 2
            if length & 0x80:  # two bytes (of three or four, the length read is 16,384 too large to fit)
                length = (length & 0x7F) | (data[2] << 7)
                start = 3
        except IndexError:  # cut short
            return None
        if start + length != len(data) or not data.startswith(head, start):
            return None
        return data[start + len(head):]

    def feed(self, data: bytes) -> list[tuple[int, int, bytes]]:
        buffer = self._buffer + data if self._buffer else data
        packets = []
        at = 0
        size = len(buffer)
        while size - at >= 2:
            first = buffer[at]
            length = buffer[at + 1]
            start = at + 2
            if length & 0x80 and size - at > 2 and buffer[at + 2] < 0x80:  # two bytes: 128 … 16,383
                length = (length & 0x7F) | (buffer[at + 2] << 7)  # (a request's, and most answers')
                start = at + 3
            elif length & 0x80:
                try:
                    length, start = _read_varint(buffer, at + 1)
                except MalformedPacket:
                    if size - at < 5:
                        break  # the length is still arriving
                    raise
            if start + length > size:
                break
            packets.append((first >> 4, first & 0x0F, buffer[start:start + length]))
            at = start + length
        self._buffer = buffer[at:]
        return packets
