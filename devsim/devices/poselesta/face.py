"""The serial faces of the POSELESTA: V6 and V7 carry tape images, V8 key codes (manual §2.6;
spec poselesta.md §2.2, §2.6, §3.1).

There is no command/response protocol: a face hands the host's bytes to the control, which uses
them only while a transfer (or, on V8, the external keyboard) takes them, and sends what a
running output transfer emits.  The line settings are the port's baud rate (P68, P70, the
printer's 1200, V8's 1200) with two stop bits; the parity of ISO code travels in bit 7 of each
byte, so on a pty the frame is 8 bits without parity.
"""

from __future__ import annotations

from typing import Any

from devsim.core.device import Face, Port, SerialSettings
from devsim.devices.poselesta.model import PoselestaCnc

__all__ = ["PoselestaPortFace"]


class PoselestaPortFace(Face):
    """One of the ports ``v6``, ``v7``, ``v8`` (V8 never sends: its port is receive-only)."""

    model: PoselestaCnc

    def __init__(self, model: Any, port: Port) -> None:
        super().__init__(model, port)
        self.name = port.name
        self._settings = SerialSettings(1200, 8, "N", 2)
        model.listen(f"{self.name}_out", self.send)

    def feed(self, data: bytes) -> None:
        self.model.port_input(self.name, data)

    @property
    def serial_settings(self) -> SerialSettings:
        """8N2 at the port's baud rate, which carries every code of the manual as its host reads
        it (ISO's parity as the eighth bit); a character takes its frame's bits on the wire
        (§2.6.1.2: ISO 11, ASCII 10, the printer 12 or 11), which is what pacing times."""
        model = self.model
        baud, bits = model.baud(self.name) or 110, model.links.frame_bits(self.name)
        settings = self._settings
        if settings.baudrate != baud or settings.frame_bits != bits:
            settings = self._settings = SerialSettings(baud, 8, "N", 2, frame_bits=bits)
        return settings
