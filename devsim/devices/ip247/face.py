"""The IP247's two host faces (spec ip247.md §3.5–§3.7): the PG port, an AS511 link carrying
the "IP247-SIM/PG v1" profile, and the PLC-side endpoint "IP247-SIM/AG v1" (length-framed
messages with the same services, absolute pages, BCD values per machine data).

The AS511 link's 500 ms inter-character timeout runs on the device clock, from the last character
on the wire: spec §3.5.1 allows "no gap of 500 ms or more" inside a transaction, and while the
device itself is still sending (a program read, manual §4.3.21 "Verfahrprogramm Lesen (Betriebsart
69)": "Der COM247 benutzt diese Betriebsart", a thousand bytes take over a second at 9600 8E1)
there is no gap.  The device's own characters are counted at its line settings whether or not
the transport paces them.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.clock import Timer
from devsim.core.device import Face, Port, SerialSettings
from devsim.devices.ip247.as511 import TIMEOUT, As511Link, Reply, function_token
from devsim.devices.ip247.attributes import AgFramer, ag_frame
from devsim.devices.ip247.module import Ip247Module
from devsim.devices.ip247.pg_profile import ACK_NEGATIVE, FUNCTIONS, MAX_PARAMETERS, Header, parse_request
from devsim.devices.ip247.s5_services import S5_SERVICES, S5Memory
from devsim.devices.ip247.services import serve

__all__ = ["AgFace", "PgFace"]


class PgFace(Face):
    """The programmer port X8 (9600 8E1, spec §2.2): one PG, point to point."""

    model: Ip247Module

    def __init__(self, model: Ip247Module, port: Port) -> None:
        super().__init__(model, port)
        # (what the link refuses or abandons, and why, goes to the device's event log: watch, MQTT)
        self.link = As511Link(self._known, self._service, MAX_PARAMETERS,
                              lambda event: model.record_event(f"pg {event}"))
        self._timer: Timer | None = None
        self._line_free = 0.0  # when the device's last character sent has left the wire

    @property
    def serial_settings(self) -> SerialSettings:
        return SerialSettings(9600, 8, "E", 1)

    def _function(self, function: int) -> Callable[[int, bytes], Reply] | None:
        """Who serves a function code: the profile's functions (:data:`.pg_profile.FUNCTIONS`),
        and the standard S5 services (:data:`.s5_services.S5_SERVICES`) when configured."""
        token = function_token(function)
        if token in FUNCTIONS:
            return self._profile
        if token in S5_SERVICES and self.model.config.get("s5_services"):
            return self._s5
        return None

    def _known(self, function: int) -> bool:
        return self._function(function) is not None

    def _service(self, function: int, parameters: bytes) -> Reply:
        served = self._function(function)
        if served is None:  # known when the transaction began, the S5 services switched off since
            served = self._s5
        return served(function, parameters)

    def _profile(self, function: int, parameters: bytes) -> Reply:
        return serve(self.model, parse_request(function, parameters))

    def _s5(self, function: int, parameters: bytes) -> Reply:
        return S5Memory(self.model.channel.data_blocks()).service(function, parameters)

    def feed(self, data: bytes) -> None:
        if self.model.config.get("powered", True) is False or self.model.booting:
            return  # a module without power, or still starting, answers nothing (spec §3.6.5, §5.16)
        sent = 0
        for chunk in self.link.feed(data):
            self.send(chunk)
            sent += len(chunk)
        now = self.model.clock.now()
        if sent:  # (the UART sends one character after the other: after what is still going out)
            self._line_free = max(self._line_free, now) + sent * self.serial_settings.char_time()
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self.link.busy:  # the gap begins when the line falls silent (spec §3.5.1)
            self._timer = self.model.clock.call_later(max(self._line_free - now, 0.0) + TIMEOUT, self._expired)

    def _expired(self) -> None:
        self._timer = None
        self.link.timeout()

    def host_disconnected(self) -> None:
        self.link.timeout()

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()


class AgFace(Face):
    """The PLC side on TCP (spec §3.7): what FB164/FB165 would exchange through the pages."""

    model: Ip247Module

    def __init__(self, model: Ip247Module, port: Port) -> None:
        super().__init__(model, port)
        self.framer = AgFramer()

    def feed(self, data: bytes) -> None:
        if self.model.booting:
            return  # (the dual-port RAM is not served before the module runs)
        base = int(self.model.config.get("base_page", 0))
        for function, payload in self.framer.feed(data):
            if not payload and function_token(function) in FUNCTIONS:
                # no page byte: a wrong parameter length (ack 82H), not absolute page 0
                self.send(ag_frame(function, serve(self.model, parse_request(function, b""), plc=True)))
                continue
            asked = payload[0] if payload else 0
            page = asked - base + 1
            if function_token(function) not in FUNCTIONS or not 1 <= page <= 4:  # the PLC gets a handling-block error
                ba = payload[1] if len(payload) > 1 else 0
                self.send(ag_frame(function, Header(ACK_NEGATIVE, asked, ba, 0, 0, 0, 0, 0).pack()))
                continue
            answer = serve(self.model, parse_request(function, bytes((page,)) + payload[1:]), plc=True)
            self.send(ag_frame(function, answer[:1] + bytes((asked,)) + answer[2:]))

    def host_disconnected(self) -> None:
        self.framer = AgFramer()
