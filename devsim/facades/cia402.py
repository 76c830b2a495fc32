"""The CiA 402 drive state machine and its profile modes over a kind's declared drive actions
(issue 13; CiA 402 part 2 §8, the "power drive system" finite state automaton).

A kind that is a drive declares :class:`DriveActions` (``Device.drive``): how to switch the power
stage, move to a position, run at a velocity, stop quickly and reset a fault, and how to read
position, velocity, enable, fault and motion.  :class:`Cia402` keeps the state the controlword
(6040h) drives and composes the statusword (6041h); in profile position mode (6060h = 1) a rising
"new set-point" bit (4) starts a move to the target position (607Ah, bit 6: relative) at the
profile velocity (6081h), bit 8 (halt) stops it with the ramp and holds new set-points back (the
set-points, their handshake with the statusword's bit 12 and bit 10 are
:mod:`devsim.facades.cia402_position`'s: no set-point is in process outside Operation enabled; the
positioning option code 60F2h says what a relative target counts from), and the position window
(6067h, 6068h) and the following error window (6065h, 6066h) are
:mod:`devsim.facades.cia402_position_watch`'s: bit 10 also needs the axis within the position
window for its time, bit 13 (following error) is 1 once the following error has stayed outside
its window for its time out (both switched off by their power-on value FFFFFFFFh); in
profile velocity mode (3) the drive follows the target velocity (60FFh) in Operation enabled (0 with
halt): the kind's jog is called when that demand changes (entering Operation enabled, halt set or
released, a new 60FFh), not for a controlword or a 60FFh that repeats what is commanded (a master
sends them in an RPDO every SYNC; the IP247 would answer a second jog with its error 2 and stop),
and the statusword's bits 10 (target reached) and 12 (speed) are the velocity supervision's of
:mod:`devsim.facades.cia402_velocity` (606Dh … 6070h) over the drive's actual velocity.
The modes a drive supports (6502h, CiA 402-2) are those whose drive action the kind declares
(:data:`MODES`); writing another mode into 6060h is refused (``ValueError``), so 6061h only ever
shows a supported one.  :meth:`Cia402.reset` is the application part of an NMT reset node (CiA 301,
the NMT state machine's "reset application" sub-state): the power-on values of :data:`DEFAULTS`, the drive disabled, Switch on disabled.
Pure but for the count of changes it keeps (:mod:`devsim.core.changes`) and the velocity
supervision's looks on the device ``clock``: the node calls it and it calls the actions.
"""

from __future__ import annotations

from typing import Any

import msgspec

from devsim.core.changes import CHANGES
from devsim.core.clock import VirtualClock
from devsim.core.kit import DriveActions
from devsim.facades.cia402_homing import HomingMode
from devsim.facades.cia402_position import SetPoints
from devsim.facades.cia402_position_watch import PositionWatch
from devsim.facades.cia402_velocity import VelocityWatch

__all__ = ["Cia402", "DEFAULTS", "DriveActions", "HOMING", "MODES", "STATES", "TRANSITIONS", "command"]


#: State → statusword bits 0…6 (CiA 402-2 §8.4.1; bit 4 "voltage enabled" where the power stage may
#: be on, bit 5 "quick stop" where it is not active, but in Switch on disabled)
STATES = {
    "switch_on_disabled": 0x0040,
    "ready_to_switch_on": 0x0021,
    "switched_on": 0x0033,
    "operation_enabled": 0x0037,
    "quick_stop_active": 0x0017,
    "fault": 0x0008,
}
PROFILE_POSITION, PROFILE_VELOCITY, HOMING = 1, 3, 6

#: Modes of operation (6060h value) → (the drive action the mode needs, its bit in 6502h "supported
#: drive modes", CiA 402-2: bit 0 profile position, bit 2 profile velocity, bit 5 homing: the
#: kind's own reference run, :mod:`devsim.facades.cia402_homing`).
MODES = {PROFILE_POSITION: ("move_to", 0), PROFILE_VELOCITY: ("jog", 2), HOMING: ("homing", 5)}

