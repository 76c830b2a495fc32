"""Reading what ``devsim plot`` draws: motion logs and wire traces, pure (no matplotlib).

* a **motion log** (:mod:`devsim.observe.motion_log`, ``--motion-log FILE.csv``) becomes one
  :class:`AxisSeries` per device and axis, with the units of its columns from the device kind's
  declared points (:func:`axis_units`), and the device's events;
* a **text trace** (:mod:`devsim.transports.trace`, ``--trace FILE``) and a **pcap trace**
  (:mod:`devsim.transports.pcap`, ``--trace FILE.pcap``) become a :class:`Traffic`: the chunks
  that crossed the line, each with its device-clock time and direction (``H>D``, ``D>H``), and
  the notes (host settings, disconnects) of a text trace.  A text trace that names its source
  (:func:`devsim.transports.trace.source_note`: devices, port, kind) has its messages decoded by
  the port's declared framing (:func:`messages`: ``M 20000`` for a GMS96 letter, ``#P51?`` for
  a SERS line); any other shows its chunks as they came.

A serial line's pcap trace (link type USER0, devsim's serial header: :mod:`devsim.transports.pcap`)
says each chunk's direction in its header, and its kind and port by their capture tag
(:func:`capture_source`): its messages are decoded as a text trace's are.  An IPv4/UDP pcap trace holds addresses, not
directions: the device is the endpoint that takes part in every packet (with both in every
packet: the lower port, then the lower address — a listening port below an ephemeral one, and
devsim's invented device address 127.0.0.1 below the host's 127.0.0.2).  :func:`load` tells the three apart by their content.
"""

from __future__ import annotations

import csv
import functools
import io
import math
import re
import struct
from pathlib import Path
from typing import Any

import msgspec

from devsim.observe.motion_log import COLUMNS, HEADER
from devsim.transports.pcap import HEADER_SIZE, LINKTYPE_USER0, parse_serial_header
from devsim.transports.trace import Source, parse_source_note, render

#: The columns every motion log has (``kind`` came later: an older log ends after ``event``).
_FIRST = HEADER[: HEADER.index("event") + 1]

__all__ = ["AxisSeries", "MotionData", "Traffic", "axis_units", "capture_source", "load", "messages", "read_motion_log",
           "read_pcap_trace", "read_text_trace"]


class AxisSeries(msgspec.Struct):
    """One axis of a motion log: its rows in time order (NaN where a cell was empty), and the
    units of its columns (``{"position": "inc", "velocity": "inc/s"}``; none for a log without kinds)."""

    device: str
    axis: str
    kind: str = ""
    units: dict[str, str] = msgspec.field(default_factory=dict)
    time: list[float] = msgspec.field(default_factory=list)
    setpoint: list[float] = msgspec.field(default_factory=list)
    position: list[float] = msgspec.field(default_factory=list)
    velocity: list[float] = msgspec.field(default_factory=list)
    following_error: list[float] = msgspec.field(default_factory=list)

    @property
    def label(self) -> str:
        return f"{self.device} {self.axis}"

    def unit(self, column: str) -> str:
        """The unit of ``column`` (``position``, ``velocity`` …); "" when unknown."""
        return self.units.get(column, "")

    def has(self, column: str) -> bool:
        return any(not math.isnan(v) for v in getattr(self, column))


class MotionData(msgspec.Struct):
    """A motion log: the axes and, per device, its events ``(time, name)`` in time order."""

    path: str
    axes: list[AxisSeries] = msgspec.field(default_factory=list)
    events: dict[str, list[tuple[float, str]]] = msgspec.field(default_factory=dict)


class Traffic(msgspec.Struct):
    """One port's wire trace: chunks ``(time, direction, bytes)``, notes ``(time, text)`` and the
    devices, port and kind it traces when it says so."""

    name: str
    chunks: list[tuple[float, str, bytes]] = msgspec.field(default_factory=list)
    notes: list[tuple[float, str]] = msgspec.field(default_factory=list)
    source: Source | None = None

    @property
    def label(self) -> str:
        """``card main`` (the devices and the port it traces), else the file's name."""
        return self.name if self.source is None else f"{','.join(self.source.devices)} {self.source.port}"


