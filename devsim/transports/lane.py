"""The lean lane: a line's plain host session carried by its transport without the line.

While nothing on a :class:`~devsim.transports.line.Line` needs to see the bytes (no injected
fault, no trace or tap, no pacing, no chunk held back, no host settings reported that could
mismatch the device's), a transport that offered to (:meth:`Line.offer_lane
<devsim.transports.line.Line.offer_lane>`) hands the host's bytes straight to the line's
target (a device's :class:`~devsim.core.device.Port`, a bus) and the target's output straight
to the host, and counts both here for the line's ``bytes_in``, ``bytes_out`` and
``bytes_delivered``.  The line opens and closes the lane when one of those features changes,
not per chunk: a fault injected or a trace opened mid-stream takes effect from the next chunk
on, as on the line's own path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.device import Standing

__all__ = ["Lane", "LaneSwitch", "Take"]


class Lane:
    """What a transport carries for a line while its lean lane is open: ``feed`` (the target's
    input), ``at_once`` (a device port's :attr:`~devsim.core.device.Port.at_once`, else None: a
    transport may hand a chunk to it first and write what it returns towards the host itself,
    and hand the chunk to ``feed`` when it returns None), ``standing`` (the port's
    :class:`~devsim.core.device.Standing` reply, else None: a transport may write it for the same
    chunk while the count of changes stands, before it asks ``at_once``) and the bytes it carried
    each way.  (Slots: every poll on the lane touches it.)"""

    __slots__ = ("feed", "at_once", "standing", "bytes_in", "bytes_out")

    def __init__(self, feed: Callable[[bytes], None],
                 at_once: Callable[[bytes], bytes | None] | None = None, standing: Standing | None = None) -> None:
        self.feed = feed
        self.at_once = at_once
        self.standing = standing
        #: Bytes from the host handed to ``feed``.
        self.bytes_in = 0
        #: Bytes of the target's output taken towards the host.
        self.bytes_out = 0


#: A transport's side of the offer: given the lane, its writer towards the host for the target's
#: output (``None``: it cannot carry the lane now); given ``None``, the lane is closed.
Take = Callable[[Lane | None], Callable[[bytes], None] | None]


class LaneSwitch:
    """A line's end of the lean lane: the transport that offered to carry it (``take``, see
    :meth:`Line.offer_lane <devsim.transports.line.Line.offer_lane>`), the lane (made at its first
    opening; its counts add up over every session) and whether it is open.  The line says when
    the lane may be open (:meth:`set`); while it is, the line's ``target`` writes to the writer
    the transport gave, otherwise to the line's own ``write``."""

    __slots__ = ("target", "write", "take", "lane", "open")

    def __init__(self, target: Any, write: Callable[[bytes], None]) -> None:
        self.target = target
        self.write = write
        self.take: Take | None = None
        self.lane: Lane | None = None
        self.open = False

    def offer(self, take: Take | None) -> None:
        """The transport offers to carry the lane (``None``: withdraws)."""
        self.close()
        self.take = take

    def set(self, lean: bool) -> None:
        """Open the lane when ``lean`` and a transport offered to carry it (and takes it now), else
        close it."""
        if not lean or self.take is None:
            self.close()
            return
        if self.open:
            return
        lane = self.lane
        if lane is None:
            target = self.target
            # (both optional: LineTarget)
            lane = self.lane = Lane(target.feed, getattr(target, "at_once", None), getattr(target, "standing", None))
        write = self.take(lane)
        if write is not None:
            self.open = True
            self.target.attach(write)

    def close(self) -> None:
        if not self.open:
            return
        self.open = False
        self.target.attach(self.write)
        if self.take is not None:
            self.take(None)

    @property
    def bytes_in(self) -> int:
        return self.lane.bytes_in if self.lane is not None else 0

    @property
    def bytes_out(self) -> int:
        return self.lane.bytes_out if self.lane is not None else 0
