"""The running transfers of V6 and V7 (manual §2.6.2, §2.6.3; spec poselesta.md §3.2, §3.5–§3.8).

A transfer is started at the panel (:meth:`~devsim.devices.poselesta.links.SerialLinks.start`) and runs on the device
clock: a read-in (:class:`ReadIn`: T3, T5, T7) takes what the host sends, an output
(:class:`Output`: T1, T2, T4, T6) sends a tape image, with the printer's 820 ms after every CR
and the cassette's 13 s leader as device-clock waits (free under virtual time).  The byte
pacing of a character frame is the line's (the port's settings give the character time).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import msgspec

from devsim.core.clock import Clock, Timer
from devsim.devices.poselesta.codes import baud_for_code
from devsim.devices.poselesta.tape import BlockRead, Ended, Failed, Notice, TapeReader

__all__ = ["CASSETTE_LEADER", "PRINTER_CR_PAUSE", "FUNCTIONS", "Function", "Output", "ReadIn"]

#: The fixed lead time of the cassette (§2.6.2.2: "ca. 13 s").
CASSETTE_LEADER = 13.0
#: The printer's pause after every CR (§2.6.2.1: "ca. 820 ms").
PRINTER_CR_PAUSE = 0.820


def _printer_baud(_code: int, _variant: str) -> int:
    """§2.6.2.1: "Baud-Rate: 1200 fest programmiert (Parameter P 68 hat keinen Einfluss)"."""
    return 1200


def _cassette_baud(code: int, variant: str) -> int:
    """§2.6.2.2: POS II 300 fixed; POS III 300/1200/4800 by P68 (other codes: 300)."""
    if variant == "II":
        return 300
    return {1: 300, 3: 1200, 5: 4800}.get(code, 300)


class Function(msgspec.Struct, frozen=True):
    """A transfer function of the table in spec §3.2.1, with its line: ``baud(code, variant)``
    from the port's baud rate code, ``printer`` for the printer's frame (§2.6.1.2: an eighth
    data bit, the MSB, always 0), the cassette's ``leader`` before the data, and the highest
    baud rate at which POS III reads the parameter catalogue in (``catalogue_baud``, 0: no limit):
    1200 for the tape reader and the DNC port (§2.6.2.3, §2.6.3: "Beim POS III ist das Einlesen
    der Parameter mit Baud-Raten bis 1200 Baud ... möglich"); the cassette section names none
    (§2.6.2.2: "Diese Einschränkung gilt beim POS III nicht")."""

    name: str  # T1 … T7
    port: str
    choice: str  # what a user selects it with on its port (``v6.transfer = printer``)
    digit: int
    direction: str  # "output" | "input"
    peer: str
    section: str
    leader: float = 0.0
    printer: bool = False
    baud: Callable[[int, str], int | None] = baud_for_code
    catalogue_baud: int = 0


#: The transfer functions by the name a user selects them with (``v6.transfer`` / ``v7.transfer``).
FUNCTIONS: dict[tuple[str, str], Function] = {(f.port, f.choice): f for f in (
    Function("T1", "v6", "printer", 1, "output", "printer Z1 (20 columns)", "§2.6.2.1", printer=True,
             baud=_printer_baud),
    Function("T2", "v6", "cassette_out", 2, "output", "cassette Z2 / ZPS 020", "§2.6.2.2", leader=CASSETTE_LEADER,
             baud=_cassette_baud),
    Function("T3", "v6", "cassette_in", 3, "input", "cassette Z2 / ZPS 020", "§2.6.2.2", leader=CASSETTE_LEADER,
             baud=_cassette_baud),
    Function("T4", "v6", "output", 7, "output", "punch / TTY", "§2.6.2.3"),
    Function("T5", "v6", "input", 8, "input", "tape reader / TTY", "§2.6.2.3", catalogue_baud=1200),
    Function("T6", "v7", "output", 7, "output", "DNC host", "§2.6.3"),
    Function("T7", "v7", "input", 8, "input", "DNC host", "§2.6.3", catalogue_baud=1200),
)}


class Link(Protocol):
    """What a transfer uses of the control's links (:class:`~devsim.devices.poselesta.links.SerialLinks`)."""

    clock: Clock

    def event(self, port: str, what: str, detail: Any = None) -> None: ...
    def store_block(self, program: int, block: Any) -> str | None: ...
    def ended(self, port: str, state: str, message: str | None = None) -> None: ...
    def char_time(self, port: str) -> float: ...
    def send(self, port: str, data: bytes) -> None: ...


class ReadIn:
    """A program read-in (spec §3.5): the leader wait (cassette), ``%``, blocks, ``M30``.

    Its :attr:`state` leaves ``receiving`` the moment the transfer ends (``done``, ``failed``,
    ``cancelled``): a block that cannot be stored ends it there (spec §3.5.1 "any --error-->
    FAILED", §3.5.3), so nothing after that block is stored or read, whether the host sent the
    rest of the tape in the same write or later (what follows reaches no transfer: §2.6).

    ``timeout`` (config ``rx_timeout_s``, spec G-TIMEOUT; the manual documents none, a tape reader
    may pause at will): a read-in that hears no byte for that long after its start (the cassette's
    leader over) or its last byte fails, event ``rx_timeout`` ([SIM-CHOICE] as a failed read-in
    does: ``WERTBEREICHES-UEBERLAUF``, the blocks read so far kept).  A feed only notes its time;
    the one timer looks again when it fires."""

    def __init__(self, link: Link, function: Function, program: int, reader: TapeReader, leader: float = 0.0,
                 *, timeout: float | None = None) -> None:
        self.link = link
        self.function = function
        self.program = program
        self.reader = reader
        self.blocks = 0
        self.line: tuple[int | None, bool] | None = None  # baud and code fixed for this transfer
        self.state = "leader" if leader > 0 else "wait_start"
        self._timer: Timer | None = link.clock.call_later(leader, self._leader_over) if leader > 0 else None
        self._timeout = timeout
        self._heard = link.clock.now()  # the start, then the last byte (for ``timeout``)
        self._quiet: Timer | None = None
        if leader <= 0:
            self._watch()

    def _leader_over(self) -> None:
        self._timer = None
        if self.state == "leader":
            self.state = "wait_start"
            self._heard = self.link.clock.now()
            self._watch()

    def _watch(self) -> None:
        if self._timeout is not None:
            self._quiet = self.link.clock.call_at(self._heard + self._timeout, self._quiet_over)

    def _quiet_over(self) -> None:
        self._quiet = None
        if not self.running:
            return
        assert self._timeout is not None
        if self.link.clock.now() < self._heard + self._timeout:
            self._watch()  # a byte came meanwhile: wait from it
            return
        self.link.event(self.function.port, "rx_timeout", self._timeout)
        self._fail(f"nothing received for {self._timeout:g} s")

    @property
    def running(self) -> bool:
        return self.state in ("leader", "wait_start", "receiving")

    def feed(self, data: bytes) -> None:
        if self.state == "leader":
            return  # the uncoated leader of the cassette: nothing counts yet (§2.6.2.2)
        self._heard = self.link.clock.now()
        events = self.reader.feed(data)
        if self.reader.started and self.state == "wait_start":
            self.state = "receiving"
        for event in events:
            if not self.running:
                break  # the transfer ended at an earlier event of this chunk
            _READ_IN_EVENTS[type(event)](self, event)

    def _block(self, event: BlockRead) -> None:
        problem = self.link.store_block(self.program, event.block)
        if problem is not None:
            self._fail(problem)
            return
        self.blocks += 1
        self.link.event(self.function.port, "block", event.block.number)

    def _ended(self, _event: Ended) -> None:
        self.link.event(self.function.port, "transfer_done", (self.program, self.blocks))
        self._end("done")

    def _failed(self, event: Failed) -> None:
        self._fail(event.reason)

    def _notice(self, event: Notice) -> None:
        self.link.event(self.function.port, event.what, event.detail)

    def _fail(self, reason: str) -> None:
        """The transfer stops with WERTBEREICHES-UEBERLAUF (§2.6; spec §3.5.3, §3.12)."""
        self.link.event(self.function.port, "failed", reason)
        self._end("failed", reason)

    def _end(self, state: str, message: str | None = None) -> None:
        self.state = state
        self.link.ended(self.function.port, state, message)

    def cancel(self) -> None:
        for timer in (self._timer, self._quiet):
            if timer is not None:
                timer.cancel()
        self._timer = self._quiet = None
        if self.running:
            self.state = "cancelled"


#: What a read-in does with each event of its reader (:class:`~devsim.devices.poselesta.tape.TapeReader`).
_READ_IN_EVENTS: dict[type, Callable[[ReadIn, Any], None]] = {
    BlockRead: ReadIn._block,
    Ended: ReadIn._ended,
    Failed: ReadIn._failed,
    Notice: ReadIn._notice,
}


#: The flow-control characters of ``honour_xoff`` (7 bits): DC1 = XON, DC3 = XOFF.
XON, XOFF = 0x11, 0x13


class Output:
    """A program output: ``pieces`` of the tape image, each sent after the wait before it
    (the leader, the printer's CR pause), one character at a time on the device clock: a
    character reaches the line when its frame (§2.6.1.2: start, data, parity, stop bits at the
    port's baud rate) has been sent, so cancelling stops the tape at the character being sent and
    nothing after it leaves.  The transfer ends with its last character.

    Each character and wait is due a frame (or the wait) after the one before was *due*, not after
    its timer fired: in real time a timer fires a little late, and timing each character from the
    late moment made the output slower than its baud rate (at 4800 baud by about 40 %; §2.6.1.1
    "Die Baud-Rate gibt die Anzahl der pro Sekunde übertragenen Bits an").  After a stall the
    output catches up by at most one character.

    :meth:`flow` (config ``honour_xoff``, spec §3.6, G-FLOW: not the control's behaviour, which
    has no handshake) takes the host's DC3 (XOFF) and DC1 (XON), in either code (bit 7 masked):
    after DC3 the character being sent finishes and the next waits for DC1."""

    def __init__(self, link: Link, function: Function, program: int, pieces: list[tuple[float, bytes]],
                 blocks: int, on_end: Callable[[], None] | None = None) -> None:
        self.link = link
        self.function = function
        self.program = program
        self.blocks = blocks
        self.state = "sending"
        self._pieces = [(wait, data) for wait, data in pieces if data]
        self._at = 0  # the next character of the first piece
        self._on_end = on_end
        self._timer: Timer | None = None
        self._due = 0.0  # when the last character (or wait) was due on the device clock
        self._paused = False  # XOFF heard (``honour_xoff``)
        self._held = False  # a character waits for XON

    def begin(self) -> None:
        """Start sending (called once the transfer is the port's running one, so that the line
        settings of the first character are already this transfer's)."""
        self._due = self.link.clock.now()
        self._schedule()

    def _after(self, seconds: float, callback: Callable[[], None]) -> Timer:
        """A timer ``seconds`` after the last due moment (a stall is caught up by one character)."""
        clock = self.link.clock
        self._due = max(self._due, clock.now() - self.link.char_time(self.function.port)) + seconds
        return clock.call_at(self._due, callback)

    def _schedule(self) -> None:
        port = self.function.port
        if not self._pieces:
            self._timer = None
            self.state = "done"
            if self._on_end is not None:
                self._on_end()
            self.link.event(port, "transfer_done", (self.program, self.blocks))
            self.link.ended(port, "done")
            return
        wait, data = self._pieces[0]
        if self._at == 0 and wait > 0:
            self._pieces[0] = (0.0, data)
            self._timer = self._after(wait, self._schedule)
            return
        self._timer = self._after(self.link.char_time(port), self._character)

    def flow(self, data: bytes) -> None:
        """The host's bytes while this output runs: the last DC3 or DC1 of them decides."""
        last = next((c & 0x7F for c in reversed(data) if c & 0x7F in (XON, XOFF)), None)
        if last is None:
            return
        self._paused = last == XOFF
        if not self._paused and self._held:
            self._held = False
            self._due = self.link.clock.now()
            self._timer = self._after(self.link.char_time(self.function.port), self._character)

    def _character(self) -> None:
        self._timer = None
        if self._paused:
            self._held = True  # XOFF: this character waits for XON
            return
        _wait, data = self._pieces[0]
        self.link.send(self.function.port, data[self._at:self._at + 1])
        self._at += 1
        if self._at >= len(data):
            self._pieces.pop(0)
            self._at = 0
        self._schedule()

    def cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self._pieces.clear()