def _printable(text: str) -> str:
    """A text message as it reads (``P51=90°``): the line ends stripped, other control characters escaped."""
    return "".join(c if c.isprintable() else render(c.encode("latin-1", errors="replace"))[1:-1]
                   for c in text.strip("\r\n"))


def _fields(described: Any) -> str:
    if isinstance(described, dict):
        return " ".join(f"{key}={value}" for key, value in described.items() if key != "frame")
    return str(described)


def messages(traffic: Traffic) -> list[tuple[float, str, str]]:
    """``(time, direction, label)`` of every message the trace's port's framing decodes, at the
    time of the chunk that completes it; [] for a trace without a source or a port without a
    framing (then its chunks are all there is)."""
    if traffic.source is None:
        return []
    from devsim.core.registry import port_framing

    framing = port_framing(traffic.source.kind, traffic.source.port)
    decoders = {"H>D": framing.decoder("host"), "D>H": framing.decoder("device")}
    label = framing.label or (lambda message: _printable(message) if isinstance(message, str) else _fields(message))
    found: list[tuple[float, str, str]] = []
    for when, direction, data in traffic.chunks:
        try:
            decoded = decoders[direction].feed(data)
        except Exception:  # noqa: BLE001 - a decoder that chokes on a trace: that port's chunks as they came
            return []
        if decoded is None:
            return []
        found.extend((when, direction, label(message)) for message in decoded)
    return found


class PlotInputError(ValueError):
    """A file ``devsim plot`` cannot read (one line, with the file's name)."""


def _number(text: str) -> float:
    try:
        return float(text) if text else math.nan
    except ValueError:
        return math.nan


_AXIS_PREFIX = re.compile(r"^axis(?:\.[A-Za-z0-9_]+)?$")


@functools.cache
def axis_units(kind: str, axis: str) -> dict[str, str]:
    """The units of ``axis``'s columns as ``kind`` declares its points (``axis.1.velocity`` in
    ``counts/s``); an axis the kind's table does not name (``axis.3`` of a configured PCD4.H3) has
    the units of its first axis; {} for a kind not installed."""
    from devsim.core.registry import UnknownKind, device_class

    try:
        points = {p.name: p for p in device_class(kind).points}
    except (UnknownKind, ImportError):
        return {}
    known = [axis] + [name.removesuffix(".position") for name in points
                      if name.endswith(".position") and _AXIS_PREFIX.match(name.removesuffix(".position"))]
    for prefix in known:
        units = {}
        for column, patterns in COLUMNS.items():  # the point the motion log takes the column from
            name = next((n for n in (p.format(axis=prefix) for p in patterns) if n in points), None)
            if name is not None and points[name].unit:
                units[column] = points[name].unit
        if units:
            return units
    return {}


