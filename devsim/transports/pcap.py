"""A wire trace as a libpcap file that Wireshark and tshark read.

The file is classic pcap (not pcapng): the little-endian global header (magic ``a1b2c3d4``
written as ``d4 c3 b2 a1``, version 2.4, microsecond timestamps, snap length 65535) and one of
two link types:

**A serial line** (every port a kind declares with a capture tag,
:attr:`devsim.core.kit.PortDef.capture`, and the Modbus RTU facade's line): link type
:data:`LINKTYPE_USER0` (147).  Every chunk that crossed the line in one direction is one record:
a 16-byte devsim header (:func:`serial_header`, docs/wireshark.md) and the bytes::

    offset size field
    0      2    magic "ds" (0x64 0x73)
    2      1    version 1
    3      1    direction: 0 host -> device, 1 device -> host
    4      1    protocol (PROTOCOLS: 1 SERS, 2 GMS96, 3 POSELESTA, 4 IP247 PG, 5 PCD4.H3 S-Bus, 16 Modbus RTU)
    5      1    port (POSELESTA 6, 7, 8 for V6, V7, V8; else 0)
    6      4    baud rate the host set, big-endian (0: not known)
    10     1    data bits (0: not known)
    11     1    parity 'N' 'E' 'O' 'M' 'S' (0: not known)
    12     1    stop bits x 10 (0: not known)
    13     1    flags: bit 0 the host's settings differ from the device's (mismatch)
    14     2    reserved, 0

The timestamp is the device clock's ``now()``.  Wireshark's "User DLTs" table hands the payload
to a built-in dissector with header size 16; devsim's Lua dissector reads the header itself.

**Any other port** (the PCD4.H3's Ether-S-Bus on UDP and TCP): link type :data:`LINKTYPE_IPV4`
(228, raw IPv4: each packet starts with its IP header).  Every chunk that crossed the line is one
IPv4/UDP packet:

* **timestamp** – the device clock's ``now()`` (simulated time: seconds since the runtime's clock
  started, so a trace begins near 1970-01-01 in Wireshark's absolute time; relative times are
  exact to the microsecond);
* **addresses** – host to device (``H>D``) goes from the host's address and port to the device's,
  device to host (``D>H``) back.  Where the transport knows the real ones it says so through
  :meth:`~devsim.transports.base.Transport.trace_peers` (UDP: the sender of the latest datagram
  and the port it was sent to; TCP and RFC 2217: the connected client and the listening port).
  Otherwise (a pty, no host yet, or IPv6 addresses, which a raw IPv4 trace cannot carry) the
  addresses are invented and stable: the host is ``127.0.0.2``, the device ``127.0.0.1``, both
  on port :func:`invented_port` of the trace's name (49152 … 65535, the same for every run of
  a port).  Real ports are kept when only the addresses are IPv6.
* **IP header** – valid header checksum, TTL 64, don't-fragment, an identification that counts
  up; a chunk longer than one UDP datagram can hold (65507 bytes) becomes several packets.
* **UDP checksum** – computed (never 0, which would mean "none").

Notes that are not data (faults, disconnects) have no place in a pcap file and are left out; the
text trace (:mod:`devsim.transports.trace`) keeps them.  A serial record carries the host's line
settings of the moment in its header.

The packet building (:func:`ipv4_udp_packet`, :func:`global_header`, :func:`packet_record`,
:func:`checksum`, :func:`serial_header`, :func:`serial_record`) is pure; :class:`PcapTracer` and
:class:`SerialPcapTracer` write with the same safety rules as
:class:`~devsim.transports.trace.Tracer` (no truncation through a symlink).
"""

from __future__ import annotations

import ipaddress
import math
import struct
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from devsim.transports.trace import TraceFile

__all__ = [
    "HEADER_SIZE",
    "LINKTYPE_IPV4",
    "LINKTYPE_USER0",
    "MAX_PAYLOAD",
    "PROTOCOLS",
    "Address",
    "LineState",
    "PcapTracer",
    "Peers",
    "SerialPcapTracer",
    "checksum",
    "global_header",
    "invented_port",
    "ipv4_udp_packet",
    "packet_record",
    "parse_serial_header",
    "serial_header",
    "serial_record",
]

#: Raw IPv4, no link-layer header (tshark decodes it as IP, then UDP).
LINKTYPE_IPV4 = 228
#: The first user link type (DLT_USER0): devsim's serial-line records, a 16-byte header and the bytes.
LINKTYPE_USER0 = 147
#: The size of the devsim header before a serial record's bytes.
HEADER_SIZE = 16
#: The protocol byte of the devsim header, by the protocol's name (a kind's ports declare theirs
#: in :class:`devsim.core.kit.CaptureTag`: nothing outside a kind keeps a table keyed by kinds).
PROTOCOLS = {"unknown": 0, "SERS": 1, "GMS96": 2, "POSELESTA": 3, "IP247 PG": 4, "PCD4.H3 S-Bus": 5, "Modbus RTU": 16}
#: The header's magic and version.
MAGIC = b"ds"
VERSION = 1
#: The most bytes one serial record carries (the snap length less the devsim header).
MAX_SERIAL_CHUNK = 65535 - HEADER_SIZE
_DIRECTIONS = {"H>D": 0, "D>H": 1}
_PARITIES = frozenset("NEOMS")
_SERIAL = struct.Struct(">2sBBBBIBBBBH")

