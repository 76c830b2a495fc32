"""A drive put on a shared RS-485 line without a bus: its port's peers as a bus sets them (the
drive itself and another drive), which is what makes the line shared (``Port.shared_line``)."""

from __future__ import annotations

from functools import cache
from typing import Any

from devsim.core.clock import VirtualClock
from devsim.core.device import Port
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers.device import SersDevice


@cache
def _other() -> Port:
    """A drive of address 127 on a line of its own clock: only its address is ever read."""
    return SersDevice(clock=VirtualClock(), config={"boot_time": 0, "address": 127}, nvram=NonVolatileMemory(None)).main


def share_line(device: Any, shared: bool) -> None:
    """Put ``device``'s main port on a line with another drive (``shared``) or on one of its own."""
    device.main.peers = (device.main, _other()) if shared else ()