def read_motion_log(path: str | Path) -> MotionData:
    """Parse a motion log written by :class:`devsim.observe.motion_log.MotionLog` (one without the
    ``kind`` column, from before it had one, too).  A last line cut short (the writer killed, the
    disk full) is left out, as a pcap's or a session's is."""
    data = MotionData(str(path))
    series: dict[tuple[str, str], AxisSeries] = {}
    seen: set[tuple[str, float, str]] = set()
    try:
        with open(path, encoding="utf-8", newline="") as stream:
            text = stream.read()
        rows = list(csv.reader(io.StringIO(text)))
    except UnicodeDecodeError as exc:  # (damaged bytes: a traceback before)
        raise PlotInputError(f"{path}: not a motion log (byte {exc.start} is not UTF-8 text)") from None
    except csv.Error as exc:  # (a field of 128 KiB and more, an unclosed quote: a traceback before)
        raise PlotInputError(f"{path}: not a motion log ({exc})") from None
    header = rows[0] if rows else None
    if header is None or tuple(header[: len(_FIRST)]) != _FIRST:
        raise PlotInputError(f"{path}: not a motion log (expected the header {','.join(HEADER)})")
    if len(rows) > 1 and not text.endswith("\n") and len(rows[-1]) < len(header):
        rows.pop()  # (cut short: no line end, columns missing)
    for number, row in enumerate(rows[1:], start=2):
        if len(row) < len(_FIRST):
            raise PlotInputError(f"{path}:{number}: expected {len(HEADER)} columns, got {len(row)}")
        when = _number(row[0])
        if math.isnan(when):
            raise PlotInputError(f"{path}:{number}: bad time {row[0]!r}")
        device, axis = row[1], row[2]
        item = series.get((device, axis))
        if item is None:
            kind = row[len(_FIRST)] if len(row) > len(_FIRST) else ""
            item = series[(device, axis)] = AxisSeries(device, axis, kind, axis_units(kind, axis) if kind else {})
        item.time.append(when)
        item.setpoint.append(_number(row[3]))
        item.position.append(_number(row[4]))
        item.velocity.append(_number(row[5]))
        item.following_error.append(_number(row[6]))
        event = row[7]
        if event and (device, when, event) not in seen:  # an event has a row per axis
            seen.add((device, when, event))
            data.events.setdefault(device, []).append((when, event))
    for item in series.values():  # rows are near time order; a plot needs them exactly so
        order = sorted(range(len(item.time)), key=item.time.__getitem__)
        for column in ("time", "setpoint", "position", "velocity", "following_error"):
            values = getattr(item, column)
            setattr(item, column, [values[i] for i in order])
    for events in data.events.values():
        events.sort()
    data.axes = list(series.values())
    return data


_DATA_LINE = re.compile(r'^(\d+(?:\.\d+)?) (H>D|D>H) ((?:[0-9a-f]{2} )*[0-9a-f]{2}) "')
_NOTE_LINE = re.compile(r"^(\d+(?:\.\d+)?) -- (.*)$")


def read_text_trace(path: str | Path) -> Traffic:
    """Parse a text trace (``12.345678 H>D 23 4f 0d "#O\\r"``, ``12.5 -- host settings ...``)."""
    traffic = Traffic(Path(path).stem)
    with open(path, encoding="ascii", errors="replace") as stream:
        for number, line in enumerate(stream, start=1):
            line = line.rstrip("\n")
            if not line:
                continue
            match = _DATA_LINE.match(line)
            if match is not None:
                traffic.chunks.append((float(match.group(1)), match.group(2), bytes.fromhex(match.group(3))))
                continue
            note = _NOTE_LINE.match(line)
            if note is None:
                raise PlotInputError(f"{path}:{number}: not a trace line: {line[:60]!r}")
            source = parse_source_note(note.group(2))
            if source is not None:
                traffic.source = source
            else:
                traffic.notes.append((float(note.group(1)), note.group(2)))
    return traffic


#: pcap magic (as read little-endian) → (byte order, time fraction per second).
_PCAP_MAGIC = {0xA1B2C3D4: ("<", 1e6), 0xD4C3B2A1: (">", 1e6), 0xA1B23C4D: ("<", 1e9), 0x4D3CB2A1: (">", 1e9)}
#: link type → bytes before the IPv4 header (raw IPv4, raw IP, Ethernet).
_LINK_OFFSET = {228: 0, 101: 0, 1: 14}


def capture_source(protocol: int, port: int, name: str) -> Source | None:
    """What a serial capture's records (devsim header: ``protocol``, ``port`` bytes) trace: the
    kind and port that declare that capture tag (:attr:`devsim.core.kit.PortDef.capture`), the
    device named ``name`` (the file's); None when no kind does (Modbus RTU, an unknown tag)."""
    from devsim.core.registry import device_class, kinds

    for kind in kinds():
        try:
            ports = device_class(kind).ports
        except Exception:  # noqa: BLE001 - a kind that does not load declares nothing here
            continue
        for declared in ports:
            tag = declared.capture
            if tag is not None and (tag.protocol, tag.port) == (protocol, port):
                return Source((name,), declared.name, kind)
    return None


