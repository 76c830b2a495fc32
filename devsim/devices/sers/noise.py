"""Lines of noise on the SERS's serial line, taken in one step (manual §3.2.4, §4.8.3.1; spec
G-ADDR, G-LINE).

Random bytes with ``#`` in them are mostly lines this drive executes whose first statement
fails at once: each is its echo up to the failing character, the error message, the echo of
the rest, the line end and the noise up to the next ``#``.  :class:`NoiseLines` takes such
lines one after the other without parsing them character by character; what it sends and
leaves behind is exactly what the byte-by-byte path of :class:`~.face.SersFace` would
(``tests/sers/test_noise_paths.py``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Protocol

from devsim.devices.sers import codec
from devsim.devices.sers.interactive import LineStatements
from devsim.devices.sers.line import (
    LINE_ENDS,
    TEXT_TO_END,
    CommandLine,
    error_text,
    first_byte_errors,
    first_failure,
    quiet,
    runs_at_once,
)
from devsim.devices.sers.model import SersDrive
from devsim.devices.sers.params import HANDSHAKE_CELL, LANGUAGE_CELL

__all__ = ["LineHost", "NoiseLines"]


class LineHost(Protocol):
    """What the noise path needs of the serial face (:class:`~.face.SersFace`, §3.2.4)."""

    line: CommandLine | None  # the line being received

    def restart(self, line: CommandLine, data: bytes, index: int) -> int:
        """A ``#`` inside the line and the address after it."""

    def end_line(self, line: CommandLine, overflow: bool) -> None:
        """The line has ended (its terminator echoed): its statements, answers and ack."""

    def on_event(self, event: object, byte: int) -> None:
        """One byte's framing event, handled byte by byte."""

    @property
    def statements(self) -> LineStatements:
        """What runs the statements of the lines the drive executes."""


#: Bytes after a ``#`` that begin an address (or leave it to the byte-by-byte path: ``##``).
_ADDRESS_START = frozenset(b"0123456789*#")


@functools.cache
def _text_starts() -> tuple[frozenset[int], frozenset[int]]:
    """The bytes that, as the first character of a line's text, are an error at once
    (:func:`first_byte_errors`), and those that may begin a text that fails later (none of those,
    no address, no line end, no ``#``, none that runs a statement by itself)."""
    fails = first_byte_errors()
    text = frozenset(range(256)) - _ADDRESS_START - frozenset(LINE_ENDS)
    at_once = frozenset(byte for byte in text if fails[byte])
    return at_once, text - at_once - runs_at_once()


#: A line this drive executed and answered that failed, and one for another drive, as the
#: face ends them (read only: their end looks at them, nothing changes them).
_FAILED = CommandLine(True, True, error=True)
_OTHERS = CommandLine()


class _Messages(dict[int, bytes]):
    """The error messages (§4.8.3.1) in one language, encoding and framing (G-ERRFMT ⚙
    ``error_trailing_star``), by errno, each made once (:func:`error_text`)."""

    def __init__(self, english: bool, encoding: str, trailing_star: bool) -> None:
        super().__init__()
        self.english, self.encoding, self.trailing_star = english, encoding, trailing_star

    def __missing__(self, errno: int) -> bytes:
        text = self[errno] = error_text(errno, self.english, self.encoding, "", self.trailing_star)
        return text


@functools.cache
def _messages(english: bool, encoding: str, trailing_star: bool = False) -> _Messages:
    """The error messages in a language, an encoding and a framing (§4.8.3.1), by errno."""
    return _Messages(english, encoding, trailing_star)


