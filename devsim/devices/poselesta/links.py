"""The transfers on V6 (external data media) and V7 (DNC): which runs on a port, its line
settings and what it reads or sends (manual §2.6, §2.6.2, §2.6.3; spec poselesta.md §2.2,
§3.2, §3.5–§3.9).

A transfer T1 … T7 is started from the panel (``v6.transfer`` / ``v7.transfer``) in the mode its
port needs (Σ for V6, EXT for V7) and is looked up in :data:`TRANSFERS`: T1 prints, T2 records
onto the cassette after its leader, T3 plays the cassette back, T4 and T6 send a program, T5
and T7 read one in.  Program P99 is the parameter catalogue (spec §3.9).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal, Protocol

from devsim.core.clock import Clock
from devsim.core.kit import Command, Table
from devsim.core.points import BadValue
from devsim.core.signals import SignalBank
from devsim.devices.poselesta.codes import BAUD_CODES, WERTBEREICHES_UEBERLAUF, baud_for_code
from devsim.devices.poselesta.parameters import CATALOGUE_FORMATS, MachineParameters
from devsim.devices.poselesta.programs import CATALOGUE, DIAGNOSTICS, ProgramMemory
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.tape import Block, Formats, TapeReader, block_words, render
from devsim.devices.poselesta.transfers import FUNCTIONS, PRINTER_CR_PAUSE, Function, Output, ReadIn

__all__ = ["PORT_MODE", "TRANSFERS", "LinkOptions", "SerialLinks"]

#: The mode a port's transfers need: Σ for V6, EXT for V7 (§2.6).
PORT_MODE = {"v6": "EXTERNAL_MEDIUM", "v7": "EXTERNAL_OPERATION"}
Transfer = ReadIn | Output


class Peer(Protocol):
    """A device a plant plugs into V6 instead of a host (the cassette recorder)."""

    def started(self, name: str) -> None: ...
    def ended(self, name: str, state: str) -> None: ...


class LinkOptions(Protocol):
    """The configuration a transfer reads (:class:`~devsim.devices.poselesta.config.PoselestaConfig`)."""

    @property
    def variant(self) -> str: ...
    @property
    def eob(self) -> str: ...
    @property
    def parity_error(self) -> Literal["abort", "skip"]: ...
    @property
    def ascii_bit7(self) -> Literal["ignore", "abort"]: ...
    @property
    def strict_block_numbers(self) -> bool: ...
    @property
    def printer_block_separator(self) -> str | None: ...
    @property
    def rx_timeout_s(self) -> float | None: ...
    @property
    def honour_xoff(self) -> bool: ...


class SerialLinks:
    """The transfers of V6 and V7 (manual §2.6; spec §3.2): ``mode()`` is the operating mode,
    ``program()`` the pre-selected program, ``booting()`` whether the control starts up, ``send``
    puts bytes on a port; ``peer`` is the cassette recorder when the plant has one on V6."""

    def __init__(self, clock: Clock, signals: SignalBank, params: MachineParameters, memory: ProgramMemory,
                 screen: Screen, options: LinkOptions, *, mode: Callable[[], str], program: Callable[[], int],
                 booting: Callable[[], bool], send: Callable[[str, bytes], None], leader_nul: int = 0,
                 trailer_nul: int = 0) -> None:
        self.clock = clock
        self._signals = signals
        self._params = params
        self._memory = memory
        self._screen = screen
        self._options = options
        self._mode = mode
        self._program = program
        self._booting = booting
        self._send = send
        self._nul = (leader_nul, trailer_nul)
        self.peer: Peer | None = None
        self.transfers: dict[str, Transfer | None] = {"v6": None, "v7": None}
        self.last_state = {"v6": "idle", "v7": "idle"}
        self.discarded = {"v6": 0, "v7": 0}
        self._xoff = options.honour_xoff  # read once: the feed path asks no config

    # -- the panel --------------------------------------------------------------------------------
    def name(self, port: str) -> str:
        running = self.transfers[port]
        if running is None:
            return "idle"
        return running.function.choice

    def state(self, port: str) -> str:
        running = self.transfers[port]
        return running.state if running is not None else self.last_state[port]

    def function(self, port: str) -> str:
        """The name (T1 … T7) of the transfer running on ``port``, or ""."""
        running = self.transfers.get(port)
        return running.function.name if running is not None else ""

    def busy(self) -> list[str]:
        return [p for p, t in self.transfers.items() if t is not None]

    def select(self, port: str, name: str) -> None:
        """``v6.transfer`` / ``v7.transfer``: ``idle`` cancels, a function's name starts it."""
        if name == "idle":
            self.stop(port, "cancelled")
            return
        self.start(port, name)

    def start(self, port: str, name: str) -> None:
        """Start T1 … T7 from the panel (spec §3.2.2 ``panel.start_transfer``)."""
        function = FUNCTIONS[(port, name)]
        if self._booting():
            raise BadValue("the control is not ready yet")
        mode = self._mode()
        if mode != PORT_MODE[port]:
            self.event(port, "wrong_mode", mode)
            raise BadValue(f"{function.name} needs mode {PORT_MODE[port]}, the control is in {mode}")
        if self.transfers[port] is not None:
            raise BadValue(f"a transfer runs on {port} already (busy)")
        program = self._program()
        if program == DIAGNOSTICS:
            raise BadValue("P79 is the diagnostic program, not a program to transfer")
        catalogue = program == CATALOGUE
        if function.direction == "input":
            self._memory.refuse_protected(program)  # before anything is deleted
        if catalogue and function.direction == "input" and not self._signals.get("key_switch"):
            self._screen.record("key_switch_locked")
            raise BadValue("the key switch is locked: the parameter catalogue cannot be read in")
        if self._rate(function) is None:
            self._screen.show(WERTBEREICHES_UEBERLAUF)
            raise BadValue(f"P{self._params.baud_code_key(port)}: baud rate code not available on "
                           f"POS {self._options.variant}")
        self._screen.clear()
        self._screen.record(f"{function.name}_start")
        TRANSFERS[function.name](self, function, program)
        if self.peer is not None and port == "v6":
            self.peer.started(function.name)  # (after the transfer: its leader ends first)

    def stop(self, port: str, state: str) -> None:
        """The panel ends a running transfer (cancel, power off)."""
        if self.transfers[port] is not None:
            self.ended(port, state)
            self.event(port, state)

    # -- the transfer functions (spec §3.2.1) --------------------------------------------------------
    def _read_in(self, function: Function, program: int, *, record: bool = True) -> None:
        """T3, T5, T7: the program (or the catalogue P99) is cleared first, then read in."""
        port = function.port
        line = None
        catalogue = program == CATALOGUE
        if catalogue:
            if self._options.variant == "III":  # the line stays as it was at the start (spec §3.9)
                line = (self._rate(function), self.iso(port))
                limit = function.catalogue_baud
                if limit and (line[0] or 0) > limit:
                    self._screen.show(WERTBEREICHES_UEBERLAUF)
                    raise BadValue(f"the catalogue is read at up to {limit} baud (P68/P70 ≤ 3)")
            self._params.begin_catalogue()  # the whole catalogue is 0 first, P68–P71 too: POS II
            # so reads it at 110 baud ISO (§2.6.2.3)
        else:
            self._memory.clear_for_read_in(program)
        options = self._options
        reader = TapeReader(
            iso=self.iso(port) if line is None else line[1], formats=self._memory.program_formats(program),
            parity_error=options.parity_error, ascii_bit7=options.ascii_bit7,
            strict_block_numbers=options.strict_block_numbers, catalogue=catalogue,
        )
        if port == "v6":
            self._v6_lines(True, record=record)
        read_in = ReadIn(self, function, program, reader, function.leader, timeout=options.rx_timeout_s)
        read_in.line = line
        self.transfers[port] = read_in

    def _play(self, function: Function, program: int) -> None:
        """T3: the cassette plays (DTR H, RTS L) after its leader."""
        self._read_in(function, program, record=False)

    def _output(self, function: Function, program: int) -> None:
        """T2, T4, T6: the program (or the catalogue) as a tape image, after the leader."""
        port = function.port
        blocks = self._blocks(program)
        eob = "\r\n" if self._options.eob == "CRLF" else "\r"
        data = render(blocks, iso=self.iso(port), formatted=port == "v6", formats=self._formats(program),
                      eob=eob, leader_nul=self._nul[0], trailer_nul=self._nul[1])
        self._send_pieces(function, program, [(function.leader, data)], len(blocks))

    def _print(self, function: Function, program: int) -> None:
        """T1 (§2.6.2.1): one word per line, CR without LF, 820 ms after every CR; 7 bits with
        bit 7 = 0 whatever P69 says (the printer's parity is a ninth bit a byte cannot carry).
        With ``printer_block_separator`` a line of its own after every block (spec G-PRN-HASH: the
        ``#`` line of the manual's printout read as a separator, not as the block's skip mark)."""
        blocks = self._blocks(program)
        formats = self._formats(program)
        separator = [self._options.printer_block_separator] if self._options.printer_block_separator else []
        lines = ["%", "", ""]  # "%" CR CR CR
        for block in sorted(blocks, key=lambda b: b.number):
            lines += block_words(block, formats, formatted=True) + separator
        lines.append("M 30")
        pieces: list[tuple[float, bytes]] = []
        wait = 0.0
        for line in lines:
            pieces.append((wait, (line + "\r").encode("ascii")))
            wait = PRINTER_CR_PAUSE
        self._send_pieces(function, program, pieces, len(blocks))

    def _formats(self, program: int) -> Formats:
        """The word formats a program leaves in: the catalogue's own, or those it was typed in."""
        return CATALOGUE_FORMATS if program == CATALOGUE else self._memory.program_formats(program)

    def _blocks(self, program: int) -> list[Block]:
        if program == CATALOGUE:
            return self._params.catalogue_blocks()
        return list(self._memory.programs.get(program, {}).values())

    def _send_pieces(self, function: Function, program: int, pieces: list[tuple[float, bytes]], blocks: int) -> None:
        if function.port == "v6":
            self._v6_lines(True)
        output = Output(self, function, program, pieces, blocks)
        self.transfers[function.port] = output
        output.begin()

    # -- what the transfers call (transfers.Cnc) ------------------------------------------------------
    def event(self, port: str, what: str, detail: Any = None) -> None:
        self._screen.port_event(port, what, detail)

    def ended(self, port: str, state: str, message: str | None = None) -> None:
        """A transfer is over (``done``, ``failed``, ``cancelled``): the port is idle again,
        V6's RTS/DTR drop, and a failure shows its screen message."""
        running = self.transfers[port]
        if running is not None:
            running.cancel()
            if self.peer is not None and port == "v6":
                self.peer.ended(running.function.name, state)
            if running.program == CATALOGUE and running.function.direction == "input" and state == "done":
                self._params.commit_catalogue()  # the parameters act after M30 (spec §3.9)
        self.transfers[port] = None
        self.last_state[port] = state
        if port == "v6":
            self._v6_lines(False)
        if state == "failed":
            self._screen.show(WERTBEREICHES_UEBERLAUF)

    def store_block(self, program: int, block: Block) -> str | None:
        """A block read in; returns why it cannot be stored (the read-in fails), or None."""
        if program == CATALOGUE:
            return self._params.store_catalogue(block)
        return self._memory.store_block(program, block)

    def send(self, port: str, data: bytes) -> None:
        self._send(port, data)

    def char_time(self, port: str) -> float:
        """Seconds per character on the port: its frame's bits (:meth:`frame_bits`) at its baud rate."""
        return self.frame_bits(port) / (self.baud(port) or BAUD_CODES[0])

    def frame_bits(self, port: str) -> int:
        """The bits of one character frame (§2.6.1.2, §2.6.2.1–§2.6.4): a start bit, 7 data bits,
        the printer's eighth data bit (MSB = 0), the parity bit of ISO code (the printer's with
        P69 = 0), 2 stop bits: ISO 11, ASCII 10, printer 12 (P69 = 0) or 11 (P69 = 1)."""
        running = self.transfers.get(port)
        printer = running is not None and running.function.printer
        return 1 + 7 + (1 if printer else 0) + (1 if self.iso(port) else 0) + 2

    # -- line settings --------------------------------------------------------------------------
    def iso(self, port: str) -> bool:
        running = self.transfers.get(port)
        if isinstance(running, ReadIn) and running.line is not None:
            return running.line[1]
        return port == "v8" or self._params.iso(port)

    def baud(self, port: str) -> int | None:
        """The port's baud rate: P68 (V6), P70 (V7); the printer 1200, the POS II cassette 300,
        V8 1200 (§2.2 of the spec)."""
        if port == "v8":
            return 1200
        running = self.transfers.get(port)
        if isinstance(running, ReadIn) and running.line is not None:
            return running.line[0]  # the line of this read-in, captured at its start
        if running is not None:
            return self._rate(running.function)
        return baud_for_code(self._params.baud_code(port), self._options.variant)

    def _rate(self, function: Function) -> int | None:
        """The baud rate of a transfer function: its own rule on the port's code (the printer's and
        the POS II cassette's, which P68 does not set, §2.6.2.1, §2.6.2.2), None when there is none."""
        return function.baud(self._params.baud_code(function.port), self._options.variant)

    # -- V6 modem lines ---------------------------------------------------------------------------
    def _v6_lines(self, on: bool, record: bool = True) -> None:
        """RTS and DTR: H while a V6 transfer runs (printer, punch); the cassette: DTR = run,
        RTS = record (spec §3.8, G-V6LINES)."""
        self._signals.set("v6_dtr", on)
        self._signals.set("v6_rts", on and record)

    # -- bytes from the host ----------------------------------------------------------------------
    def feed(self, port: str, data: bytes) -> None:
        running = self.transfers[port]
        if not isinstance(running, ReadIn):
            self.discarded[port] += len(data)  # no input function active, an output included (spec §2.6)
            if self._xoff and running is not None:
                running.flow(data)  # honour_xoff (spec G-FLOW): DC3 / DC1 pause and resume the output
            return
        running.feed(data)
        self._memory.flush()  # the chunk's blocks, saved together (devsim.devices.poselesta.programs)


TransferHandler = Callable[[SerialLinks, Function, int], None]


def _row(name: str, handler: TransferHandler) -> Command[TransferHandler]:
    function = next(f for f in FUNCTIONS.values() if f.name == name)
    return Command(name, handler, function.section, f"{function.port.upper()} {function.choice}: {function.direction} "
                   f"({function.peer}), mode digit {function.digit}")


#: The transfer functions T1 … T7 (spec §3.2.1), started by :meth:`SerialLinks.start`.
TRANSFERS: Table[TransferHandler] = Table([
    _row("T1", SerialLinks._print),
    _row("T2", SerialLinks._output),
    _row("T3", SerialLinks._play),
    _row("T4", SerialLinks._output),
    _row("T5", SerialLinks._read_in),
    _row("T6", SerialLinks._output),
    _row("T7", SerialLinks._read_in),
])