#: The most payload one IPv4/UDP packet carries (65535 - 20 IP - 8 UDP).
MAX_PAYLOAD = 65535 - 28
SNAPLEN = 65535

#: An (address, port) pair; the address as text (``"127.0.0.1"``).
Address = tuple[str, int]
#: The (host, device) addresses of the conversation on a port, when a transport knows them.
Peers = tuple[Address, Address]

INVENTED_HOST = "127.0.0.2"
INVENTED_DEVICE = "127.0.0.1"


def checksum(data: bytes) -> int:
    """The Internet checksum (RFC 1071): one's complement of the one's complement sum of the
    16-bit big-endian words of ``data`` (padded with a zero byte when odd)."""
    if len(data) % 2:
        data += b"\0"
    total = sum(struct.unpack(f"!{len(data) // 2}H", data))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return ~total & 0xFFFF


def ipv4_udp_packet(src: Address, dst: Address, payload: bytes, ident: int = 0) -> bytes:
    """One IPv4 packet carrying one UDP datagram of ``payload`` from ``src`` to ``dst``."""
    if len(payload) > MAX_PAYLOAD:
        raise ValueError(f"a UDP payload holds at most {MAX_PAYLOAD} bytes, not {len(payload)}")
    source = ipaddress.IPv4Address(src[0]).packed
    target = ipaddress.IPv4Address(dst[0]).packed
    udp_length = 8 + len(payload)
    pseudo = source + target + struct.pack("!BBH", 0, 17, udp_length)
    udp = struct.pack("!HHHH", src[1], dst[1], udp_length, 0) + payload
    udp_sum = checksum(pseudo + udp) or 0xFFFF  # 0 would mean "no checksum"
    udp = udp[:6] + struct.pack("!H", udp_sum) + udp[8:]
    header = struct.pack(
        "!BBHHHBBH4s4s", 0x45, 0, 20 + udp_length, ident & 0xFFFF, 0x4000, 64, 17, 0, source, target
    )
    header = header[:10] + struct.pack("!H", checksum(header)) + header[12:]
    return header + udp


def global_header(linktype: int = LINKTYPE_IPV4) -> bytes:
    """The 24-byte pcap file header: little-endian, version 2.4, microseconds."""
    return struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, SNAPLEN, linktype)


def packet_record(when: float, packet: bytes) -> bytes:
    """One pcap record: the 16-byte record header (seconds, microseconds, lengths) and the packet."""
    when = max(0.0, when) if math.isfinite(when) else 0.0
    micros = round(when * 1_000_000)
    seconds, micros = divmod(micros, 1_000_000)
    return struct.pack("<IIII", seconds & 0xFFFFFFFF, micros, len(packet), len(packet)) + packet


def serial_header(direction: str, protocol: int, port: int, baud: int, bits: int, parity: str, stop: float,
                  mismatch: bool) -> bytes:
    """The 16-byte devsim header of one serial record (see the module docstring): ``direction``
    ``"H>D"`` or ``"D>H"``; ``baud``, ``bits``, ``parity`` (``""``), ``stop`` 0 where not known."""
    if direction not in _DIRECTIONS:
        raise ValueError(f"direction must be 'H>D' or 'D>H', not {direction!r}")
    if parity and parity not in _PARITIES:
        raise ValueError(f"parity is one of N, E, O, M, S (or '' when not known), not {parity!r}")
    if not (0 <= protocol <= 255 and 0 <= port <= 255 and 0 <= baud <= 0xFFFFFFFF and 0 <= bits <= 8):
        raise ValueError(f"out of range: protocol {protocol}, port {port}, baud {baud}, bits {bits}")
    stop_tenths = round(stop * 10) if stop and math.isfinite(stop) else 0
    if not 0 <= stop_tenths <= 255:
        raise ValueError(f"stop bits out of range: {stop}")
    return _SERIAL.pack(MAGIC, VERSION, _DIRECTIONS[direction], protocol, port, baud, bits,
                        ord(parity) if parity else 0, stop_tenths, 1 if mismatch else 0, 0)


def parse_serial_header(header: bytes) -> dict[str, Any]:
    """The fields of a devsim header (the inverse of :func:`serial_header`); ``ValueError`` when
    ``header`` is not one."""
    if len(header) < HEADER_SIZE:
        raise ValueError(f"a devsim header has {HEADER_SIZE} bytes, not {len(header)}")
    magic, version, direction, protocol, port, baud, bits, parity, stop, flags, _ = _SERIAL.unpack_from(header)
    if magic != MAGIC or version != VERSION or direction > 1:
        raise ValueError(f"not a devsim serial header: {bytes(header[:HEADER_SIZE]).hex(' ')}")
    return {"direction": "D>H" if direction else "H>D", "protocol": protocol, "port": port, "baud": baud,
            "bits": bits, "parity": chr(parity) if parity else "", "stop": stop / 10, "mismatch": bool(flags & 1)}


