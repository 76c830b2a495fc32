"""The serial face of the Stögra SERS (manual "SERS Version V04, Firmware ab 120901"; spec sers.md).

This module is the ASCII line protocol of the drive, held over the model (:class:`SersDrive`): framing, drive selection on a multidrop line,
echo modes (P1017, §4.8.6.9), acknowledgements (§4.1), error messages (§4.8.3.1), parameter
queries (§4.7) and the execution of interactive statements (§4.2).  The physics behind it –
positioning, jog, homing, limit switches, faults – lives in the model's parts (:mod:`.model`).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable
from typing import Any, ClassVar

from devsim.core.device import Face, Port, SerialSettings
from devsim.core.kit import Command, Table
from devsim.core.record import field, record
from devsim.devices.sers import codec
from devsim.devices.sers import statements as st
from devsim.devices.sers.access import address_number
from devsim.devices.sers.errors import SersError, message
from devsim.devices.sers.model import SersDrive

__all__ = ["INTERACTIVE", "SersFace"]

# Characters that only ever extend the statement in progress (a number, the '?' of a query):
# nothing can complete with them, so they need no parse (the next character will do it).
_EXTENDS_ONLY = frozenset("0123456789.?")
# The first character of a text run that is not one of those.
_COMPLETES = re.compile(b"[^" + re.escape("".join(sorted(_EXTENDS_ONLY)).encode()) + b"]")
# The rest of a line: its text and its end (within 60 characters: checked by the caller).
_TEXT_TO_END = re.compile(rb"([^\r\n#]+)[\r\n]")
_LINE_ENDS = (codec.CR, codec.LF)


@record(frozen=False)
class _Line:
    """What the device knows about the command line being received."""

    execute: bool = False  # this drive carries out the statements
    reply: bool = False  # this drive echoes and answers
    held: bytearray = field(default_factory=bytearray)  # echo of '#' and address digits
    text: str = ""  # statement text of the current segment
    executed: int = 0  # statements of the segment already executed
    error: bool = False
    skip_next: bool = False  # single-statement IF was false
    skip_block: int = 0  # inside a false IF..THEN block (depth)
    deferred: bytearray = field(default_factory=bytearray)  # RS-485 mode: answers until line end
    store: list[str] = field(default_factory=list)  # programming mode: statements for the EEPROM


class SersFace(Face):
    """The ASCII line protocol of one SERS on a serial line (RS-232, or RS-485 multidrop)."""

    model: SersDrive

    def __init__(self, model: SersDrive, port: Port) -> None:
        super().__init__(model, port)
        self.framer = codec.Framer()
        self._line: _Line | None = None
        self._last_replied = False
        self._spontaneous: list[bytes] = []
        self._settings: SerialSettings | None = None
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
            poll = _poll_line(data)
            if poll is not None and self._answer_poll(poll, data):
                return
        index, end = 0, len(data)
        while index < end:
            line = self._line
            if model.addressed is False and self._unconcerned(line):
                stop = framer.skip_unaddressed(data, index, model.line_address)  # other drives' lines
                if stop > index:
                    if framer.in_line and (line is None or _ends_line(data, index, stop)):
                        line = _Line()  # a line that began in the skip (not the one that ended there)
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
                if framer.idle or byte not in _LINE_ENDS:
                    index = framer.skip_noise(data, index)  # noise between lines: one search
                    continue
                # (a CR or LF right after a line end: the second half of a pair, byte by byte)
            elif line is not None and framer.in_text:
                if byte in _LINE_ENDS:
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

    def _unconcerned(self, line: _Line | None) -> bool:
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
            self._line = _Line(held=bytearray(data[index:stop]))  # echoed once the address ends
            return stop
        self._line = line = _Line()
        self._select(line, address)
        if not line.execute and not line.reply:  # another drive's line: only its end matters
            finish = framer.skip_text(data, stop)
            if finish < len(data) and data[finish] in _LINE_ENDS:
                self._line_end(line, data[finish], framer.end_line(data[finish]))
                return finish + 1
            return finish
        whole = _TEXT_TO_END.match(data, stop) if line.execute else None
        end = whole.end() if whole is not None else 0
        text = _quiet(whole[1]) if whole is not None and end - index - 1 <= codec.MAX_LINE else None
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

    def _answer_poll(self, poll: _Poll, data: bytes) -> bool:
        """A chunk that is one whole query line (a host's poll, see :func:`_poll_line`), between
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
        self._line = line = _Line()  # (what the query sets off waits for the line end)
        line.execute = line.reply = True
        try:  # what _progress does with the line's one statement, a query (_query)
            self._out(line, model.answers.query_text(poll.query) + "\n\r")
        except SersError as exc:
            self._error(line, exc.errno, exc.detail)
        finally:
            model.interpreter.poke()
        self._reply_end(line)
        return True

    def _failing_line(self, line: _Line, data: bytes, stop: int, end: int) -> int:
        """The rest of a whole line in the chunk whose first statement is an error before any
        statement completes (what noise mostly is): its echo up to the character that made
        the error, the error, the echo of the rest and of the line end, in one step, as
        :meth:`_take_text`, :meth:`_progress` and the line end would do it piece by piece.
        Any other line goes on piece by piece (returns ``stop``)."""
        framer = self.framer
        window = max(0, codec.MAX_LINE - framer.length)  # characters kept (the rest are dropped)
        failure = _first_failure(data[stop : min(end - 1, stop + window)])
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
        hash_, no_address, search, fails = codec.HASH, codec.NO_ADDRESS, codec.TEXT_END.search, _first_byte_errors()
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
                failure = _first_failure(data[stop:keep])
                if failure is None:
                    return index
                cut, errno = stop + failure[0], failure[1]
            # the line fails at data[cut - 1]: take it
            self._note_address(address, execute)
            self._line = line = _Line()
            line.execute = line.error = True
            line.reply = reply
            if reply and mode in (0, 1):
                send(data[index:cut])
            model.power_stage.record_error(errno)  # (what _error does, its message from a table)
            mode = model.answers.handshake_mode
            echo = mode in (0, 1)
            text = _error_text(errno, model.answers.english, model.cfg.encoding) if reply else b""
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
                if byte in _LINE_ENDS:  # the other half of a CR/LF pair, or noise
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

    def _restart(self, line: _Line, data: bytes, index: int) -> int:
        """A ``#`` inside the line's text and the address after it (what :meth:`_on_restart`
        does, and then the address handlers, byte by byte)."""
        self._progress(line, final=True)
        if self._line is not line or not self.model.logic_alive or self.model.booting:
            return index + 1  # (the statements reset the drive: the '#' is gone with the line)
        line.text, line.executed = "", 0
        complete, address, stop = self.framer.begin_line(data, index)
        line.held = bytearray(data[index:stop])
        if complete:
            self._select(line, address)
        return stop

    def _take_text(self, line: _Line, data: bytes, index: int) -> int:
        """A run of text characters from ``index`` taken at once: what :meth:`_on_text` does
        character by character.  Each piece up to a character that can complete a statement is
        echoed in one write, appended, and the line parsed once (a statement's answer so
        follows the echo of the character that completed it).  Returns how many were taken;
        it stops early when a statement ends the line's execution (an error, a reset)."""
        framer, model = self.framer, self.model
        stop = framer.text_run(data, index)
        start = index
        while index < stop:
            found = _COMPLETES.search(data, index, stop)
            cut = stop if found is None else found.end()
            framer.take_text(cut - index)
            if line.reply and self.echo:
                self.send(data[index:cut])
            line.text += data[index:cut].decode("latin-1")
            index = cut
            if found is not None:
                self._progress(line, final=False)
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
        if event.char not in _EXTENDS_ONLY:
            self._progress(line, final=False)

    def _on_ignored(self, event: codec.Ignored, byte: int) -> None:
        if event.pair and self._last_replied and self.echo:
            self.send(bytes((byte,)))

    def _on_restart(self, event: codec.Restart, byte: int) -> None:
        line = self._line
        if event.mid_line and line is not None:
            self._progress(line, final=True)
            line.text, line.executed = "", 0
            line.held = bytearray(b"#")
        else:
            self._line = _Line(held=bytearray(b"#"))

    def _on_address_char(self, event: codec.AddressChar, byte: int) -> None:
        if self._line is not None:
            self._line.held.append(byte)

    def _on_address(self, event: codec.Address, byte: int) -> None:
        if self._line is not None:
            self._select(self._line, event.value)

    def _on_line_end(self, event: codec.LineEnd, byte: int) -> None:
        if self._line is not None:
            self._line_end(self._line, byte, event.overflow)

    def _line_end(self, line: _Line, byte: int, overflow: bool) -> None:
        if line.reply and self.echo:
            self.send(bytes((byte,)))
        self._end_line(line, overflow)

    def _end_line(self, line: _Line, overflow: bool) -> None:
        """The line has ended (its terminator echoed): the rest of its statements run, then
        the deferred answers and the acknowledgement (§4.1)."""
        if line.execute and not line.error:
            self._progress(line, final=True)
            if overflow and not line.error:
                self.model.power_stage.warn(1024)
                self._error(line, 124)
            if line.store and not line.error:
                try:
                    self.model.program.add_line(line.store, _label_number)
                except SersError as exc:
                    self._error(line, exc.errno, exc.detail)
                line.store = []
        self._reply_end(line)

    def _reply_end(self, line: _Line) -> None:
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

    def _select(self, line: _Line, address: int | str | None) -> None:
        line.execute, line.reply = self._selection(address)
        self._note_address(address, line.execute)
        if line.held:
            if line.reply and self.echo:
                self.send(bytes(line.held))
            line.held.clear()

    # -- statements ----------------------------------------------------------------------
    def _progress(self, line: _Line, final: bool) -> None:
        if line.error or not line.execute:
            return
        result = st.parse(line.text, final)
        for stmt, end in result.statements[line.executed :]:
            if not final and end == len(line.text) and _answers(stmt):
                break  # §3.2.4a: a statement with an answer completes with the next character
            line.executed += 1
            try:
                self._statement(line, stmt)
            except SersError as exc:
                self._error(line, exc.errno, exc.detail)
                return
            finally:
                self.model.interpreter.poke()
        if result.errno is not None and line.executed == len(result.statements):
            self._error(line, result.errno)

    def _statement(self, line: _Line, stmt: st.Statement) -> None:
        if self.model.program.editing:
            if self._stores_in_program(stmt):
                if not isinstance(stmt, st.Comment):
                    line.store.append(stmt.text)  # stored when the line ends without an error
                return
            if isinstance(stmt, st.Change):
                self.model.program.change(self._changed_statement(stmt))
                return
            if isinstance(stmt, st.Command) and stmt.name == "DEL":
                self.model.program.delete()
                return
        if line.skip_block:
            if isinstance(stmt, st.If) and stmt.then:
                line.skip_block += 1
            elif isinstance(stmt, st.End):
                line.skip_block -= 1
            elif isinstance(stmt, st.Else) and line.skip_block == 1:
                line.skip_block = 0
            return
        if line.skip_next:
            line.skip_next = False
            return
        handler = INTERACTIVE.get(type(stmt).__name__)
        if handler is None or not handler(self, line, stmt):
            self.model.execution.execute(stmt)  # the drive's own statements (execution.STATEMENTS)

    # -- statements with an answer or line state (the table INTERACTIVE) ---------------------
    def _if(self, line: _Line, stmt: st.If) -> bool:
        true = self.model.operands.evaluate(stmt.cond)
        if stmt.then:
            if not true:
                line.skip_block = 1
        else:
            line.skip_next = not true
        return True

    def _else(self, line: _Line, stmt: st.Else) -> bool:
        line.skip_block = 1  # the THEN part ran: skip to END
        return True

    def _query(self, line: _Line, stmt: st.Query) -> bool:
        self._out(line, self.model.answers.query_text(stmt) + "\n\r")
        return True

    def _list(self, line: _Line, stmt: st.ListCmd) -> bool:
        model = self.model
        if stmt.params:
            rows = model.answers.list_parameters(stmt.arg)
        else:
            rows = model.program.listing(model.answers.list_options, model.answers.render_statement, stmt.arg)
        self._out(line, "".join(f"{row}\n\r" for row in rows))
        return True

    def _assign(self, line: _Line, stmt: st.Assign) -> bool:
        if stmt.target.kind not in ("P", "alias") or not self._is_master_query(stmt):
            return False
        # a master asks through P2 (IF/WAIT) or P3 (read): answer the value (§4.8.5.5, G-MASTER)
        number = address_number(stmt.target)
        asked = int(self.model.operands.operand_value(stmt.value)) if not isinstance(stmt.value, str) else 0
        self.model.params.values[number] = asked
        self._out(line, f"P{number}={self.model.access.plain_value(asked)}\n\r")
        return True

    def _version(self, line: _Line, stmt: st.Command) -> bool:
        if stmt.name != "VER":
            return False
        self._out(line, f"P1133={self.model.access.firmware}\n\r")
        return True

    def _trace(self, line: _Line, stmt: st.Trace) -> bool:
        if stmt.query:
            self._out(line, f"TR={int(self.model.interpreter.trace_mode)}\n\r")
            return True
        # TR: one program step; the executed statement is shown like a LIST row (G-TRACE)
        self.model.interpreter.trace_mode = True
        shown = self.model.interpreter.trace_step()
        if shown is not None:
            self._out(line, shown + "\n\r")
        return True

    def _is_master_query(self, stmt: st.Assign) -> bool:
        try:
            return address_number(stmt.target) in (2, 3)
        except SersError:
            return False

    def _changed_statement(self, stmt: st.Change) -> str:
        """C n (§4.2): the assignment at the current position with the constant n."""
        current = self.model.program.current()
        parsed = st.parse(current, final=True) if current is not None else None
        if parsed is None or parsed.errno is not None or len(parsed.statements) != 1:
            raise SersError(49)
        old = parsed.statements[0][0]
        if not isinstance(old, st.Assign) or not isinstance(old.value, st.Number):
            raise SersError(49)
        return f"{old.target.text}={stmt.value.text}"

    def _stores_in_program(self, stmt: st.Statement) -> bool:
        """In programming mode everything is stored except LIST, DEL, TR…, C n and QUIT."""
        if isinstance(stmt, st.ListCmd | st.Trace | st.Change):
            return False
        if isinstance(stmt, st.Command) and stmt.name in ("DEL", "QUIT"):
            return False
        if isinstance(stmt, st.Assign) and stmt.target.kind == "P" and stmt.target.ref == 0:
            return False  # P0=0 leaves programming mode
        return True

    # -- output ----------------------------------------------------------------------------
    @property
    def echo(self) -> bool:
        return self.model.answers.handshake_mode in (0, 1)

    def _out(self, line: _Line, text: str) -> None:
        self._put(line, text.encode(self.model.cfg.encoding, errors="replace"))

    def _put(self, line: _Line, data: bytes) -> None:
        """An answer of the line: at once, or with RS-485 handshake (P1017 = 2) at its end."""
        if not line.reply:
            return
        if self.model.answers.handshake_mode == 2:
            line.deferred += data
        else:
            self.send(data)

    def _error(self, line: _Line, errno: int, detail: str = "") -> None:
        line.error = True
        self.model.power_stage.record_error(errno)
        self._put(line, _error_text(errno, self.model.answers.english, self.model.cfg.encoding, detail))

    def spontaneous(self, text: str) -> None:
        """Messages such as ``@2POS=1`` go out between lines, never inside one (G-SPONT)."""
        self._spontaneous.append(text.encode(self.model.cfg.encoding, errors="replace") + b"\n\r")
        if self._line is None:
            self._flush_spontaneous()

    def _flush_spontaneous(self) -> None:
        while self._spontaneous:
            self.send(self._spontaneous.pop(0))


#: Statements the serial face answers itself (a value, a listing, the version) or that steer
#: the line (IF/ELSE/END); a handler returning False leaves the statement to the drive.
INTERACTIVE: Table[Callable[[SersFace, _Line, Any], bool]] = Table(
    [
        Command("If", SersFace._if, "§4.6.1", "IF condition [THEN … ELSE … END]"),
        Command("Else", SersFace._else, "§4.6.1", "ELSE: skip to END"),
        Command("End", lambda face, line, stmt: True, "§4.6.1", "END of an IF block"),
        Command("Query", SersFace._query, "§4.7", "P<n>? / P<n>?? / alias?: the value or the name"),
        Command("ListCmd", SersFace._list, "§4.2", "LIST / LISTP: the program or the parameters"),
        Command("Assign", SersFace._assign, "§4.8.5.5", "P2=/P3= from a master: answer the value"),
        Command("Command", SersFace._version, "§4.8.2.5", "VER: the firmware version"),
        Command("Trace", SersFace._trace, "§4.5.4", "TR? / TR: trace mode, one step"),
    ]
)


def _answers(stmt: st.Statement) -> bool:
    """Statements that send text: their output must follow the echo of the next character."""
    if isinstance(stmt, st.Query | st.ListCmd):
        return True
    if isinstance(stmt, st.Trace):
        return stmt.query
    return isinstance(stmt, st.Command) and stmt.name == "VER"


@functools.lru_cache(maxsize=1024)
def _quiet(text: bytes) -> str | None:
    """A line's text if nothing in it runs, answers or fails before its line end as the text
    arrives character by character (so it may be taken in one step, see
    :meth:`SersFace._begin_line`), else None: at every character that can complete a
    statement, the text so far holds no error and no statement except one answering at its
    very end."""
    chars = text.decode("latin-1")
    for at, char in enumerate(chars):
        if char in _EXTENDS_ONLY:
            continue
        result = st.parse(chars[: at + 1], False)
        if result.errno is not None:
            return None
        done = result.statements
        if done and (len(done) > 1 or done[0][1] != at + 1 or not _answers(done[0][0])):
            return None
    return chars


@record
class _Poll:
    """A whole line that asks one thing (``#1P11?`` and its end), parsed once."""

    address: int | str | None
    query: st.Query
    length: int  # characters counted for the line: all but its end


@functools.lru_cache(maxsize=1024)
def _poll_line(data: bytes) -> _Poll | None:
    """``data`` as a :class:`_Poll` if it is exactly one whole line, within the 60 characters,
    whose text is a single query (what a host polls with, again and again), else None.  Such a
    line, taken character by character, runs nothing before its end (:func:`_quiet`)."""
    if not 2 < len(data) <= codec.MAX_LINE + 1 or data[0] != codec.HASH or data[-1] not in _LINE_ENDS:
        return None
    if data.find(b"#", 1) >= 0 or data.find(b"\r", 0, -1) >= 0 or data.find(b"\n", 0, -1) >= 0:
        return None
    complete, address, stop = codec.Framer().begin_line(data, 0)
    text = _quiet(data[stop:-1]) if complete else None
    if text is None:
        return None
    result = st.parse(text, True)
    if result.errno is not None or len(result.statements) != 1 or not isinstance(result.statements[0][0], st.Query):
        return None
    return _Poll(address, result.statements[0][0], len(data) - 1)


@functools.lru_cache(maxsize=512)
def _error_text(errno: int, english: bool, encoding: str, detail: str = "") -> bytes:
    """An error message as the drive sends it (§4.8.3.1): ``*`` and its text on a line of its own."""
    return ("\n*" + message(errno, english, detail) + "\n\r").encode(encoding, errors="replace")


def _ends_line(data: bytes, start: int, stop: int) -> bool:
    """Whether a CR or LF is among ``data[start:stop]``."""
    return data.find(b"\r", start, stop) >= 0 or data.find(b"\n", start, stop) >= 0


@functools.cache
def _first_byte_errors() -> tuple[int, ...]:
    """For each byte value: the errno of a line's text whose first character it is (not CR,
    LF, ``#``) when that character is an error as it arrives (what :func:`_first_failure`
    finds at the first character), else 0.  Made at the first use."""
    errors = []
    for byte in range(256):
        char = chr(byte)
        result = st.parse(char, False) if char not in _EXTENDS_ONLY else None
        errors.append(result.errno or 0 if result is not None and not result.statements else 0)
    return tuple(errors)


@functools.lru_cache(maxsize=1024)
def _first_failure(text: bytes) -> tuple[int, int] | None:
    """Where a line's text fails before any statement completes, as it arrives character by
    character: ``(characters up to and including the one that made the error, errno)``, or
    None (a statement completes first, or no error)."""
    chars = text.decode("latin-1")
    for at, char in enumerate(chars):
        if char in _EXTENDS_ONLY:
            continue
        result = st.parse(chars[: at + 1], False)
        if result.statements:
            return None
        if result.errno is not None:
            return at + 1, result.errno
    return None


def _label_number(text: str) -> int | None:
    result = st.parse(text, final=True)
    if result.errno is None and len(result.statements) == 1:
        stmt = result.statements[0][0]
        if isinstance(stmt, st.Label):
            return stmt.number
    return None
