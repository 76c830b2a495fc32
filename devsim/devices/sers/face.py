"""The serial face of the Stögra SERS (manual "SERS Version V04, Firmware ab 120901"; spec sers.md).

The ASCII line protocol of the drive over its model (:class:`~.model.SersDrive`): framing,
drive selection on a multidrop line, echo modes (P1017, §4.8.6.9), acknowledgements (§4.1),
error messages (§4.8.3.1), parameter queries (§4.7) and the execution of interactive
statements (§4.2).  The physics behind it –
positioning, jog, homing, limit switches, faults – lives in the model's parts (:mod:`.model`).
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Face, Port, SerialSettings
from devsim.devices.sers import codec
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.interactive import LineStatements
from devsim.devices.sers.line import (
    COMPLETES,
    EXTENDS_ONLY,
    LINE_ENDS,
    TEXT_TO_END,
    CommandLine,
    KeptPoll,
    Poll,
    ends_line,
    error_text,
    first_failure,
    poll_line,
    quiet,
)
from devsim.devices.sers.model import SersDrive
from devsim.devices.sers.noise import NoiseLines
from devsim.devices.sers.params import HANDSHAKE_CELL, LANGUAGE_CELL
from devsim.devices.sers.polls import KeptPolls

__all__ = ["SersFace"]

#: The line of a host's poll while its answer is made (:meth:`SersFace._answer_poll`): between
#: lines again when it is sent, so only ever compared with None, never changed; a poll's line
#: that gets an error or a deferred answer is a line of its own.
_ANSWERING = CommandLine(True, True)


class SersFace(Face):
    """The ASCII line protocol of one SERS on a serial line (RS-232, or RS-485 multidrop;
    §3.2, §4.1, §4.8.6.9)."""

    model: SersDrive
    __slots__ = ("framer", "line", "_last_replied", "_spontaneous", "_settings", "statements", "_noise_lines", "polls",
                 "answer_at_once", "_noise_rest", "_star", "_ok_after_error", "_ack_each")

    def __init__(self, model: SersDrive, port: Port) -> None:
        super().__init__(model, port)
        self.framer = codec.Framer()
        #: The command line being received (None between lines).
        self.line: CommandLine | None = None
        self._last_replied = False
        self._spontaneous: list[bytes] = []
        self._settings: SerialSettings | None = None
        cfg = model.cfg  # (read once) G-ERRFMT ⚙ error_trailing_star, ok_after_error; G-CRLF ⚙ ack_each_terminator
        self._star, self._ok_after_error, self._ack_each = cfg.error_trailing_star, cfg.ok_after_error, cfg.ack_each_terminator
        self.statements = LineStatements(model, self._out, self._error)
        noise = NoiseLines(model, self.framer, self.send, self)
        self._noise_lines, self._noise_rest = noise.take, noise.rest  # (bound once: a hot path)
        #: The polls answered since power-on (the last one while nothing else came since)
        self.polls = KeptPolls(model, port, self.framer)
        self.answer_at_once = self.polls.answer_at_once  # (a repeated poll: Face.answer_at_once)
        model.listen("power_on", self._reset_serial)
        model.listen("spontaneous", self.spontaneous)
        model.listen("line_out", self._line_out)

    # -- line settings -------------------------------------------------------------------
    @property
    def serial_settings(self) -> SerialSettings:
        settings = self._settings
        if settings is None or settings.baudrate != self.model.cfg.baud:
            settings = self._settings = SerialSettings(self.model.cfg.baud, 8, "N", 1)
        return settings

    # -- power ---------------------------------------------------------------------------
    def _reset_serial(self) -> None:
        self.framer.reset()
        self.line = None
        self._last_replied = False
        self._spontaneous.clear()
        self.polls.forget()

    # -- bytes from the host -------------------------------------------------------------
    def feed(self, data: bytes) -> None:
        # (answers to one chunk of input leave in one write: the kit's port batches them)
        model = self.model
        if self.polls.kept is not None and (kept := self.polls.take(data)) is not None:
            return self._reply_poll(kept, data)  # (a repeated poll; its framing done)
        model.peers = self.port.peers
        if model.master.awaiting and model.logic_alive:
            model.master.feed(data)  # a slave's answer to this master
        if not model.logic_alive or model.booting:
            return  # G-BOOT: input during the 2 s initialisation is discarded
        framer = self.framer
        # (a host's poll is one short chunk: a longer one, noise or a flood, is not hashed and kept)
        if self.line is None and not framer.in_line and len(data) <= codec.MAX_LINE + 1:
            poll = poll_line(data)
            if poll is not None and self._answer_poll(poll, data):
                return
        self.polls.kept = None  # (anything else: the framing and the selection may change)
        index, end = 0, len(data)
        while index < end:
            line = self.line
            if model.addressed is False and self._unconcerned(line):
                stop = framer.skip_unaddressed(data, index, model.line_address)  # other drives' lines
                if stop > index:
                    if framer.in_line and (line is None or ends_line(data, index, stop)):
                        line = CommandLine()  # a line that began in the skip (not the one that ended there)
                    self.line = line if framer.in_line else None
                    index = stop
                    continue
            byte = data[index]
            if not framer.in_line:
                if byte == codec.HASH:
                    stop = self._noise_lines(data, index)  # lines of noise, one after the other
                    if stop > index:
                        index = stop
                        if not model.logic_alive or model.booting:
                            return
                        continue
                    index = self._begin_line(data, index)  # '#' and the address in one step
                    continue
                if framer.idle or byte not in LINE_ENDS:
                    index = framer.skip_noise(data, index)  # noise between lines: one search
                    continue
                # (a CR or LF right after a line end: the second half of a pair, byte by byte)
            elif line is not None and framer.in_text:
                if byte in LINE_ENDS:
                    index += 1
                    self._line_end(line, byte, framer.end_line(byte))
                    if not model.logic_alive or model.booting:
                        return
                    continue
                if byte == codec.HASH:
                    index = self.restart(line, data, index)  # '#' inside the line
                    if not model.logic_alive or model.booting:
                        return
                    continue
                if line.execute and not line.error and framer.length < codec.MAX_LINE:
                    taken = self.take_text(line, data, index)  # a run of text in one step
                    if taken:
                        index += taken
                        if not model.logic_alive or model.booting:
                            return
                        continue
                else:  # text nobody executes, beyond 60 characters (dropped) or failed: only echoed
                    index = self._noise_rest(line, data, index)  # (a failed line's end and lines after it too)
                    if not model.logic_alive or model.booting:
                        return
                    continue
            index += 1
            for event in framer.feed(byte):
                self.on_event(event, byte)
            if not model.logic_alive or model.booting:
                return

    def _line_out(self, data: bytes) -> None:
        """A master's statement to a slave: sent, and no poll kept (its ``#n`` changed the selection)."""
        self.polls.kept = None
        self.send(data)

    def hear(self, data: bytes) -> None:
        """Bytes another drive on the bus sent: a master's statements for a slave, a slave's
        answer for a master (:meth:`SersDrive.hears_as_master`, §3.6.2)."""
        if not self.model.hears_as_master(data):
            self.feed(data)

    def _unconcerned(self, line: CommandLine | None) -> bool:
        """Whether nothing this drive does depends on the bytes until the next ``#`` with its
        address or ``*`` while it is not selected (see :meth:`codec.Framer.skip_unaddressed`): outside
        a line or in one it neither executes nor answers, no echo of a CR/LF pair owed, no
        message waiting for a line end."""
        if self._last_replied or self._spontaneous:
            return False
        if line is None:
            return not self.framer.in_line
        return not (line.execute or line.reply) and self.framer.in_text

    def _begin_line(self, data: bytes, index: int) -> int:
        """A ``#`` outside a line and the drive address after it (what :meth:`_on_restart`,
        :meth:`_on_address_char` and :meth:`_on_address` do byte by byte).  When this drive
        executes the line and the chunk holds all of it, and its statements all complete only
        at its end (a host's poll), the whole line is taken in one step: nothing runs before
        the line end, so its echo leaves at once and the statements run as at the line end."""
        framer = self.framer
        complete, address, stop = framer.begin_line(data, index)
        if not complete:
            self.line = CommandLine(held=bytearray(data[index:stop]))  # echoed once the address ends
            return stop
        self.line = line = CommandLine()
        self._select(line, address)
        if not line.execute and not line.reply:  # another drive's line: only its end matters
            finish = framer.skip_text(data, stop)
            if finish < len(data) and data[finish] in LINE_ENDS:
                self._line_end(line, data[finish], framer.end_line(data[finish]))
                return finish + 1
            return finish
        whole = TEXT_TO_END.match(data, stop) if line.execute else None
        end = whole.end() if whole is not None else 0
        text = quiet(whole[1]) if whole is not None and end - index - 1 <= codec.MAX_LINE else None
        if text is None:
            if line.reply and self.echo:
                self.send(data[index:stop])
            if whole is not None:
                return self._failing_line(line, data, stop, end)
            return stop
        framer.take_text(end - 1 - stop)
        if line.reply and self.echo:
            self.send(data[index:end])
        line.text = text
        self.end_line(line, framer.end_line(data[end - 1]))
        return end

    def _answer_poll(self, poll: Poll, data: bytes) -> bool:
        """A chunk that is one whole query line (a host's poll, :func:`poll_line`) between lines,
        for this drive outside programming mode (else False, nothing done): what :meth:`_begin_line`
        does with it, without framing the line again; kept for the next one (:class:`KeptPoll`)."""
        model = self.model
        address = poll.address
        if not model.selection(address)[1] or model.program.editing:
            return False
        model.note_address(address, True)
        self.framer.whole_line(poll.length, data[-1])
        self._reply_poll(self.polls.keep(data, poll, model.cfg), data)
        return True

    def _reply_poll(self, kept: KeptPoll, data: bytes) -> None:
        """The echo, answer and acknowledgement of a poll taken whole (:meth:`_answer_poll`), as
        the statements' progress and the line end make them for its one statement, a query."""
        model = self.model
        self.line = _ANSWERING  # (what the query sets off waits for the line end)
        mode = model.params.values.cells[HANDSHAKE_CELL]
        try:
            answer = self.polls.answer(kept)
        except SersError as exc:
            self.line = line = CommandLine(True, True)
            if mode in (0, 1):
                self.send(data)  # the echo, then the error
            self._error(line, exc.errno, exc.detail)
            model.interpreter.poke()
            self._reply_end(line)
            return
        if (interpreter := model.interpreter).waiting == "wait":  # (poke does nothing else)
            interpreter.poke()
        if mode in (0, 1) and not self._spontaneous:  # echo, answer and acknowledgement in one piece
            self.send(kept.reply_with(data, answer, model.answers.ack_line()))
            self._last_replied = True
            self.line = None
            return
        self.line = line = CommandLine(True, True)
        if mode in (0, 1):
            self.send(data)
        self._put(line, answer)
        self._reply_end(line)

    def _failing_line(self, line: CommandLine, data: bytes, stop: int, end: int) -> int:
        """The rest of a whole line in the chunk whose first statement is an error before any
        statement completes (what noise mostly is): its echo up to the character that made
        the error, the error, the echo of the rest and of the line end, in one step, as
        :meth:`take_text`, :meth:`.interactive.LineStatements.progress` and the line end would
        do it piece by piece.  Any other line goes on piece by piece (returns ``stop``)."""
        framer = self.framer
        window = max(0, codec.MAX_LINE - framer.length)  # characters kept (the rest are dropped)
        failure = first_failure(data[stop : min(end - 1, stop + window)])
        if failure is None:
            return stop
        cut, errno = failure
        if line.reply and self.echo:
            self.send(data[stop : stop + cut])
        self._error(line, errno)
        finish = framer.skip_text(data, stop)  # the line end (its length and overflow counted)
        if line.reply and self.echo:
            self.send(data[stop + cut : finish])
        self._line_end(line, data[finish], framer.end_line(data[finish]))
        return finish + 1

    def restart(self, line: CommandLine, data: bytes, index: int) -> int:
        """A ``#`` inside the line's text and the address after it (what :meth:`_on_restart`
        does, and then the address handlers, byte by byte)."""
        self.statements.progress(line, final=True)
        if self.line is not line or not self.model.logic_alive or self.model.booting:
            return index + 1  # (the statements reset the drive: the '#' is gone with the line)
        line.text, line.executed = "", 0
        complete, address, stop = self.framer.begin_line(data, index)
        line.held = bytearray(data[index:stop])
        if complete:
            self._select(line, address)
        return stop

    def take_text(self, line: CommandLine, data: bytes, index: int) -> int:
        """A run of text characters from ``index`` taken at once: what :meth:`_on_text` does
        character by character.  Each piece up to a character that can complete a statement is
        echoed in one write, appended, and the line parsed once (a statement's answer so
        follows the echo of the character that completed it).  Returns how many were taken;
        it stops early when a statement ends the line's execution (an error, a reset)."""
        framer, model = self.framer, self.model
        stop = framer.text_run(data, index)
        start = index
        while index < stop:
            found = COMPLETES.search(data, index, stop)
            cut = stop if found is None else found.end()
            framer.take_text(cut - index)
            if line.reply and self.echo:
                self.send(data[index:cut])
            line.text += data[index:cut].decode("latin-1")
            index = cut
            if found is not None:
                self.statements.progress(line, final=False)
                if line.error or self.line is not line or not model.logic_alive or model.booting:
                    break
        return index - start

    def on_event(self, event: object, byte: int) -> None:
        self._handlers[type(event)](self, event, byte)

    def _on_text(self, event: codec.TextChar, byte: int) -> None:
        line = self.line
        if line is None:
            return
        if line.reply and self.echo:
            self.send(bytes((byte,)))
        if event.dropped or line.error or not line.execute:
            return
        line.text += event.char
        if event.char not in EXTENDS_ONLY:
            self.statements.progress(line, final=False)

    def _on_ignored(self, event: codec.Ignored, byte: int) -> None:
        """The second half of a CR/LF pair after a line this drive answered: echoed, and with
        ``ack_each_terminator`` (G-CRLF ⚙) acknowledged as a terminator of its own."""
        if event.pair and self._last_replied:
            self.send((bytes((byte,)) if self.echo else b"") + (self.model.answers.ack_line() if self._ack_each else b""))

    def _on_restart(self, event: codec.Restart, byte: int) -> None:
        line = self.line
        if event.mid_line and line is not None:
            self.statements.progress(line, final=True)
            line.text, line.executed = "", 0
            line.held = bytearray(b"#")
        else:
            self.line = CommandLine(held=bytearray(b"#"))

    def _on_address_char(self, event: codec.AddressChar, byte: int) -> None:
        if self.line is not None:
            self.line.held.append(byte)

    def _on_address(self, event: codec.Address, byte: int) -> None:
        if self.line is not None:
            self._select(self.line, event.value)

    def _on_line_end(self, event: codec.LineEnd, byte: int) -> None:
        if self.line is not None:
            self._line_end(self.line, byte, event.overflow)

    def _line_end(self, line: CommandLine, byte: int, overflow: bool) -> None:
        if line.reply and self.echo:
            self.send(bytes((byte,)))
        self.end_line(line, overflow)

    def end_line(self, line: CommandLine, overflow: bool) -> None:
        """The line has ended (its terminator echoed): the rest of its statements run, then
        the deferred answers and the acknowledgement (§4.1)."""
        if line.execute and not line.error:
            if overflow:  # the statement the limit cut is lost with what followed it (spec G-LINE)
                self.model.power_stage.warn(1024)
                self._error(line, 124)
            else:
                self.statements.progress(line, final=True)
            if line.store and not line.error:
                try:
                    self.model.program.add_line(line.store,
                                                joins_next=line.text.rstrip(" \t").endswith(";"))
                except SersError as exc:
                    self._error(line, exc.errno, exc.detail)
                line.store = []
        self._reply_end(line)

    def _reply_end(self, line: CommandLine) -> None:
        """The end of a line whose statements have run: its deferred answers and the
        acknowledgement (§4.1), then the messages that waited for the line end."""
        if line.reply:
            if line.deferred:
                self.send(bytes(line.deferred))
            if not line.error or self._ok_after_error:  # (G-ERRFMT ⚙ ``ok_after_error``)
                self.send(self.model.answers.ack_line())
        self._last_replied = line.reply
        self.line = None
        if self._spontaneous:  # (messages that waited for the line end; most lines: none)
            self._flush_spontaneous()

    _handlers: ClassVar[dict[type, Any]] = {
        codec.TextChar: _on_text,
        codec.Ignored: _on_ignored,
        codec.Restart: _on_restart,
        codec.AddressChar: _on_address_char,
        codec.Address: _on_address,
        codec.LineEnd: _on_line_end,
    }

    def _select(self, line: CommandLine, address: int | str | None) -> None:
        line.execute, line.reply = self.model.selection(address)
        self.model.note_address(address, line.execute)
        if line.held:
            if line.reply and self.echo:
                self.send(bytes(line.held))
            line.held.clear()

    # -- output ----------------------------------------------------------------------------
    @property
    def echo(self) -> bool:
        return self.model.params.values.cells[HANDSHAKE_CELL] in (0, 1)

    def _out(self, line: CommandLine, text: str) -> None:
        self._put(line, text.encode(self.model.cfg.encoding, errors="replace"))

    def _put(self, line: CommandLine, data: bytes) -> None:
        """An answer of the line: at once, or with RS-485 handshake (P1017 = 2) at its end."""
        if not line.reply:
            return
        if self.model.params.values.cells[HANDSHAKE_CELL] == 2:
            line.deferred += data
        else:
            self.send(data)

    def _error(self, line: CommandLine, errno: int, detail: str = "") -> None:
        line.error, model = True, self.model
        model.power_stage.record_error(errno, refused=True)
        self._put(line, error_text(errno, model.params.values.cells[LANGUAGE_CELL] == 1, model.cfg.encoding, detail, self._star))

    def spontaneous(self, text: str) -> None:
        """Messages such as ``@2POS=1`` go out between lines, never inside one (G-SPONT)."""
        self._spontaneous.append(text.encode(self.model.cfg.encoding, errors="replace") + b"\n\r")
        if self.line is None:
            self._flush_spontaneous()

    def _flush_spontaneous(self) -> None:
        while self._spontaneous:
            self.send(self._spontaneous.pop(0))