def serial_record(when: float, header: bytes, data: bytes) -> bytes:
    """One pcap record of link type :data:`LINKTYPE_USER0`: the devsim ``header`` and ``data``."""
    if len(header) + len(data) > SNAPLEN:
        raise ValueError(f"a record holds at most {SNAPLEN} bytes, not {len(header) + len(data)}")
    return packet_record(when, header + data)


def invented_port(name: str) -> int:
    """A stable port number (49152 … 65535) for a trace named ``name``."""
    return 49152 + zlib.crc32(name.encode()) % 16384


def _ipv4(address: str) -> bool:
    try:
        ipaddress.IPv4Address(address)
    except ValueError:
        return False
    return True


class PcapTracer:
    """Writes a pcap trace file (truncated when opened); the same interface as
    :class:`~devsim.transports.trace.Tracer`.

    ``peers`` is asked, for every chunk, for the (host, device) addresses of the conversation
    (``None``: not known, the invented ones are used); ``name`` picks the invented port; ``wait``:
    a fifo's writes wait for its reader (:class:`~devsim.transports.trace.TraceFile`)."""

    def __init__(
        self,
        path: str | Path,
        *,
        peers: Callable[[], Peers | None] | None = None,
        name: str = "",
        wait: bool = False,
    ) -> None:
        self.path = str(path)
        self._peers = peers
        port = invented_port(name or Path(self.path).stem)
        self._invented: Peers = ((INVENTED_HOST, port), (INVENTED_DEVICE, port))
        self._ident = 0
        self._file = TraceFile(self.path, text=False, head=global_header(), wait=wait)

    @property
    def closed(self) -> bool:
        return self._file.closed

    def addresses(self) -> Peers:
        """The (host, device) addresses the next packet gets."""
        known = self._peers() if self._peers is not None else None
        if known is None:
            return self._invented
        (host, host_port), (device, device_port) = known
        if not (_ipv4(host) and _ipv4(device)):
            return ((INVENTED_HOST, host_port), (INVENTED_DEVICE, device_port))
        return known

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        """One chunk; ``direction`` is ``"H>D"`` or ``"D>H"`` (``note`` is not kept)."""
        if direction not in ("H>D", "D>H"):
            raise ValueError(f"direction must be 'H>D' or 'D>H', not {direction!r}")
        if not data or self._file.closed:
            return
        host, device = self.addresses()
        src, dst = (host, device) if direction == "H>D" else (device, host)
        out = bytearray()
        for start in range(0, len(data), MAX_PAYLOAD):
            self._ident = (self._ident + 1) & 0xFFFF
            out += packet_record(when, ipv4_udp_packet(src, dst, bytes(data[start : start + MAX_PAYLOAD]), self._ident))
        self._file.write(out)

    def note(self, text: str, when: float) -> None:
        """Events that are not data have no place in a pcap file."""

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> PcapTracer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


#: The line settings a serial record's header carries: ``baud``, ``bits``, ``parity``, ``stop``
#: (0 / ``""`` where not known) and ``mismatch`` (:func:`devsim.transports.line.wire_settings`).
LineState = dict[str, Any]

_UNKNOWN: LineState = {"baud": 0, "bits": 0, "parity": "", "stop": 0, "mismatch": False}


class SerialPcapTracer:
    """Writes a pcap trace of a serial line (link type :data:`LINKTYPE_USER0`, truncated when
    opened); the same interface as :class:`~devsim.transports.trace.Tracer`.

    ``protocol`` and ``port`` are the header's bytes (the port's capture tag); ``settings`` is
    asked, for every chunk, for the line settings of the moment (``None``: the trace has no line,
    every setting "not known"); ``wait``: a fifo's writes wait for its reader
    (:class:`~devsim.transports.trace.TraceFile`)."""

    def __init__(self, path: str | Path, *, protocol: int = 0, port: int = 0,
                 settings: Callable[[], LineState] | None = None, wait: bool = False) -> None:
        self.path = str(path)
        self.protocol = protocol
        self.port = port
        self.settings = settings
        self._file = TraceFile(self.path, text=False, head=global_header(LINKTYPE_USER0), wait=wait)

    @property
    def closed(self) -> bool:
        return self._file.closed

    def header(self, direction: str) -> bytes:
        """The devsim header the next chunk in ``direction`` gets."""
        state = self.settings() if self.settings is not None else _UNKNOWN
        return serial_header(direction, self.protocol, self.port, state["baud"], state["bits"], state["parity"],
                             state["stop"], state["mismatch"])

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        """One chunk; ``direction`` is ``"H>D"`` or ``"D>H"`` (``note`` is not kept)."""
        header = self.header(direction)  # checks the direction
        if not data or self._file.closed:
            return
        out = bytearray()
        for start in range(0, len(data), MAX_SERIAL_CHUNK):
            out += serial_record(when, header, bytes(data[start : start + MAX_SERIAL_CHUNK]))
        self._file.write(out)

    def note(self, text: str, when: float) -> None:
        """Events that are not data have no place in a pcap file."""

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> SerialPcapTracer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
