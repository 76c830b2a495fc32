"""The CiA 402 state machine alone (issue 35; CiA 402-2 §8: the "power drive system" finite state
automaton, the controlword's command coding, the statusword's state coding): :class:`Cia402`
over a drive whose state the test sets, every controlword against the standard's tables written
here as a small oracle, in-process.  The same machine on a bus with real kinds is in
test_cia402.py and test_cia402_contract.py."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from devsim.core.kit import DriveActions
from devsim.facades.cia402 import DEFAULTS, PROFILE_POSITION, PROFILE_VELOCITY, Cia402

SOD, READY, ON, ENABLED, QUICK, FAULT = (
    "switch_on_disabled", "ready_to_switch_on", "switched_on", "operation_enabled", "quick_stop_active", "fault")
#: The statusword's state coding (CiA 402-2 §8.4.1, Table "State coding"): (mask, value) of bits 0 … 6.
CODING = {SOD: (0x4F, 0x40), READY: (0x6F, 0x21), ON: (0x6F, 0x23), ENABLED: (0x6F, 0x27),
          QUICK: (0x6F, 0x07), FAULT: (0x4F, 0x08)}
#: The states with the power stage on.
POWERED = (ENABLED, QUICK)


def command(word: int) -> str:
    """The controlword's command coding (CiA 402-2 §8.4.2, bits 0 … 3; bit 7 is the fault reset)."""
    if not word & 0x02:
        return "disable voltage"  # 0xxx xx0x
    if not word & 0x04:
        return "quick stop"  # 0xxx x01x
    if not word & 0x01:
        return "shutdown"  # 0xxx x110
    if not word & 0x08:
        return "switch on"  # 0xxx 0111 (in Operation enabled: disable operation)
    return "enable operation"  # 0xxx 1111


#: The transitions (CiA 402-2 §8.4.3): (state, command) -> next state; a pair not listed stays.
#: The command coding's "switch on + enable operation" (0xxx 1111 in Ready to switch on) makes 3 + 4.
TRANSITIONS = {
    (SOD, "shutdown"): READY,  # 2
    (READY, "switch on"): ON,  # 3
    (READY, "enable operation"): ENABLED,  # 3 + 4
    (ON, "enable operation"): ENABLED,  # 4
    (ENABLED, "switch on"): ON,  # 5 (disable operation)
    (ON, "shutdown"): READY,  # 6
    (READY, "disable voltage"): SOD, (READY, "quick stop"): SOD,  # 7
    (ENABLED, "shutdown"): READY,  # 8
    (ENABLED, "disable voltage"): SOD,  # 9
    (ON, "disable voltage"): SOD, (ON, "quick stop"): SOD,  # 10
    (ENABLED, "quick stop"): QUICK,  # 11
    (QUICK, "disable voltage"): SOD,  # 12
    (QUICK, "enable operation"): ENABLED,  # 16
}


@dataclass
class Motor:
    """The drive the actions act on: its state is the test's to set; ``calls`` logs the actions."""

    enabled: bool = False
    fault: bool = False
    moving: bool = False
    position: float = 0.0
    velocity: float = 0.0
    following_error: float = 0.0
    fault_stays: bool = False  # a fault reset that does not clear the fault
    calls: list[tuple[Any, ...]] = field(default_factory=list)


def _enable(m: Motor, on: bool) -> None:
    m.calls.append(("enable", on))
    m.enabled = on


def _reset_fault(m: Motor) -> None:
    m.calls.append(("reset_fault",))
    m.fault = m.fault_stays


ACTIONS = DriveActions(
    enable=_enable,
    move_to=lambda m, target, speed: m.calls.append(("move_to", target, speed)),
    jog=lambda m, speed: m.calls.append(("jog", speed)),
    quick_stop=lambda m: m.calls.append(("quick_stop",)),
    reset_fault=_reset_fault,
    position=lambda m: m.position,
    velocity=lambda m: m.velocity,
    enabled=lambda m: m.enabled,
    fault=lambda m: m.fault,
    moving=lambda m: m.moving,
    following_error=lambda m: m.following_error,
)


