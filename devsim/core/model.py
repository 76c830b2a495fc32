"""The base of a kind's model: the machine behind the ports, knowing no protocol.

A model owns axes, I/O (a :class:`~devsim.core.signals.SignalBank`), parameters, programs,
faults and memory.  Protocol faces (:class:`devsim.core.device.Face`) and facades act on it; it
never calls them.  What a face must hear from the model (a spontaneous message, the end of a
boot) travels through listeners the face registers (:meth:`Model.listen`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from devsim.core.clock import Clock
from devsim.core.nvram import NonVolatileMemory
from devsim.core.signals import SignalBank

__all__ = ["Model"]

Listener = Callable[..., None]


class Model:
    """Clock, configuration, memory, signals and the event log every model has.

    These are slots, so that a kind's own attributes have the instance dictionary to themselves:
    CPython 3.11 shares the keys of an instance dictionary among a class's instances only up to
    29 of them, and past that every device carries a table of its own (1.3 KB a device).
    """

    __slots__ = ("clock", "config", "nvram", "name", "signals", "booting", "events", "_listeners", "heard",
                 "__dict__", "__weakref__")

    def __init__(
        self,
        *,
        clock: Clock,
        config: Mapping[str, Any] | None = None,
        nvram: NonVolatileMemory | None = None,
        name: str = "",
    ) -> None:
        self.clock = clock
        self.config: dict[str, Any] = dict(config or {})
        self.nvram = nvram if nvram is not None else NonVolatileMemory(None)
        self.name = name
        self.signals = SignalBank()
        #: True while the device initialises after power-on and does not listen yet.
        self.booting = False
        #: (simulated time, name) of notable moments, e.g. ``move_end``, for timing checks.
        self.events: list[tuple[float, str]] = []
        self._listeners: dict[str, list[Listener]] = {}
        #: Called before an announcement reaches someone who hears it (a SERS drive does not run a
        #: looping program ahead over a moment somebody hears); None: no kind needs to know.
        self.heard: Callable[[], None] | None = None

    # -- notifications to faces and the runtime ---------------------------------------------
    def listen(self, topic: str, listener: Listener) -> Callable[[], None]:
        """Call ``listener(*args)`` whenever the model announces ``topic``; returns an undo."""
        listeners = self._listeners.setdefault(topic, [])
        listeners.append(listener)
        return lambda: listeners.remove(listener) if listener in listeners else None

    def announce(self, topic: str, *args: Any) -> None:
        listeners = self._listeners.get(topic)
        if listeners:  # (most topics of most devices have nobody listening)
            if (heard := self.heard) is not None:
                heard()
            for listener in list(listeners):
                listener(*args)

    def booted(self) -> None:
        """The power-on initialisation has finished: the device listens (topic ``ready``)."""
        self.booting = False
        self.announce("ready")

    def record_event(self, name: str) -> None:
        """Note a moment (``move_start``, ``move_end``, ``error`` ...) for timing expectations;
        listeners of topic ``recorded`` hear ``(time, name)`` (the motion log, a monitor).  (Topic
        ``event`` is a kind's own: the POSELESTA announces ``(port, what, detail)`` there.)"""
        now = self.clock.now()
        self.events.append((now, name))
        if len(self.events) > 10000:
            del self.events[:5000]
        self.announce("recorded", now, name)

    def report_error(self, code: str, *, refused: bool = False) -> None:
        """An error the device reports, by its code in the kind's error table
        (:attr:`devsim.core.kit.Reference.errors`), where the logs find its text; ``refused``: the
        device answered a host's command with it.  Listeners of topic ``device_error`` hear
        ``(code, refused)``; call it right before a ``record_event("error")`` (or ``"error N"``)
        of the same moment, which the logs then leave out."""
        self.announce("device_error", str(code), refused)

    def unobserved_until(self, when: float) -> None:
        """Nobody looks at the model before simulated time ``when`` (``-inf``: someone may look
        at any moment): a hint a model may use to compute ahead; the default ignores it."""

    # -- power ------------------------------------------------------------------------------
    def power_cycle(self, *, wipe: bool = False) -> None:
        """Switch the device off and on again; ``wipe`` erases non-volatile memory first.  Every
        kind announces topic ``power_on`` as it powers up (a power cycle, a ``power`` fault ending):
        a face starts its link afresh, a facade's interface boots with it (a CANopen node)."""
        if wipe:
            self.nvram.wipe()

    def close(self) -> None:
        """Cancel timers; the model is not used afterwards."""
