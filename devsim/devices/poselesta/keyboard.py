"""The V8 external keyboard (manual §2.6.4; spec poselesta.md §3.10, vectors §6.9).

Each key sends one code, ISO (even parity in bit 7) at 1200 baud; the control needs at least
100 ms between two codes, else its input buffer overflows.  Modelled as: a key takes 100 ms to
process, one more may wait, a third arriving meanwhile is lost.  Keys count only while input
V21/9 selects the external keyboard; every accepted key sounds the buzzer (V16/6) unless P67 = 1.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.clock import Clock, Timer
from devsim.devices.poselesta.codes import KEY_CODES, parity_ok

__all__ = ["KEY_TIME", "Keyboard"]

#: How long the control takes over one key code (§2.6.4: "mindestens 100 ms Pause").
KEY_TIME = 0.100


class Keyboard:
    """The receive side of V8: parity, valid codes, the one-key buffer and its overflow."""

    def __init__(
        self,
        clock: Clock,
        *,
        external: Callable[[], bool],
        accept: Callable[[int], None],
        event: Callable[[str, int], None],
    ) -> None:
        self.clock = clock
        self._external = external
        self._accept = accept
        self._event = event
        self.waiting: int | None = None
        self._timer: Timer | None = None
        self.accepted = 0
        self.lost = 0

    def feed(self, data: bytes) -> None:
        for byte in data:
            self._receive(byte)

    def _receive(self, byte: int) -> None:
        code = byte & 0x7F
        if not parity_ok(byte):
            self._event("v8_parity_error", byte)
            return
        if code not in KEY_CODES:
            self._event("v8_unknown_code", code)
            return
        if not self._external():
            self._event("v8_ignored_internal_selected", code)
            return
        if self._timer is None:
            self._process(code)
        elif self.waiting is None:
            self.waiting = code
        else:
            self.lost += 1
            self._event("v8_overflow", code)

    def _process(self, code: int) -> None:
        self.accepted += 1
        self._accept(code)
        self._timer = self.clock.call_later(KEY_TIME, self._done)

    def _done(self) -> None:
        self._timer = None
        code, self.waiting = self.waiting, None
        if code is not None:
            self._process(code)

    def reset(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self._timer = None
        self.waiting = None
