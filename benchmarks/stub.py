"""A stand-in device for checking the benchmarks' plumbing (``--kind stub``).

It echoes the command and answers every CR like a SERS in echo mode (``\\n0\\nok1\\n\\r``),
doing as little work as a device possibly can.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device, Face


class StubFace(Face):
    def __init__(self, model: Any, port: Any) -> None:
        super().__init__(model, port)
        self._buf = bytearray()

    def feed(self, data: bytes) -> None:
        self.send(data)
        self._buf += data
        while b"\r" in self._buf:
            _, _, rest = bytes(self._buf).partition(b"\r")
            self._buf = bytearray(rest)
            self.send(b"\n0\nok1\n\r")


class StubDevice(Device):
    kind: ClassVar[str] = "stub"
    description: ClassVar[str] = "benchmark stand-in"
    face_classes: ClassVar[dict[str, Any]] = {"main": StubFace}