class NoiseLines:
    """The lines of noise one SERS's face takes in one step (§3.2.4, §4.8.3.1)."""

    def __init__(self, model: SersDrive, framer: codec.Framer, send: Callable[[bytes], None], face: LineHost) -> None:
        self.model = model
        self.framer = framer
        self.send = send
        self.face = face
        #: :func:`first_byte_errors`, :func:`_text_starts` and the bytes that may begin a failing
        #: line (either of those), looked up at the first line (not at every run)
        self._starts: tuple[tuple[int, ...], frozenset[int], frozenset[int], frozenset[int]] | None = None
        #: G-ERRFMT ⚙ ``error_trailing_star``; with ⚙ ``ok_after_error`` (each failed line is
        #: acknowledged) or G-CRLF ⚙ ``ack_each_terminator`` (the second half of a CR/LF pair is)
        #: runs of failing lines are not taken in one piece (:meth:`_failing_lines` sends no acknowledgement)
        self._star = model.cfg.error_trailing_star
        self._runs = not (model.cfg.ok_after_error or model.cfg.ack_each_terminator)

    def _tables(self) -> tuple[tuple[int, ...], frozenset[int], frozenset[int], frozenset[int]]:
        at_once, later = _text_starts()
        self._starts = starts = (first_byte_errors(), at_once, later, at_once | later)
        return starts

    def take(self, data: bytes, index: int) -> int:
        """From a ``#`` outside a line: whole lines this drive executes whose first statement
        fails before any statement completes (what random noise mostly is), with the restarts
        of the failed line, its end and the noise up to the next ``#``, one line after the
        other, as the face's ``_begin_line``, ``_failing_line``, ``restart``, the line end
        and the noise skip would do them; runs of lines failing before a statement completes
        in one step (:meth:`_failing_lines`); a line whose first character runs a statement (``H``,
        ``S``) run as the face's :meth:`~.face.SersFace.take_text` runs it (its echo with the
        ``#``'s, its statement at once, the rest of the line left to the face when it goes on),
        and taken on the same way when that fails.  Stops before a line it does not take (one for
        another drive, one that runs a statement, one whose text in the chunk does not fail)
        or inside one (a restart for another drive or whose address the chunk cuts off, the
        chunk's end), with the line and the framing as those paths leave them; returns where
        (``index``: nothing taken).  The echo up to the failing character leaves before the
        error is recorded, the rest of the line's answers with its end, before the line's end
        is handled."""
        model, framer, send, face, end = self.model, self.framer, self.send, self.face, len(data)
        no_address, text_end, runs = codec.NO_ADDRESS, codec.text_end, runs_at_once()
        fails, _, _, starts = self._starts or self._tables()
        mode = model.params.values.cells[HANDSHAKE_CELL]  # (only a statement changes it: none runs here)
        while True:
            # data[index] is a '#' outside a line
            stop = index + 1
            if stop < end and data[stop] in no_address:  # (most noise: no address)
                if model.addressed is False:
                    return index  # (the general path skips lines for other drives in one step)
                addressed = model.addressed
                if addressed is None:  # (the first line: the initial selection, made by selected)
                    addressed = model.addressed if model.selected else False
                if addressed is True and self._runs and data[stop] in starts:  # (most of that: lines failing at once, or soon)
                    taken, going_on = self._failing_lines(data, index)
                    if taken > index:
                        if going_on or taken == end:
                            return taken
                        index = taken
                        continue
                address = None
            else:
                complete, address, stop = codec.read_address(data, index)
                if not complete:
                    return index
            execute, reply = model.selection(address)
            if not execute:  # (another drive's line, or none while this one is not selected)
                return index if address is None else self._others_line(data, index, stop, address)
            failure: tuple[int, int] | None = None
            if data[stop] not in runs or stop - index >= codec.MAX_LINE:  # (H, S kept: no failure first)
                finish = text_end(data, stop)  # (the chunk may end the text)
                keep = min(finish, index + codec.MAX_LINE)  # the text kept (60 characters from the '#')
                if keep <= stop:
                    return index
                errno = fails[data[stop]]
                if errno:
                    failure = (1, errno)
                else:
                    failure = first_failure(data[stop:keep])
                    if failure is None:  # (a statement completes first, or no error in the chunk)
                        return self._begun_line(data, index, stop, address, reply, mode)
            model.note_address(address, execute)
            if failure is not None:  # the line fails at data[cut - 1]: take it
                cut, errno = stop + failure[0], failure[1]
                face.line = line = CommandLine()
                line.execute = line.error = True
                line.reply = reply
                if reply and mode in (0, 1):
                    send(data[index:cut])
                model.power_stage.record_error(errno, refused=True)  # (what _error does, its message from a table)
                cells = model.params.values.cells
                mode = cells[HANDSHAKE_CELL]
                echo = mode in (0, 1)
                text = _messages(cells[LANGUAGE_CELL] == 1, model.cfg.encoding, self._star)[errno] if reply else b""
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
            else:  # its first character runs a statement (H, S) as it arrives (§3.2.4a)
                face.line = line = CommandLine(execute, reply)
                framer.take_line(stop - index, 1)  # ('#', the address and that character)
                if reply and mode in (0, 1):
                    send(data[index : stop + 1])  # (their echo in one piece)
                line.text = chr(data[stop])
                face.statements.progress(line, False)
                cut = stop + 1
                if not line.error or face.line is not line or not model.logic_alive or model.booting:
                    return cut  # (it went on, or reset the drive: the general path goes on)
                mode = model.params.values.cells[HANDSHAKE_CELL]  # (the statements may have changed it)
                echo = mode in (0, 1)
                finish = framer.skip_text(data, cut)  # the rest of the text, failed: only echoed
                text = data[cut:finish] if line.reply and echo else b""
            index, more = self._rest(data, line, finish, text, echo)
            if not more:
                return index

    def rest(self, line: CommandLine, data: bytes, index: int) -> int:
        """From ``index`` in the text of a line whose text nobody executes (another drive's, one
        beyond 60 characters, one that failed): the text up to its end or a restart echoed in
        one piece, as the face's byte path echoes it, and returns where it stopped; of a failed
        line (what noise mostly leaves at a chunk's start), its end too and the lines after it,
        as :meth:`take` takes them (§3.2.4, §4.8.3.1).  ``data[index]`` is text."""
        finish = self.framer.skip_text(data, index)
        echo = self.model.params.values.cells[HANDSHAKE_CELL] in (0, 1)
        text = data[index:finish] if line.reply and echo else b""
        if not line.error:
            self.send(text)
            return finish
        index, more = self._rest(data, line, finish, text, echo)
        return self.take(data, index) if more else index

    def _rest(self, data: bytes, line: CommandLine, finish: int, text: bytes, echo: bool) -> tuple[int, bool]:
        """The rest of a failed line from ``finish``, where its text (``text`` its echo, not sent
        yet) ends: its restarts (only echoed), its end, the other half of a CR/LF pair, the
        noise up to the next ``#``.  Returns where it stopped, and whether that is a ``#``
        outside a line (else: the chunk's end, the line going on, the drive reset or not
        selected)."""
        model, framer, send, face, end = self.model, self.framer, self.send, self.face, len(data)
        hash_, text_end = codec.HASH, codec.text_end
        if finish == end:  # (the line goes on in the next chunk)
            send(text)
            return end, False
        while data[finish] == hash_:  # a restart in the failed line: only echoed
            complete, address, stop = codec.read_address(data, finish)
            executes, answers = model.selection(address) if complete else (False, False)
            if not executes:  # (another drive's address, or one the chunk cuts off)
                send(text)
                return face.restart(line, data, finish), False
            line.execute, line.reply = executes, answers
            model.note_address(address, executes)
            line.text, line.executed = "", 0
            after = text_end(data, stop)
            framer.take_line(stop - finish, after - stop)
            if line.reply and echo:
                text += data[finish:after]  # the address held until complete, and the text
            finish = after
            if finish == end:
                send(text)
                return end, False
        byte = data[finish]
        if line.reply and echo:
            text += data[finish : finish + 1]
        overflow = framer.end_line(byte)
        send(text)
        face.end_line(line, overflow)
        index = finish + 1
        if not model.logic_alive or model.booting or model.addressed is False:
            return index, False
        if index < end:
            byte = data[index]
            if byte in LINE_ENDS:  # the other half of a CR/LF pair, or noise
                index += 1
                for event in framer.feed(byte):
                    face.on_event(event, byte)
                if index == end:
                    return end, False
                byte = data[index]
            if byte != hash_:
                index = framer.skip_noise(data, index)
        if index >= end:
            return end, False
        return index, True  # (a '#' outside a line)

    def _others_line(self, data: bytes, index: int, stop: int, address: int | str) -> int:
        """A line with another drive's address (``data[index:stop]``, complete): from now on
        that drive is selected, not this one (G-ADDR, §4.1); the line is framed to its end, as
        the face's ``_begin_line`` frames it, and ended there (nothing echoed, nothing run).
        Returns where it ended (after its line end), or where its text stops (a restart, the
        chunk's end), the line left in the face."""
        framer, face = self.framer, self.face
        self.model.note_address(address, False)
        framer.take_line(stop - index, 0)
        finish = framer.skip_text(data, stop)
        if finish < len(data) and data[finish] in LINE_ENDS:
            face.end_line(_OTHERS, framer.end_line(data[finish]))
            return finish + 1
        face.line = CommandLine()
        return finish

    def _begun_line(self, data: bytes, index: int, stop: int, address: int | str | None, reply: bool,
                    mode: int) -> int:
        """A line this drive executes whose text does not fail before a statement completes
        (§3.2.4a): begun as the face's ``_begin_line`` begins it, the ``#`` and the address
        echoed and the text left to the face's text run (returns ``stop``), unless its whole
        text is in the chunk and runs nothing before its end (:func:`quiet`: the face takes
        that line in one step; returns ``index``, nothing done)."""
        whole = TEXT_TO_END.match(data, stop)
        if whole is not None and whole.end() - index - 1 <= codec.MAX_LINE and quiet(whole[1]) is not None:
            return index
        self.model.note_address(address, True)
        self.framer.take_line(stop - index, 0)
        self.face.line = CommandLine(True, reply)
        if reply and mode in (0, 1):
            self.send(data[index:stop])
        return stop

    def _failing_lines(self, data: bytes, index: int) -> tuple[int, bool]:
        """From a ``#`` outside a line, while this drive is selected: the lines that follow one
        another in the chunk each failing before any statement completes, without an address,
        in one step: their echoes and error messages in one piece (the first line's echo up to
        its error before the errors are recorded, as :meth:`take` sends it), the errors
        recorded, the lines ended.  Each line is ``#``, its text up to the character that fails
        (the first, what most noise is, or a later one: :func:`first_failure`), the rest of its
        text (restarts without an address in it only echoed), its end, the other half of a
        CR/LF pair (echoed) and the noise up to the next ``#`` (not).  The last one may go on
        instead: at a restart with an address (or one the chunk cuts off), handed to the face's
        ``restart``, or at the chunk's end, the line and the framing left as :meth:`take`
        leaves them.  Returns where it stopped and whether the line goes on there (else it is
        the next ``#`` or the chunk's end); ``index`` when the line there is not one of them
        (or the chunk cuts it off before it fails)."""
        fails, at_once, _, starts = self._starts or self._tables()
        if data[index + 1] not in starts:
            return index, False
        model, face = self.model, self.face
        cells = model.params.values.cells
        message = _messages(cells[LANGUAGE_CELL] == 1, model.cfg.encoding, self._star)
        address_start, end, find = _ADDRESS_START, len(data), data.find
        #: each line's echo up to its error, its error message and the rest of its echo
        pieces: list[bytes] = []
        errnos: list[int] = []
        at, last_end, going_on = index, None, False
        while True:  # data[at] is a '#' outside a line, followed by a byte
            first = data[at + 1]
            if first not in starts:
                break
            stop = find(b"\r", at + 2)
            feed = find(b"\n", at + 2, end if stop < 0 else stop)
            if feed >= 0:
                stop = feed
            elif stop < 0:
                stop = end  # (the chunk ends inside the line)
            after = find(b"#", at + 2)  # (a restart in the line, or the next line's '#')
            restart = after if after < stop else -1
            if first in at_once:
                cut, errno = at + 2, fails[first]
            else:  # (the text kept: up to a restart, at most 60 characters from the '#')
                failure = first_failure(data[at + 1 : min(stop if restart < 0 else restart, at + codec.MAX_LINE)])
                if failure is None:
                    break  # (a statement completes first, or nothing fails in the chunk)
                cut, errno = at + 1 + failure[0], failure[1]
            while restart >= 0 and restart + 1 < end and data[restart + 1] not in address_start:
                after = find(b"#", restart + 1)  # (past the line's end: the next line's '#')
                restart = after if after < stop else -1
            errnos.append(errno)
            if restart >= 0 or stop == end:  # the line goes on: a restart with an address, the chunk's end
                stop = end if restart < 0 else restart
                pieces += (data[at:cut], message[errno], data[cut:stop])
                going_on = True
                break
            byte, stop = data[stop], stop + 1
            if stop < end and data[stop] in LINE_ENDS and data[stop] != byte:
                stop += 1  # the other half of a CR/LF pair, echoed
                byte = None
            pieces += (data[at:cut], message[errno], data[cut:stop])
            at = after
            if at < 0 or at + 1 == end:  # (noise to the end, or a '#' that ends the chunk)
                last_end = byte if stop == end else None
                at = end if at < 0 else at
                break
        if not errnos:
            return index, False
        self.framer.lines_taken(last_end)
        if going_on:  # the '#' and the text so far, restarts without an address among them
            self.framer.take_line(1, stop - at - 1)
        deferred = b""
        if cells[HANDSHAKE_CELL] in (0, 1):
            self.send(pieces[0])
            model.power_stage.record_errors(errnos)
            pieces[0] = b""
            self.send(b"".join(pieces))
        else:  # (no echo: echo mode 2, each message at its line's end)
            model.power_stage.record_errors(errnos)
            messages = pieces[1::3]
            if going_on:
                deferred = messages.pop()
            self.send(b"".join(messages))
        if len(errnos) > going_on:  # (the lines that ended, the last of them as the face ends it)
            face.end_line(_FAILED, False)
        if not going_on:
            return at, False
        face.line = line = CommandLine(True, True, error=True)
        line.deferred += deferred
        return (face.restart(line, data, stop) if stop < end else end), True
