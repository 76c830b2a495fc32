"""A stand-in device for checking the benchmarks' plumbing (``--kind stub``).

It echoes the command and answers every CR like a SERS in echo mode (``\\n0\\nok1\\n\\r``),
doing as little work as a device possibly can.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device, Face

_ANSWER = b"\n0\nok1\n\r"


class StubFace(Face):
    __slots__ = ()

    def feed(self, data: bytes) -> None:
        """The echo, then an answer for every CR in it, in one piece (what the port would join
        anyway); nothing else depends on earlier bytes."""
        lines = data.count(b"\r")
        self.send(data + _ANSWER * lines if lines else data)


class StubDevice(Device):
    kind: ClassVar[str] = "stub"
    description: ClassVar[str] = "benchmark stand-in"
    face_classes: ClassVar[dict[str, Any]] = {"main": StubFace}
