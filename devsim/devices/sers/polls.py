"""The polls a SERS's serial face keeps, and the repeated poll answered in one step (manual §4.1,
§4.7; issue 31).

A host polls the same lines again and again (``#P11?``): the face answers a poll's line once the
general way and keeps it (:class:`~.line.KeptPoll`); a chunk of the same bytes is then answered
from what was kept while nothing else reached the line (:meth:`KeptPolls.take`).  When that
answer is one piece, the port writes it without handing the chunk to the face at all
(:meth:`KeptPolls.answer_at_once`, the face's :attr:`~devsim.core.device.Face.answer_at_once`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devsim.core.changes import CHANGES
from devsim.core.device import Port
from devsim.devices.sers import codec
from devsim.devices.sers.answers import OK_LINES
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.line import KeptPoll, Poll
from devsim.devices.sers.params import HANDSHAKE_CELL

if TYPE_CHECKING:
    from devsim.devices.sers.model import SersDrive

__all__ = ["KeptPolls"]


class KeptPolls:
    """The polls one face answered since power-on (at most :attr:`KeptPoll.MOST`) and the last one
    if nothing else came since (:attr:`kept`, which the face drops when anything else comes).
    It holds the model's parts a repeated poll reads (one read less each per poll; a poll
    touches each object it reads: slots, one block of memory)."""

    __slots__ = ("polls", "kept", "model", "port", "framer", "master", "program", "interpreter", "access",
                 "answers", "values", "power", "motion")

    def __init__(self, model: SersDrive, port: Port, framer: codec.Framer) -> None:
        self.polls: dict[bytes, KeptPoll] | None = None
        self.kept: KeptPoll | None = None
        self.model, self.port, self.framer = model, port, framer
        self.master, self.program, self.interpreter = model.master, model.program, model.interpreter
        self.access, self.answers, self.values = model.access, model.answers, model.params.values
        self.power, self.motion = model.power_stage, model.motion

    def forget(self) -> None:
        """Power-on: nothing kept."""
        self.polls = self.kept = None

    def keep(self, data: bytes, poll: Poll, cfg: object) -> KeptPoll:
        """The poll kept for the chunk ``data`` under ``cfg``, or one made and added (the polls
        emptied when full): the last one from now on."""
        polls = self.polls
        if polls is None:
            polls = self.polls = {}
        kept = polls.get(data)
        if kept is None or kept.cfg is not cfg:
            kept = KeptPoll(data, poll, cfg)
            if len(polls) >= KeptPoll.MOST:
                polls = self.polls = {}
            polls[data] = kept
        self.kept = kept
        return kept

    def take(self, data: bytes) -> KeptPoll | None:
        """The poll kept for the chunk ``data`` if the face may answer it from what was kept (a
        poll was answered last, so the line is between lines and the drive selected: only a line
        or a power-on change that; the same configuration; the logic alive; no request of this
        drive as a master awaiting its slave's answer; not in programming mode), framed as the
        face's framer would frame it and the last one from now on; else None, nothing done.
        (Call it only while :attr:`kept` is not None.  :meth:`answer_at_once` repeats these
        checks inline for the same poll as the last.)"""
        model = self.model
        model.peers = self.port.peers
        kept = self.kept
        if ((data == kept.data or (kept := self.polls.get(data)) is not None)  # type: ignore[union-attr]
                and model.cfg is kept.cfg and model.logic_alive and not self.master.awaiting
                and not self.program.editing):
            if kept is not self.kept:  # (line, selection, boot as the last left them; this one's framing)
                self.framer.whole_line(kept.poll.length, data[-1])
                self.kept = kept
            return kept
        return None

    def answer_at_once(self, data: bytes) -> bytes | None:
        """A chunk :meth:`take` takes, when the face would answer it in one piece (echo mode 0 or 1,
        P1017; no program parked on a WAIT, which the answer pokes; the value read without an
        error): the echo, answer and acknowledgement, unsent (the port writes them).  Else None,
        with nothing done that the face's ``feed`` does not do the same way again.  (The face is
        then as its ``feed`` leaves it: while a poll is kept it is between lines, with no message
        waiting and the last line answered, ``tests/sers/test_poll_path.py``.)  While nothing
        reached any device since it gave the same poll's reply (the kept poll's ``stamp``), only
        the value is read again: the rest of what the reply depends on cannot have changed."""
        if (kept := self.kept) is None:
            return None
        if data == kept.data and kept.stamp == CHANGES.count and (read := kept.read) is not None:
            # nothing reached any device since this reply was given, all checked below
            # (devsim.core.changes): only the value may have changed, with time alone
            try:
                if (value := read(self.access)) == kept.value and type(value) is type(kept.value):
                    return self._given(kept, data)
            except SersError:
                pass  # (the checks below meet it again)
        if data == kept.data:  # (the same poll as the last: what take() checks of it, inline)
            model = self.model
            model.peers = self.port.peers
            if (model.cfg is not kept.cfg or not model.logic_alive or self.master.awaiting
                    or self.program.editing):
                return None
        elif (kept := self.take(data)) is None:
            return None
        if (self.values.cells[HANDSHAKE_CELL] not in (0, 1) or self.interpreter.waiting == "wait"
                or (kept.read is None and kept.raw is None)):
            return None
        # (what answer() and KeptPoll.reply_with do, inline for a plain value: a call less each per poll)
        try:  # (the readers and the answer lines only read: feed reads again and meets the error again)
            if (read := kept.read) is None:
                answer = self.answer(kept)  # (a weighted value)
            elif (value := read(self.access)) == kept.value and type(value) is type(kept.value):
                answer = kept.answer
            else:
                answer = kept.remake(value, self.answers, self.model.cfg.encoding)
        except SersError:
            return None
        # (ack_line() inline: not in programming mode, as checked above and nothing read since changes)
        power = self.power
        if power.errors:
            ack = OK_LINES[4]
        else:
            ack = OK_LINES[(1 if self.motion.pos_ok else 0) + (2 if power.warnings else 0)]
        if answer is not kept.answer or ack is not kept.ack or not kept.reply:
            kept.reply, kept.ack = b"".join((data, answer, ack)), ack
        kept.stamp = CHANGES.count
        return self._given(kept, data)

    def _given(self, kept: KeptPoll, data: bytes) -> bytes:
        """The kept poll's reply, given at once for ``data``: the port's standing reply while the
        value changes only with the drive's state (the port then gives it itself while the count of
        changes stands), else none (the port's standing reply follows the face's last answer)."""
        if kept.timeless:
            self.port.standing.hold(data, kept.reply)
        else:
            self.port.standing.stamp = -1
        return kept.reply

    def answer(self, kept: KeptPoll) -> bytes:
        """The kept poll's answer line as the drive stands now (a :class:`SersError` as the
        query's own).  (A plain value's branch is repeated inline in :meth:`answer_at_once`.)"""
        if (read := kept.read) is None:
            if (raw := kept.raw) is None:
                return kept.answer_line(self.answers, self.model.cfg.encoding)
            value, scaling = raw(self.access), self.access.params.scaling
            if value == kept.value and type(value) is type(kept.value) and scaling is kept.scaling:
                return kept.answer  # (a weighted value: the same value under the same weighting)
            answer = kept.answer_line(self.answers, self.model.cfg.encoding)
            kept.value, kept.scaling, kept.answer, kept.reply = value, scaling, answer, b""
            return answer
        if (value := read(self.access)) == kept.value and type(value) is type(kept.value):
            return kept.answer  # (a value shown as it is: its line made again only when it changed)
        return kept.remake(value, self.answers, self.model.cfg.encoding)
