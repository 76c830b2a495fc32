"""The statusword in profile velocity mode (CiA 402-2, profile velocity mode: bit 10 "target
reached", bit 12 "speed") and the objects that define it, 606Dh velocity window, 606Eh velocity
window time, 606Fh velocity threshold and 6070h velocity threshold time, checked with canopen as
the master on python-can's virtual bus (virtual time).  The standard's definitions, as the oracle
here: bit 10 (halt = 0) is 1 once the velocity actual value (606Ch) has stayed within the velocity
window of the target velocity (60FFh) for the velocity window time, (halt = 1) once the axis has
stayed within the window of velocity 0 that long; bit 12 is 0 ("speed is not 0") once the velocity
actual value has stayed above the velocity threshold for the velocity threshold time, else 1
("speed is 0")."""

from __future__ import annotations

import math
import queue
from collections.abc import Callable
from typing import Any

import pytest

from tests.facades.test_cia402 import Drive, enable, mapped
from tests.facades.test_cia402_contract import DRIVES

TARGET_REACHED, SPEED_IS_0 = 0x0400, 0x1000
STEP = 0.001  # s: the test's own look at the drive's velocity


def actual(drive: Drive) -> int:
    """The velocity actual value as 606Ch shows it, read from the kind's model (no bus)."""
    return round(drive.runtime.call(drive.device.drive.velocity, drive.device.model))


def scan(drive: Drive, holds: Callable[[int], bool], timeout: float) -> float:
    """Step virtual time by ``STEP`` until ``holds(velocity actual value)``; the time it first holds."""
    end = drive.runtime.now() + timeout
    while not holds(actual(drive)):
        assert drive.runtime.now() < end, "the velocity never got there"
        drive.runtime.advance(STEP)
    return drive.runtime.now()


def walk(drive: Drive, seconds: float, demand: int, windows: tuple[int, float, int, float],
         read: Callable[[], int], slack: float = 0.002, running: bool = False) -> list[set[int]]:
    """Step ``seconds`` of virtual time by ``STEP`` from a command that changed the ``demand`` (the
    axis ``running`` above the threshold for long before it, or standing); at
    every step compare bits 10 and 12 of ``read()`` with the standard's definition over the test's
    own look at the velocity (``windows``: 606Dh, 606Eh in s, 606Fh, 6070h in s).  They may differ
    only within ``slack`` of the command or of a change of the definition's value.  The values each
    bit took."""
    window, window_time, threshold, threshold_time = windows
    inside: float | None = None
    above: float | None = -math.inf if running else None
    rows = []
    for _ in range(round(seconds / STEP)):
        now, velocity = drive.runtime.now(), actual(drive)
        inside = (now if inside is None else inside) if abs(velocity - demand) <= window else None
        above = (now if above is None else above) if abs(velocity) > threshold else None
        expected = TARGET_REACHED if inside is not None and now - inside >= window_time - 1e-9 else 0
        if above is None or now - above < threshold_time - 1e-9:
            expected |= SPEED_IS_0
        rows.append((now, expected, read() & (TARGET_REACHED | SPEED_IS_0)))
        drive.runtime.advance(STEP)
    for now, expected, seen in rows:
        if seen != expected and now - rows[0][0] > slack + 1e-9:
            near = {e for t, e, _ in rows if abs(t - now) <= slack + 1e-9}
            assert len(near) > 1, (round(now, 4), hex(expected), hex(seen))
    return [{e & bit for _, e, _ in rows} for bit in (TARGET_REACHED, SPEED_IS_0)]


def test_the_velocity_objects_over_sdo(drive: Drive) -> None:
    """606Dh … 6070h: UNSIGNED16, rw, their EDS default as power-on value, kept as written."""
    node = drive.node
    for index in (0x606D, 0x606E, 0x606F, 0x6070):
        entry = node.object_dictionary[index]
        assert entry.data_type == 0x0006 and entry.writable and entry.readable and entry.pdo_mappable
        assert node.sdo[index].raw == entry.default
    for index, value in ((0x606D, 50), (0x606E, 200), (0x606F, 30), (0x6070, 100)):
        node.sdo[index].raw = value
        assert node.sdo[index].raw == value


