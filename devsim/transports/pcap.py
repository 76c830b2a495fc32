"""A wire trace as a libpcap file that Wireshark and tshark read.

The file is classic pcap (not pcapng): the little-endian global header (magic ``a1b2c3d4``
written as ``d4 c3 b2 a1``, version 2.4, microsecond timestamps, snap length 65535) and link
type :data:`LINKTYPE_IPV4` (228, raw IPv4: each packet starts with its IP header).  Every chunk
that crossed the line is one IPv4/UDP packet:

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

Notes that are not data (host settings, faults, disconnects) have no place in a pcap file and are
left out; the text trace (:mod:`devsim.transports.trace`) keeps them.

The packet building (:func:`ipv4_udp_packet`, :func:`global_header`, :func:`packet_record`,
:func:`checksum`) is pure; :class:`PcapTracer` writes with the same safety rules as
:class:`~devsim.transports.trace.Tracer` (no truncation through a symlink).
"""

from __future__ import annotations

import ipaddress
import math
import struct
import zlib
from collections.abc import Callable
from pathlib import Path

from devsim.transports.trace import create_trace_file

__all__ = [
    "LINKTYPE_IPV4",
    "MAX_PAYLOAD",
    "Address",
    "PcapTracer",
    "Peers",
    "checksum",
    "global_header",
    "invented_port",
    "ipv4_udp_packet",
    "packet_record",
]

#: Raw IPv4, no link-layer header (tshark decodes it as IP, then UDP).
LINKTYPE_IPV4 = 228
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
    (``None``: not known, the invented ones are used); ``name`` picks the invented port."""

    def __init__(
        self,
        path: str | Path,
        *,
        peers: Callable[[], Peers | None] | None = None,
        name: str = "",
    ) -> None:
        self.path = str(path)
        self._peers = peers
        port = invented_port(name or Path(self.path).stem)
        self._invented: Peers = ((INVENTED_HOST, port), (INVENTED_DEVICE, port))
        self._ident = 0
        self._file = open(create_trace_file(self.path), "wb")  # noqa: SIM115 - closed by close()
        self._file.write(global_header())
        self._file.flush()

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
        self._file.flush()

    def note(self, text: str, when: float) -> None:
        """Events that are not data have no place in a pcap file."""

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> PcapTracer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
