"""What a transport is: somewhere a host's bytes come from and the device's bytes go to.

A transport knows no device.  It moves bytes between a host (a program holding a pty, a TCP
client, an RFC 2217 client) and an :class:`Endpoint` – in practice a
:class:`devsim.transports.line.Line`, which adds what a real cable does (pacing, baud-rate
mismatch, tracing) in front of a device or a multidrop bus.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Protocol

from devsim.core.device import SerialSettings

__all__ = ["Endpoint", "Transport"]


class Endpoint(Protocol):
    """The device side of a transport."""

    def attach(self, write: Callable[[bytes], None] | None) -> None:
        """Where to send bytes for the host (``None``: nobody listening)."""

    def feed(self, data: bytes) -> None:
        """Bytes from the host."""

    def host_settings(self, settings: SerialSettings) -> None:
        """The host opened or reconfigured its port with these line settings."""

    def host_disconnected(self) -> None:
        """The host went away (closed the pty, dropped the TCP connection)."""


class Transport(ABC):
    """Serves one endpoint on one host-facing port until closed."""

    #: Human-readable address of the port, printed by ``devsim run``.
    address: str = ""

    @abstractmethod
    async def start(self, endpoint: Endpoint) -> None:
        """Open the port and start serving ``endpoint`` (returns once the port exists)."""

    @abstractmethod
    async def close(self) -> None:
        """Stop serving and release the port."""

    @property
    def url(self) -> str:
        """A pyserial URL or device path a host can open."""
        return self.address

    def trace_peers(self) -> tuple[tuple[str, int], tuple[str, int]] | None:
        """The (host, device) ``(address, port)`` pairs of the conversation now on this port,
        for pcap traces; ``None`` where the transport has no such addresses (a pty) or no host yet."""
        return None
