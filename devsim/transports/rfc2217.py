"""RFC 2217 (Telnet COM Port Control): a serial device server whose line settings travel
with the data.

The Telnet and RFC 2217 state machine is pyserial's own server side,
:class:`serial.rfc2217.PortManager`, the same code ``rfc2217_server.py`` uses.  PortManager
expects a serial port to configure; here it gets :class:`NegotiatedPort`, a stand-in that only
records what the client negotiates (baud rate, data bits, parity, stop bits, flow control, DTR,
RTS, break) and presents the modem lines of a powered device (CTS, DSR and CD on, RI off).  The
negotiated settings go to ``endpoint.host_settings()``, so a client that opens the port at the
wrong baud rate talks to the device through a garbling :class:`~devsim.transports.line.Line`.

One client at a time exactly as with :class:`~devsim.transports.tcp.TcpTransport`: another one is
refused at once, or takes the place of a host idle for longer than the idle-drop time.
Open the port with pyserial as ``rfc2217://HOST:PORT`` (:attr:`Rfc2217Transport.url`).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterator
from typing import Any

from serial.rfc2217 import (
    M_IAC_SEEN,
    M_NORMAL,
    SE,
    SET_BAUDRATE,
    SET_DATASIZE,
    SET_PARITY,
    SET_STOPSIZE,
    PortManager,
)

from devsim.core.device import SerialSettings
from devsim.transports.base import Endpoint
from devsim.transports.tcp import TcpTransport, _Session

__all__ = ["MAX_SUBOPTION", "NegotiatedPort", "Rfc2217Transport"]


class NegotiatedPort:
    """The serial-port stand-in PortManager configures: it records, it does not drive a UART.

    ``on_change`` is called whenever the client sets one of the four line settings.
    """

    cts = True
    dsr = True
    ri = False
    cd = True

    def __init__(self, initial: SerialSettings, on_change: Callable[[], None]) -> None:
        self._baudrate = initial.baudrate
        self._bytesize = initial.bytesize
        self._parity = initial.parity
        self._stopbits: float = initial.stopbits
        self._on_change = on_change
        self.xonxoff = False
        self.rtscts = False
        self.dtr = True
        self.rts = True
        self.break_condition = False

    def _set(self, name: str, value: Any) -> None:
        # Reported even when unchanged: the client has now told us what it uses.
        setattr(self, name, value)
        self._on_change()

    @property
    def baudrate(self) -> int:
        return self._baudrate

    @baudrate.setter
    def baudrate(self, value: int) -> None:
        if value <= 0:
            raise ValueError(f"invalid baud rate {value}")
        self._set("_baudrate", int(value))

    @property
    def bytesize(self) -> int:
        return self._bytesize

    @bytesize.setter
    def bytesize(self, value: int) -> None:
        if value not in (5, 6, 7, 8):
            raise ValueError(f"invalid data size {value}")
        self._set("_bytesize", int(value))

    @property
    def parity(self) -> str:
        return self._parity

    @parity.setter
    def parity(self, value: str) -> None:
        self._set("_parity", value)

    @property
    def stopbits(self) -> float:
        return self._stopbits

    @stopbits.setter
    def stopbits(self, value: float) -> None:
        self._set("_stopbits", value)

    @property
    def settings(self) -> SerialSettings:
        stop = self._stopbits
        return SerialSettings(
            baudrate=self._baudrate,
            bytesize=self._bytesize,
            parity=self._parity,
            stopbits=int(stop) if float(stop).is_integer() else stop,
        )

    def reset_input_buffer(self) -> None:
        """Purge request: nothing is buffered on this side."""

    def reset_output_buffer(self) -> None:
        """Purge request: nothing is buffered on this side."""


#: RFC 2217's request for the current value of each line setting (the value 0), by command.
_ASK_CURRENT = {SET_BAUDRATE: bytes(4), SET_DATASIZE: bytes(1), SET_PARITY: bytes(1), SET_STOPSIZE: bytes(1)}


#: Bytes of one subnegotiation kept at most (RFC 2217's longest is a signature text; a setting is
#: 2 + 4 bytes).  [SIM-CHOICE] a bound: a client's IAC SB with no IAC SE after it kept every byte
#: it sent from then on.
MAX_SUBOPTION = 256


class _Manager(PortManager):
    """pyserial's server side, safe from a client's malformed subnegotiation: a parity or stop
    size code RFC 2217 does not define, a value cut short.  pyserial catches only ``ValueError``,
    so these raised out of the telnet filter: the connection was dropped with a traceback, and
    the filter's state was left inside the subnegotiation.  Such a setting is answered as RFC 2217
    answers one the server does not take, with the current value; a mask cut short is ignored.
    An IAC SE outside a subnegotiation ends nothing and is dropped (pyserial's filter made
    ``bytes(None)`` of it, a TypeError out of the filter).  A subnegotiation keeps its first
    :data:`MAX_SUBOPTION` bytes; the rest up to its IAC SE is dropped."""

    def filter(self, data: bytes) -> Iterator[bytes]:
        start = 0
        while (end := data.find(SE, start)) >= 0:
            # (the filter's state before this SE decides: IAC seen, no subnegotiation open)
            yield from self._bounded(data[start:end])
            if self.mode == M_IAC_SEEN and self.suboption is None:
                self.mode = M_NORMAL
            else:
                yield from super().filter(SE)
            start = end + 1
        yield from self._bounded(data[start:])

    def _bounded(self, data: bytes) -> Iterator[bytes]:
        yield from super().filter(data)
        if self.suboption is not None and len(self.suboption) > MAX_SUBOPTION:
            del self.suboption[MAX_SUBOPTION:]

    def _telnet_process_subnegotiation(self, suboption: bytes) -> None:
        try:
            super()._telnet_process_subnegotiation(suboption)
        except (KeyError, TypeError, struct.error):
            current = _ASK_CURRENT.get(suboption[1:2])
            if current is not None:
                super()._telnet_process_subnegotiation(suboption[:2] + current)


class _Client:
    """Per-client RFC 2217 state."""

    def __init__(self, session: _Session, endpoint: Endpoint, initial: SerialSettings) -> None:
        self.session = session
        self.endpoint = endpoint
        self.pending = bytearray()  # data filtered out of the current chunk, not yet fed
        self.dirty = False
        self.reported: SerialSettings | None = None
        self.port = NegotiatedPort(initial, self._changed)
        self.manager = _Manager(self.port, self)  # sends the initial option requests

    def write(self, data: bytes) -> None:
        """PortManager's connection: Telnet replies go straight to the socket."""
        self.session.send(bytes(data))

    def _changed(self) -> None:
        # Data before the change was sent under the old settings: deliver it first.
        self._flush_data()
        self.dirty = True

    def _flush_settings(self) -> None:
        if self.dirty:
            self.dirty = False
            settings = self.port.settings
            if settings != self.reported:
                self.reported = settings
                self.endpoint.host_settings(settings)

    def _flush_data(self) -> None:
        if self.pending:
            self._flush_settings()
            data = bytes(self.pending)
            self.pending.clear()
            self.endpoint.feed(data)

    def received(self, data: bytes) -> None:
        for byte in self.manager.filter(data):
            self.pending += byte
        self._flush_data()
        self._flush_settings()


class Rfc2217Transport(TcpTransport):
    """An RFC 2217 server port serving one endpoint, one client at a time."""

    scheme = "rfc2217"

    def limit_hosts(self, hosts: int, idle_drop: float | None = None, split: Any = None) -> None:
        """An RFC 2217 port is a serial port: one host, whatever the port serves elsewhere."""
        super().limit_hosts(1, idle_drop)

    def _session_started(self, session: _Session, endpoint: Endpoint) -> None:
        preset = getattr(endpoint, "serial_settings", None)
        initial = preset if isinstance(preset, SerialSettings) else SerialSettings()
        session.state = _Client(session, endpoint, initial)

    def _session_data(self, session: _Session, data: bytes, endpoint: Endpoint) -> None:
        client = session.state
        if isinstance(client, _Client):
            client.received(data)

    def _send(self, session: _Session, data: bytes) -> None:
        client = session.state
        if isinstance(client, _Client):
            session.send(b"".join(client.manager.escape(data)))
