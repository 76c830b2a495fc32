"""A device: one model under one protocol face per serial port, described by declared tables.

A kind subclasses :class:`Device` and declares, as class attributes:

* ``model_class`` – the machine (a :class:`~devsim.core.model.Model`): axes, I/O, parameters,
  programs, faults, memory; it knows no protocol;
* ``face_classes`` – per port name, the protocol face that decodes the host's bytes with a pure
  codec and acts on the model (``face_class(model, port)``); a face holds the model, never
  inherits it;
* ``ports`` – the serial ports (:class:`~devsim.core.kit.PortDef`, default one port ``main``);
* ``points`` – every control name (:class:`~devsim.core.points.PointTable`): ``read``, ``set``,
  ``state`` and ``names`` come from it, values are checked before they take effect;
* ``faults`` – the declared faults (:class:`~devsim.core.kit.FaultTable`).

A transport's line reaches a port through :meth:`Device.port` (``feed``, ``attach``,
``host_disconnected``, ``serial_settings``); ``feed``/``attach``/``send`` on the device itself
mean the ``main`` port.  Several devices can share one line (RS-485 multidrop): see
:class:`devsim.core.bus.Bus`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import msgspec

from devsim.core.changes import CHANGES
from devsim.core.clock import Clock
from devsim.core.kit import MAIN_PORT, DriveActions, FaultTable, PortDef, Reference
from devsim.core.model import Model
from devsim.core.nvram import NonVolatileMemory
from devsim.core.points import BadValue, PointTable, ReadOnlyName, UnknownName, parse_bool
from devsim.core.settings import Settings

__all__ = [
    "BadValue",
    "ByteSink",
    "Device",
    "Face",
    "Port",
    "ReadOnlyName",
    "SerialSettings",
    "Standing",
    "UnknownName",
]

ByteSink = Callable[[bytes], None]


class SerialSettings(msgspec.Struct, frozen=True):
    """Line settings of a UART: what the device is configured for, or what the host opened."""

    baudrate: int = 9600
    bytesize: int = 8
    parity: str = "N"  # "N", "E", "O", "M", "S"
    stopbits: float = 1
    #: False when the data bits and parity were not visible (a Linux pty forces 8N1 whatever the
    #: host sets): ``bytesize`` and ``parity`` are then the device's own, assumed, not seen.
    frame_seen: bool = True
    #: Bits one character takes on the wire where the device's code fills less of its frame than
    #: the settings say (the POSELESTA's 7-bit ASCII code, start and 2 stop bits, on its 8N2 port:
    #: 10, not 11); 0: what the settings make of it.  Only the character time uses it.
    frame_bits: int = 0

    def describe(self) -> str:
        """``9600 8E1``; what was not seen is not claimed: ``9600 baud, 1 stop bit (data bits and
        parity not visible)``."""
        stop = int(self.stopbits) if float(self.stopbits).is_integer() else self.stopbits
        if not self.frame_seen:
            return f"{self.baudrate} baud, {stop} stop bit{'' if stop == 1 else 's'} (data bits and parity not visible)"
        return f"{self.baudrate} {self.bytesize}{self.parity}{stop}"

    @classmethod
    def parse(cls, text: str) -> SerialSettings:
        """``"19200 8E1"`` as line settings (baud rate, data bits, parity, stop bits); ValueError
        for text of another shape or settings no UART has (:meth:`problem`)."""
        try:
            baud, frame = text.split()
            settings = cls(int(baud), int(frame[0]), frame[1].upper(), float(frame[2:]))
        except (ValueError, IndexError):
            raise ValueError(f"line settings are like '19200 8E1', not {text!r}") from None
        if (problem := settings.problem()) is not None:
            raise ValueError(f"line settings {text!r}: {problem}")
        return settings

    def problem(self) -> str | None:
        """Why a UART cannot be set to these settings (a file edited by hand), or None."""
        if not 0 < self.baudrate <= 10_000_000:
            return f"baudrate {self.baudrate} is no baud rate"
        if self.bytesize not in (5, 6, 7, 8):
            return f"bytesize {self.bytesize} is not 5, 6, 7 or 8"
        if self.parity not in ("N", "E", "O", "M", "S"):
            return f"parity {self.parity!r} is not N, E, O, M or S"
        if self.stopbits not in (1, 1.5, 2):
            return f"stopbits {self.stopbits:g} is not 1, 1.5 or 2"
        return None

    def char_time(self) -> float:
        """Seconds one character occupies on the wire (start + data + parity + stop bits, or
        :attr:`frame_bits`)."""
        bits = self.frame_bits or 1 + self.bytesize + (0 if self.parity == "N" else 1) + float(self.stopbits)
        return bits / self.baudrate


class Face:
    """A protocol face on one port: the host's bytes in, answers out, acting on the model.

    Subclasses implement :meth:`feed` and, where the device has them, :attr:`serial_settings`
    (from its DIP switches), :meth:`host_disconnected` and :meth:`close`.  Answers leave through
    ``self.port.send``.  (A face that lists its attributes in ``__slots__`` has no instance
    dictionary: one block of memory for a poll to touch instead of two.)"""

    __slots__ = ("model", "port", "send")

    def __init__(self, model: Any, port: Port) -> None:
        self.model = model
        self.port = port
        #: Answers towards the host (the port's own method: no extra call on the hot path).
        self.send: Callable[[bytes], None] = port.send

    def feed(self, data: bytes) -> None:
        """Bytes from the host, in arrival order, possibly split anywhere."""
        raise NotImplementedError

    def hear(self, data: bytes) -> None:
        """Bytes another device on a multidrop bus sent (see :mod:`devsim.core.bus`), not the
        host; default: taken like the host's."""
        self.feed(data)

    #: Optional, for a face whose usual chunk (a host's repeated poll) is answered with one piece of
    #: output and nothing else: ``answer_at_once(data)`` returns that piece, sent by nothing (the
    #: port writes it: no batch, no :meth:`Port.send`), having done to the face exactly what
    #: :meth:`feed` would; or None, having done nothing that :meth:`feed` would not do the same way
    #: again, and the port hands the chunk to :meth:`feed`.  None here: every chunk goes to ``feed``.
    #: A face whose reply holds while nothing changes, whatever the time, may hold it standing too
    #: (``port.standing``, :class:`Standing`): the port then gives it without asking.
    answer_at_once: Callable[[bytes], bytes | None] | None = None

    def host_disconnected(self) -> None:
        """The host closed the port (or its TCP connection dropped); default: nothing."""

    @property
    def serial_settings(self) -> SerialSettings:
        return SerialSettings()

    def close(self) -> None:
        """Cancel the face's timers; it is not used afterwards."""


