"""Named digital and analog signals with change events.

A device keeps its inputs (limit switches, STOP, I1..I8), outputs (O1..O4, the ready relay) and
simulated quantities (supply voltage, heat-sink temperature) in one :class:`SignalBank`.  The
control API, scenarios and the axis model write inputs and quantities; the device reacts through
subscriptions and writes its outputs.  Each device owns its own bank (no module-level state).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal

import msgspec

__all__ = ["Signal", "SignalBank", "SignalKind"]

SignalKind = Literal["input", "output", "quantity"]
Listener = Callable[[str, Any, Any], None]


class Signal(msgspec.Struct):
    name: str
    kind: SignalKind
    value: Any
    doc: str = ""
    #: A tuple, made anew by each (un)subscription: most signals of a plant's thousand devices
    #: share the empty one, and ``set`` iterates the listeners as they were when it began.
    listeners: tuple[Listener, ...] = ()


class SignalBank:
    """A device's named signals; ``set`` fires listeners only when the value changes."""

    def __init__(self) -> None:
        self._signals: dict[str, Signal] = {}

    def define(self, name: str, kind: SignalKind, initial: Any, doc: str = "") -> Signal:
        if name in self._signals:
            raise ValueError(f"signal {name!r} defined twice")
        sig = Signal(name, kind, initial, doc)
        self._signals[name] = sig
        return sig

    def __contains__(self, name: str) -> bool:
        return name in self._signals

    def names(self, kind: SignalKind | None = None) -> list[str]:
        return [n for n, s in self._signals.items() if kind is None or s.kind == kind]

    def signal(self, name: str) -> Signal:
        try:
            return self._signals[name]
        except KeyError:
            raise KeyError(f"no signal named {name!r}") from None

    def get(self, name: str) -> Any:
        return self.signal(name).value

    def set(self, name: str, value: Any) -> bool:
        """Set a signal; returns True (and notifies listeners) if the value changed."""
        sig = self.signal(name)
        old = sig.value
        if old == value:
            return False
        sig.value = value
        for listener in sig.listeners:
            listener(name, old, value)
        return True

    def subscribe(self, name: str, listener: Listener) -> Callable[[], None]:
        sig = self.signal(name)
        sig.listeners = (*sig.listeners, listener)

        def unsubscribe() -> None:
            listeners = list(sig.listeners)
            listeners.remove(listener)
            sig.listeners = tuple(listeners)

        return unsubscribe

    def snapshot(self, kind: SignalKind | None = None) -> dict[str, Any]:
        return {n: s.value for n, s in self._signals.items() if kind is None or s.kind == kind}
