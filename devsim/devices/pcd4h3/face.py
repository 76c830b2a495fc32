"""The PCD's S-Bus faces (spec pcd4h3.md §9.2, §9.3): the serial data mode on a pty (``sbus``)
and Ether-S-Bus on UDP (``ether_udp``, one telegram per datagram) and TCP (``ether_tcp``, frames
back to back).  CRC and framing errors and other stations get silence, unsupported commands a
NAK; the answer leaves ``response_delay_ms`` after the request, on the device clock.
"""

from __future__ import annotations

from devsim.core.clock import Timer
from devsim.core.device import Face, Port, SerialSettings
from devsim.devices.pcd4h3.model import Pcd4
from devsim.devices.pcd4h3.sbus import (
    EtherReceiver,
    SerialReceiver,
    ether_ack,
    ether_reply,
    parse_ether,
    serial_ack,
    serial_reply,
)
from devsim.devices.pcd4h3.services import Answer, serve, telegram

__all__ = ["EtherDatagramFace", "EtherStreamFace", "SbusFace"]


class _Delayed(Face):
    """Answers sent after the PCD's response delay, in order."""

    model: Pcd4

    def __init__(self, model: Pcd4, port: Port) -> None:
        super().__init__(model, port)
        self._timers: list[Timer] = []

    def _answer(self, data: bytes) -> None:
        delay = float(self.model.settings["response_delay_ms"]) / 1000
        if delay <= 0:
            self.send(data)
            return

        def go() -> None:
            self._timers.remove(timer)
            self.send(data)

        timer = self.model.clock.call_later(delay, go)
        self._timers.append(timer)

    def close(self) -> None:
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()


class SbusFace(_Delayed):
    """S-Bus serial data mode (SM2): FS B5h, stuffing, CRC-16 (§9.2); 9600 8N1 by default."""

    def __init__(self, model: Pcd4, port: Port) -> None:
        super().__init__(model, port)
        self.receiver = SerialReceiver(model.station, telegram, crc_excludes_fs=model.settings["crc_excludes_fs"])

    @property
    def serial_settings(self) -> SerialSettings:
        return SerialSettings(9600, 8, "N", 1)

    def feed(self, data: bytes) -> None:
        for request in self.receiver.feed(data):
            answer = serve(self.model, request)
            if answer is not None:
                self._answer(serial_reply(answer) if isinstance(answer, bytes) else serial_ack(answer))

    def host_disconnected(self) -> None:
        self.receiver.reset()


def _ether_answer(frame: bytes, model: Pcd4) -> bytes | None:
    parsed = parse_ether(frame)
    if parsed is None:
        return None
    version, sequence, request = parsed
    if request.station not in (model.station, 255):
        return None
    answer: Answer = serve(model, request)
    if answer is None:
        return None
    return ether_reply(version, sequence, answer) if isinstance(answer, bytes) else ether_ack(version, sequence, answer)


class EtherDatagramFace(_Delayed):
    """Ether-S-Bus on UDP: each datagram one telegram (§9.3)."""

    def feed(self, data: bytes) -> None:
        reply = _ether_answer(bytes(data), self.model)
        if reply is not None:
            self._answer(reply)


class EtherStreamFace(_Delayed):
    """Ether-S-Bus on TCP: telegrams back to back, delimited by their length field (§9.3)."""

    def __init__(self, model: Pcd4, port: Port) -> None:
        super().__init__(model, port)
        self.receiver = EtherReceiver()

    def feed(self, data: bytes) -> None:
        for frame in self.receiver.feed(data):
            reply = _ether_answer(frame, self.model)
            if reply is not None:
                self._answer(reply)

    def host_disconnected(self) -> None:
        self.receiver = EtherReceiver()
