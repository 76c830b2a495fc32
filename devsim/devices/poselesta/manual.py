"""Manual motion in MANUAL and PROGRAM_ENTRY: the direction keys V20/5–12, jogging steps
V21/1–5, rapid V21/6, the handwheel V5 with its axis selection V20/1–4, and open loop V21/7
(manual §2.2.3, §2.3.5–§2.3.9, §2.3.22, §2.4.2, §2.4.6; spec poselesta.md §5.2, §5.4).

A direction key moves its axis while it is H, on the axis's own ramps, at the feed pot's share
of the axis's maximum feed (P48–P51); rapid lifts that to P44–P47 along the ramp.  With a jog
step selected a key press moves that many increments (the smallest selected step wins, a press
during a step is ignored; rapid does not apply).  Only a moving axis has its travel command; the
machine standstill output is L while any axis moves; position reached is never output here.
As in a block, a key's travel command goes out first and the axis moves once the axis enable
V22/3 is H (§2.4.2: "Nach Ausgabe der Fahrbefehle wartet die Steuerung die Achsfreigabe ab,
bevor in den Achsen verfahren wird"; §2.3.15): while it is L the key waits, a continuous key let
go or Not-Stop gives the wait up, and a feed once released is not stopped by the enable going L.
The machine standstill output goes L with the release (§2.4.6: "Durch die nächste Achsfreigabe").
In PROGRAM_ENTRY NC-Stop (V19/1 L) acts: every axis brakes along its ramp and the keys and the
handwheel do not move while it is L (§2.3.1: "Ein NC-Stop bewirkt einen Halt der Achsbewegungen
entlang der Bremsrampe … NC-Stop ist im Handbetrieb unwirksam"; only MANUAL is exempt).
[SIM-CHOICE] the braked motion is given up, its travel command drops and NC-Start does not
continue it: a key pressed again after NC-Stop moves again (the manual's NC-Start continues, and
its "Bei NC-Stop werden die Fahrbefehle nicht zurückgesetzt" (§2.4.2) keeps, a program's
positioning; for the keys of Programmierung/Playback it says neither).

The handwheel (``handwheel.turn``: detents, at ``handwheel.rate_hz``) moves every axis whose
activation input is H by P76 increments per detent, times the hand panel's factor (×10 in
selector position 1, ×1 in position 2), driving the position command directly (no ramp of its
own).  Activating a handwheel makes the machine standstill output L at once; [SIM-CHOICE] a
detent is not held back by the axis enable (§2.4.6 treats the handwheel apart, and the manual
says nothing of its travel commands).  With open loop
(V21/7 H, switched only at standstill) the axes of P77 follow whatever moves them
(``axis.<a>.push``): their following error and set-point are 0, the travel command still shows.
A change of V21/7 while an axis moves is "ignored until standstill" (spec §5.4, event
``open_loop_change_deferred``; §2.3.9 "darf nur bei Stillstand ein- oder ausgeschaltet werden"):
the level V21/7 then has takes effect once the axes stand (no travel command, machine standstill).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.points import BadValue
from devsim.core.signals import SignalBank
from devsim.devices.poselesta.axes import Axes
from devsim.devices.poselesta.limits import LimitSwitches
from devsim.devices.poselesta.parameters import MachineParameters
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.signals import AXES

__all__ = ["JOG_STEPS", "ManualMotion"]

JOG_STEPS = (1, 10, 100, 1000, 10000)
MANUAL_MODES = ("MANUAL", "PROGRAM_ENTRY")


class ManualMotion:
    """Manual motion of one control: direction keys, jog steps, rapid, handwheel and open loop
    (manual §2.2.3, §2.3.5–§2.3.9; spec §5.4).  ``mode()`` and ``booting()`` say whether manual
    motion is possible, ``program_moving()`` whether a block moves the axes (open loop switches
    only at standstill), ``feed_pot()`` the feed pot's factor."""

    def __init__(self, signals: SignalBank, axes: Axes, params: MachineParameters, limits: LimitSwitches,
                 screen: Screen, *, mode: Callable[[], str], booting: Callable[[], bool],
                 program_moving: Callable[[], bool], feed_pot: Callable[[], float]) -> None:
        self._signals = signals
        self._axes = axes
        self._params = params
        self._limits = limits
        self._screen = screen
        self._mode = mode
        self._booting = booting
        self._program_moving = program_moving
        self._feed_pot = feed_pot
        self.moving: set[str] = set()
        self._waiting: dict[str, Callable[[], None]] = {}  # travel command out, the axis enable L (§2.3.15)
        self.handwheel_factor = 1
        self.handwheel_rate = 10.0  # detents per second
        self.open_loop = False  # in effect (switched at standstill)
        self._open_loop_deferred = False  # V21/7 changed during motion: taken at standstill
        key, handwheel, speed = self._key, self._handwheel_selected, self._speed_changed  # one bound method each
        for a in AXES:
            for direction in ("pos", "neg"):
                signals.subscribe(f"jog_{direction}_{a}", key)
            signals.subscribe(f"handwheel_{a}", handwheel)
        for name in ("rapid", "feed_pot_v"):
            signals.subscribe(name, speed)
        signals.subscribe("open_loop", self._open_loop_input)
        signals.subscribe("machine_standstill", self._standstill)
        signals.subscribe("axis_enable", self._axis_enable)
        signals.subscribe("nc_stop", self._nc_stop)

    # -- the handwheel (§2.2.3, spec §5.4) ------------------------------------------------------------
    def _handwheel_selected(self, _name: str, _old: Any, _new: Any) -> None:
        if self._mode() in MANUAL_MODES and not self.moving:
            selected = any(self._signals.get(f"handwheel_{a}") for a in AXES)
            self._signals.set("machine_standstill", not selected)  # at once, even without motion (§2.4.6)

    def turn(self, detents: int) -> None:
        """Turn the handwheel by ``detents`` (negative: backwards)."""
        if not self._possible():
            self._screen.record("handwheel_ignored")
            return
        step = int(self._params.handwheel_step) * self.handwheel_factor
        for a in AXES:  # (P76 = 0, after a catalogue read-in without it: a detent moves nothing)
            if not self._signals.get(f"handwheel_{a}") or detents == 0 or step <= 0:
                continue
            if self._limits.refuses(a, detents):
                continue
            axis = self._axes[a]
            speed = abs(self.handwheel_rate) * step
            self.moving.add(a)
            self._signals.set(f"travel_{a}", True)
            axis.move_to(self._axes.planned_position(a) + detents * step, speed, speed * 1000,
                         on_done=lambda a=a: self._handwheel_done(a))

    def _handwheel_done(self, a: str) -> None:
        self._stopped(a)
        self._handwheel_selected("", None, None)

    # -- open loop (§2.3.9, spec §5.2) -----------------------------------------------------------------
    def _open_loop_input(self, _name: str, _old: Any, new: Any) -> None:
        if self._program_moving() or self.moving:
            self._screen.record("open_loop_change_deferred")  # only at standstill (§2.3.9)
            self._open_loop_deferred = True
            return
        self.open_loop = bool(new)

    def _standstill(self, _name: str, _old: Any, new: Any) -> None:
        if new:
            self._take_deferred_open_loop()

    def _take_deferred_open_loop(self) -> None:
        """The axes stand (machine standstill H, or a wait for the enable given up): a V21/7 change
        deferred during motion takes effect with the level V21/7 has now (spec §5.4)."""
        if self._open_loop_deferred and not self.moving:
            self._open_loop_deferred = False
            self.open_loop = bool(self._signals.get("open_loop"))

    def in_open_loop(self, a: str) -> bool:
        return self.open_loop and self._params.is_open_loop(a)

    def push(self, a: str, mm: float) -> None:
        """An outside force moves an open-loop axis by ``mm`` (10 mm/s): the display follows."""
        if not self.in_open_loop(a):
            raise BadValue(f"{a.upper()} is not in open loop (V21/7 H and P77)")
        axis = self._axes[a]
        speed = self._axes.from_mm(a, 10.0)
        self._start(a)
        axis.move_to(self._axes.planned_position(a) + self._axes.from_mm(a, mm), speed, speed * 100,
                     on_done=lambda: self._stopped(a))

    def _key(self, name: str, old: Any, new: Any) -> None:
        _, direction, a = name.split("_")
        sign = 1 if direction == "pos" else -1
        if not self._possible():
            return
        step = self._step()
        axis = self._axes[a]
        accel = self._axes.accel(a)
        if new and not old and self._limits.refuses(a, sign):
            return  # only away from an actuated limit switch or back to the field (spec §5.5)
        if new and not old:
            if step is not None:
                if a in self.moving:
                    return  # a press during a running step is ignored (spec §5.4)
                self._travel(a, lambda: axis.move_to(axis.position() + sign * step, self._speed(a, rapid=False),
                                                     accel, on_done=lambda: self._stopped(a)))
            else:
                self._travel(a, lambda: axis.jog(sign, self._speed(a, rapid=True), accel))
        elif old and not new and step is None and a in self._waiting:
            del self._waiting[a]  # let go before the feed was released
            self._stopped(a)
        elif old and not new and step is None and a in self.moving:
            axis.stop(accel, on_done=lambda: self._stopped(a))

    def _travel(self, a: str, motion: Callable[[], None]) -> None:
        """The travel command goes out; the axis moves once the axis enable is H (§2.4.2, §2.3.15)."""
        self.moving.add(a)
        self._signals.set(f"travel_{a}", True)
        if self._signals.get("axis_enable"):
            self._release(motion)
        else:
            self._waiting[a] = motion

    def _release(self, motion: Callable[[], None]) -> None:
        self._signals.set("machine_standstill", False)  # by the axis enable (§2.4.6)
        motion()

    def _axis_enable(self, _name: str, _old: Any, new: Any) -> None:
        """V22/3 H: the feed of every axis whose travel command waits is released."""
        if not new:
            return  # a released feed goes on (§2.3.15)
        waiting, self._waiting = self._waiting, {}
        for motion in waiting.values():
            self._release(motion)

    def _nc_stop(self, _name: str, _old: Any, new: Any) -> None:
        """V19/1 L: in PROGRAM_ENTRY the axes brake along their ramps (§2.3.1; not in MANUAL)."""
        if not new and self._mode() in MANUAL_MODES and self._nc_stop_effective():
            self.brake()

    def _nc_stop_effective(self) -> bool:
        return self._mode() != "MANUAL" and not self._signals.get("nc_stop")

    def _possible(self) -> bool:
        """Manual motion: MANUAL or PROGRAM_ENTRY, the control ready, Not-Stop released, NC-Stop
        not effective (§2.3.1)."""
        return (self._mode() in MANUAL_MODES and not self._booting() and bool(self._signals.get("emergency_stop"))
                and not self._nc_stop_effective())

    def _step(self) -> int | None:
        for n in JOG_STEPS:  # the smallest selected step wins
            if self._signals.get(f"jog_step_{n}"):
                return n
        return None

    def _speed(self, a: str, *, rapid: bool) -> float:
        if rapid and self._signals.get("rapid"):
            return max(self._axes.rapid(a), 1e-9)
        return max(self._axes.max_feed(a) * self._feed_pot(), 1e-9)

    def _speed_changed(self, _name: str, _old: Any, _new: Any) -> None:
        """The feed pot and rapid act along the ramp on keys held down (manual §2.3.6 graph)."""
        if self._step() is not None:
            return
        for a in list(self.moving):
            if a in self._waiting:
                continue  # not released yet: it starts at the speed of its release
            held = [d for d in (1, -1) if self._signals.get(f"jog_{'pos' if d > 0 else 'neg'}_{a}")]
            if held:
                self._axes[a].jog(held[0], self._speed(a, rapid=True), self._axes.accel(a))

    def _start(self, a: str) -> None:
        self.moving.add(a)
        self._signals.set(f"travel_{a}", True)
        self._signals.set("machine_standstill", False)

    def _stopped(self, a: str) -> None:
        self.moving.discard(a)
        self._signals.set(f"travel_{a}", False)
        if not self.moving:
            self._signals.set("machine_standstill", True)
            self._take_deferred_open_loop()  # (standstill may have stayed H: a wait given up)

    def left_field(self) -> None:
        """Outside the working field every moving axis brakes (§2.4.4), as by NC-Stop."""
        self.brake()

    def brake(self) -> None:
        """Every moving axis brakes along its ramp (NC-Stop in PROGRAM_ENTRY, §2.3.1; the field left)."""
        self._give_up_waiting()
        for a in list(self.moving):
            self._axes[a].stop(self._axes.accel(a), on_done=lambda a=a: self._stopped(a))

    def _give_up_waiting(self) -> None:
        """The waits for the axis enable end (Not-Stop, a mode change: §2.3.15)."""
        waiting, self._waiting = self._waiting, {}
        for a in waiting:
            self._stopped(a)

    def reset(self) -> None:
        self._give_up_waiting()
        for a in list(self.moving):
            self._axes[a].stop(self._axes.accel(a))
            self._stopped(a)