def drive_in(state: str, motor: Motor | None = None) -> tuple[Cia402, Motor]:
    """A machine brought into ``state`` the standard's way (from Switch on disabled)."""
    motor = motor or Motor()
    machine = Cia402(ACTIONS, motor)
    path = {SOD: (), READY: (0x06,), ON: (0x06, 0x07), ENABLED: (0x06, 0x07, 0x0F), QUICK: (0x06, 0x07, 0x0F, 0x0B),
            FAULT: ()}[state]
    for word in path:
        machine.write_controlword(word)
    if state == QUICK:
        motor.moving = True  # still stopping
    if state == FAULT:
        motor.fault = True
    assert machine.statusword & CODING[state][0] == CODING[state][1]
    motor.calls.clear()
    return machine, motor


def state_of(machine: Cia402) -> str:
    word = machine.statusword
    found = [s for s, (mask, value) in CODING.items() if word & mask == value]
    assert len(found) == 1, hex(word)
    return found[0]


@given(state=st.sampled_from(sorted(CODING)), word=st.integers(0, 0xFFFF))
@example(state=SOD, word=0x0E)  # shutdown with bit 3 set
@example(state=QUICK, word=0x06)  # shutdown: no transition from Quick stop active
@example(state=QUICK, word=0x02)  # quick stop again while stopping
@example(state=QUICK, word=0x07)
@example(state=READY, word=0x0F)
@example(state=SOD, word=0x07)
@example(state=ON, word=0x0B)
@example(state=ENABLED, word=0x8F)
@example(state=FAULT, word=0x0F)
def test_every_controlword_in_every_state_makes_the_standards_transition(state: str, word: int) -> None:
    machine, motor = drive_in(state)
    machine.controlword = 0xFF  # (no rising edge of bit 4, 7)
    motor.moving = True  # (a quick stop still stopping)
    machine.write_controlword(word)
    expected = FAULT if state == FAULT else TRANSITIONS.get((state, command(word)), state)
    assert state_of(machine) == expected
    assert machine.controlword == word
    enables = [c for c in motor.calls if c[0] == "enable"]
    if expected == ENABLED and state != ENABLED and state != QUICK:
        assert enables == [("enable", True)]
    elif state in POWERED and expected not in POWERED:
        assert enables == [("enable", False)]
    elif state == QUICK and expected == ENABLED:
        assert enables in ([], [("enable", True)])  # (already on)
    else:
        assert enables == []
    assert (("quick_stop",) in motor.calls) == (state == ENABLED and expected == QUICK)


def test_the_statusword_of_each_state_bit_by_bit() -> None:
    """Bits 0 … 6 (state coding), bit 9 remote always, bit 10 target reached when not moving."""
    words = {SOD: 0x0240, READY: 0x0221, ON: 0x0233, ENABLED: 0x0237, FAULT: 0x0208}
    for state, word in words.items():
        machine, motor = drive_in(state)
        assert machine.statusword == word | 0x0400
        motor.moving = True
        assert machine.statusword == word
    machine, motor = drive_in(QUICK)
    assert machine.statusword == 0x0217  # bit 5 quick stop (0 = active), still moving
    assert motor.enabled


def test_quick_stop_active_ends_in_switch_on_disabled_when_the_axis_stands() -> None:
    machine, motor = drive_in(QUICK)
    machine.write_controlword(0x0B)  # the quick stop command held
    assert state_of(machine) == QUICK and motor.enabled and motor.calls == []
    motor.moving = False
    assert machine.statusword == 0x0640  # switch on disabled, target reached
    assert motor.calls == [("enable", False)] and not motor.enabled


def test_a_drive_that_switches_itself_off_shows_switched_on() -> None:
    machine, motor = drive_in(ENABLED)
    motor.enabled = False
    assert state_of(machine) == ON
    machine.write_controlword(0x0F)
    assert state_of(machine) == ENABLED and motor.calls == [("enable", True)]


@pytest.mark.parametrize("state", [SOD, READY, ON, ENABLED, QUICK])
def test_a_fault_is_the_fault_state_and_a_rising_bit_7_resets_it(state: str) -> None:
    """Fault (§8.4.3, transitions 13, 14, 15): any state; only the fault reset (bit 7 from 0 to 1)
    leaves it, to Switch on disabled, and only when the fault is gone."""
    machine, motor = drive_in(state)
    motor.fault = True
    machine.write_controlword(0x0F)
    assert machine.state == FAULT and state_of(machine) == FAULT and motor.calls == []
    machine.write_controlword(0x8F)
    assert motor.calls == [("reset_fault",)] and state_of(machine) == SOD
    machine.write_controlword(0x06)
    assert state_of(machine) == READY


