"""Named digital and analog signals with change events.

A device keeps its inputs (limit switches, STOP, I1..I8), outputs (O1..O4, the ready relay) and
simulated quantities (supply voltage, heat-sink temperature) in one :class:`SignalBank`.  The
control API, scenarios and the axis model write inputs and quantities; the device reacts through
subscriptions and writes its outputs.  Each device owns its own bank (no module-level state).

A bank keeps only what differs from device to device: a value and the listeners per signal, in
two lists by the signal's position.  The names, kinds and descriptions, and the positions by
name, are a :class:`_Layout` shared by every bank that defined the same signals in the same
order (a thousand devices of a kind share one).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any, Literal

__all__ = ["Signal", "SignalBank", "SignalKind"]

SignalKind = Literal["input", "output", "quantity"]
Listener = Callable[[str, Any, Any], None]
#: What defines a signal in a layout: its name, kind and description.
Definition = tuple[str, SignalKind, str]


class _Layout:
    """Signals' names, kinds and descriptions, and their positions by name: immutable once
    made, shared by the banks that defined the same signals in the same order."""

    __slots__ = ("definitions", "positions", "_next")

    def __init__(self, definitions: tuple[Definition, ...]) -> None:
        self.definitions = definitions
        self.positions = {name: i for i, (name, _kind, _doc) in enumerate(definitions)}
        #: The layouts that extend this one by a batch of definitions (made once, then shared).
        self._next: dict[tuple[Definition, ...], _Layout] = {}

    def extended(self, batch: tuple[Definition, ...]) -> _Layout:
        made = self._next.get(batch)
        if made is None:
            made = self._next[batch] = _Layout(self.definitions + batch)
        return made


_EMPTY = _Layout(())


class Signal:
    """One signal of a bank, as a view: its name, kind and description, and its value, which
    may be set here without notifying anyone (a device's initial state); :meth:`SignalBank.set`
    notifies."""

    __slots__ = ("_bank", "_position", "name", "kind", "doc")

    def __init__(self, bank: SignalBank, position: int) -> None:
        self._bank = bank
        self._position = position
        self.name, self.kind, self.doc = bank._layout.definitions[position]

    @property
    def value(self) -> Any:
        return self._bank._values[self._position]

    @value.setter
    def value(self, value: Any) -> None:
        self._bank._values[self._position] = value

    @property
    def listeners(self) -> tuple[Listener, ...]:
        return self._bank._listeners[self._position]


class SignalBank:
    """A device's named signals; ``set`` fires listeners only when the value changes."""

    __slots__ = ("_layout", "_values", "_listeners", "_every")
    #: Not the bank's state (a snapshot of a device leaves them out): which signals there are
    #: and who listens to them.
    not_state = frozenset({"_layout", "_listeners", "_every"})

    def __init__(self) -> None:
        self._layout = _EMPTY
        self._values: list[Any] = []
        #: A tuple per signal, made anew by each (un)subscription: most signals of a plant's
        #: thousand devices share the empty one, and ``set`` iterates the listeners as they were
        #: when it began.
        self._listeners: list[tuple[Listener, ...]] = []
        #: Listeners to every signal, called after each signal's own.
        self._every: tuple[Listener, ...] = ()

    def define(self, name: str, kind: SignalKind, initial: Any, doc: str = "") -> Signal:
        self.declare(((name, kind, initial, doc),))
        return Signal(self, len(self._values) - 1)

    def declare(self, signals: Iterable[tuple[str, SignalKind, Any, str]]) -> None:
        """Define several signals at once: ``(name, kind, initial, doc)`` each."""
        batch = tuple(signals)
        positions = self._layout.positions
        seen: set[str] = set()
        for name, _kind, _initial, _doc in batch:
            if name in positions or name in seen:
                raise ValueError(f"signal {name!r} defined twice")
            seen.add(name)
        self._layout = self._layout.extended(tuple((name, kind, doc) for name, kind, _initial, doc in batch))
        self._values.extend(initial for _name, _kind, initial, _doc in batch)
        self._listeners.extend(() for _ in batch)

    def __contains__(self, name: str) -> bool:
        return name in self._layout.positions

    def names(self, kind: SignalKind | None = None) -> list[str]:
        return [n for n, k, _doc in self._layout.definitions if kind is None or k == kind]

    def _position(self, name: str) -> int:
        try:
            return self._layout.positions[name]
        except KeyError:
            raise KeyError(f"no signal named {name!r}") from None

    def signal(self, name: str) -> Signal:
        return Signal(self, self._position(name))

    def get(self, name: str) -> Any:
        try:
            return self._values[self._layout.positions[name]]
        except KeyError:
            raise KeyError(f"no signal named {name!r}") from None

    def set(self, name: str, value: Any) -> bool:
        """Set a signal; returns True (and notifies listeners) if the value changed."""
        try:
            position = self._layout.positions[name]
        except KeyError:
            raise KeyError(f"no signal named {name!r}") from None
        values = self._values
        old = values[position]
        if old == value:
            return False
        values[position] = value
        for listener in self._listeners[position]:
            listener(name, old, value)
        for listener in self._every:
            listener(name, old, value)
        return True

    def subscribe_all(self, listener: Listener) -> None:
        """``listener`` hears every change of every signal, after the signal's own listeners (one
        entry for the bank, not one per signal)."""
        self._every = (*self._every, listener)

    def subscribe(self, name: str, listener: Listener) -> Callable[[], None]:
        position = self._position(name)
        self._listeners[position] = (*self._listeners[position], listener)

        def unsubscribe() -> None:
            listeners = list(self._listeners[position])
            listeners.remove(listener)
            self._listeners[position] = tuple(listeners)

        return unsubscribe

    def snapshot(self, kind: SignalKind | None = None) -> dict[str, Any]:
        values = self._values
        return {n: values[i] for i, (n, k, _doc) in enumerate(self._layout.definitions)
                if kind is None or k == kind}
