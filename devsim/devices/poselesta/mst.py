"""M, S, T and mode output on the data bus V17 with the strobes V16 and the MST acknowledge
V22/7 (manual §2.4.1, §2.4.7, §2.4.8, §2.3.19; spec poselesta.md §4.4, the timeline of §6.3).

For each function: the code goes on the bus; after t1 its strobe goes H; the strobe stays H
until the acknowledge is H *and* t1 has passed; after the strobe falls the control waits for the
acknowledge to go L, then t2, then the next code (or 00 after the last).  The mode code (BA) has
a fixed timing that ignores the acknowledge: bus, t1, strobe H, t1, strobe L, t2, bus 00; the
functions of a block started meanwhile follow it.  t1 = t2 = P72 (1 … 99 ms; 0 is taken as 1 ms,
spec §4.8).

:class:`PlcHelper` is the plant side the manual describes: the acknowledge bridged to the strobes
(the strobe is then t1 long), a PLC that answers after a delay, or nobody (``manual``); it can
also acknowledge a tool change (M06) and release a non-self-holding M10 after a delay.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.clock import Clock, Timer
from devsim.core.signals import SignalBank

__all__ = ["MST_STROBES", "MstBus", "PlcHelper", "bcd"]

#: The strobe of each kind of function (V16/1–4); the mode code has ``strobe_ba`` (V16/5).
MST_STROBES = {"M": "strobe_m", "S1": "strobe_s1", "S2": "strobe_s2", "T": "strobe_t"}
PULSE = 0.050  # s: the helper's acknowledge pulses


def bcd(value: int) -> int:
    """Two decimal digits as the bus carries them: 37 → 0x37 (§2.4.1)."""
    return ((value // 10) % 10) << 4 | value % 10


class MstBus:
    """The output sequencer: one function list at a time (a block phase), the BA code between."""

    def __init__(self, clock: Clock, signals: SignalBank, t1: Callable[[], float],
                 on_put: Callable[[str, int], None] | None = None) -> None:
        self.clock, self.signals, self.t1 = clock, signals, t1
        self.on_put = on_put  # (kind, value) when a function goes on the bus: decoded M outputs
        self._queue: list[tuple[str, int]] = []
        self._current: tuple[str, int] | None = None
        self._done: Callable[[], None] | None = None
        self._timer: Timer | None = None
        self._rise = 0.0
        self.phase = "idle"  # idle, put, strobe, ack_low, gap, ba
        signals.subscribe("mst_ack", self._ack_changed)

    @property
    def busy(self) -> bool:
        return self.phase != "idle"

    # -- M, S, T --------------------------------------------------------------------------------
    def output(self, functions: list[tuple[str, int]], done: Callable[[], None]) -> None:
        """Put ``functions`` (``("M", 3)``, ``("S1", 50)`` …, values as decimal numbers) out in
        order; ``done`` runs when the last has been taken over."""
        if not functions:
            done()
            return
        self._queue = list(functions)
        self._done = done
        if self.phase != "ba":  # (a mode code on the bus keeps its fixed sequence: they follow it, §2.4.8)
            self._next()

    def _next(self) -> None:
        if not self._queue:
            self._current = None
            self.signals.set("data_bus", 0)
            self.phase = "idle"
            done, self._done = self._done, None
            if done is not None:
                done()
            return
        kind, value = self._current = self._queue.pop(0)
        self.signals.set("data_bus", bcd(value))
        self.phase = "put"
        if self.on_put is not None:
            self.on_put(kind, value)
        self._after(self.t1(), self._strobe_on)

    def _strobe_on(self) -> None:
        assert self._current is not None
        self.phase = "strobe"
        self._rise = self.clock.now()
        self.signals.set(MST_STROBES[self._current[0]], True)
        self._after(self.t1(), self._check_release)

    def _check_release(self) -> None:
        """The strobe falls once the acknowledge is H and t1 has passed since it rose."""
        if self.phase != "strobe" or self._current is None:
            return
        if not self.signals.get("mst_ack") or self.clock.now() < self._rise + self.t1() - 1e-12:
            return
        self.phase = "ack_low"
        self.signals.set(MST_STROBES[self._current[0]], False)
        self._check_ack_low()

    def _check_ack_low(self) -> None:
        if self.phase == "ack_low" and not self.signals.get("mst_ack"):
            self.phase = "gap"
            self._after(self.t1(), self._next)  # t2 = t1 (P72)

    def _ack_changed(self, _name: str, _old: Any, new: Any) -> None:
        if new and self.phase == "strobe":
            self._check_release()
        elif not new and self.phase == "ack_low":
            self._check_ack_low()

    # -- the mode code --------------------------------------------------------------------------
    def mode(self, code: int) -> None:
        """BA output with its fixed timing (§2.4.8); only between M/S/T phases."""
        if self._current is not None:
            return  # (a mode change never happens while a block outputs: the caller refuses it)
        self._abandon_ba()
        self.phase = "ba"
        self.signals.set("data_bus", code)
        steps = (lambda: self.signals.set("strobe_ba", True), lambda: self.signals.set("strobe_ba", False),
                 self._ba_done)

        def step(index: int) -> None:
            steps[index]()
            if index + 1 < len(steps):
                self._after(self.t1(), lambda: step(index + 1))

        self._after(self.t1(), lambda: step(0))

    def _ba_done(self) -> None:
        self.signals.set("data_bus", 0)
        self.phase = "idle"
        if self._done is not None:
            self._next()  # the functions of a block started while the mode code went out

    def _abandon_ba(self) -> None:
        if self.phase == "ba":
            self._cancel_timer()
            self.signals.set("strobe_ba", False)
            self.phase = "idle"

    # -- Not-Stop, power ---------------------------------------------------------------------------
    def abandon(self) -> None:
        """Not-Stop: the handshake in progress is given up, strobes L, bus 00 (spec §4.3.5)."""
        self._cancel_timer()
        self._queue, self._current, self._done = [], None, None
        for strobe in (*MST_STROBES.values(), "strobe_ba"):
            self.signals.set(strobe, False)
        self.signals.set("data_bus", 0)
        self.phase = "idle"

    def _after(self, seconds: float, callback: Callable[[], None]) -> None:
        self._cancel_timer()
        self._timer = self.clock.call_later(seconds, callback)

    def _cancel_timer(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None


class PlcHelper:
    """The PLC side of the MST acknowledge, as a plant wires it (spec §4.4.3, §8 S15, S16):
    ``bridged`` (acknowledge = any of the M/S/T strobes), ``delayed`` (H ``rise`` s after a strobe
    rises, L ``fall`` s after it falls) or ``manual`` (the test or the user sets ``input.mst_ack``)."""

    def __init__(self, clock: Clock, signals: SignalBank, mode: str, rise: float, fall: float,
                 tool_change: float | None = None, m10_release: float | None = None) -> None:
        self.clock, self.signals, self.mode, self.rise, self.fall = clock, signals, mode, rise, fall
        self.tool_change, self.m10_release = tool_change, m10_release
        self._timer: Timer | None = None
        self._others: list[Timer] = []
        if mode != "manual":
            for strobe in MST_STROBES.values():
                signals.subscribe(strobe, self._strobe)
        if tool_change is not None:
            signals.subscribe("m06", lambda _n, _o, new: new and self._pulse(tool_change, "tool_change_ack", True))
        if m10_release is not None:
            signals.subscribe("m10", lambda _n, _o, new: new and signals.get("m10_ack")
                              and self._pulse(m10_release, "m10_ack", False))

    def _pulse(self, delay: float, name: str, level: bool) -> None:
        """The PLC answers a tool change (V22/5 H) or releases M10 (V22/6 L) for 50 ms."""
        def on() -> None:
            self.signals.set(name, level)
            self._others.append(self.clock.call_later(PULSE, lambda: self.signals.set(name, not level)))

        self._others.append(self.clock.call_later(delay, on))

    def _strobe(self, _name: str, _old: Any, new: Any) -> None:
        if self.mode == "bridged":
            self.signals.set("mst_ack", any(self.signals.get(s) for s in MST_STROBES.values()))
            return
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self.clock.call_later(self.rise if new else self.fall,
                                            lambda: self.signals.set("mst_ack", bool(new)))

    def cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        for timer in self._others:
            timer.cancel()
        self._others.clear()
