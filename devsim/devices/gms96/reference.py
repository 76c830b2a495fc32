"""Reference runs ``Q`` (manual §2.3.1 Q; spec §3.8.14, §5.6, §5.12).

Q0 cam + index mark, Q1 index mark, Q2 cam, Q3 controller (re)activation (``Q3;64``: resolver
absolute position), Q6 search on a 24 V input (P2.7 edge criterion), Q8 spindle simulation and
Q-1 per N19 with drive-off to N33.  P2 bits: .0 NC cam, .1 reversed direction, .2 keep the
counter, .3 cam on E2.0, .6 message 23 instead of failure at the P3 distance limit.  After an
end criterion the axis brakes and repositions onto the detected point (firmware ≥ v3.79).
Switch and index crossings are solved by the axis (RegionSwitch, ``watch_index``), never sampled.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from devsim.core.axis import Watch

if TYPE_CHECKING:
    from devsim.devices.gms96.device import Gms96Device

__all__ = ["ReferenceRun", "MESSAGE_DISTANCE_LIMIT"]

MESSAGE_DISTANCE_LIMIT = 23


class ReferenceRun:
    """One running reference sequence; ``done(success)`` is called exactly once."""

    def __init__(self, dev: Gms96Device, p1: int, p2: int, p3: int, done: Callable[[bool], None]) -> None:
        self.dev = dev
        self.p1, self.p2, self.p3 = p1, p2 & 0xFF, p3
        self.done = done
        self.finished = False
        self.phase = "start"
        self.cam_phase = False  # FB 254 (Accu1 = 3) = 1 during cam search / drive-off
        self.travelled = 0.0
        self.fast_kind = "work"
        self._leg_start = dev.indexer.axis.position()
        self._limit_watch: list[Watch] = []
        self._index_watch: Watch | None = None
        self._unsub: Callable[[], None] | None = None
        self.was_active = not dev.idxoff

    # -- helpers --------------------------------------------------------------------------------
    @property
    def neg(self) -> int:
        """The "negative" direction of the manual (positive with P2.1)."""
        return 1 if self.p2 & 0x02 else -1

    def cam_input(self) -> str:
        return "E2.0" if self.p2 & 0x08 else "E2.1"

    def cam_active(self) -> bool:
        level = bool(self.dev.signals.get(self.cam_input()))
        return level == (not self.p2 & 0x01)

    def _cleanup(self) -> None:
        for w in self._limit_watch:
            w.cancel()
        self._limit_watch = []
        if self._index_watch is not None:
            self._index_watch.cancel()
            self._index_watch = None
        if self._unsub is not None:
            self._unsub()
            self._unsub = None

    def _leg(self, direction: int, kind: str) -> None:
        """Start an endless search leg; the P3 distance limit is a watched crossing."""
        axis = self.dev.indexer.axis
        self.travelled += abs(axis.position() - self._leg_start)
        self._leg_start = axis.position()
        for w in self._limit_watch:
            w.cancel()
        self._limit_watch = []
        if self.p3 > 0:
            rest = max(self.p3 - self.travelled, 0.0)
            edge = self._leg_start + direction * rest
            self._limit_watch.append(
                axis.watch(edge, lambda s, d=direction: (s == d) and self._distance_limit())
            )
        self.dev.indexer.run(direction, kind)

    def _watch_cam(self, callback: Callable[[bool], None]) -> None:
        if self._unsub is not None:
            self._unsub()
        self._unsub = self.dev.signals.subscribe(self.cam_input(), lambda *_: callback(self.cam_active()))

    # -- sequence -------------------------------------------------------------------------------
    def start(self) -> None:
        p1 = self.p1
        if p1 == -1:
            n19 = self.dev.n(19)
            self.p1, self.p2 = n19 & 0xFF, (n19 >> 8) & 0xFF
            self.fast_kind = "rapid_nv"
            self.after_success = self._drive_off
            p1 = self.p1
        if p1 == 0 or p1 == 2:
            self._cam_search()
        elif p1 == 1:
            self._index_search()
        elif p1 == 6:
            self._input_search()
        else:
            self._finish(False)

    def _cam_search(self) -> None:
        self.cam_phase = True
        if self.cam_active():
            self._drive_off_cam()
            return
        self.phase = "cam_search"
        self._watch_cam(lambda active: active and self.phase == "cam_search" and self._drive_off_cam())
        self._leg(self.neg, self.fast_kind)

    def _drive_off_cam(self) -> None:
        self.phase = "cam_off"
        self._watch_cam(lambda active: (not active) and self.phase == "cam_off" and self._off_cam())
        self._leg(-self.neg, "search")

    def _off_cam(self) -> None:
        self.cam_phase = False
        if self._unsub is not None:
            self._unsub()
            self._unsub = None
        if self.p1 == 2:
            self._reposition(self.dev.indexer.axis.position())
        else:
            self._index_search()

    def _index_search(self) -> None:
        self.phase = "index_search"
        axis = self.dev.indexer.axis

        def mark(direction: int) -> None:
            if self.phase == "index_search" and direction == self.neg:
                self._reposition(self._nearest_mark(axis.position()))

        self._index_watch = axis.watch_index(mark)
        self._leg(self.neg, "search")

    def _nearest_mark(self, x: float) -> float:
        axis = self.dev.indexer.axis
        period, off = axis.counts_per_rev, axis.index_offset
        return round((x - off) / period) * period + off

    def _input_search(self) -> None:
        """Q6: until the input reaches its active level (with P2.7 only by a change to it)."""
        self.phase = "input_search"
        need_edge = bool(self.p2 & 0x80) and self.cam_active()

        def changed(active: bool) -> None:
            nonlocal need_edge
            if self.phase != "input_search":
                return
            if need_edge:
                if not active:
                    need_edge = False
                return
            if active:
                self._reposition(self.dev.indexer.axis.position())

        if self.cam_active() and not need_edge:
            self._reposition(self.dev.indexer.axis.position())
            return
        self._watch_cam(changed)
        self._leg(self.neg, self.fast_kind)

    def _reposition(self, point: float) -> None:
        self.phase = "reposition"
        if self._index_watch is not None:
            self._index_watch.cancel()
            self._index_watch = None
        for w in self._limit_watch:
            w.cancel()
        self._limit_watch = []
        self.dev.indexer.go(point, "search", self._at_point)

    def _at_point(self) -> None:
        if not self.p2 & 0x04:
            self.dev.set_counter_here(0)
        self.dev.idxoff = False
        follow = getattr(self, "after_success", None)
        if follow is not None:
            follow()
        else:
            self._finish(True)

    def _drive_off(self) -> None:
        self.phase = "drive_off"
        self.dev.indexer.go(self.dev.machine_to_physical(self.dev.n(33)), "rapid_nv", lambda: self._finish(True))

    def _distance_limit(self) -> None:
        if self.finished or self.phase == "reposition":
            return
        self.phase = "limit"
        self._cleanup()
        keep = bool(self.p2 & 0x40)

        def stopped() -> None:
            if keep:
                self.dev.image.post_message(MESSAGE_DISTANCE_LIMIT)
                self.dev.idxoff = not self.was_active
            self._finish(False, idxoff=not keep)

        self.dev.indexer.halt(stopped)

    def abort(self) -> None:
        if self.finished:
            return
        self._cleanup()
        self.finished = True
        self.cam_phase = False
        self.dev.idxoff = True

    def _finish(self, success: bool, idxoff: bool | None = None) -> None:
        if self.finished:
            return
        self._cleanup()
        self.finished = True
        self.cam_phase = False
        if not success and (idxoff if idxoff is not None else True):
            self.dev.idxoff = True
        self.dev.record_event("reference_done" if success else "reference_failed")
        self.done(success)