def test_target_reached_and_speed_follow_the_windows_and_their_times(drive: Drive) -> None:
    """The PCD4.H3's axis 1 runs up to 2 000 counts/s and stops again, its servo ringing around the
    velocity (±75 counts/s): at every millisecond bit 10 is 1 when 606Ch has stayed within the
    velocity window of the target for the window time, bit 12 is 0 when it has stayed above the
    threshold for the threshold time, else 1 (at once, as soon as it is below it)."""
    enable(drive)
    node = drive.node
    node.sdo[0x6060].raw = 3  # profile velocity
    windows = (100, 0.200, 30, 0.100)
    window, window_time, threshold, threshold_time = windows
    node.sdo[0x606D].raw, node.sdo[0x606E].raw = window, round(window_time * 1000)
    node.sdo[0x606F].raw, node.sdo[0x6070].raw = threshold, round(threshold_time * 1000)
    drive.runtime.advance(window_time)
    assert drive.status & (TARGET_REACHED | SPEED_IS_0) == TARGET_REACHED | SPEED_IS_0  # at 0, target 0
    node.sdo[0x60FF].raw = 2000
    assert walk(drive, 1.5, 2000, windows, lambda: drive.status) == [{0, TARGET_REACHED}, {0, SPEED_IS_0}]
    assert drive.status & (TARGET_REACHED | SPEED_IS_0) == TARGET_REACHED  # running at the target velocity
    node.sdo[0x60FF].raw = 0
    assert drive.status & (TARGET_REACHED | SPEED_IS_0) == 0  # a new target: not reached, and still running
    assert walk(drive, 1.0, 0, windows, lambda: drive.status, running=True) == [{0, TARGET_REACHED}, {0, SPEED_IS_0}]
    assert drive.status & TARGET_REACHED


def test_with_halt_target_reached_is_the_axis_standing(drive: Drive) -> None:
    """Halt (controlword bit 8) in profile velocity mode: bit 10 is 0 while the axis decelerates and
    1 once its velocity is 0 (within the velocity window of 0 for the window time)."""
    enable(drive)
    node = drive.node
    node.sdo[0x6060].raw = 3
    node.sdo[0x606D].raw, node.sdo[0x606E].raw = 20, 0
    node.sdo[0x60FF].raw = 2000
    drive.runtime.advance(2.0)
    assert drive.status & TARGET_REACHED
    drive.control(0x010F)  # halt
    assert not drive.status & TARGET_REACHED  # the axis decelerates
    scan(drive, lambda v: abs(v) <= 20, 5.0)
    assert drive.status & TARGET_REACHED
    drive.control(0x000F)  # halt released: the target velocity again
    assert not drive.status & TARGET_REACHED


def test_the_statusword_over_tpdos_shows_target_reached_when_it_is(drive: Drive) -> None:
    """TPDO1 = statusword on every SYNC and TPDO2 = statusword on change (type 255, looked at every
    10 ms): with no SDO read of the statusword, each carries bits 10 and 12 as the standard defines
    them, run up and stop."""
    enable(drive)
    node = drive.node
    node.sdo[0x6060].raw = 3
    windows = (100, 0.300, 10, 0.050)
    node.sdo[0x606D].raw, node.sdo[0x606E].raw, node.sdo[0x606F].raw, node.sdo[0x6070].raw = 100, 300, 10, 50
    node.tpdo.read()
    on_sync = mapped(node.tpdo[1], 0x6041, trans_type=1)
    on_change = mapped(node.tpdo[2], 0x6041, trans_type=255)
    node.tpdo.save()
    synced: queue.Queue[int] = queue.Queue()
    changed: list[int] = []
    on_sync.add_callback(lambda m: synced.put(m["Statusword"].raw))
    on_change.add_callback(lambda m: changed.append(m["Statusword"].raw))
    node.nmt.state = "OPERATIONAL"

    def sync() -> int:
        drive.master.sync.transmit()
        return synced.get(timeout=5)

    def last_change() -> int:
        assert node.sdo[0x1017].raw == 0  # (a round trip: the TPDOs sent before it have arrived)
        return changed[-1]

    for read, slack in ((sync, 0.002), (last_change, 0.012)):
        for target in (2000, 0):
            node.sdo[0x60FF].raw = target
            assert walk(drive, 1.0, target, windows, read, slack, running=target == 0) == [
                {0, TARGET_REACHED}, {0, SPEED_IS_0}]
        drive.runtime.advance(1.0)


