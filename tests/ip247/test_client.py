"""The PG-side client against the device side of the link (spec ip247.md §3.5, §3.6.7)."""

from __future__ import annotations

import pytest

from devsim.devices.ip247.as511 import As511Link, Refused
from devsim.devices.ip247.client import As511Error, PgClient

SYS_ID = bytes.fromhex("00 04 46 00 00 00 00 00 49 50 32 34 37 20 41 30 32 2E 31 20 00 0B 00 01 00 00")


class Wire:
    """The PG's serial port wired straight to the device's link layer (both pure, in memory)."""

    def __init__(self, link: As511Link) -> None:
        self.link, self.pending = link, bytearray()

    def write(self, data: bytes) -> int:
        self.pending += b"".join(self.link.feed(data))
        return len(data)

    def read(self, size: int = 1) -> bytes:
        data, self.pending = bytes(self.pending[:size]), self.pending[size:]
        return data


def device(replies: dict[int, object]) -> As511Link:
    return As511Link(lambda fn: fn in replies, lambda fn, params: replies[fn])  # type: ignore[arg-type, return-value]


def test_a_read_a_write_without_data_and_refusals() -> None:
    client = PgClient(Wire(device({0x64: SYS_ID, 0x61: None, 0x65: Refused(), 0x62: b"\x10\x00\x10"})))
    assert client.transaction(0x64, bytes.fromhex("04 46 00 00")) == SYS_ID
    assert client.transaction(0x61, bytes.fromhex("01 08 01 05 00 00 00 00 00 00"), data_phase=False) is None
    assert client.transaction(0x62, b"\x01") == b"\x10\x00\x10"  # DLE doubling, also as the first byte
    with pytest.raises(As511Error, match="refused"):
        client.transaction(0x18, b"")  # vector (f): unknown function
    with pytest.raises(As511Error, match="refused"):
        client.transaction(0x65, b"\x04\x17\x05")
    assert client.transaction(0x64, bytes.fromhex("04 46 00 00")) == SYS_ID  # the link is ready again


def test_a_silent_device_is_a_timeout() -> None:
    class Silent:
        def write(self, data: bytes) -> int:
            return len(data)

        def read(self, size: int = 1) -> bytes:
            return b""

    with pytest.raises(As511Error, match="timeout"):
        PgClient(Silent()).transaction(0x64, b"")
