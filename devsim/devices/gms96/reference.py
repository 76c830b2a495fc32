"""Reference runs ``Q`` (manual §2.3.1 Q; spec §3.8.14, §5.6, §5.12).

Q0 cam + index mark, Q1 index mark, Q2 cam, Q3 controller (re)activation (``Q3;64``: resolver
absolute position), Q6 search on a 24 V input (P2.7 edge criterion) and Q-1 per N19 with
drive-off to N33 (the Q8 spindle simulation is :mod:`.spindle`).  P2 bits: .0 NC cam, .1 reversed direction, .2 keep the
counter, .3 cam on E2.0, .5 the index mark from the counter input's reference track, .6 message 23 instead of failure at the P3 distance limit.  After an
end criterion the axis brakes and repositions onto the detected point (firmware ≥ v3.79).
Switch and index crossings are solved on the ACTUAL position (``ActualSwitch``,
``Indexer.watch_actual_index``), never sampled; the detected point is the actual position then.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.axis import Watch
from devsim.core.clock import Clock, Timer
from devsim.core.kit import Command, Table
from devsim.core.settings import Settings
from devsim.core.signals import SignalBank
from devsim.devices.gms96 import tables
from devsim.devices.gms96.coordinates import Coordinates
from devsim.devices.gms96.image import ProcessImage
from devsim.devices.gms96.motion import ActualWatch, Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.stage import PowerStage

__all__ = ["ReferenceRun", "References"]


class References:
    """What the reference runs of one card work with (manual §2.3.1 Q; spec §5.6): the indexer,
    the power stage's IDXOFF, the frames, N19/N33, the cam inputs, the message buffer."""

    def __init__(
        self,
        *,
        clock: Clock,
        indexer: Indexer,
        stage: PowerStage,
        coordinates: Coordinates,
        params: NParameters,
        signals: SignalBank,
        image: ProcessImage,
        geometry: Settings,
        record_event: Callable[[str], None],
        report_error: Callable[[str], None] = lambda code: None,
    ) -> None:
        self.clock = clock
        self.indexer = indexer
        self.stage = stage
        self.coordinates = coordinates
        self.params = params
        self.signals = signals
        self.image = image
        self.geometry = geometry  # the configured axis: counter_marks (P2.5)
        self.record_event = record_event
        self.report_error = report_error  # a message of the error table (tables.MESSAGES), for the logs

    def run(self, p1: int, p2: int, p3: int, done: Callable[[bool], None], *, counter_track: bool) -> ReferenceRun:
        """A new run of ``Q P1;P2;P3`` (``counter_track``: P2.5, the counter input's marks)."""
        return ReferenceRun(self, p1, p2, p3, done, counter_track=counter_track)

    def resolver_position(self) -> int:
        """Absolute position within the pole pass, -period/2..period/2-1 (P2.6 with P3 = 0, and
        ``Q3;64``); the pole pass starts at an (electronic) index mark (``index_offset`` +
        k·``index_period``)."""
        axis = self.indexer.axis
        period, off = axis.counts_per_rev, axis.index_offset
        half = period // 2
        return int((round(self.indexer.actual() - off) + half) % period) - half


