"""The serial face of the Stögra SERS (manual "SERS Version V04, Firmware ab 120901"; spec sers.md).

This module is the ASCII line protocol of the drive, held over the model (:class:`SersDrive`): framing, drive selection on a multidrop line,
echo modes (P1017, §4.8.6.9), acknowledgements (§4.1), error messages (§4.8.3.1), parameter
queries (§4.7) and the execution of interactive statements (§4.2).  The physics behind it –
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
    Poll,
    ends_line,
    error_text,
    first_byte_errors,
    first_failure,
    label_number,
    poll_line,
    quiet,
)
from devsim.devices.sers.model import SersDrive

__all__ = ["SersFace"]


class SersFace(Face):
    """The ASCII line protocol of one SERS on a serial line (RS-232, or RS-485 multidrop)."""

    model: SersDrive

    def __init__(self, model: SersDrive, port: Port) -> None:
        super().__init__(model, port)
        self.framer = codec.Framer()
        self._line: CommandLine | None = None
        self._last_replied = False
        self._spontaneous: list[bytes] = []
        self._settings: SerialSettings | None = None
        self.statements = LineStatements(model, self._out, self._error)
        model.listen("power_on", self._reset_serial)
        model.listen("spontaneous", self.spontaneous)
        model.listen("line_out", self.send)

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
        self._line = None
        self._last_replied = False
        self._spontaneous.clear()

    # -- bytes from the host -------------------------------------------------------------
    def feed(self, data: bytes) -> None:
        # (answers to one chunk of input leave in one write: the kit's port batches them)
        model = self.model
        model.shared_line = self.port.shared_line
        if model.master.awaiting and model.logic_alive:
            model.master.feed(data)  # a slave's answer to this master
        if not model.logic_alive or model.booting:
            return  # G-BOOT: input during the 2 s initialisation is discarded
        framer = self.framer
        # (a host's poll is one short chunk: a longer one, noise or a flood, is not hashed and kept)
        if self._line is None and not framer.in_line and len(data) <= codec.MAX_LINE + 1:
            poll = poll_line(data)
            if poll is not None and self._answer_poll(poll, data):
                return
        index, end = 0, len(data)
        while index < end:
            line = self._line
            if model.addressed is False and self._unconcerned(line):
                stop = framer.skip_unaddressed(data, index, model.line_address)  # other drives' lines
                if stop > index:
                    if framer.in_line and (line is None or ends_line(data, index, stop)):
                        line = CommandLine()  # a line that began in the skip (not the one that ended there)
                    self._line = line if framer.in_line else None
                    index = stop
                    continue
            byte = data[index]
            if not framer.in_line:
                if byte == codec.HASH:
                    stop = self._failing_lines(data, index)  # lines of noise, one after the other
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
                    index = self._restart(line, data, index)  # '#' inside the line
                    if not model.logic_alive or model.booting:
                        return
                    continue
                if line.execute and not line.error and framer.length < codec.MAX_LINE:
                    taken = self._take_text(line, data, index)  # a run of text in one step
                    if taken:
                        index += taken
                        if not model.logic_alive or model.booting:
                            return
                        continue
                else:  # text nobody executes, or beyond 60 characters (dropped): only echoed
                    stop = framer.skip_text(data, index)
                    if line.reply and self.echo:
                        self.send(data[index:stop])
                    index = stop
                    continue
            index += 1
            for event in framer.feed(byte):
                self._on_event(event, byte)
            if not model.logic_alive or model.booting:
                return

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
            self._line = CommandLine(held=bytearray(data[index:stop]))  # echoed once the address ends
            return stop
        self._line = line = CommandLine()
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
        self._end_line(line, framer.end_line(data[end - 1]))
        return end

    def _answer_poll(self, poll: Poll, data: bytes) -> bool:
        """A chunk that is one whole query line (a host's poll, see :func:`poll_line`), between
        lines: what :meth:`_begin_line` does with it, without framing and checking the line
        again.  Only for a line this drive executes and answers, outside programming mode;
        returns False (having done nothing) for any other."""
        model = self.model
        address = poll.address
        if not self._selection(address)[1] or model.program.editing:
            return False
        self._note_address(address, True)
        self.framer.whole_line(poll.length, data[-1])
        if self.echo:
            self.send(data)
        self._line = line = CommandLine()  # (what the query sets off waits for the line end)
        line.execute = line.reply = True
        try:  # what _progress does with the line's one statement, a query (_query)
            self._out(line, model.answers.query_text(poll.query) + "\n\r")
        except SersError as exc:
            self._error(line, exc.errno, exc.detail)
        finally:
            model.interpreter.poke()
        self._reply_end(line)
        return True

    def _failing_line(self, line: CommandLine, data: bytes, stop: int, end: int) -> int:
        """The rest of a whole line in the chunk whose first statement is an error before any
        statement completes (what noise mostly is): its echo up to the character that made
        the error, the error, the echo of the rest and of the line end, in one step, as
        :meth:`_take_text`, :meth:`_progress` and the line end would do it piece by piece.
        Any other line goes on piece by piece (returns ``stop``)."""
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

    def _failing_lines(self, data: bytes, index: int) -> int:
        """From a ``#`` outside a line: whole lines this drive executes whose first statement
        fails before any statement completes (what random noise mostly is), with the restarts
        of the failed line, its end and the noise up to the next ``#``, one line after the
        other, as :meth:`_begin_line`, :meth:`_failing_line`, :meth:`_restart`, the line end
        and the noise skip would do them.  Stops before a line it does not take (one for
        another drive, one that runs a statement, one whose text in the chunk does not fail)
        or inside one (a restart for another drive or whose address the chunk cuts off, the
        chunk's end), with the line and the framing as those paths leave them; returns where
        (``index``: nothing taken).  The echo up to the failing character leaves before the
        error is recorded, the rest of the line's answers with its end, before the line's end
        is handled."""
        model, framer, send, end = self.model, self.framer, self.send, len(data)
        hash_, no_address, search, fails = codec.HASH, codec.NO_ADDRESS, codec.TEXT_END.search, first_byte_errors()
        mode = model.answers.handshake_mode  # (only a statement changes it: none runs here)
        while True:
            # data[index] is a '#' outside a line
            if model.addressed is False:
                return index  # (the general path skips lines for other drives in one step)
            stop = index + 1
            if stop < end and data[stop] in no_address:  # (most noise: no address)
                address = None
            else:
                complete, address, stop = codec.read_address(data, index)
                if not complete:
                    return index
            execute, reply = self._selection(address)
            if not execute:
                return index
            found = search(data, stop)
            finish = end if found is None else found.start()  # (the chunk may end the text)
            keep = min(finish, index + codec.MAX_LINE)  # the text kept (60 characters from the '#')
            if keep <= stop:
                return index
            errno = fails[data[stop]]
            if errno:
                cut = stop + 1
            else:
                failure = first_failure(data[stop:keep])
                if failure is None:
                    return index
                cut, errno = stop + failure[0], failure[1]
            # the line fails at data[cut - 1]: take it
            self._note_address(address, execute)
            self._line = line = CommandLine()
            line.execute = line.error = True
            line.reply = reply
            if reply and mode in (0, 1):
                send(data[index:cut])
            model.power_stage.record_error(errno)  # (what _error does, its message from a table)
            mode = model.answers.handshake_mode
            echo = mode in (0, 1)
            text = error_text(errno, model.answers.english, model.cfg.encoding) if reply else b""
            if mode == 2:
                line.deferred += text
                text = b""
            if not model.logic_alive or model.booting:
                framer.take_line(stop - index, cut - stop)
                send(text)
                return cut
            framer.take_line(stop - index, finish - stop)
            if reply and echo:
                text += data[cut:finish]
            if finish == end:  # (the line goes on in the next chunk)
                send(text)
                return end
            while data[finish] == hash_:  # a restart in the failed line: only echoed
                complete, address, stop = codec.read_address(data, finish)
                executes, answers = self._selection(address) if complete else (False, False)
                if not executes:  # (another drive's address, or one the chunk cuts off)
                    send(text)
                    return self._restart(line, data, finish)
                line.execute, line.reply = executes, answers
                self._note_address(address, executes)
                line.text, line.executed = "", 0
                found = search(data, stop)
                after = end if found is None else found.start()
                framer.take_line(stop - finish, after - stop)
                if line.reply and echo:
                    text += data[finish:after]  # the address held until complete, and the text
                finish = after
                if finish == end:
                    send(text)
                    return end
            byte = data[finish]
            if line.reply and echo:
                text += data[finish : finish + 1]
            overflow = framer.end_line(byte)
            send(text)
            self._end_line(line, overflow)
            index = finish + 1
            if not model.logic_alive or model.booting or model.addressed is False:
                return index
            if index < end:
                byte = data[index]
                if byte in LINE_ENDS:  # the other half of a CR/LF pair, or noise
                    index += 1
                    for event in framer.feed(byte):
                        self._on_event(event, byte)
                    if index == end:
                        return end
                    byte = data[index]
                if byte != hash_:
                    index = framer.skip_noise(data, index)
            if index >= end:
                return end

    def _restart(self, line: CommandLine, data: bytes, index: int) -> int:
        """A ``#`` inside the line's text and the address after it (what :meth:`_on_restart`
        does, and then the address handlers, byte by byte)."""
        self.statements.progress(line, final=True)
        if self._line is not line or not self.model.logic_alive or self.model.booting:
            return index + 1  # (the statements reset the drive: the '#' is gone with the line)
        line.text, line.executed = "", 0
        complete, address, stop = self.framer.begin_line(data, index)
        line.held = bytearray(data[index:stop])
        if complete:
            self._select(line, address)
        return stop

    def _take_text(self, line: CommandLine, data: bytes, index: int) -> int:
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
                if line.error or self._line is not line or not model.logic_alive or model.booting:
                    break
        return index - start

    def host_disconnected(self) -> None:
        """A host that leaves mid-line leaves a partial line; the next '#' restarts anyway."""

    def _on_event(self, event: object, byte: int) -> None:
        self._handlers[type(event)](self, event, byte)

    def _on_text(self, event: codec.TextChar, byte: int) -> None:
        line = self._line
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
        if event.pair and self._last_replied and self.echo:
            self.send(bytes((byte,)))

    def _on_restart(self, event: codec.Restart, byte: int) -> None:
        line = self._line
        if event.mid_line and line is not None:
            self.statements.progress(line, final=True)
            line.text, line.executed = "", 0
            line.held = bytearray(b"#")
        else:
            self._line = CommandLine(held=bytearray(b"#"))

    def _on_address_char(self, event: codec.AddressChar, byte: int) -> None:
        if self._line is not None:
            self._line.held.append(byte)

    def _on_address(self, event: codec.Address, byte: int) -> None:
        if self._line is not None:
            self._select(self._line, event.value)

    def _on_line_end(self, event: codec.LineEnd, byte: int) -> None:
        if self._line is not None:
            self._line_end(self._line, byte, event.overflow)

    def _line_end(self, line: CommandLine, byte: int, overflow: bool) -> None:
        if line.reply and self.echo:
            self.send(bytes((byte,)))
        self._end_line(line, overflow)

    def _end_line(self, line: CommandLine, overflow: bool) -> None:
        """The line has ended (its terminator echoed): the rest of its statements run, then
        the deferred answers and the acknowledgement (§4.1)."""
        if line.execute and not line.error:
            self.statements.progress(line, final=True)
            if overflow and not line.error:
                self.model.power_stage.warn(1024)
                self._error(line, 124)
            if line.store and not line.error:
                try:
                    self.model.program.add_line(line.store, label_number)
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
            if not line.error:
                self.send(b"\n" + self.model.answers.ack_text().encode("latin-1") + b"\n\r")
        self._last_replied = line.reply
        self._line = None
        self._flush_spontaneous()

    _handlers: ClassVar[dict[type, Any]] = {
        codec.TextChar: _on_text,
        codec.Ignored: _on_ignored,
        codec.Restart: _on_restart,
        codec.AddressChar: _on_address_char,
        codec.Address: _on_address,
        codec.LineEnd: _on_line_end,
    }

    def _selection(self, address: int | str | None) -> tuple[bool, bool]:
        """Whether this drive executes and answers a line with ``address`` after its ``#``
        (G-ADDR), changing nothing: without one, if it is selected; ``*``, executed by all and
        answered by none (a broadcast); its own address, both; another, neither."""
        if address is None:
            selected = self.model.selected
            return selected, selected
        if address == "*":
            return True, False
        mine = address == self.model.line_address
        return mine, mine

    def _note_address(self, address: int | str | None, mine: bool) -> None:
        """A line's address selects its drive and deselects the others (G-ADDR); a line
        without one, or a broadcast, changes nothing.  ``mine``: the address is this drive's."""
        if address is not None and address != "*":
            self.model.addressed = mine

    def _select(self, line: CommandLine, address: int | str | None) -> None:
        line.execute, line.reply = self._selection(address)
        self._note_address(address, line.execute)
        if line.held:
            if line.reply and self.echo:
                self.send(bytes(line.held))
            line.held.clear()

    # -- output ----------------------------------------------------------------------------
    @property
    def echo(self) -> bool:
        return self.model.answers.handshake_mode in (0, 1)

    def _out(self, line: CommandLine, text: str) -> None:
        self._put(line, text.encode(self.model.cfg.encoding, errors="replace"))

    def _put(self, line: CommandLine, data: bytes) -> None:
        """An answer of the line: at once, or with RS-485 handshake (P1017 = 2) at its end."""
        if not line.reply:
            return
        if self.model.answers.handshake_mode == 2:
            line.deferred += data
        else:
            self.send(data)

    def _error(self, line: CommandLine, errno: int, detail: str = "") -> None:
        line.error = True
        self.model.power_stage.record_error(errno)
        self._put(line, error_text(errno, self.model.answers.english, self.model.cfg.encoding, detail))

    def spontaneous(self, text: str) -> None:
        """Messages such as ``@2POS=1`` go out between lines, never inside one (G-SPONT)."""
        self._spontaneous.append(text.encode(self.model.cfg.encoding, errors="replace") + b"\n\r")
        if self._line is None:
            self._flush_spontaneous()

    def _flush_spontaneous(self) -> None:
        while self._spontaneous:
            self.send(self._spontaneous.pop(0))
