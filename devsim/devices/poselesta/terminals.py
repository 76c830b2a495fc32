"""The terminals of the control inputs and the control's view of them (manual §2.3: "Zeitverzögerung
L ---> H: 2,5 ... 15 ms + ~25 ms, H ---> L: 15 ... 50 ms Rechenzeit"; §2.3.23: the reference mark
activation, "beim Öffnen max. 5 ms, beim Schliessen max. 0,2 ms").

What the plant drives onto a terminal (``input.<name>``) reaches the control's logic, its screens
and its outputs only after the input delay of that edge: one device-clock timer per pending edge, no
polling.  A level that returns before it has been seen is never seen (the input filter).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from typing import Any

from devsim.core.clock import Clock, Timer
from devsim.core.signals import SignalBank

__all__ = ["InputTerminals"]


class InputTerminals:
    """The input terminals V19–V22 and V24 (manual §2.3, §2.3.23): ``delays`` gives each delayed
    input its (L→H, H→L) delay in seconds; other signals pass at once.  ``get`` reads the level on
    the terminal, the signal bank holds what the control sees."""

    def __init__(self, clock: Clock, signals: SignalBank, delays: Mapping[str, tuple[float, float]]) -> None:
        self._clock = clock
        self._signals = signals
        self._delays = delays  # read only (shared by the controls configured alike)
        self._pending: dict[str, tuple[Any, Timer]] = {}  # a level on its way: (level, its timer)

    def get(self, name: str) -> Any:
        """The level on the terminal (what the plant drives)."""
        pending = self._pending.get(name)
        return pending[0] if pending is not None else self._signals.get(name)

    def set(self, name: str, value: Any) -> None:
        """The plant drives a terminal; the control sees the level after the edge's delay."""
        if name not in self._delays:
            self._signals.set(name, value)
            return
        pending = self._pending.pop(name, None)
        if pending is not None:
            pending[1].cancel()
        if value == self._signals.get(name):
            return  # back before the control saw the other level
        rise, fall = self._delays[name]
        delay = rise if value else fall
        if delay <= 0:
            self._signals.set(name, value)
            return
        self._pending[name] = (value, self._clock.call_later(delay, partial(self._seen, name, value)))

    def _seen(self, name: str, value: Any) -> None:
        self._pending.pop(name, None)
        self._signals.set(name, value)

    def settle(self) -> None:
        """Power-on: the control reads every terminal as it is."""
        pending, self._pending = self._pending, {}
        for name, (value, timer) in pending.items():
            timer.cancel()
            self._signals.set(name, value)

    def cancel(self) -> None:
        """The control is switched off: what it had not seen yet stays on the terminals (``settle``)."""
        for _value, timer in self._pending.values():
            timer.cancel()
