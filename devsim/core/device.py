"""The device base class and the byte interface between a line and a device.

A device is a byte-in / byte-out state machine with simulated physics behind it.  It never
touches a socket: a transport hands it the host's bytes through :meth:`Device.feed`, and the
device emits its answers through the ``write`` callback given to :meth:`Device.attach`.
Several devices can share one line (RS-485 multidrop): see :class:`devsim.core.bus.Bus`.

The control API reaches a device through :meth:`Device.read`, :meth:`Device.set`,
:meth:`Device.power_cycle` and :meth:`Device.state`; names are dotted paths such as
``axis.position``, ``param.P51``, ``input.limit_right`` or ``display``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from devsim.core.clock import Clock
from devsim.core.nvram import NonVolatileMemory
from devsim.core.signals import SignalBank

__all__ = ["ByteSink", "Device", "SerialSettings", "UnknownName"]

ByteSink = Callable[[bytes], None]


@dataclass(frozen=True)
class SerialSettings:
    """Line settings of a UART: what the device is configured for, or what the host opened."""

    baudrate: int = 9600
    bytesize: int = 8
    parity: str = "N"  # "N", "E", "O", "M", "S"
    stopbits: float = 1

    def describe(self) -> str:
        stop = int(self.stopbits) if float(self.stopbits).is_integer() else self.stopbits
        return f"{self.baudrate} {self.bytesize}{self.parity}{stop}"

    def char_time(self) -> float:
        """Seconds one character occupies on the wire (start + data + parity + stop bits)."""
        bits = 1 + self.bytesize + (0 if self.parity == "N" else 1) + float(self.stopbits)
        return bits / self.baudrate


class UnknownName(KeyError):
    """The control API asked for a name the device does not have."""


class Device(ABC):
    """Base class of every simulated controller.

    Subclasses set ``kind`` and ``description`` and implement :meth:`feed`, :meth:`read`,
    :meth:`set` and :meth:`state`.  ``config`` is the already validated device configuration
    (DIP switches, parameters, axis geometry) as a plain mapping.
    """

    kind: ClassVar[str] = ""
    description: ClassVar[str] = ""
    #: On a multidrop bus, also hear what the other devices send (not only the host).
    hears_others: ClassVar[bool] = False

    def __init__(
        self,
        *,
        clock: Clock,
        config: Mapping[str, Any] | None = None,
        nvram: NonVolatileMemory | None = None,
        name: str | None = None,
    ) -> None:
        self.clock = clock
        self.config: dict[str, Any] = dict(config or {})
        self.nvram = nvram if nvram is not None else NonVolatileMemory(None)
        self.name = name or self.kind
        self.signals = SignalBank()
        #: True when other devices share the line (RS-485 multidrop); set by the bus.
        self.shared_line = False
        #: True while the device initialises after power-on and does not listen yet.
        self.booting = False
        #: (simulated time, name) of notable moments, e.g. ("move_end", 1.321) for timing checks.
        self.events: list[tuple[float, str]] = []
        self._write: ByteSink | None = None

    # -- byte interface ------------------------------------------------------------------
    def attach(self, write: ByteSink | None) -> None:
        """Connect (or with ``None`` disconnect) the device's output to a line."""
        self._write = write

    def send(self, data: bytes) -> None:
        """Emit bytes towards the host (dropped when nothing is attached, like a dead line)."""
        if data and self._write is not None:
            self._write(data)

    @abstractmethod
    def feed(self, data: bytes) -> None:
        """Bytes from the host, in arrival order, possibly split anywhere."""

    def host_disconnected(self) -> None:  # noqa: B027 - optional hook, default does nothing
        """The host closed the port (or its TCP connection dropped); default: nothing."""

    @property
    def serial_settings(self) -> SerialSettings:
        """The UART settings the device is configured for (from its DIP switches)."""
        return SerialSettings()

    # -- control API ---------------------------------------------------------------------
    @abstractmethod
    def read(self, name: str) -> Any:
        """Read one piece of state by dotted name; raises :class:`UnknownName`."""

    @abstractmethod
    def set(self, name: str, value: Any) -> None:
        """Set an input or quantity by dotted name; raises :class:`UnknownName`."""

    @abstractmethod
    def state(self) -> dict[str, Any]:
        """A JSON-serialisable snapshot of the interesting state."""

    def record_event(self, name: str) -> None:
        """Note a moment (``move_start``, ``move_end``, ``error`` ...) for timing expectations."""
        self.events.append((self.clock.now(), name))
        if len(self.events) > 10000:
            del self.events[:5000]

    def apply_state(self, state: Mapping[str, Any]) -> None:
        """Initial state from a plant or scenario file: settable names and their values."""
        for name, value in state.items():
            self.set(name, value)

    def fault(self, kind: str, active: bool) -> None:
        """Start (or end) a device fault such as ``blocked_axis`` or ``emergency_stop``."""
        raise UnknownName(f"{self.kind} has no fault {kind!r}")

    def power_cycle(self, *, wipe: bool = False) -> None:
        """Switch the device off and on again; ``wipe`` erases non-volatile memory first."""
        if wipe:
            self.nvram.wipe()

    def close(self) -> None:  # noqa: B027 - optional hook, default does nothing
        """Cancel timers; the device is not used afterwards."""