#: The power-on values of the 402 objects a master writes (the EDS's DefaultValue; CiA 301: an NMT
#: reset node restores the application objects' power-on values).  The velocity window and
#: threshold (606Dh, 606Fh) are in the drive's velocity units, their times (606Eh, 6070h) in ms; the
#: homing objects' 0 (6098h, 6099h, 609Ah) is "no method" and "the device's own speeds and ramp".
#: The following error window and the position window (6065h, 6067h) are FFFFFFFFh, switched off
#: (CiA 402-2), their times (6066h, 6068h) 0 ms: bits 10 and 13 as the node had them before it had
#: these objects; the positioning option code (60F2h) 0002h, relative moves from the position
#: actual value, likewise ([SIM-CHOICE]: the standard leaves the power-on values to the device).
DEFAULTS = {"controlword": 0, "mode": PROFILE_POSITION, "target_position": 0, "profile_velocity": 1000,
            "target_velocity": 0, "velocity_window": 100, "velocity_window_time": 0, "velocity_threshold": 10,
            "velocity_threshold_time": 0, "home_offset": 0, "homing_method": 0, "homing_speed_switch": 0,
            "homing_speed_zero": 0, "homing_acceleration": 0, "following_error_window": 0xFFFF_FFFF,
            "following_error_time_out": 0, "position_window": 0xFFFF_FFFF, "position_window_time": 0,
            "positioning_option_code": 0x0002}


def command(word: int) -> str:
    """The command a controlword codes (CiA 402-2 §8.4.2, bits 0 … 3; bit 7, the fault reset, is
    read in the Fault state alone)."""
    if not word & 0x02:
        return "disable_voltage"  # 0xxx xx0x
    if not word & 0x04:
        return "quick_stop"  # 0xxx x01x
    if not word & 0x01:
        return "shutdown"  # 0xxx x110
    if not word & 0x08:
        return "switch_on"  # 0xxx 0111 (in Operation enabled: disable operation)
    return "enable_operation"  # 0xxx 1111


#: (state, command) → the next state (CiA 402-2 §8.4.3, transitions 2 … 12 and 16; the fault's
#: 13 … 15 are the drive's and the fault reset's).  Enable operation in Ready to switch on is the
#: command coding's "switch on + enable operation" (§8.4.2, since DSP 402 V3.0): transitions 3 and
#: 4 at once, the drive passing through Switched on.  A command not listed for a state changes
#: nothing: Quick stop active, in particular, is left only by disable voltage, enable operation or
#: the axis standing (:attr:`Cia402.statusword`).
TRANSITIONS = {
    ("switch_on_disabled", "shutdown"): "ready_to_switch_on",  # 2
    ("ready_to_switch_on", "switch_on"): "switched_on",  # 3
    ("ready_to_switch_on", "enable_operation"): "operation_enabled",  # 3 + 4
    ("switched_on", "enable_operation"): "operation_enabled",  # 4
    ("operation_enabled", "switch_on"): "switched_on",  # 5 (disable operation)
    ("switched_on", "shutdown"): "ready_to_switch_on",  # 6
    ("ready_to_switch_on", "disable_voltage"): "switch_on_disabled",  # 7
    ("ready_to_switch_on", "quick_stop"): "switch_on_disabled",  # 7
    ("operation_enabled", "shutdown"): "ready_to_switch_on",  # 8
    ("operation_enabled", "disable_voltage"): "switch_on_disabled",  # 9
    ("switched_on", "disable_voltage"): "switch_on_disabled",  # 10
    ("switched_on", "quick_stop"): "switch_on_disabled",  # 10
    ("operation_enabled", "quick_stop"): "quick_stop_active",  # 11
    ("quick_stop_active", "disable_voltage"): "switch_on_disabled",  # 12
    ("quick_stop_active", "enable_operation"): "operation_enabled",  # 16
}