class ReferenceRun:
    """One running reference sequence (manual §2.3.1 Q; spec §5.6); ``done(success)`` is called exactly once.  With
    ``counter_track`` (P2.5) the index mark comes from the counter input's reference track (marks
    at ``axis.counter_marks``) instead of the motor encoder."""

    def __init__(
        self,
        refs: References,
        p1: int,
        p2: int,
        p3: int,
        done: Callable[[bool], None],
        *,
        counter_track: bool = False,
    ) -> None:
        self.refs = refs
        self.counter_track = counter_track
        self.p1, self.p2, self.p3 = p1, p2 & 0xFF, p3
        self.done = done
        self.finished = False
        self.phase = "start"
        self.cam_phase = False  # FB 254 (Accu1 = 3) = 1 during cam search / drive-off
        self.travelled = 0.0  # path length of the finished legs (for the P3 limit)
        self.fast_kind = "work"
        self.after_success: Callable[[], None] | None = None  # the drive-off to N33
        self._leg_start = refs.indexer.axis.position()
        self._leg_dir = 0
        self._leg_over = 0.0  # braking overshoot (against the leg's direction) at its start
        self._limit_watch: list[Watch] = []
        self._limit_timer: Timer | None = None
        self._index_watch: ActualWatch | None = None
        self._unsub: Callable[[], None] | None = None
        self.was_active = not refs.stage.idxoff
        self._marks: list[Watch] = []  # the counter track's marks (P2.5)

    # -- helpers --------------------------------------------------------------------------------
    @property
    def neg(self) -> int:
        """The "negative" direction of the manual (positive with P2.1)."""
        return 1 if self.p2 & 0x02 else -1

    def cam_input(self) -> str:
        return "E2.0" if self.p2 & 0x08 else "E2.1"

    def cam_active(self) -> bool:
        level = bool(self.refs.signals.get(self.cam_input()))
        return level == (not self.p2 & 0x01)

    def _cancel_limit(self) -> None:
        for w in self._limit_watch:
            w.cancel()
        self._limit_watch = []
        if self._limit_timer is not None:
            self._limit_timer.cancel()
            self._limit_timer = None

    def _cleanup(self) -> None:
        self._cancel_marks()
        self._cancel_limit()
        if self._index_watch is not None:
            self._index_watch.cancel()
            self._index_watch = None
        if self._unsub is not None:
            self._unsub()
            self._unsub = None

    def _leg(self, direction: int, kind: str) -> None:
        """Start an endless search leg; the P3 distance limit is a watched crossing.

        The limit counts the path travelled (spec §5.6): a leg that reverses a moving axis first
        brakes past its start point by ``over`` and comes back, which is travel too."""
        axis = self.refs.indexer.axis
        x = axis.position()
        if self._leg_dir:
            gone = 2.0 * self._leg_over + (x - self._leg_start) * self._leg_dir
            self.travelled += max(gone, abs(x - self._leg_start))
        v = axis.velocity()
        over = v * v / (2.0 * self.refs.indexer.accel()[0]) if v * direction < 0 else 0.0
        self._leg_start, self._leg_dir, self._leg_over = x, direction, over
        self._cancel_limit()
        if self.p3 > 0:
            rest = self.p3 - self.travelled
            if rest <= 0:
                self._limit_timer = self.refs.clock.call_later(0.0, self._distance_limit)
            elif rest <= over:  # reached while still braking in the old direction
                self._limit_watch.append(
                    axis.watch(x - direction * rest, lambda s, d=-direction: (s == d) and self._distance_limit())
                )
            else:
                edge = x + direction * (rest - 2.0 * over)
                self._limit_watch.append(
                    axis.watch(edge, lambda s, d=direction: (s == d) and self._distance_limit())
                )
        self.refs.indexer.run(direction, kind)

    def _watch_cam(self, callback: Callable[[bool], None]) -> None:
        if self._unsub is not None:
            self._unsub()
        self._unsub = self.refs.signals.subscribe(self.cam_input(), lambda *_: callback(self.cam_active()))

    # -- sequence -------------------------------------------------------------------------------
    def start(self) -> None:
        p1 = self.p1
        if p1 == -1:
            n19 = self.refs.params.reference_type
            self.p1, self.p2 = n19 & 0xFF, (n19 >> 8) & 0xFF
            self.fast_kind = "rapid_nv"
            self.after_success = self._drive_off
            p1 = self.p1
        sequence = SEQUENCES.get(str(p1)) or ReferenceRun.unknown_type
        sequence(self)

    def controller_only(self) -> None:
        """Q3, only through Q-1 (the executor runs a plain Q3 itself)."""
        if self.p2 & 0x40 and self.p3 == 0:
            self.refs.coordinates.set_counter_here(self._resolver_position())
        self.refs.stage.idxoff = False
        self._succeeded()

    def unknown_type(self) -> None:
        self._finish(False)

    def cam_search(self) -> None:
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
            self._reposition(self.refs.indexer.actual())
        else:
            self.index_search()

    def index_search(self) -> None:
        """Search the index mark in the "negative" direction (Q1; Q0 after the cam)."""
        if self.counter_track:
            self._track_search()
            return
        self.phase = "index_search"
        ix = self.refs.indexer

        def mark(direction: int) -> None:
            if self.phase == "index_search" and direction == self.neg:
                self._reposition(self._nearest_mark(ix.actual()))

        self._index_watch = ix.watch_actual_index(mark)
        self._leg(self.neg, "search")

    def _track_search(self) -> None:
        """P2.5: the index search on the counter input's reference track (spec §3.8.14)."""
        self.phase = "index_search"
        axis = self.refs.indexer.axis
        self._marks = []

        def mark(at: float, direction: int) -> None:
            if self.phase == "index_search" and direction == self.neg:
                self._cancel_marks()
                self._reposition(at)

        for at in self.refs.geometry.counter_marks:
            point = at if self.neg > 0 else at + 1e-6
            self._marks.append(axis.watch(point, lambda side, at=at: mark(at, side)))
        self._leg(self.neg, "search")

    def _cancel_marks(self) -> None:
        for w in self._marks:
            w.cancel()
        self._marks = []

    def _nearest_mark(self, x: float) -> float:
        axis = self.refs.indexer.axis
        period, off = axis.counts_per_rev, axis.index_offset
        return round((x - off) / period) * period + off

    def input_search(self) -> None:
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
                self._reposition(self.refs.indexer.actual())

        if self.cam_active() and not need_edge:
            self._reposition(self.refs.indexer.actual())
            return
        self._watch_cam(changed)
        self._leg(self.neg, self.fast_kind)

    def _reposition(self, point: float) -> None:
        self.phase = "reposition"
        if self._index_watch is not None:
            self._index_watch.cancel()
            self._index_watch = None
        if self._unsub is not None:
            self._unsub()
            self._unsub = None
        self._cancel_limit()
        self.refs.indexer.go(point, "search", self._at_point)

    def _resolver_position(self) -> int:
        return self.refs.resolver_position()

    def _at_point(self) -> None:
        if self.p2 & 0x40 and self.p3 == 0:
            self.refs.coordinates.set_counter_here(self._resolver_position())
        elif not self.p2 & 0x04:
            self.refs.coordinates.set_counter_here(0)
        self.refs.stage.idxoff = False
        self._succeeded()

    def _succeeded(self) -> None:
        if self.after_success is not None:
            self.after_success()
        else:
            self._finish(True)

    def _drive_off(self) -> None:
        self.phase = "drive_off"
        self.refs.indexer.go(self.refs.coordinates.machine_to_physical(self.refs.params.drive_off_position), "rapid_nv", lambda: self._finish(True))

    def _distance_limit(self) -> None:
        if self.finished or self.phase == "reposition":
            return
        self.phase = "limit"
        self._cleanup()
        keep = bool(self.p2 & 0x40)

        def stopped() -> None:
            if keep:
                self.refs.image.post_message(tables.MESSAGE_REFERENCE_DISTANCE_LIMIT)
                self.refs.report_error(str(tables.MESSAGE_REFERENCE_DISTANCE_LIMIT))
                self.refs.stage.idxoff = not self.was_active
            self._finish(False, idxoff=not keep)

        self.refs.indexer.halt(stopped)

    def abort(self) -> None:
        if self.finished:
            return
        self._cleanup()
        self.finished = True
        self.cam_phase = False
        self.refs.stage.idxoff = True

    def _finish(self, success: bool, idxoff: bool | None = None) -> None:
        if self.finished:
            return
        self._cleanup()
        self.finished = True
        self.cam_phase = False
        if not success and (idxoff if idxoff is not None else True):
            self.refs.stage.idxoff = True
        self.refs.record_event("reference_done" if success else "reference_failed")
        self.done(success)


#: The search sequence of each reference type ``Q P1`` (after ``Q-1`` took P1 from N19).
SEQUENCES: Table[Callable[[ReferenceRun], None]] = Table(
    [
        Command("0", ReferenceRun.cam_search, "§2.3.1 Q", "Q0: cam, drive off it, then the index mark"),
        Command("1", ReferenceRun.index_search, "§2.3.1 Q", "Q1: the index mark"),
        Command("2", ReferenceRun.cam_search, "§2.3.1 Q", "Q2: the cam"),
        Command("3", ReferenceRun.controller_only, "§2.3.1 Q", "Q3: the position controller (through Q-1)"),
        Command("6", ReferenceRun.input_search, "§2.3.1 Q", "Q6: a 24 V input"),
    ]
)