def in_profile_velocity(node: Any) -> None:
    """Operation enabled (shutdown, switch on, enable operation) in profile velocity mode (6060h = 3)."""
    for word in (0x06, 0x07, 0x0F):
        node.sdo[0x6040].raw = word
    node.sdo[0x6060].raw = 3


@pytest.mark.parametrize("kind", DRIVES)
def test_every_drive_shows_its_own_velocity_against_the_target(kind: str) -> None:
    """For every kind that is a drive: in profile velocity mode, run up, run, stop, bits 10 and 12
    are what 606Ch against 60FFh, 606Dh and 606Fh make them (the times 0), as the master reads them
    (at one virtual instant, so 606Ch and 6041h see the same axis)."""
    drive = Drive(kind, 9, name=kind, ready=True)
    node = drive.node
    try:
        in_profile_velocity(node)
        node.sdo[0x606D].raw, node.sdo[0x606E].raw, node.sdo[0x606F].raw, node.sdo[0x6070].raw = 20, 0, 10, 0
        assert node.sdo[0x6041].raw & (TARGET_REACHED | SPEED_IS_0) == TARGET_REACHED | SPEED_IS_0  # standing
        seen = set()
        for target in (2000, -1500, 0):
            node.sdo[0x60FF].raw = target
            for _ in range(12):
                drive.runtime.advance(0.25)
                velocity, status = node.sdo[0x606C].raw, node.sdo[0x6041].raw
                reached, standing = abs(velocity - target) <= 20, abs(velocity) <= 10
                assert bool(status & TARGET_REACHED) == reached, (kind, target, velocity, hex(status))
                assert bool(status & SPEED_IS_0) == standing, (kind, target, velocity, hex(status))
                seen.add(standing)
        assert False in seen, kind  # (the axis ran)
    finally:
        drive.close()


def cyclic_master(kind: str) -> tuple[Drive, Any, Any]:
    """A ``kind`` in profile velocity mode, Operation enabled, OPERATIONAL, with RPDO1 = controlword
    (type 255, taken as it arrives) and RPDO2 = controlword and target velocity (type 1, taken at the
    next SYNC), as a master maps them to send them every SYNC."""
    drive = Drive(kind, 9, name=kind, ready=True)
    node = drive.node
    try:
        in_profile_velocity(node)
        node.rpdo.read()
        control = mapped(node.rpdo[1], 0x6040, trans_type=255)
        both = mapped(node.rpdo[2], 0x6040, 0x60FF, trans_type=1)
        node.rpdo.save()
        node.nmt.state = "OPERATIONAL"
    except BaseException:
        drive.close()
        raise
    return drive, control, both


def cycles(drive: Drive, control: Any, both: Any, target: int, count: int) -> None:
    """``count`` cycles of 50 ms, each with both RPDOs (controlword 0Fh, ``target``), the SYNC, and
    SDO writes of 6040h and 60FFh with the same values, 10 ms apart; after every one the axis runs
    at ``target`` (606Ch within 20 of it), Operation enabled, target reached."""
    node = drive.node
    control["Controlword"].raw = both["Controlword"].raw = 0x0F
    both["Target velocity"].raw = target

    def sdo_control() -> None:
        node.sdo[0x6040].raw = 0x0F

    def sdo_target() -> None:
        node.sdo[0x60FF].raw = target

    for cycle in range(count):
        for write in (control.transmit, both.transmit, drive.master.sync.transmit, sdo_control, sdo_target):
            write()
            drive.runtime.advance(0.010)
            velocity = node.sdo[0x606C].raw  # (a round trip: an RPDO sent before it has been taken)
            assert abs(velocity - target) <= 20, (drive.device.kind, target, cycle, write.__name__, velocity)
            assert node.sdo[0x6041].raw & (0x6F | TARGET_REACHED) == 0x27 | TARGET_REACHED


