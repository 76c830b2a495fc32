"""The IP247 test helpers: a module on a real pty, driven through its PG port (spec ip247.md §3.5,
§3.6), and COM247's machine data with changes (§6.2)."""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

import msgspec
import serial

from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.client import PgClient
from devsim.devices.ip247.jobs import BACKWARD, FORWARD, START, STOP, TAKE_OVER
from devsim.devices.ip247.machine_data import decode, encode
from tests.ip247.test_machine_data import COM247, words

__all__ = ["BACKWARD", "FORWARD", "START", "STOP", "TAKE_OVER", "Make", "Module", "record"]


def record(**changes: object) -> str:
    """COM247's machine data (§6.2) with some items changed, as the record's hex words."""
    md = msgspec.structs.replace(decode(words(COM247)), **changes)
    return " ".join(f"{w:04X}" for w in encode(md))


class Module:
    """A module on a real pty, driven through its PG port with the AS511 client, in virtual time
    (the ``devsim_device`` fixture); most tests load COM247's machine data (§6.2: module 11,
    r = 1.1 µm, sync no) on axis 1."""

    def __init__(self, sim: Any) -> None:
        self.device = self.clock = sim  # read, set, fault; advance
        self.m = sim.device.model
        self.port = serial.serial_for_url(sim.port_url("pg"), baudrate=9600, parity="E", timeout=5)
        self.client = PgClient(self.port)

    def call(self, function: int, data: bytes) -> bytes:
        answer = self.client.transaction(function, data)
        assert answer is not None
        return answer

    def operate(self, page: int, ba: int, cmd: int, b: int = 0, w: int = 0, dd: int = 0) -> bytes:
        return self.call(0x61, struct.pack(">BBBBHi", page, ba, cmd, b, w, dd))

    def write(self, page: int, ba: int, db: int, record: list[int], flags: int = 0) -> bytes:
        return self.call(0x63, bytes((page, ba, db, flags)) + struct.pack(f">{len(record)}H", *record))

    def load_md(self, axis: int = 1, record: str = COM247) -> bytes:
        self.device.set(f"input.ANF{axis}", True)  # NC limit switches, not actuated: 24 V
        self.device.set(f"input.END{axis}", True)
        data = words(record)
        data[3] = (data[3] & 0xFF00) | axis
        return self.write(axis, 20, 100 + axis, data)

    def store(self, number: int, text: str) -> bytes:
        return self.write(4, 22, number, lang.record_words(number, text))

    def ready(self, axis: int = 1) -> None:
        assert self.load_md(axis)[8] == 0
        assert self.operate(axis, 5, START, b=1)[4] == 0  # "Referenzpunkt setzen"


Make = Callable[..., Module]
