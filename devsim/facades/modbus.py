"""A device's declared points served over Modbus (issue 13; issue 29: conforming to the Modbus
Application Protocol Specification V1.1b3 and the Modbus Messaging on TCP/IP Implementation Guide
V1.0b): Modbus TCP on a socket of its own, Modbus RTU on any devsim serial transport (a pty, raw
TCP, RFC 2217).  Every read takes the device's present values, every write goes through the
device's ``set`` with its validation; a value the device refuses is exception 03 (illegal data
value), an address outside the map 02 (illegal data address).  Extra ``devsim-motion[modbus]``.

The requests are answered by :mod:`devsim.facades.modbus_pdu` (one table of function codes); this
module frames them.  pymodbus 3.16's server stood here before issue 29: it answered an unknown
function with ``80 01``, a read of 0 or too many registers with ``80 01`` on TCP and silence on
RTU, only the first of several requests in one TCP segment, and went silent for good after one
request with a protocol identifier other than 0; its CRC (``FramerRTU.compute_CRC``) is still used.
The map is :class:`devsim.facades.modbus_map.ModbusMap`; everything here runs in the runtime's
event loop, beside the device's own ports.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import struct
import time
from collections.abc import Callable, Sequence
from typing import Any

from pymodbus.framer import FramerRTU

import devsim
from devsim.core.device import Device, SerialSettings
from devsim.core.kit import CaptureTag
from devsim.core.points import BadValue, ReadOnlyName
from devsim.facades import modbus_ident, modbus_pdu
from devsim.facades.modbus_map import ModbusMap, from_words, to_words
from devsim.facades.modbus_pdu import ILLEGAL_ADDRESS, ILLEGAL_VALUE, Refused
from devsim.transports.hosts import DEFAULT_IDLE_DROP, admit, dropped, listen_backlog, refuse

__all__ = ["ModbusFacade", "ModbusRtuEndpoint", "ModbusTcpServer", "device_map", "device_unit", "line_settings", "serve_tcp",
           "start_modbus"]

#: A Modbus RTU line's pcap records: protocol 16 (docs/wireshark.md; Wireshark's ``mbrtu`` decodes them).
MODBUS_RTU_CAPTURE = CaptureTag(16)

#: Messaging on TCP/IP §4.4.1.2: 0xFF is the unit identifier of a server addressed by its IP
#: address, and "the value 0 is also accepted to communicate directly to a MODBUS/TCP device".
DIRECT_UNITS = (0x00, 0xFF)
#: Messaging on TCP/IP §4.4.2.5 (exception 0B): "the targeted device failed to respond".
GATEWAY_NO_RESPONSE = 0x0B
#: Messaging on TCP/IP §3.1.3: the MBAP header; its length counts the unit identifier and the PDU
#: (at most 253 bytes, Application Protocol §4.1).
MBAP = struct.Struct(">HHHB")
MAX_PDU = 253
#: How many Modbus TCP clients the server serves at once.  Messaging on TCP/IP §4.2.1 leaves the
#: number of connections to the implementation (a device keeps a small pool and closes an unused
#: connection for a new one): 8 ([DECISION]); one more client is refused unless one has been idle
#: longer than the idle-drop time (:mod:`devsim.transports.hosts`).
MODBUS_TCP_HOSTS = 8
#: Bytes of answers a Modbus TCP connection holds unsent before it stops reading requests
#: ([SIM-CHOICE], :class:`_TcpSession`).
HELD = 64 * 1024
#: Requests a Modbus TCP connection answers in one turn of the event loop ([SIM-CHOICE]): a read
#: of 256 KiB of pipelined requests (21,845 reads of 125 registers, 1.4 ms each) waits its turns
#: beside the other ports, the control API and a SIGTERM instead of holding the loop for 30 s.
TURN = 100


class ModbusFacade:
    """One device behind its Modbus map with unit id ``unit``: the :class:`~devsim.facades.modbus_pdu.Tables`
    the application layer reads and writes."""

    def __init__(self, device: Device, mapping: ModbusMap | None = None, unit: int = 1) -> None:
        self.device = device
        self.map = mapping if mapping is not None else ModbusMap.generate(device.points)
        self.unit = unit

    def answer(self, pdu: bytes) -> bytes:
        """The response PDU to a request PDU (Application Protocol §6, §7)."""
        return modbus_pdu.answer(self, pdu)

    def identification(self) -> dict[int, bytes]:
        """The Read Device Identification objects (Application Protocol §6.21): devsim, the
        kind, devsim's version, the kind's description, the device's name (:mod:`modbus_ident`)."""
        return modbus_ident.identification(self.device.kind, type(self.device).description, self.device.name,
                                           devsim.__version__)

    def read_bits(self, table: str, address: int, count: int) -> list[bool]:
        entries = [self._entry(table, address + i) for i in range(count)]
        return [bool(self._value(entry.name)) for entry, _ in entries]

    def write_bits(self, address: int, values: Sequence[bool]) -> None:
        targets = [self._entry("coil", address + i)[0].name for i in range(len(values))]
        self._set([(name, self._check(name, bool(value))) for name, value in zip(targets, values, strict=True)])

    def read_words(self, table: str, address: int, count: int) -> list[int]:
        found = [self._entry(table, address + i) for i in range(count)]
        words = {entry.name: to_words(self._value(entry.name), entry.scale) for entry, _ in found}  # (one read a pair)
        return [words[entry.name][offset] for entry, offset in found]

    def write_words(self, address: int, values: Sequence[int]) -> None:
        touched = {}
        for i in range(len(values)):
            entry, _ = self._entry("holding", address + i)
            touched[entry.name] = entry
        changes = []
        for entry in touched.values():  # a pair written in part keeps its other word
            words = list(to_words(self._value(entry.name), entry.scale))
            for i in range(2):
                written = entry.address + i - address
                if 0 <= written < len(values):
                    words[i] = int(values[written])
            changes.append((entry.name, self._check(entry.name, from_words(*words, entry.scale, entry.type))))
        self._set(changes)

    def _entry(self, table: str, address: int) -> Any:
        found = self.map.find(table, address)
        if found is None:
            raise Refused(ILLEGAL_ADDRESS)
        return found

    def _check(self, name: str, value: Any) -> Any:
        try:
            return self.device.check(name, value)
        except (BadValue, ReadOnlyName, ValueError):
            raise Refused(ILLEGAL_VALUE) from None

    def _set(self, changes: list[tuple[str, Any]]) -> None:
        """Every value checked first, then all set: a refused one leaves the others unwritten."""
        try:
            for name, value in changes:
                self.device.set(name, value)
        except (BadValue, ReadOnlyName, ValueError):
            raise Refused(ILLEGAL_VALUE) from None

    def _value(self, name: str) -> Any:
        point = self.device.points.find(name)
        if point is None or point.get is None:
            return 0  # a write-only point reads 0
        value = self.device.read(name)
        return 0 if value is None else value