@pytest.mark.parametrize("kind", ["ip247", "sers"])
def test_an_unchanged_controlword_or_target_velocity_is_no_new_command(kind: str) -> None:
    """CiA 402-2, profile velocity mode: in Operation enabled the drive follows the target velocity
    (60FFh); a controlword that commands what is commanded already, or the target velocity written
    with the value it has, is no new command.  A master sending the controlword (RPDO1) and
    controlword and target velocity (RPDO2) every cycle, as at every SYNC, or writing them again one
    by one by SDO, leaves the axis running at the target at every cycle (the IP247 answers a second
    jog while one runs with its error 2, "Nicht erlaubter Auftrag … Beispiel: Starten einer bereits
    laufenden Achse.  Die laufende Betriebsart wird abgebrochen")."""
    drive, control, both = cyclic_master(kind)
    node = drive.node
    try:
        node.sdo[0x60FF].raw = 2000
        drive.runtime.advance(1.0)  # (run up)
        start = node.sdo[0x6064].raw
        cycles(drive, control, both, 2000, 40)
        assert node.sdo[0x6064].raw - start == pytest.approx(2000 * 2.0, abs=100), kind  # (ran all the time)
        node.sdo[0x6040].raw = 0x010F  # halt: the demand is 0, the axis stops …
        drive.runtime.advance(2.0)
        assert abs(node.sdo[0x606C].raw) <= 20, kind
        node.sdo[0x6040].raw = 0x000F  # … and runs at the target again as the halt is released
        drive.runtime.advance(1.0)
        cycles(drive, control, both, 2000, 10)
    finally:
        drive.close()


@pytest.mark.parametrize("kind", DRIVES)
def test_a_target_velocity_of_0_and_a_quick_stop_stop_every_drive(kind: str) -> None:
    """Profile velocity mode (CiA 402-2): the drive follows 60FFh, so 60FFh = 0 brings the axis to
    standstill (606Ch 0, 6064h no longer changing) and keeps it there; so does a quick stop
    (controlword 0Bh), after which the drive is in Switch on disabled (CiA 402-2 §8.4.3,
    transition 11 and the quick stop's end)."""
    drive = Drive(kind, 9, name=kind, ready=True)
    node = drive.node
    try:
        in_profile_velocity(node)
        for stop in ("60FFh = 0", "quick stop"):
            node.sdo[0x60FF].raw = -2000
            drive.runtime.advance(1.0)
            assert node.sdo[0x606C].raw < -100, (kind, stop)
            if stop == "quick stop":
                node.sdo[0x6040].raw = 0x0B
            else:
                node.sdo[0x60FF].raw = 0
            drive.runtime.advance(2.0)
            position = node.sdo[0x6064].raw
            assert node.sdo[0x606C].raw == 0, (kind, stop)
            drive.runtime.advance(1.0)
            assert node.sdo[0x6064].raw == position and node.sdo[0x606C].raw == 0, (kind, stop)
        assert node.sdo[0x6041].raw & 0x4F == 0x40, kind  # the quick stop over: Switch on disabled
    finally:
        drive.close()


def test_the_gms96_brakes_a_jog_to_0_with_its_own_ramp() -> None:
    """The GMS96 in profile velocity mode: 60FFh = 0 is the card's #0 Abbruch (manual §2.3.2), and
    the running jog brakes with the card's acceleration B, "Die Geschwindigkeit wird beim
    Beschleunigen pro Millisekunde maximal um diesen Wert erhöht. Sinusquadrat-Rampen benötigen
    (Faktor π/2) mehr Zeit" (manual §2.3.1 B): from v to standstill in v / B ms (× π/2 with N24's
    sin² ramps)."""
    drive = Drive("gms96", 9, name="gms96", ready=True)
    node = drive.node
    try:
        in_profile_velocity(node)
        node.sdo[0x60FF].raw = -2000
        drive.runtime.advance(1.0)
        running = actual(drive)
        assert running < -100
        b = drive.runtime.read("gms96", "param.B")  # Hz/ms
        sine = drive.runtime.call(lambda: drive.device.model.params.ramp_type) == 1
        braking = abs(running) / b / 1000 * (math.pi / 2 if sine else 1.0)
        node.sdo[0x60FF].raw = 0
        start = drive.runtime.now()
        assert scan(drive, lambda v: v == 0, 2.0) - start == pytest.approx(braking, abs=0.002)
        position = node.sdo[0x6064].raw
        drive.runtime.advance(1.0)
        assert node.sdo[0x6064].raw == position and node.sdo[0x606C].raw == 0
    finally:
        drive.close()