def test_only_a_rising_bit_7_resets_a_fault_and_a_fault_that_stays_stays() -> None:
    machine, motor = drive_in(FAULT, Motor(fault_stays=True))
    machine.write_controlword(0x80)
    assert motor.calls == [("reset_fault",)] and state_of(machine) == FAULT
    machine.write_controlword(0x80)  # held: no edge
    assert motor.calls == [("reset_fault",)]
    machine.write_controlword(0x00)
    machine.write_controlword(0x86)
    assert motor.calls == [("reset_fault",)] * 2 and machine.state == FAULT
    motor.fault_stays = False
    machine.write_controlword(0x06)
    machine.write_controlword(0x86)
    assert state_of(machine) == SOD


def test_a_fault_found_by_the_statusword_is_the_fault_state() -> None:
    machine, motor = drive_in(ENABLED)
    motor.fault = True
    assert machine.statusword & 0x4F == 0x08 and machine.state == FAULT


@given(target=st.integers(-(2**31), 2**31 - 1), position=st.integers(-10**6, 10**6), relative=st.booleans(),
       speed=st.integers(1, 2**31 - 1))
def test_a_rising_new_set_point_moves_to_the_target(target: int, position: int, relative: bool, speed: int) -> None:
    """Profile position mode (6060h = 1, CiA 402-2 §12): bit 4 from 0 to 1 starts a move to 607Ah
    (bit 6: relative to the actual position) at 6081h; bit 12 of the statusword acknowledges it
    while bit 4 is held; the move starts once."""
    machine, motor = drive_in(ENABLED)
    motor.position = float(position)
    machine.target_position, machine.profile_velocity = target, speed
    machine.write_controlword(0x1F | relative << 6)
    assert motor.calls == [("move_to", float(target + position * relative), float(speed))]
    assert machine.statusword & 0x1000
    machine.write_controlword(0x1F | relative << 6)
    assert len(motor.calls) == 1 and machine.statusword & 0x1000
    machine.write_controlword(0x0F)
    assert not machine.statusword & 0x1000 and len(motor.calls) == 1


def test_a_new_set_point_outside_operation_enabled_or_in_another_mode_moves_nothing() -> None:
    machine, motor = drive_in(ON)
    machine.write_controlword(0x17)
    assert motor.calls == [] and not machine.statusword & 0x1000
    machine, motor = drive_in(ENABLED)
    machine.write_mode(PROFILE_VELOCITY)
    machine.target_velocity = 0
    machine.write_controlword(0x1F)
    assert [c[0] for c in motor.calls] == ["jog"] and not machine.setpoint_ack
    assert machine.statusword & 0x1000  # (bit 12 in profile velocity mode: speed is 0)


def test_entering_operation_enabled_with_bit_4_set_starts_the_move() -> None:
    machine, motor = drive_in(ON)
    machine.target_position = 500
    machine.write_controlword(0x1F)
    assert motor.calls == [("enable", True), ("move_to", 500.0, float(DEFAULTS["profile_velocity"]))]