class _TcpSession(asyncio.Protocol):
    """One Modbus TCP connection (Messaging on TCP/IP §4.4.2): every request of a segment is
    answered, in order; one with a protocol identifier other than 0 is discarded unanswered
    (§4.4.2.2), a length no PDU has closes the connection.

    [SIM-CHOICE] A client that sends requests and does not read the answers is not read either
    while more than :data:`HELD` bytes of answers wait unsent (TCP's own flow control then holds
    it back, as a device whose send buffer is full stops taking requests): what the session holds
    is those bytes, one answer and the requests of one read; the socket's send buffer is HELD too.
    Before, every request was answered into asyncio's unbounded write buffer (24 bytes of answer
    for 12 of request, up to 259 for a read of 125 registers), and the rest of a read was cut off
    request by request (each cut a copy of the rest).  A read of many requests is answered :data:`TURN` at a time, a loop turn each,
    the connection not read meanwhile: before, a read of 256 KiB of requests held the loop, and a
    SIGTERM, for half a minute and more."""

    def __init__(self, facade: ModbusFacade, sessions: _Sessions) -> None:
        self.facade = facade
        self.sessions = sessions
        self.buffer = bytearray()  # requests not answered yet (at most one read, and a part of one)
        self.transport: asyncio.Transport | None = None
        self.peer: object = None
        self.since = self.heard = 0.0
        self.full = False  # more than HELD bytes of answers wait unsent: requests wait unread
        self.held_peak = 0  # the most bytes of answers asyncio held unsent after a read's answers
        self._turn: asyncio.Handle | None = None  # the next turn's answers (a read of many requests)

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        self.peer = transport.get_extra_info("peername")
        self.since, self.heard = time.time(), time.monotonic()
        transport.set_write_buffer_limits(high=HELD)
        sock = transport.get_extra_info("socket")
        if sock is not None:  # (the kernel autotunes a send buffer to MBs for a client that does not read)
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, HELD)
        self.sessions.admit(self)

    def data_received(self, data: bytes) -> None:
        self.heard = time.monotonic()
        self.buffer += data
        self._serve()

    def pause_writing(self) -> None:
        self.full = True

    def resume_writing(self) -> None:
        self.full = False
        if self._turn is not None:
            self._turn.cancel()
        self._serve()

    def _serve(self) -> None:
        """Answer up to :data:`TURN` whole requests of :attr:`buffer`, in order, until the answers
        fill the write buffer (:meth:`pause_writing`); read on only when the buffer is answered."""
        self._turn = None
        buffer, start, answered = self.buffer, 0, 0
        try:
            while len(buffer) - start >= MBAP.size and self.transport is not None and not self.full:
                if answered == TURN:
                    break
                answered += 1
                transaction, protocol, length, unit = MBAP.unpack_from(buffer, start)
                if not 2 <= length <= MAX_PDU + 1:
                    # No PDU has this length (1 … 253 bytes, Application Protocol §4.1): past it the
                    # stream cannot be framed any more: the connection is closed.
                    self.transport.close()
                    self.transport = None
                    return
                end = start + 6 + length
                if len(buffer) < end:
                    break
                pdu, start = bytes(buffer[start + MBAP.size:end]), end
                if protocol != 0:
                    # §4.4.2.2: "If it is different from MODBUS protocol type, the indication is
                    # simply discarded": no answer; the requests after it are served.
                    continue
                response = self.answer(unit, pdu)
                self.transport.write(MBAP.pack(transaction, 0, len(response) + 1, unit) + response)
        finally:
            del buffer[:start]
            if self.transport is not None:  # (the answers of one call pile up: its end is their peak)
                self.held_peak = max(self.held_peak, self.transport.get_write_buffer_size())
        transport = self.transport
        if transport is None or transport.is_closing():
            return
        if self.full or answered == TURN:
            transport.pause_reading()  # (asyncio's pause and resume are idempotent)
            if not self.full:  # the next turn's requests, after whatever else the loop has to do
                self._turn = asyncio.get_running_loop().call_soon(self._serve)
        else:
            transport.resume_reading()

    def connection_lost(self, exc: Exception | None) -> None:
        self.transport = None
        self.sessions.discard(self)
        if self._turn is not None:
            self._turn.cancel()
            self._turn = None

    def answer(self, unit: int, pdu: bytes) -> bytes:
        """The device answers its own unit id, 0xFF and 0 (§4.4.1.2); to any other unit id, as a
        gateway with nothing behind it, exception 0B."""
        if unit in DIRECT_UNITS or unit == self.facade.unit:
            return self.facade.answer(pdu)
        return modbus_pdu.exception(pdu[0], GATEWAY_NO_RESPONSE)

    def close(self) -> None:
        if self.transport is not None:
            self.transport.close()


