"""Peers on V6 a plant can plug in instead of a host (spec poselesta.md Appendix A, §3.8): the
ELESTA cassette recorder Z2 / ZPS 020 (manual §2.6.2.2).  T2 records onto its tape what the
control sends after the 13 s leader; T3 plays the tape back into the control once the leader has
run (a host on the V6 pty may still send: both reach the read-in, as on a shared line)."""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.clock import Clock, Timer
from devsim.core.nvram import NonVolatileMemory, stored_hex
from devsim.devices.poselesta.transfers import CASSETTE_LEADER

__all__ = ["Cassette"]


class Cassette:
    """The cassette recorder on V6 (manual §2.6.2.2): one tape, kept in the plant's memory across
    power cycles.  ``function()`` is the name of the transfer running on V6 (``T2``, ``T3`` or
    ""), ``play(data)`` what the tape plays into V6; it hears what V6 sends through :meth:`heard`."""

    def __init__(self, clock: Clock, nvram: NonVolatileMemory, *, function: Callable[[], str],
                 play: Callable[[bytes], None]) -> None:
        self._clock = clock
        self._nvram = nvram
        self._function = function
        self._play_in = play
        self.tape = _stored_tape(nvram.get("cassette", ""))
        self._recording = b""
        self._timer: Timer | None = None

    def heard(self, data: bytes) -> None:
        if self._function() == "T2":
            self._recording += data

    def started(self, name: str) -> None:
        """A V6 transfer starts: T2 begins a new recording, T3 plays after the leader."""
        if name == "T2":
            self._recording = b""
        elif name == "T3":
            self._timer = self._clock.call_later(CASSETTE_LEADER, self._play)

    def ended(self, name: str, state: str) -> None:
        if name == "T2" and state == "done":
            self.tape = self._recording
            self._nvram.put("cassette", self.tape.hex())
        if self._timer is not None and name == "T3":
            self._timer.cancel()
            self._timer = None

    def _play(self) -> None:
        self._timer = None
        if self._function() == "T3":
            self._play_in(self.tape)

    def eject(self) -> None:
        self.tape = b""
        self._nvram.put("cassette", "")


def _stored_tape(stored: object) -> bytes:
    """The tape as the recorder keeps it (``bytes.hex()``: lowercase hex pairs, ``""`` when
    ejected or never recorded); anything else is a ValueError, so that the start refuses the
    memory naming the file (UnfitMemory) as for the control's other sections.  Before, a number,
    ``null``, ``[]`` or ``{}`` was ``or ""``'d into an empty tape (the recording gone, not a word
    said), and ``fromhex`` read capitals, blanks and newlines no recording writes."""
    tape = stored_hex(stored)
    if tape is None:
        raise ValueError(f"the stored cassette {stored!r:.40} is no tape the recorder keeps (lowercase hex bytes)")
    return tape