@given(velocity=st.integers(-(2**31), 2**31 - 1), halt=st.booleans())
def test_profile_velocity_runs_at_the_target_unless_halted(velocity: int, halt: bool) -> None:
    """Profile velocity mode (6060h = 3, CiA 402-2 §14): the axis runs at 60FFh; bit 8 (halt)
    stops it with the ramp; a new 60FFh takes effect at once unless halted (the same value again
    is no new one)."""
    machine, motor = drive_in(ENABLED)
    machine.write_mode(PROFILE_VELOCITY)
    machine.target_velocity = velocity
    machine.write_controlword(0x0F | halt << 8)
    assert motor.calls == [("jog", 0.0 if halt else float(velocity))]
    machine.write_target_velocity(velocity // 2)
    assert machine.target_velocity == velocity // 2
    assert motor.calls[1:] == ([] if halt or velocity // 2 == velocity else [("jog", float(velocity // 2))])


@given(words=st.lists(st.sampled_from([0x0F, 0x010F, 0x0007, 0x000B, 0x0006, 0x001F, 0x004F]), max_size=12),
       targets=st.lists(st.integers(-3, 3), min_size=12, max_size=12))
@example(words=[0x0F, 0x0F, 0x010F, 0x010F, 0x0F], targets=[2, 2, 2, 2, 3] + [0] * 7)
def test_profile_velocity_commands_the_drive_only_when_its_demand_changes(words: list[int],
                                                                          targets: list[int]) -> None:
    """Profile velocity mode (CiA 402-2): in Operation enabled the drive follows 60FFh (0 with
    halt).  A master writing the controlword and 60FFh again and again (in an RPDO every SYNC)
    commands the drive only when what it is to follow changes: after each pair of writes the jogs
    called are those that change the demand since the last jog, or since the machine entered
    Operation enabled (oracle: the demand, compared with the last one commanded, forgotten out of
    Operation enabled)."""
    machine, motor = drive_in(ENABLED)
    machine.write_mode(PROFILE_VELOCITY)
    commanded: float | None = None
    for word, target in zip([0x0F, *words], targets, strict=False):
        for write, value in ((machine.write_controlword, word), (machine.write_target_velocity, target)):
            motor.calls.clear()
            write(value)
            expected = []
            if state_of(machine) == ENABLED:
                demand = 0.0 if machine.controlword & 0x100 else float(machine.target_velocity)
                if demand != commanded:
                    expected, commanded = [("jog", demand)], demand
            else:
                commanded = None
            assert [c for c in motor.calls if c[0] == "jog"] == expected, (hex(word), target)


def test_a_target_velocity_outside_operation_enabled_or_profile_velocity_is_kept_only() -> None:
    machine, motor = drive_in(ON)
    machine.write_mode(PROFILE_VELOCITY)
    machine.write_target_velocity(100)
    assert motor.calls == [] and machine.target_velocity == 100
    machine, motor = drive_in(ENABLED)
    machine.write_target_velocity(100)  # profile position
    assert motor.calls == [] and machine.target_velocity == 100


def test_supported_modes_are_those_whose_action_the_kind_declares() -> None:
    """6502h (CiA 402-2): bit 0 profile position, bit 2 profile velocity; 6060h takes only those."""
    machine, _ = drive_in(SOD)
    assert machine.supported_modes == 0b101
    for mode in (PROFILE_VELOCITY, PROFILE_POSITION):
        machine.write_mode(mode)
        assert machine.mode == mode
    for mode in (0, 2, 4, 6, 7, 8, -1, 255):
        with pytest.raises(ValueError, match=f"mode of operation {mode} is not supported"):
            machine.write_mode(mode)
        assert machine.mode == PROFILE_POSITION
    no_jog = Cia402(DriveActions(**{**{f: getattr(ACTIONS, f) for f in ACTIONS.__struct_fields__}, "jog": None}),
                    Motor())
    assert no_jog.supported_modes == 0b001
    with pytest.raises(ValueError):
        no_jog.write_mode(PROFILE_VELOCITY)
    no_move = Cia402(DriveActions(**{**{f: getattr(ACTIONS, f) for f in ACTIONS.__struct_fields__},
                                     "move_to": None}), Motor())
    assert no_move.supported_modes == 0b100
    no_move.write_mode(PROFILE_VELOCITY)
    with pytest.raises(ValueError):
        no_move.write_mode(PROFILE_POSITION)


def test_power_on_values_and_the_reset_of_the_application() -> None:
    """CiA 301 NMT reset node: the 402 objects to their power-on values, the drive disabled."""
    machine, motor = drive_in(SOD)
    assert (machine.controlword, machine.mode, machine.target_position, machine.profile_velocity,
            machine.target_velocity, machine.setpoint_ack) == (0, 1, 0, 1000, 0, False)
    assert DEFAULTS == {"controlword": 0, "mode": 1, "target_position": 0, "profile_velocity": 1000,
                        "target_velocity": 0, "velocity_window": 100, "velocity_window_time": 0,
                        "velocity_threshold": 10, "velocity_threshold_time": 0, "home_offset": 0, "homing_method": 0,
                        "homing_speed_switch": 0, "homing_speed_zero": 0, "homing_acceleration": 0,
                        "following_error_window": 0xFFFF_FFFF, "following_error_time_out": 0,
                        "position_window": 0xFFFF_FFFF, "position_window_time": 0, "positioning_option_code": 2}
    machine, motor = drive_in(ENABLED)
    machine.target_position, machine.profile_velocity, machine.target_velocity = 5, 6, 7
    machine.write_controlword(0x1F)
    assert machine.setpoint_ack
    machine.reset()
    assert not machine.setpoint_ack
    machine, motor = drive_in(ENABLED)
    machine.target_position, machine.profile_velocity, machine.target_velocity = 5, 6, 7
    machine.write_mode(PROFILE_VELOCITY)
    for name in ("window", "window_time", "threshold", "threshold_time"):
        machine.watch.set(name, 7)
    machine.reset()
    watch = machine.watch
    assert (watch.window, watch.window_time, watch.threshold, watch.threshold_time) == (100, 0, 10, 0)
    assert ("enable", False) in motor.calls and not motor.enabled
    assert state_of(machine) == SOD
    assert (machine.controlword, machine.mode, machine.target_position, machine.profile_velocity,
            machine.target_velocity, machine.setpoint_ack) == (0, 1, 0, 1000, 0, False)
    motor.calls.clear()
    machine.reset()  # disabled already: nothing to switch off
    assert motor.calls == []


def test_a_fault_that_went_away_stays_the_fault_state_until_the_fault_reset() -> None:
    """Fault is left by transition 15 alone (the fault reset), also when the drive's fault has
    gone by itself."""
    machine, motor = drive_in(FAULT)
    motor.fault = False
    assert state_of(machine) == FAULT
    for word in (0x06, 0x07, 0x0F, 0x02, 0x00):
        machine.write_controlword(word)
        assert state_of(machine) == FAULT and motor.calls == []
    machine.write_controlword(0x80)
    assert motor.calls == [("reset_fault",)] and state_of(machine) == SOD


def test_halt_stops_a_profile_position_move_with_the_ramp_and_holds_new_set_points() -> None:
    """Profile position mode (CiA 402-2 §12, controlword bit 8 "halt": 0 positioning is executed,
    1 the axis is stopped, with the profile deceleration): a rising halt stops a running move with
    the ramp (the jog action at 0, which the actions define as a stop with the ramp); while it
    is set a rising new set-point starts nothing and is not acknowledged; without a move there
    is nothing to stop."""
    machine, motor = drive_in(ENABLED)
    machine.target_position = 1000
    machine.write_controlword(0x1F)
    motor.moving = True
    machine.write_controlword(0x11F)  # halt
    assert motor.calls == [("move_to", 1000.0, float(DEFAULTS["profile_velocity"])), ("jog", 0.0)]
    machine.write_controlword(0x11F)  # (held: no second stop)
    assert len(motor.calls) == 2
    motor.moving = False
    machine.write_controlword(0x10F)
    machine.write_controlword(0x11F)  # a new set-point while halted
    assert len(motor.calls) == 2 and not machine.statusword & 0x1000
    assert machine.statusword & 0x0400  # target reached: halted, velocity 0
    machine.write_controlword(0x0F)
    machine.write_controlword(0x1F)  # halt released: the next set-point moves
    assert motor.calls[2:] == [("move_to", 1000.0, float(DEFAULTS["profile_velocity"]))]


def test_what_a_relative_target_counts_from_is_the_positioning_option_code() -> None:
    """60F2h bits 0 and 1 (CiA 402-2, relative option) for a relative set-point (controlword bit
    6): 10b, the power-on value, from the position actual value; 01b from the position demand
    value (actual value + following error); 00b from the preceding target (0 before the first
    positioning of the mode); codes the node cannot honour are refused and change nothing."""
    machine, motor = drive_in(ENABLED)
    motor.position, motor.following_error = 100.0, 7.0
    machine.target_position = 1000
    speed = float(DEFAULTS["profile_velocity"])
    for option, target in ((0x0002, 1100.0), (0x0001, 1107.0), (0x0000, 2107.0)):
        machine.setpoints.write_option(option)
        machine.write_controlword(0x4F)
        machine.write_controlword(0x5F)  # new set-point, relative
        assert motor.calls[-1] == ("move_to", target, speed), option
    for code in (0x0003, 0x0004, 0x0040, 0x0100, 0x8000):
        with pytest.raises(ValueError):
            machine.setpoints.write_option(code)
    assert machine.setpoints.option == 0x0000
    machine.write_mode(PROFILE_VELOCITY)
    machine.write_mode(PROFILE_POSITION)  # (the mode begins anew: no preceding target)
    machine.write_controlword(0x4F)
    machine.write_controlword(0x5F)
    assert motor.calls[-1] == ("move_to", 1000.0, speed)
    machine.reset()
    assert machine.setpoints.option == DEFAULTS["positioning_option_code"] == 0x0002