class _Sessions:
    """The connections a Modbus TCP server serves: at most ``hosts``; one more is refused, or
    takes the place of one idle longer than ``idle_drop`` seconds (:mod:`devsim.transports.hosts`)."""

    def __init__(self, hosts: int, idle_drop: float) -> None:
        self.hosts, self.idle_drop = hosts, idle_drop
        self.served: list[_TcpSession] = []
        self.address = ""

    def __iter__(self) -> Any:
        return iter(list(self.served))

    def __len__(self) -> int:
        return len(self.served)

    def admit(self, session: _TcpSession) -> None:
        admission = admit(self.served, self.hosts, self.idle_drop, lambda s: s.heard)
        if admission.action == "refuse":
            refuse(self.address, session.peer, self.hosts, [(s.peer, s.since) for s in self.served])
            session.close()
            session.transport = None
            return
        if admission.action == "drop":
            victim = admission.victim
            assert isinstance(victim, _TcpSession)
            dropped(self.address, victim.peer, time.monotonic() - victim.heard, session.peer)
            self.discard(victim)
            victim.close()
        self.served.append(session)

    def discard(self, session: _TcpSession) -> None:
        if session in self.served:
            self.served.remove(session)


class ModbusTcpServer:
    """The facade's Modbus TCP server: listens on a socket; :meth:`shutdown` closes it and the
    connections it serves."""

    def __init__(self, server: asyncio.Server, sessions: _Sessions) -> None:
        self.server = server
        self.sessions = sessions

    @property
    def port(self) -> int:
        return int(self.server.sockets[0].getsockname()[1])

    async def shutdown(self) -> None:
        self.server.close()
        for session in list(self.sessions):  # (Python 3.12's wait_closed waits for every client)
            session.close()
        await self.server.wait_closed()