class Cia402:
    """One axis's 402 state, driving ``actions`` on ``model``; the velocity supervision looks on
    ``clock`` (the device's; without one, a clock that stands still)."""

    _commanded: float | None  # profile velocity mode: the velocity the drive was commanded last

    def __init__(self, actions: DriveActions, model: Any, clock: Any = None) -> None:
        self.homing = HomingMode(actions, model, DEFAULTS)
        self.actions, self.model = self._shifted(actions), model
        clock = clock if clock is not None else VirtualClock()
        self.watch = VelocityWatch(clock, self._velocities, DEFAULTS)
        self.setpoints = SetPoints(self.actions, model, clock, DEFAULTS["positioning_option_code"])
        self.position_watch = PositionWatch(clock, self._positions, DEFAULTS)
        self._power_on()

    def _shifted(self, actions: DriveActions) -> DriveActions:
        """The drive's actions with positions in the zero position homing set (607Ch): 6064h, the
        targets of 607Ah and the relative ones all count from there."""
        homing, move_to = self.homing, actions.move_to
        return msgspec.structs.replace(
            actions, position=lambda m: actions.position(m) + homing.shift,
            move_to=None if move_to is None else lambda m, target, speed: move_to(m, target - homing.shift, speed))

    @property
    def state(self) -> str:
        return self._state

    @state.setter
    def state(self, state: str) -> None:
        if state != "operation_enabled":
            self._commanded = None  # (out of Operation enabled the drive follows nothing)
            self.setpoints.drop()  # (and no set-point is in process)
            self.homing.interrupt(stop=False)  # (nor a homing: the state's own command stops the axis)
        self._state = state

    def _power_on(self) -> None:
        self.state = "switch_on_disabled"
        self.controlword, self.mode = DEFAULTS["controlword"], DEFAULTS["mode"]
        self.target_position, self.profile_velocity = DEFAULTS["target_position"], DEFAULTS["profile_velocity"]
        self.target_velocity = DEFAULTS["target_velocity"]
        self.setpoints.reset()
        self.setpoints.option = DEFAULTS["positioning_option_code"]
        self.homing.reset()
        self.error_code = 0  # the EMCY code of the last fault the drive announced (603Fh)
        self.watch.reset()
        self.position_watch.reset()

    def _velocities(self) -> tuple[float, float] | None:
        """In profile velocity mode: the drive's velocity and the velocity demanded, the target
        velocity in Operation enabled unless halted (bit 8), else 0 (the axis is stopped)."""
        if self.mode != PROFILE_VELOCITY:
            return None
        running = self.state == "operation_enabled" and not self.controlword & 0x100
        return self.actions.velocity(self.model), float(self.target_velocity if running else 0)

    def _positions(self) -> tuple[int, float | None, int | None] | None:
        """In profile position mode: the position actual value and the target of the last
        positioning (as 6064h shows them), and in Operation enabled the following error (60F4h)."""
        if self.mode != PROFILE_POSITION:
            return None
        a = self.actions
        error = round(a.following_error(self.model)) if self.state == "operation_enabled" else None
        goal = self.setpoints.goal
        return round(a.position(self.model)), None if goal is None else round(goal), error

    # -- the error objects (603Fh, CiA 402-2; 1001h, CiA 301) -------------------------------------------
    def in_fault(self) -> bool:
        """The Fault state, or a fault the drive has now (the statusword's view)."""
        return self.state == "fault" or bool(self.actions.fault(self.model))

    @property
    def error_code_object(self) -> int:
        """603Fh: in a fault, the error code of the last EMCY (CiA 402-2: the lower 16 bits of the
        EMCY's error code; 1000h, generic error, for a fault no EMCY named); 0 without one."""
        return (self.error_code or 0x1000) if self.in_fault() else 0

    @property
    def error_register(self) -> int:
        """1001h: bit 0, generic error, in any error situation (CiA 301), as the EMCY carries it."""
        return 0x01 if self.in_fault() else 0x00

    # -- modes of operation (6060h, 6061h, 6502h) -------------------------------------------------------
    @property
    def supported_modes(self) -> int:
        """6502h: a bit per mode whose drive action the kind declares."""
        return sum(1 << bit for action, bit in MODES.values() if getattr(self.actions, action, None) is not None)

    def write_mode(self, mode: int) -> None:
        """6060h: a mode the drive supports, else ``ValueError`` (the node aborts 0609 0030h)."""
        action_bit = MODES.get(mode)
        if action_bit is None or not self.supported_modes >> action_bit[1] & 1:
            raise ValueError(f"mode of operation {mode} is not supported")
        if mode != self.mode:
            self.homing.interrupt()  # (a homing under way ends with its mode)
            self._commanded = None  # (the velocity the drive follows is the new mode's to command)
            self.setpoints.reset()  # (and the set-points in process end)
        self.mode = mode
        self.watch.look(command=True)
        self.position_watch.look(command=True)

    # -- NMT reset node (CiA 301, reset application) ----------------------------------------------------------
    def reset(self) -> None:
        """The 402 objects back to their power-on values, the drive disabled, Switch on disabled."""
        if self.actions.enabled(self.model):
            CHANGES.count += 1  # (the drive actions change the model: a door, devsim.core.changes)
            self.actions.enable(self.model, False)
        self._power_on()

    # -- controlword (6040h) ---------------------------------------------------------------------
    def write_controlword(self, word: int) -> None:
        before, self.controlword = self.controlword, word & 0xFFFF
        CHANGES.count += 1  # (the drive actions change the model: a door, devsim.core.changes)
        a = self.actions
        if self.state == "fault" or a.fault(self.model):
            self.state = "fault"
            if word & 0x80 and not before & 0x80:  # fault reset (rising bit 7)
                a.reset_fault(self.model)
                if not a.fault(self.model):
                    self.state = "switch_on_disabled"
            return
        state = TRANSITIONS.get((self.state, command(word)), self.state)
        if state == "quick_stop_active" and self.state != state:
            a.quick_stop(self.model)
            self.state = state
        else:
            self._go(state)
        if self.state == "operation_enabled":
            self._profile(before, word)
        self.watch.look(command=True)
        self.position_watch.look(command=True)

    def _go(self, state: str) -> None:
        if state == self.state:
            return
        was_enabled = self.state in ("operation_enabled", "quick_stop_active")
        self.state = state
        if state == "operation_enabled":
            self.actions.enable(self.model, True)
        elif was_enabled:
            self.actions.enable(self.model, False)

    @property
    def setpoint_ack(self) -> bool:
        """Profile position mode's set-point acknowledge (statusword bit 12)."""
        return self.setpoints.ack

    def cancel(self) -> None:
        """No more looks on the clock (the node closes)."""
        self.watch.cancel()
        self.setpoints.cancel()
        self.position_watch.cancel()

    def _profile(self, before: int, word: int) -> None:
        if self.mode == PROFILE_POSITION:  # bits 4 … 8: :mod:`devsim.facades.cia402_position`
            self.setpoints.control(before, word, self.target_position, self.profile_velocity)
        elif self.mode == HOMING:  # bits 4 and 8: :mod:`devsim.facades.cia402_homing`
            self.homing.control(before, word)
        elif self.mode == PROFILE_VELOCITY:
            self._follow()

    def _follow(self) -> None:
        """Profile velocity mode in Operation enabled: the drive runs at the target velocity (0 with
        halt); it is commanded when that differs from what it was commanded last."""
        demand = float(self.target_velocity) if not self.controlword & 0x100 else 0.0
        if demand != self._commanded:
            self.actions.jog(self.model, demand)
            self._commanded = demand

    def write_target_velocity(self, value: int) -> None:
        self.target_velocity = value
        if self.state == "operation_enabled" and self.mode == PROFILE_VELOCITY:
            CHANGES.count += 1  # (the drive actions change the model: a door, devsim.core.changes)
            self._follow()
        self.watch.look(command=True)

    # -- statusword (6041h) ------------------------------------------------------------------------
    @property
    def statusword(self) -> int:
        a = self.actions
        if a.fault(self.model):
            self.state = "fault"
        elif self.state == "operation_enabled" and not a.enabled(self.model):
            self.state = "switched_on"  # the drive switched itself off
        elif self.state == "quick_stop_active" and not a.moving(self.model):
            CHANGES.count += 1  # (the drive actions change the model: a door, devsim.core.changes)
            self.actions.enable(self.model, False)
            self.state = "switch_on_disabled"
        word = STATES[self.state] | 0x0200  # bit 9: remote
        if self.mode == PROFILE_VELOCITY:
            return word | self.watch.bits()  # bits 10 (target reached) and 12 (speed)
        if self.mode == HOMING:
            return word | self.homing.bits()  # bits 10, 12 (homing attained) and 13 (homing error)
        self.setpoints.look()  # (a waiting set-point that starts now is the target the window looks at)
        following = self.position_watch.bits()  # bit 13 (following error)
        halted = bool(self.controlword & 0x100)
        return word | following | self.setpoints.bits(halted, self.position_watch.reached())  # bits 10 and 12
