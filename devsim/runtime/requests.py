"""The control API's requests as typed records, one per op (README "Control API").

The op table (:data:`devsim.runtime.ops.CONTROL`) names each record's op and the handler that
carries it out; a request that arrives as JSON (the control server, the fleet) is converted into
its record, one that is made in process (``devsim ctl``, the pytest plugin, the MQTT and OPC UA
command paths) is built directly.  Pure data: no I/O, no runtime.

A ``device`` that is optional (``now``, ``advance``, ``info``) only routes the request in a fleet: one
process has one clock.
"""

from __future__ import annotations

from typing import Any

import msgspec

__all__ = [
    "MIN_WATCH_PERIOD",
    "Advance",
    "Capture",
    "ControlRequest",
    "Devices",
    "Info",
    "Line",
    "LineFault",
    "Names",
    "Now",
    "PowerCycle",
    "Read",
    "Scenario",
    "Set",
    "State",
    "SwitchFault",
    "Telegrams",
    "Watch",
]


class ControlRequest(msgspec.Struct, frozen=True):
    """The base of every request record."""


class Read(ControlRequest, frozen=True):
    device: str
    name: str


class Set(ControlRequest, frozen=True):
    device: str
    name: str
    value: Any = None


class State(ControlRequest, frozen=True):
    device: str


class PowerCycle(ControlRequest, frozen=True):
    device: str
    wipe: bool = False


class Advance(ControlRequest, frozen=True):
    seconds: float | None = None
    device: str | None = None


class Now(ControlRequest, frozen=True):
    device: str | None = None


class Devices(ControlRequest, frozen=True):
    pass


class Info(ControlRequest, frozen=True):
    device: str | None = None


class Line(ControlRequest, frozen=True):
    device: str
    port: str = "main"


class Names(ControlRequest, frozen=True):
    device: str


class SwitchFault(ControlRequest, frozen=True):
    device: str
    kind: str
    active: Any = True


class LineFault(ControlRequest, frozen=True):
    device: str
    kind: str
    active: Any = True
    port: str = "main"
    params: dict[str, Any] = {}


class Telegrams(ControlRequest, frozen=True):
    device: str
    port: str = "main"
    count: int = 20


#: The shortest sampling period of a watch (device seconds): a shorter one samples millions of
#: times per simulated second, and one client's watch would stop the simulator for every other.
MIN_WATCH_PERIOD = 0.001


class Watch(ControlRequest, frozen=True):
    device: str
    names: list[str] | None = None
    period: float | None = None  # (MIN_WATCH_PERIOD at least)


class Capture(ControlRequest, frozen=True):
    device: str
    port: str = "main"


class Scenario(ControlRequest, frozen=True):
    device: str | None = None