async def serve_tcp(facade: ModbusFacade, host: str = "127.0.0.1", port: int = 502, *,
                    hosts: int = MODBUS_TCP_HOSTS, idle_drop: float | None = None) -> tuple[ModbusTcpServer, int]:
    """Modbus TCP on ``host:port`` (loopback unless the user names a host) for at most ``hosts``
    clients at once (``idle_drop``: seconds, default :data:`~devsim.transports.hosts.DEFAULT_IDLE_DROP`);
    returns the server and the port it listens on (``port`` 0: one the system chose)."""
    loop = asyncio.get_running_loop()
    sessions = _Sessions(hosts, DEFAULT_IDLE_DROP if idle_drop is None else idle_drop)
    listening = await loop.create_server(lambda: _TcpSession(facade, sessions), host, port, backlog=listen_backlog())
    server = ModbusTcpServer(listening, sessions)
    sessions.address = f"[{host}]:{server.port}" if ":" in host else f"{host}:{server.port}"
    return server, server.port


class ModbusRtuEndpoint:
    """Modbus RTU as the target of a devsim line (a pty, raw TCP, RFC 2217): frames are cut by
    structure (the function table's lengths, checked by the CRC), the device answers its unit id;
    other unit ids get silence, unit 0 (a broadcast) is carried out without an answer (Modbus over
    Serial Line V1.02 §2.2)."""

    def __init__(self, facade: ModbusFacade, settings: SerialSettings | None = None) -> None:
        self.facade = facade
        self._buffer = b""
        self._write: Callable[[bytes], None] | None = None
        self._settings = settings or SerialSettings(19200, 8, "E", 1)

    @property
    def serial_settings(self) -> SerialSettings:
        return self._settings

    def attach(self, write: Callable[[bytes], None] | None) -> None:
        self._write = write

    def host_disconnected(self) -> None:
        self._buffer = b""

    def feed(self, data: bytes) -> None:
        self._buffer += data
        while len(self._buffer) >= 4:
            size = self._frame_size(self._buffer)
            if size is None or (0 < size <= len(self._buffer) and not _crc_ok(self._buffer[:size])):
                self._buffer = self._buffer[1:]  # not a frame start (garbage, or misread): resynchronise
                continue
            if size == 0 or len(self._buffer) < size:
                later = self._next_frame(self._buffer)
                if later is None:
                    break  # wait for the rest
                self._buffer = self._buffer[later:]  # a frame cut short: a whole one follows it
                continue
            frame, self._buffer = self._buffer[:size], self._buffer[size:]
            self._serve(frame[0], frame[1:-2])
        if len(self._buffer) > 512:
            self._buffer = self._buffer[-256:]

    def _serve(self, unit: int, pdu: bytes) -> None:
        if unit not in (self.facade.unit, 0):
            return
        response = self.facade.answer(pdu)
        if unit != 0 and self._write is not None:
            self._write(_with_crc(bytes((unit,)) + response))

    @staticmethod
    def _frame_size(data: bytes) -> int | None:
        """How long the frame starting at ``data`` is (0: not known yet), or None if no request
        starts here.  A function the table knows gives its length; for any other code (and
        function 43 with another MEI type) the frame ends where its CRC first holds (it is
        answered with exception 01)."""
        function = modbus_pdu.FUNCTIONS.get(data[1])
        if function is not None and (length := function.rtu_length(data)) != modbus_pdu.CRC_ENDED:
            return length
        size = _crc_end(data[:MAX_PDU + 3])
        if size is None:
            return 0 if len(data) < MAX_PDU + 3 else None
        return size

    @staticmethod
    def _next_frame(data: bytes) -> int | None:
        """Where, after the first byte, a whole request of a known function with a good CRC starts:
        the frame at the start was cut short (noise, a host that gave up), and waiting for its
        rest would keep the next requests waiting too."""
        for start in range(1, len(data) - 3):
            function = modbus_pdu.FUNCTIONS.get(data[start + 1])
            if function is None:
                continue
            size = function.rtu_length(data[start:])
            if size > 0 and start + size <= len(data) and _crc_ok(data[start:start + size]):
                return start
        return None