class Standing:
    """A reply the face gave at once for a chunk, that holds for the same chunk while the count
    of changes stands (:mod:`devsim.core.changes`), however the time goes on: the port gives it
    again without asking the face, and so does a lean lane (:mod:`devsim.transports.lane`).  A face
    holds one here only when nothing it answers in it changes with time alone (slots: a poll
    reads it)."""

    __slots__ = ("stamp", "data", "reply")

    def __init__(self) -> None:
        self.stamp = -1  # (never the count)
        self.data = b""
        self.reply = b""

    def hold(self, data: bytes, reply: bytes) -> None:
        """``reply`` stands for ``data`` from now until the next change."""
        self.stamp, self.data, self.reply = CHANGES.count, data, reply

    def given(self, data: bytes) -> bytes | None:
        """The reply standing for the chunk ``data``: nothing changed since it was held; else None."""
        return self.reply if self.stamp == CHANGES.count and data == self.data else None


class Port:
    """One serial port of a device, as a line or a bus sees it (slots: every poll passes through)."""

    __slots__ = ("device", "spec", "name", "face", "_write", "_batch", "peers", "_mute", "at_once", "standing")

    def __init__(self, device: Device, spec: PortDef) -> None:
        self.device = device
        self.spec = spec
        self.name = spec.name
        self.face: Face | None = None
        #: The face's :attr:`~Face.answer_at_once` (None: the face has none, or the port is
        #: receive-only); a lean lane calls it itself (:mod:`devsim.transports.lane`).
        self.at_once: Callable[[bytes], bytes | None] | None = None
        self._write: ByteSink | None = None
        self._batch: list[bytes] | None = None  # the answers to the chunk being fed
        self._mute = spec.receive_only  # (what send asks at every answer)
        #: The reply the face holds standing (:class:`Standing`; none until it holds one)
        self.standing = Standing()
        #: The ports on this port's line, this one too (set by the bus; empty: a line of its own).
        self.peers: tuple[Port, ...] = ()

    @property
    def shared_line(self) -> bool:
        """Other devices share the line (RS-485 multidrop)."""
        return len(self.peers) > 1

    @property
    def hears_others(self) -> bool:
        return self.device.hears_others

    @property
    def talks_to_others(self) -> bool:
        return self.device.talks_to_others

    def attach(self, write: ByteSink | None) -> None:
        """Connect (or with ``None`` disconnect) the port's output to a line."""
        self._write = write

    def send(self, data: bytes) -> None:
        """Emit bytes towards the host (dropped when nothing is attached, like a dead line, and
        on a receive-only port)."""
        if not data or self._mute:
            return
        batch = self._batch
        if batch is not None:
            batch.append(data if type(data) is bytes else bytes(data))  # (a buffer may change after)
        elif self._write is not None:
            self._write(data)

    def feed(self, data: bytes) -> None:
        """Bytes from the host to the face.  What the face answers while it digests them leaves
        in one write (same bytes, same order, one syscall: what a UART's transmit FIFO does); a
        chunk the face answers at once (:attr:`Face.answer_at_once`) leaves as the face made it,
        and so does one whose reply the face holds standing (:class:`Standing`), without the face."""
        face = self.face
        if face is None:
            return
        if self._batch is not None:  # re-entered (a bus handing on): the outer call flushes
            CHANGES.count += 1  # (a door: devsim.core.changes)
            face.feed(data)
            return
        if (reply := self.standing.given(data)) is not None:
            if (write := self._write) is not None:
                write(reply)  # (what the face would answer at once: nothing changed since)
            return
        if (at_once := self.at_once) is not None and (reply := at_once(data)) is not None:
            if reply and (write := self._write) is not None:
                write(reply)  # (what send and the batch would make of one piece)
            return
        CHANGES.count += 1  # (a door: devsim.core.changes; not for a chunk answered at once)
        self._batched(face.feed, data)

    def hear(self, data: bytes) -> None:
        """Bytes another device on the bus sent, for the face's :meth:`Face.hear`; its answers
        leave in one write, as :meth:`feed`'s do."""
        face = self.face
        if face is None:
            return
        CHANGES.count += 1  # (a door: devsim.core.changes)
        if self._batch is not None:  # re-entered: the outer call flushes
            face.hear(data)
            return
        self._batched(face.hear, data)

    def _batched(self, take: Callable[[bytes], None], data: bytes) -> None:
        """``take(data)``, what the face sends meanwhile gathered and written in one piece."""
        self._batch = batch = []
        try:
            take(data)
        finally:
            self._batch = None
            if batch and (write := self._write) is not None:
                # (one piece, the usual answer to a poll, leaves as it is: no copy into a buffer)
                write(batch[0] if len(batch) == 1 else b"".join(batch))

    def host_disconnected(self) -> None:
        if self.face is not None:
            CHANGES.count += 1  # (a door: devsim.core.changes)
            self.face.host_disconnected()

    @property
    def serial_settings(self) -> SerialSettings:
        return self.face.serial_settings if self.face is not None else SerialSettings()