def _read_serial_records(raw: bytes, order: str, fraction: float, traffic: Traffic) -> Traffic:
    """The chunks of a serial line's pcap trace: each record a devsim header and the bytes; the
    source (kind and port, for :func:`messages`) from the first record's capture tag."""
    offset = 24
    while offset + 16 <= len(raw):
        seconds, part, captured, _length = struct.unpack_from(f"{order}IIII", raw, offset)
        record = raw[offset + 16 : offset + 16 + captured]
        offset += 16 + captured
        try:
            header = parse_serial_header(record)
        except ValueError:
            continue  # not one of devsim's records
        if not traffic.chunks:
            traffic.source = capture_source(int(header["protocol"]), int(header["port"]), traffic.name)
        traffic.chunks.append((seconds + part / fraction, str(header["direction"]), record[HEADER_SIZE:]))
    return traffic


def read_pcap_trace(path: str | Path) -> Traffic:
    """Parse a classic pcap file (what ``--trace FILE.pcap`` writes): a serial line's records
    (link type USER0) or IPv4/UDP packets."""
    raw = Path(path).read_bytes()
    if len(raw) < 24:
        raise PlotInputError(f"{path}: too short for a pcap file")
    magic = struct.unpack_from("<I", raw)[0]
    if magic not in _PCAP_MAGIC:
        raise PlotInputError(f"{path}: not a classic pcap file (magic {magic:08x})")
    order, fraction = _PCAP_MAGIC[magic]
    linktype = struct.unpack_from(f"{order}I", raw, 20)[0]
    if linktype == LINKTYPE_USER0:
        return _read_serial_records(raw, order, fraction, Traffic(Path(path).stem))
    if linktype not in _LINK_OFFSET:
        raise PlotInputError(f"{path}: link type {linktype} is neither devsim's serial records (USER0 147) "
                             "nor IPv4 (raw IPv4 228, raw IP 101, Ethernet 1)")
    skip = _LINK_OFFSET[linktype]
    packets: list[tuple[float, tuple[bytes, int], tuple[bytes, int], bytes]] = []
    offset = 24
    while offset + 16 <= len(raw):
        seconds, part, captured, _length = struct.unpack_from(f"{order}IIII", raw, offset)
        packet = raw[offset + 16 + skip : offset + 16 + captured]
        offset += 16 + captured
        if len(packet) < 28 or packet[0] >> 4 != 4 or packet[9] != 17:
            continue  # not IPv4/UDP
        header = (packet[0] & 0x0F) * 4
        src_port, dst_port, udp_length = struct.unpack_from("!HHH", packet, header)
        payload = packet[header + 8 : header + udp_length]
        packets.append((seconds + part / fraction, (packet[12:16], src_port), (packet[16:20], dst_port), payload))
    traffic = Traffic(Path(path).stem)
    if not packets:
        return traffic
    everywhere = set.intersection(*({src, dst} for _, src, dst, _ in packets))
    candidates = everywhere or {packets[0][2]}
    device = min(candidates, key=lambda end: (end[1], end[0]))
    for when, _src, dst, payload in packets:
        traffic.chunks.append((when, "H>D" if dst == device else "D>H", payload))
    return traffic


def load(path: str | Path) -> MotionData | Traffic:
    """A motion log, a pcap trace or a text trace, told apart by the file's first bytes."""
    try:
        with open(path, "rb") as stream:
            head = stream.read(64)
    except OSError as exc:
        raise PlotInputError(f"{path}: {exc.strerror or exc}") from None
    if len(head) >= 4 and struct.unpack_from("<I", head)[0] in _PCAP_MAGIC:
        return read_pcap_trace(path)
    if head.startswith(",".join(HEADER[:3]).encode()):
        return read_motion_log(path)
    return read_text_trace(path)