def _crc_ok(frame: bytes) -> bool:
    return FramerRTU.compute_CRC(frame[:-2]) == int.from_bytes(frame[-2:], "big")


def _with_crc(frame: bytes) -> bytes:
    return frame + FramerRTU.compute_CRC(frame).to_bytes(2, "big")


def _crc_end(data: bytes) -> int | None:
    """The shortest frame (4 bytes or more) at the start of ``data`` whose CRC holds, in one pass
    (Modbus over Serial Line V1.02 §6.2.2: CRC-16, low byte first; pymodbus's table)."""
    crc = 0xFFFF
    for end in range(len(data) - 2):
        crc = (crc >> 8) ^ FramerRTU.crc16_table[(crc ^ data[end]) & 0xFF]
        if end >= 1 and data[end + 1] == crc & 0xFF and data[end + 2] == crc >> 8:
            return end + 3
    return None


def line_settings(text: str) -> SerialSettings:
    """``"19200 8E1"`` as line settings (:meth:`SerialSettings.parse <devsim.core.device.SerialSettings.parse>`)."""
    return SerialSettings.parse(text)


def device_map(device: Device, layout: str = "points", overrides: dict[str, Any] | None = None) -> ModbusMap:
    """The map a device is served with: generated from its points (``points``), or the kind's own
    mirror of its families (``mirror``, e.g. the PCD's registers and flags, spec pcd4h3 §9.8)."""
    return ModbusMap.layout(device.points, layout, overrides)


def device_unit(device: Device, layout: str = "points") -> int:
    """The unit id a device answers unless one is named: 1, or in the kind's own layout (the
    mirror) the one the kind gives (``Device.modbus_unit``: the PCD's S-Bus station, spec pcd4h3
    §9.8) where it is a Modbus unit id (1 … 247)."""
    unit_of = type(device).modbus_unit
    if layout == "mirror" and unit_of is not None:
        unit = unit_of(device.model)
        if 1 <= unit <= 247:
            return unit
    return 1


async def start_modbus(runtime: Any, device: Device, spec: str, *, unit: int | None = None,
                       overrides: dict[str, Any] | None = None, trace: str | None = None,
                       line: str = "19200 8E1", layout: str = "points") -> tuple[str, Any]:
    """Serve ``device`` over Modbus in ``runtime`` (in its loop) as ``spec`` says: ``tcp:[HOST:]PORT``
    (Modbus TCP, loopback unless a host is named; pymodbus's own server, not traced), ``rtu`` (RTU
    on a new pty) or ``rtu:LINK`` (a pty with a stable symlink) at the ``line`` settings (Modbus's
    default 19200 8E1), answering ``unit`` (None: :func:`device_unit`).  The port key is ``NAME.modbus``; returns what a host opens and the pty
    transport (None for TCP)."""
    facade = ModbusFacade(device, device_map(device, layout, overrides),
                          unit if unit is not None else device_unit(device, layout))
    key = f"{device.name}.modbus"
    scheme, _, rest = spec.partition(":")
    if scheme == "tcp":
        host, _, number = rest.rpartition(":")
        server, bound = await serve_tcp(facade, host or "127.0.0.1", int(number or 502),
                                        idle_drop=getattr(runtime, "idle_drop", None))
        runtime.add_closer(server.shutdown)
        address = f"{host or '127.0.0.1'}:{bound}"
        runtime.ports[key] = address
        return address, None
    if scheme != "rtu":
        raise ValueError(f"--modbus: expected tcp:[HOST:]PORT, rtu or rtu:LINK, not {spec!r}")
    from devsim.transports.pty import PtyTransport

    transport = PtyTransport(link=rest or None)
    await runtime.serve_target([key], ModbusRtuEndpoint(facade, line_settings(line)), transport, trace=trace,
                               capture=MODBUS_RTU_CAPTURE)
    return str(getattr(transport, "url", "") or transport.address), transport