class Device:
    """A simulated controller: its model, a face per port, and the declared tables."""

    kind: ClassVar[str] = ""
    description: ClassVar[str] = ""
    #: What a user can configure (DIP switches, options): a :class:`devsim.core.settings.Settings`
    #: class, or None.
    config_model: ClassVar[type[Settings] | None] = None
    #: On a multidrop bus, also hear what the other devices send (not only the host).
    hears_others: ClassVar[bool] = False
    ports: ClassVar[tuple[PortDef, ...]] = MAIN_PORT
    points: ClassVar[PointTable] = PointTable()
    faults: ClassVar[FaultTable] = FaultTable()
    model_class: ClassVar[Callable[..., Model]] = Model
    #: What the model does as a drive, for drive-profile facades (CiA 402); None: not a drive.
    drive: ClassVar[DriveActions | None] = None
    #: Settable names and values that make the drive able to move (machine data, a reference
    #: point …), for tests and plants: ``device.apply_state(cls.drive_setup)``.
    drive_setup: ClassVar[Mapping[str, Any]] = {}
    face_classes: ClassVar[Mapping[str, Callable[[Any, Port], Face]]] = {}
    #: The Modbus unit id of the kind's own Modbus layout (the ``mirror``), from its model: the
    #: PCD's S-Bus station (spec pcd4h3 §9.8); None: unit 1, as the generated map's.
    modbus_unit: ClassVar[Callable[[Any], int] | None] = None

    def __init__(
        self,
        *,
        clock: Clock,
        config: Mapping[str, Any] | None = None,
        nvram: NonVolatileMemory | None = None,
        name: str | None = None,
    ) -> None:
        self.clock = clock
        self.name = name or self.kind
        self.nvram = nvram if nvram is not None else NonVolatileMemory(None)
        self.config: dict[str, Any] = dict(config or {})
        self.model = self.model_class(clock=clock, config=self.config, nvram=self.nvram, name=self.name)
        self._ports = {spec.name: Port(self, spec) for spec in self.ports}
        self._main = self._ports[self.ports[0].name]
        for port_name, port in self._ports.items():
            face_class = self.face_classes.get(port_name)
            if face_class is not None:
                port.face = face = face_class(self.model, port)
                port.at_once = None if port._mute else face.answer_at_once

    # -- ports -----------------------------------------------------------------------------
    def port(self, name: str = "main") -> Port:
        try:
            return self._ports[name]
        except KeyError:
            raise UnknownName(f"{self.name} has no port {name!r} (ports: {', '.join(self._ports)})") from None

    def port_names(self) -> list[str]:
        return list(self._ports)

    def face(self, port: str = "main") -> Face:
        face = self.port(port).face
        if face is None:
            raise UnknownName(f"{self.name} has no face on port {port!r}")
        return face

    @property
    def main(self) -> Port:
        return self._main

    def attach(self, write: ByteSink | None) -> None:
        self.main.attach(write)

    def feed(self, data: bytes) -> None:
        self._main.feed(data)

    def send(self, data: bytes) -> None:
        self._main.send(data)

    def host_disconnected(self) -> None:
        self.main.host_disconnected()

    @property
    def serial_settings(self) -> SerialSettings:
        return self.main.serial_settings

    @property
    def shared_line(self) -> bool:
        return self.main.shared_line

    # -- what the runtime watches ------------------------------------------------------------
    @property
    def booting(self) -> bool:
        return bool(self.model.booting)

    @property
    def events(self) -> list[tuple[float, str]]:
        return self.model.events

    @property
    def signals(self) -> Any:
        return self.model.signals

    def on_ready(self, listener: Callable[[], None]) -> Callable[[], None]:
        """Call ``listener`` each time the device finishes booting and listens, and at once if
        it listens already."""
        undo = self.model.listen("ready", listener)
        if not self.booting:
            listener()
        return undo

    # -- control API (derived from the declared points and faults) ---------------------------
    def names(self) -> list[str]:
        return self.points.names()

    def read(self, name: str) -> Any:
        return self.points.read(self.model, name, self.name)

    def set(self, name: str, value: Any) -> None:
        self.points.set(self.model, name, value, self.name)

    def check(self, name: str, value: Any) -> Any:
        """Validate a value for a settable name without changing anything; returns it parsed."""
        return self.points.parse(name, value, self.name)[1]

    def state(self) -> dict[str, Any]:
        data: dict[str, Any] = {"kind": self.kind}
        data.update(self.points.state(self.model))
        return data

    def apply_state(self, state: Mapping[str, Any]) -> None:
        """Initial state from a plant or scenario file: settable names and their values, all
        checked before the first takes effect.  A value the device itself refuses when it is put (a
        program's text that does not fit the formats in force) raises :class:`BadValue` naming the
        point; the values before it have taken effect."""
        checked = [self.points.parse(name, value, self.name) for name, value in state.items()]
        CHANGES.count += 1  # (a door: devsim.core.changes)
        for point, value in checked:
            assert point.put is not None
            try:
                point.put(self.model, value)
            except BadValue as exc:  # one the device refuses although it parsed (a program's text)
                raise BadValue(f"{point.name}: {exc}") from None

    def fault(self, kind: str, active: Any) -> None:
        """Start (or end) a declared device fault such as ``blocked_axis`` or ``emergency_stop``;
        then the model announces ``fault_switched(kind, active)`` (a facade's fault events)."""
        CHANGES.count += 1  # (a door: devsim.core.changes)
        self.faults.apply(self.model, kind, active, self.name)
        on = parse_bool(active)
        self.active_faults = tuple(name for name in self.faults.names()
                                   if (name == kind and on) or (name != kind and name in self.active_faults))
        self.model.announce("fault_switched", kind, on)

    #: The declared faults switched on (through :meth:`fault`) and not switched off since, in
    #: declaration order; a watch starts with them (a monitor that attaches later sees them).
    active_faults: tuple[str, ...] = ()

    def record_event(self, name: str) -> None:
        self.model.record_event(name)

    @property
    def talks_to_others(self) -> bool:
        """On a multidrop bus, it may send on its own what another device that hears others
        acts on (a SERS master's statements to its slaves): a scenario runner then lets none
        of those run ahead.  By default every device may."""
        return True

    def unobserved_until(self, when: float) -> None:
        """Nobody looks at the device before simulated time ``when`` (``-inf``: someone may at
        any moment): a scenario's runner says so while it waits for its next step."""
        CHANGES.count += 1  # (a door: devsim.core.changes)
        self.model.unobserved_until(when)

    def power_cycle(self, *, wipe: bool = False) -> None:
        """Switch the device off and on again; ``wipe`` erases non-volatile memory first."""
        CHANGES.count += 1  # (a door: devsim.core.changes)
        self.model.power_cycle(wipe=wipe)

    def close(self) -> None:
        """Cancel timers; the device is not used afterwards."""
        for port in self._ports.values():
            if port.face is not None:
                port.face.close()
        self.model.close()
        self.nvram.close()

    # -- the generated reference -------------------------------------------------------------
    @classmethod
    def reference(cls) -> Reference:
        """Commands, parameters, error codes and config keys for ``devsim doc`` (a kind adds
        its tables here)."""
        return Reference()