@pytest.mark.parametrize("kind", ["ip247", "sers"])
def test_a_changed_target_velocity_commands_the_drive(kind: str) -> None:
    """CiA 402-2, profile velocity mode: the drive follows a new target velocity, sent in the RPDO
    the master sends every cycle (taken at the SYNC): another speed, the other way, another speed
    again while the last change is still under way.  The IP247 cannot change the speed of a running jog ("Sie
    können die Geschwindigkeit während der Fahrt nicht ändern") but switches between its jog modes
    BA1 and BA2 while moving: "Die Achse hält dann an und führt anschließend ihre Bewegung in der
    neuen Tippenbetriebsart aus" (manual §4.2.1); a second BA1 would be its error 2."""
    drive, control, both = cyclic_master(kind)
    node = drive.node
    try:
        cycles(drive, control, both, 0, 2)
        both["Target velocity"].raw = 2000
        both.transmit()
        drive.master.sync.transmit()
        assert node.sdo[0x1017].raw == 0  # (a round trip: the RPDO has been taken)
        drive.runtime.advance(2.0)
        cycles(drive, control, both, 2000, 10)
        for target in (1000, -1500, 2500):
            both["Target velocity"].raw = target
            both.transmit()
            drive.master.sync.transmit()
            assert node.sdo[0x1017].raw == 0
            drive.runtime.advance(2.0)
            cycles(drive, control, both, target, 10)
        both["Target velocity"].raw = -1000
        both.transmit()
        drive.master.sync.transmit()
        assert node.sdo[0x1017].raw == 0  # (a round trip: the RPDO has been taken)
        drive.runtime.advance(0.0125)
        both["Target velocity"].raw = 1200  # while the axis brakes for the last change
        both.transmit()
        drive.master.sync.transmit()
        assert node.sdo[0x1017].raw == 0  # (a round trip: the RPDO has been taken)
        drive.runtime.advance(3.0)
        cycles(drive, control, both, 1200, 10)
        error = drive.runtime.call(lambda: drive.device.model.units[0].error) if kind == "ip247" else 0
        assert error == 0, kind
    finally:
        drive.close()


@pytest.mark.parametrize("leave", [0x07, 0x06, 0x00], ids=["disable operation", "shutdown", "disable voltage"])
@pytest.mark.parametrize("kind", DRIVES)
def test_out_of_operation_enabled_the_axis_does_not_run(kind: str, leave: int) -> None:
    """CiA 402-2 §8.4.1: in Switched on, Ready to switch on and Switch on disabled the drive
    function is disabled.  A jog in profile velocity mode, then disable operation (transition 5),
    shutdown (8) or disable voltage (9): the axis comes to a standstill and stays there; the
    statusword's bits 10 and 12 then say so (within the window of velocity 0, speed 0)."""
    drive = Drive(kind, 9, name=kind, ready=True)
    node = drive.node
    try:
        in_profile_velocity(node)
        node.sdo[0x60FF].raw = 2000
        drive.runtime.advance(1.5)
        assert node.sdo[0x606C].raw > 100, kind
        node.sdo[0x6040].raw = leave
        drive.runtime.advance(2.0)
        position = node.sdo[0x6064].raw
        assert node.sdo[0x606C].raw == 0, (kind, hex(leave))
        drive.runtime.advance(1.0)
        assert node.sdo[0x6064].raw == position, (kind, hex(leave))
        status = node.sdo[0x6041].raw
        assert status & 0x0004 == 0 and status & (TARGET_REACHED | SPEED_IS_0) == TARGET_REACHED | SPEED_IS_0, kind
    finally:
        drive.close()
