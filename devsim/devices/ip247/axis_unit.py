"""One IP247 axis page: its state, its motion and its switches (manual §2.7, §2.8, §4.1, §4.2;
spec ip247.md §4.1, §4.13, §5.1–§5.8, §5.15).

The axis is open loop: the shared closed-form :class:`~devsim.core.axis.Axis` carries the motor
side's machine position M in base units, moved by the exponential ramp pieces of
:mod:`.motion`.  The holder coordinate is H = M − M0 (M0 fixed by the reference point), the
reported actual value the tool tip's (:class:`.coordinates.Coordinates`).  The operating modes
that move the axis are in :mod:`.modes`; errors are module error numbers (spec §4.3), which the
page hands to the module it sits on (:class:`AxisEvents`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Set
from typing import Any, Protocol

from devsim.core.axis import Axis
from devsim.core.clock import Clock
from devsim.core.signals import SignalBank
from devsim.devices.ip247.attributes import rmld
from devsim.devices.ip247.basp import Basp
from devsim.devices.ip247.coordinates import Coordinates
from devsim.devices.ip247.jobs import AxisView
from devsim.devices.ip247.machine_data import MachineData
from devsim.devices.ip247.motion import ExpPiece, move_pieces
from devsim.devices.ip247.motor import SteppingMotor
from devsim.devices.ip247.reset_output import ResetOutput
from devsim.devices.ip247.switches import MechanicalSwitch

__all__ = ["AxisEvents", "AxisUnit", "ProgramContext", "ReferenceContext", "rp_level", "switch_bounds"]

FOREVER = 1e9  # seconds: a jog's cruise lasts until something stops it
#: The machine data whose change clears the reference point (manual §4.3.12): reference
#: coordinate, pulses per revolution, travel per revolution, reference direction, synchronisation.
REFERENCE_RELEVANT = ("reference", "pulses_per_rev", "gear", "reference_direction", "reference_sync")


def rp_level(md: MachineData | None, direction: int) -> bool:
    """The direction output RP for a move: the MD polarity fixes which level is forward (manual
    §2.5.1.1; spec §2.2 [DECISION]: 1 forward with the positive edge, 0 with the negative)."""
    positive = md is None or md.pulse_polarity == 0x40
    return (direction > 0) == positive


def switch_bounds(geometry: dict[str, Any], name: str) -> tuple[float, float] | None:
    """Where switch ``name`` (anf, end, cam) is actuated, from the axis geometry (config)."""
    where = geometry.get(name)
    if where is None:
        return None
    if name == "anf":
        return -math.inf, float(where)
    if name == "end":
        return float(where), math.inf
    return float(where[0]), float(where[1])


class AxisEvents(Protocol):
    """What an axis page tells the module it sits on (spec §4.1, §4.3)."""

    def set_error(self, unit: AxisUnit, error: int) -> None: ...
    def changed(self, unit: AxisUnit) -> None: ...
    def record_event(self, name: str) -> None: ...


class ProgramContext(Protocol):
    """The program context of an axis in BA8/BA9 (:class:`.automatic.ProgramRun`)."""

    number: int
    calls: list[int]
    halted: bool
    interrupted: bool

    def abort(self) -> None: ...
    def command(self, ba: int, cmd: int) -> int | None: ...


class ReferenceContext(Protocol):
    """A reference run in progress (:class:`.reference.ReferenceRun`): the axis forwards its
    limit and cam inputs to it."""

    def limit(self, name: str) -> None: ...
    def cam(self, active: bool) -> None: ...
    def cancel(self) -> None: ...


#: An axis page's motion bookkeeping in slots, the rest in its instance dictionary: that one shares
#: its keys among the axes while it holds 29 or fewer (see :class:`devsim.core.model.Model`).
_SLOTS = ("_d", "_decel_at", "_done", "_follows", "_h0", "_mech0", "_previous_md", "_sense", "_switches", "_x0",
          "pattern_base", "sw_watch", "__dict__", "__weakref__")


class AxisUnit:
    """Axis page 1 … 3 (spec §4.1.1): the state FB164 shows, the motion primitives the modes and
    programs use (manual §2.8, spec §5.3–§5.8) and the limit switches (spec §5.7)."""

    __slots__ = _SLOTS

    def __init__(self, number: int, geometry: dict[str, Any], *, clock: Clock, signals: SignalBank,
                 events: AxisEvents, basp: Basp, wiring_faults: Set[str]) -> None:
        self.number, self.clock, self.signals, self.events = number, clock, signals, events
        self.basp, self.wiring_faults = basp, wiring_faults
        self.axis = Axis(clock, name=f"axis{number}")
        self.md: MachineData | None = None
        self.md_words: list[int] | None = None
        self.rs = ResetOutput(f"RS{number}", signals, clock, lambda: self.md_valid)
        self._previous_md: MachineData | None = None  # the last record loaded (kept when deleted)
        self.mode, self.last_cmd, self.running = 4, 0, False
        self.reference_set = False
        self.error = 8  # "Zustand nach Spannungsausfall" (spec §4.14 [DECISION])
        self.coords = Coordinates(0, 0, 0)
        self.m0 = 0.0  # motor position of the holder coordinate 0 (pushing forward)
        self._h0, self._d = 0.0, 0  # the load at the start of the current move, its direction
        self.braking = False  # stopping after a Stopp or a fault: jobs wait in the job lists
        self.in_position = False
        self.target: float | None = None  # holder target of the current (or aborted) positioning
        self.target_tool = 0  # the tool offset the target was computed with (manual §2.7.7)
        self.m_function = 2
        self.teach_in: int | None = None
        self.taught: list[str] = []  # the blocks stored in teach-in so far
        self.locks: set[int] = set()  # directions locked by a limit switch (+1 forward, -1 backward)
        self.waiting_start: Callable[[], None] | None = None  # a job waiting for external start
        self.automatic: ProgramContext | None = None  # the program context (BA8/BA9), see .automatic
        self.reference_run: ReferenceContext | None = None  # see .reference
        self.pattern_base = 0.0  # machine position where the current-pattern counter was 0
        self._done: Callable[[bool], None] | None = None
        self._decel_at = math.inf  # when the current positioning move starts its last braking
        self.sw_watch: Any = None  # the SW limit a jog watches
        self.motor = SteppingMotor(geometry.get("max_start_hz"), geometry.get("pullout_hz"))
        self._mech0, self._x0, self._follows, self._sense = 0.0, 0.0, math.inf, 1
        self._switches = [self._region(geometry, name) for name in ("anf", "end", "cam")]

    # -- what the module and the faces see --------------------------------------------------------
    @property
    def md_valid(self) -> bool:
        return self.md is not None and self.md.error == 0

    @property
    def holder(self) -> float:
        """The load (holder) coordinate H.  With backlash b the motor leads the load by the
        play on the side it pushes: during a move in direction d the load stands until the
        motor has taken the play up, then follows it (spec §5.8)."""
        p = self.axis.position() - self.m0
        if self._d == 0:
            return p
        free = p - self._side(self._d)
        return max(self._h0, free) if self._d > 0 else min(self._h0, free)

    def _side(self, direction: int) -> float:
        """Motor minus load while pushing in ``direction``: 0 forward, −b backward."""
        return -float(self.md.backlash) if direction < 0 and self.md is not None else 0.0

    def set_holder(self, value: float, direction: int = 0) -> None:
        """H := ``value`` where the axis stands (reference point, power-up).  With a direction
        (a reference drive) the play is taken up on that side; without, the next move takes
        none up (spec §5.8: not on the first move after power-up or "Referenzpunkt setzen")."""
        self._h0, self._d = value, direction
        self.m0 = self.axis.position() - value - self._side(direction)

    def begin(self, direction: int) -> None:
        """A move in ``direction`` starts from the load's current coordinate."""
        h = self.holder
        if self._d == 0:
            self.m0 = self.axis.position() - h - self._side(direction)  # no play to take up
        self._h0, self._d = h, direction
        self.signals.set(f"RP{self.number}", rp_level(self.md, direction))

    def machine(self, holder: float, direction: int) -> float:
        """The motor position that puts the load at ``holder`` after a move in ``direction``."""
        return holder + self._side(direction) + self.m0

    def actual(self) -> int:
        """The reported actual value, the tool tip in base units (0 without valid MD: none, or
        a record the module refused, whose range may be empty)."""
        if not self.md_valid:
            return 0
        return self.coords.actual(round(self.holder))

    def residual(self) -> int:
        """The distance to the target the tool tip was sent to: a tool offset made after a stop
        updates it, so that a relative move by it reaches the original target (manual §2.7.7)."""
        if self.target is None or self.md is None:
            return 0
        return round(self.target - self.holder - (self.coords.tool_offset - self.target_tool))

    def attributes(self) -> int:
        md = self.md
        return rmld(unit=md.unit if md else 1, in_position=self.in_position,
                    reference_sync=bool(md and md.reference_sync == 0), teach_in=self.teach_in is not None,
                    reference_missing=not self.reference_set, md_missing=md is None, finished=not self.running)

    def view(self) -> AxisView:
        return AxisView(self.number, self.md_valid, self.reference_set, self.running, self.mode,
                        self.teach_in is not None, bool(self.md and self.md.rotary))

    # -- what the page tells the module (spec §4.3) ----------------------------------------------
    def set_error(self, error: int) -> None:
        self.events.set_error(self, error)

    def changed(self) -> None:
        self.events.changed(self)

    def fail(self, error: int) -> None:
        """Stop the axis and its program (a limit switch, an external stop): error ``error``."""
        if self.automatic is not None:
            self.automatic.abort()
        self.brake()
        self.set_error(error)

    def pulse_rs(self) -> None:
        """A 100 ms high pulse on RS; the pattern counter restarts at 0 (spec §2.8.1, §5.6.3)."""
        self.rs.pulse()
        self.pattern_base = self.axis.position()

    def limit_levels(self) -> tuple[bool, bool]:
        """The levels of the limit inputs ANF and END (True = 24 V)."""
        return bool(self.signals.get(f"ANF{self.number}")), bool(self.signals.get(f"END{self.number}"))

    # -- machine data -----------------------------------------------------------------------------
    def load_md(self, md: MachineData | None, words: list[int] | None, *, first: bool) -> None:
        """New machine data (BA20, ``first``; from battery RAM at power-up otherwise), or none
        (BA21 with ``md`` None, which keeps the reference).  The reference point survives new
        data whose reference-relevant items equal the previous record's, a deleted one's too
        (manual §4.3.12: the PLC side must delete before it writes)."""
        old = self.md or self._previous_md
        self.md, self.md_words = md, words
        self.rs.update()
        if md is None:
            return
        self._previous_md = md
        kept = self.coords if not first else Coordinates(0, 0, 0)  # new MD reset the offsets (spec §5.9)
        self.coords = Coordinates(md.limit_begin, md.limit_end, md.reference, md.rotary, kept.zo_mode, 0,
                                  kept.to_ba15, kept.to_prog)
        if old is None or any(getattr(old, k) != getattr(md, k) for k in REFERENCE_RELEVANT):
            self.reference_set = False  # (spec §4.1.2 bit 5)
        self.wire_switches()

    def power_up(self) -> None:
        """Reference lost; the actual value reads as the reference coordinate (spec §4.14)."""
        self.axis.quick_stop()
        self.mode, self.last_cmd, self.running, self.reference_set = 4, 0, False, False
        self.error, self.in_position, self.target, self.m_function = 8, False, None, 2
        self.teach_in, self.waiting_start, self.automatic, self._done = None, None, None, None
        if self.reference_run is not None:
            self.reference_run.cancel()
        self.locks.clear()
        if self.md is not None:
            self.set_holder(self.md.reference)
        self.set_pe()
        self.rs.cancel()
        self.rs.update()

    # -- the external start/stop input (spec §5.10) -------------------------------------------------
    def held(self, start: Callable[[], None]) -> int | None:
        """Start a motion job, or, while the START-N/STOP input is 1, hold it until the input
        falls (error 6, "Motor wartet auf externen Start"); returns 6 when held.  Without the
        power unit's BB the job is refused (53); under BASP too (55)."""
        signals = self.signals
        if not signals.get(f"BB{self.number}"):
            return 53
        if self.basp.active:
            return 55
        if not signals.get(f"START{self.number}"):
            start()
            return None
        self.waiting_start = start
        self.set_running(True)
        return 6

    def release(self) -> None:
        """The input fell: the waiting job starts (its error 6 is gone)."""
        start, self.waiting_start = self.waiting_start, None
        if start is None:
            return
        if self.error == 6:
            self.error = 0
        self.set_running(False)
        start()

    # -- motion -----------------------------------------------------------------------------------
    def set_running(self, running: bool) -> None:
        self.running = running
        if not running:
            self.braking = False
        self.changed()

    def _start(self, pieces: list[tuple[float, Any]], done: Callable[[bool], None] | None) -> None:
        self.in_position = False
        self.set_pe()
        self._done = done
        self.events.record_event("move_start")
        self.set_running(True)
        self._follow(pieces)
        self._decel_at = self.clock.now() + sum(d for d, _ in pieces[:-1]) if pieces else math.inf

    def _follow(self, pieces: list[tuple[float, Any]]) -> None:
        md = self.md
        mechanical, from_rest = self.mechanical_position(), not self.axis.moving
        stalled = not from_rest and self._stalled
        self.axis.follow(pieces, self._ended)  # (a new plan drops the old plan's on_done)
        self._mech0, self._x0 = mechanical, self.axis.position()
        self._follows = self.motor.follows(pieces, md.resolution, from_rest) if md is not None else math.inf
        if stalled:
            self._follows = 0.0  # a stalled motor stays stalled until the axis stands
        self._sense = self.wiring()
        for switch in self._switches:
            if switch is not None:
                switch.arm(self._x0, self._mech0, self._sense, self._follows)

    def wiring(self) -> int:
        """How the motor answers the pulses (spec §5.15 wiring faults): 1, −1 with T/RP swapped
        (it turns the other way), 0 with RS stuck active or no special voltage (it stands)."""
        faults = self.wiring_faults
        if f"rs_stuck_{self.number}" in faults or "no_special_voltage" in faults:
            return 0
        return -1 if f"rp_swapped_{self.number}" in faults else 1

    @property
    def _stalled(self) -> bool:
        return abs(self.axis.position() - self._x0) > self._follows

    def mechanical_position(self) -> float:
        """Where the motor really is (spec §5.15): the motor position less the steps it lost."""
        travelled = self.axis.position() - self._x0
        return self._mech0 + self._sense * math.copysign(min(abs(travelled), self._follows), travelled)

    def _ended(self) -> None:
        self.braking = False
        self.events.record_event("move_end")
        done, self._done = self._done, None
        self.set_running(False)
        if done is not None:
            done(True)

    def position_to(self, holder_target: float, f: float, done: Callable[[bool], None] | None = None) -> None:
        """A positioning move of the holder to ``holder_target`` (BA6, BA7, program traverses)."""
        md = self.md
        assert md is not None
        direction = 1 if holder_target > self.holder else -1 if holder_target < self.holder else 0
        if direction:
            self.begin(direction)
        end = self.machine(holder_target, direction or self._d)
        pieces = move_pieces(self.axis.position(), end - self.axis.position() if direction else 0.0, f, md.ramp,
                             md.resolution)
        self.follow_path(pieces, holder_target, end, done)

    def follow_path(self, pieces: list[tuple[float, Any]], holder_target: float, end: float,
                    done: Callable[[bool], None] | None = None) -> None:
        """Move along ``pieces`` (from :meth:`begin`) to motor position ``end``, the holder to
        ``holder_target``: "position reached" there, the residual meanwhile."""
        self.target, self.target_tool = holder_target, self.coords.tool_offset

        def reached(ok: bool) -> None:
            if ok:
                self.in_position = True
                self.target = holder_target
                self.axis.set_position(end)  # the pulses are exact
                self.set_pe()
            if done is not None:
                done(ok)

        if not pieces:
            self._done = None
            reached(True)
            return
        self._start(pieces, reached)

    def jog(self, direction: int, f: float, done: Callable[[bool], None] | None = None) -> None:
        md = self.md
        assert md is not None
        ramp, r, x = md.ramp, md.resolution, self.axis.position()
        self.begin(direction)
        pieces: list[tuple[float, Any]] = []
        if f > md.f_ss:
            f = min(f, float(md.f_max))
            t_v = ramp.time_to(f)
            pieces.append((t_v, ExpPiece(ramp, r, x, direction, "accel", t_v, f)))
            x += direction * r * ramp.pulses_to(f)
        pieces.append((FOREVER, ExpPiece(ramp, r, x, direction, "constant", 0.0, f)))
        self.target = None
        self._start(pieces, done)

    def brake(self, then: Callable[[bool], None] | None = None) -> None:
        """Stop with the deceleration ramp; a positioning move already braking onto its target
        finishes there (spec §5.11.5).  ``then(reached)`` runs when the axis stands."""
        md, done = self.md, self._done
        if md is None or not self.axis.moving:
            self._done = None
            if self.running:
                self.set_running(False)
            if then is not None:
                then(False)
            return
        if self.clock.now() >= self._decel_at and done is not None:
            self._done = lambda ok: (done(ok), then(ok) if then is not None else None)
            return
        self._done = (lambda ok: then(False)) if then is not None else None
        v = self.axis.velocity()
        f0, sign = abs(v) / md.resolution, (1 if v > 0 else -1)
        if f0 <= md.f_ss * (1 + 1e-9):
            self.axis.quick_stop()  # at or below f_ss the pulse train simply stops
            self._ended()
            return
        t_v = md.ramp.time_to(f0)
        self.braking = True
        self._follow([(t_v, ExpPiece(md.ramp, md.resolution, self.axis.position(), sign, "decel", t_v, f0))])
        self._decel_at = self.clock.now()

    # -- limit switches (spec §5.7) ---------------------------------------------------------------
    def _region(self, geometry: dict[str, Any], name: str) -> MechanicalSwitch | None:
        bounds = switch_bounds(geometry, name)
        if bounds is None:
            return None
        return MechanicalSwitch(self.axis, *bounds, self.mechanical_position(),
                                lambda active, n=name: self._switch(n, active))

    def _switch(self, name: str, actuated: bool, polarity: int | None = None) -> None:
        """A switch the geometry drives: its level as wired for the MD polarity (NC: 24 V at rest)."""
        if polarity is None:
            polarity = self.md.limit_polarity if self.md is not None else 0
        level = actuated if name == "cam" or polarity == 0 else not actuated
        self.signals.set(f"{'BERO' if name == 'cam' else name.upper()}{self.number}", level)

    def wire_switches(self, polarity: int | None = None) -> None:
        """Set the geometry's switch inputs for a limit-switch polarity (the MD's by default;
        an incoming record's before it is checked)."""
        for name, region in zip(("anf", "end", "cam"), self._switches, strict=True):
            if region is not None:
                self._switch(name, region.active, polarity)

    def actuated(self, name: str) -> bool:
        """Whether limit input ``anf``/``end`` reads as actuated (MD n+33 polarity)."""
        level = bool(self.signals.get(f"{name.upper()}{self.number}"))
        return level if self.md is None or self.md.limit_polarity == 0 else not level

    def limit_refusal(self, direction: int) -> int | None:
        """A move towards a limit switch: refused with 25 (Anfang) / 26 (Ende) while that
        direction is locked, or while its switch is actuated now, even at standstill (manual
        §2.5.3.10: a switch is seen when the axis moves "oder bewegen soll" towards it; §2.8.3:
        a switch actuated by hand locks its direction).  Refusing locks the direction."""
        if direction == 0:
            return None
        if self.actuated("anf" if direction < 0 else "end"):
            self.locks.add(direction)
        return (25 if direction < 0 else 26) if direction in self.locks else None

    def limit_input(self, name: str) -> None:
        """An ANF/END input changed: a switch in the direction of travel stops the axis (errors
        25/26) and locks that direction; leaving it in the other direction releases it."""
        direction = -1 if name == "anf" else 1
        if self.reference_run is not None:
            if self.actuated(name):
                self.reference_run.limit(name)
            return
        if self.actuated(name):
            if self.running and self._d == direction:
                self.locks.add(direction)
                self.fail(25 if direction < 0 else 26)
                return
        elif self._d == -direction:
            self.locks.discard(direction)

    def cam_input(self, active: bool) -> None:
        if self.reference_run is not None:
            self.reference_run.cam(active)
        elif active:
            self.locks.clear()  # passing the reference cam releases a locked direction (spec §5.7)

    def arm_sw_limit(self, direction: int) -> None:
        """Jog on a linear axis with reference: brake when the holder passes the SW limit."""
        md = self.md
        if self.sw_watch is not None:
            self.sw_watch.cancel()
            self.sw_watch = None
        if md is None or md.rotary or not self.reference_set:
            return
        low, high = self.coords.range()
        limit = self.machine((high if direction > 0 else low) + self.coords.zero_offset, direction)
        if (self.axis.position() - limit) * direction >= 0:
            self.brake()
            self.set_error(29 if direction > 0 else 28)
            return

        def passed(_direction: int) -> None:
            if self.running and self.mode in (1, 2) and self._d == direction:
                self.brake()
                self.set_error(29 if direction > 0 else 28)

        self.sw_watch = self.axis.watch(limit, passed)

    def set_pe(self) -> None:
        self.signals.set(f"PE{self.number}", self.in_position and not self.basp.forces_pe)
