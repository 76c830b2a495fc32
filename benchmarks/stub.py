"""A stand-in device for checking the benchmarks' plumbing (``--kind stub``).

It echoes the command and answers every CR like a SERS in echo mode (``\\n0\\nok1\\n\\r``),
doing as little work as a device possibly can.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device, UnknownName


class StubDevice(Device):
    kind: ClassVar[str] = "stub"
    description: ClassVar[str] = "benchmark stand-in"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._buf = bytearray()

    def feed(self, data: bytes) -> None:
        self.send(data)
        self._buf += data
        while b"\r" in self._buf:
            _, _, rest = bytes(self._buf).partition(b"\r")
            self._buf = bytearray(rest)
            self.send(b"\n0\nok1\n\r")

    def read(self, name: str) -> Any:
        raise UnknownName(name)

    def set(self, name: str, value: Any) -> None:
        raise UnknownName(name)

    def state(self) -> dict[str, Any]:
        return {}
