"""CiA 402 over CANopen for a kind that declares itself a drive (issue 13; the PCD4.H3's axis 1):
canopen's remote node as the master drives the state machine from Switch on disabled to
Operation enabled, runs a profile-position move that ends at the closed-form time of the
LM628's triangle (virtual time), runs in profile velocity mode, provokes a following error and
sees EMCY and the Fault state, and resets it."""

from __future__ import annotations

import queue
import time
import uuid
from pathlib import Path
from typing import Any

import canopen
import pytest

from devsim.facades.canopen_node import CanopenFacade
from devsim.runtime import Runtime
from tests.support.can import NOTIFIER_CYCLE
from tests.support.can import network as can_network

ROOT = Path(__file__).resolve().parents[2]


class Drive:
    """A device of ``kind`` as CANopen node ``node_id`` in a runtime (virtual time), canopen's
    remote node as the master, both on one python-can virtual bus.  ``ready`` first runs past the
    power-on initialisation and applies what the kind needs to move (``Device.drive_setup``)."""

    def __init__(self, kind: str = "pcd4h3", node_id: int = 3, *, name: str = "pcd", ready: bool = False,
                 config: dict[str, Any] | None = None) -> None:
        channel = f"devsim-{uuid.uuid4().hex}"
        self.runtime = Runtime(virtual=True).start()
        self.slave, self.master = can_network(), can_network()
        self.slave.connect(interface="virtual", channel=channel)
        self.master.connect(interface="virtual", channel=channel)
        try:
            self.device = self.runtime.add_device(kind, name, config or {})
            if ready:
                self.runtime.advance(3.0)
                self.runtime.call(self.device.apply_state, self.device.drive_setup)
            self.facade = CanopenFacade(self.device, node_id, call=self.runtime.call)
            self.node = self.master.add_node(node_id, str(ROOT / "docs" / "eds" / f"{kind}.eds"))
            self.facade.attach(self.slave)
        except BaseException:
            self.close()
            raise

    def __enter__(self) -> Drive:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def status(self) -> int:
        return int(self.node.sdo[0x6041].raw)

    def control(self, word: int) -> None:
        self.node.sdo[0x6040].raw = word

    def moving(self) -> bool:
        """Whether the device's axis moves (asked in the runtime's thread)."""
        return bool(self.runtime.call(self.device.drive.moving, self.device.model))

    def emcy(self, code: int) -> list[Any]:
        """The EMCY messages with ``code`` the master got, waiting (bounded) for the first: it
        crosses python-can's notifier thread."""
        deadline = time.monotonic() + 5
        while not [e for e in self.node.emcy.log if e.code == code] and time.monotonic() < deadline:
            self.node.emcy.wait(code, timeout=0.05)
        return [e for e in self.node.emcy.log if e.code == code]

    def close(self) -> None:
        self.slave.disconnect()
        self.master.disconnect()
        self.runtime.stop()


def enable(drive: Drive) -> None:
    assert drive.status & 0x4F == 0x40  # Switch on disabled
    drive.control(0x06)  # shutdown
    assert drive.status & 0x6F == 0x21  # Ready to switch on
    drive.control(0x07)  # switch on
    assert drive.status & 0x6F == 0x23  # Switched on
    drive.control(0x0F)  # enable operation
    assert drive.status & 0x6F == 0x27  # Operation enabled
    assert drive.runtime.read("pcd", "axis.1.motor_off") is False


def mapped(pdo: Any, *objects: int, **parameters: int) -> Any:
    """``pdo`` mapping ``objects`` in order, with its transmission ``parameters``
    (``trans_type``, ``event_timer``, ``inhibit_time``), enabled (saved by the caller)."""
    pdo.clear()
    for index in objects:
        pdo.add_variable(index)
    for name, value in parameters.items():
        setattr(pdo, name, value)
    pdo.enabled = True
    return pdo


def test_profile_position_move_at_the_closed_form_time(drive: Drive) -> None:
    enable(drive)
    drive.node.sdo[0x6060].raw = 1  # profile position
    drive.node.sdo[0x607A].raw = 100_000  # counts: 100 mm with k = 100
    drive.node.sdo[0x6081].raw = 50_000  # counts/s: Veloc 500, so the move is the 6.34 s triangle (§5.2)
    start = drive.runtime.now()
    drive.control(0x1F)  # new set-point
    assert drive.status & 0x1400 == 0x1000  # set-point acknowledged, target not reached
    drive.control(0x0F)
    assert drive.runtime.run_until(lambda: drive.device.read("axis.1.status") & 0x04, 10.0)  # trajectory complete
    assert drive.runtime.now() - start == pytest.approx(6.34, abs=0.05)
    drive.runtime.advance(0.5)
    assert drive.status & 0x0400 and abs(drive.node.sdo[0x6064].raw - 100_000) <= 3
    assert drive.node.sdo[0x6061].raw == 1


def test_profile_velocity_mode(drive: Drive) -> None:
    enable(drive)
    drive.node.sdo[0x6060].raw = 3  # profile velocity
    drive.node.sdo[0x60FF].raw = -20_000  # counts/s
    drive.control(0x0F)
    drive.runtime.advance(4.0)
    assert drive.node.sdo[0x606C].raw == pytest.approx(-20_000 * 0.999, rel=0.01)  # (341 µs vs 341.33 µs)
    drive.node.sdo[0x60FF].raw = 0
    drive.runtime.advance(4.0)
    assert abs(drive.node.sdo[0x606C].raw) < 50


def into_a_following_error(drive: Drive) -> None:
    """A move that a blockage stops until the PCD's following error (ExcPEr) ends it."""
    enable(drive)
    drive.node.sdo[0x607A].raw = 100_000
    drive.node.sdo[0x6081].raw = 50_000
    drive.control(0x1F)
    drive.runtime.advance(1.0)
    drive.runtime.fault("pcd", "blocked_1", True)
    assert drive.runtime.run_until(lambda: drive.runtime.read("pcd", "axis.1.ExcPEr"), 3.0)


def test_a_following_error_is_an_emcy_and_the_fault_state_then_reset(drive: Drive) -> None:
    into_a_following_error(drive)
    received = drive.emcy(0x8611)
    assert received and received[0].register & 0x01
    assert drive.status & 0x4F == 0x08  # Fault
    # CiA 402-2 603Fh: the EMCY's error code; CiA 301 1001h: bit 0 "at any error situation"
    assert drive.node.sdo[0x603F].raw == 0x8611
    assert drive.node.sdo[0x1001].raw & 0x01 == received[0].register & 0x01 == 0x01
    drive.runtime.fault("pcd", "blocked_1", False)
    drive.control(0x80)  # fault reset
    assert drive.status & 0x4F == 0x40  # Switch on disabled
    assert drive.node.sdo[0x603F].raw == 0 and drive.node.sdo[0x1001].raw == 0
    enable(drive)


def test_the_sers_as_a_402_drive() -> None:
    """The SERS declares its drive actions too: ON by Enable operation, an absolute WA … E by a
    new set-point (12 800 increments at 6 400 inc/s), a jog in profile velocity mode; an
    undervoltage error is the Fault state, cleared by a fault reset once the supply is back."""
    drive = Drive("sers", 2, name="sers", ready=True)
    runtime, device, node = drive.runtime, drive.device, drive.node
    try:
        for word, state in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):
            node.sdo[0x6040].raw = word
            assert node.sdo[0x6041].raw & 0x6F == state
        assert runtime.read("sers", "energized") is True
        node.sdo[0x607A].raw = 12_800
        node.sdo[0x6081].raw = 6_400
        node.sdo[0x6040].raw = 0x1F
        assert runtime.run_until(lambda: not device.read("motion"), 10.0)
        assert node.sdo[0x6064].raw == 12_800 and node.sdo[0x6041].raw & 0x0400
        node.sdo[0x6060].raw = 3
        node.sdo[0x60FF].raw = -3_200
        node.sdo[0x6040].raw = 0x0F
        runtime.advance(2.0)
        assert node.sdo[0x606C].raw == -3_200
        runtime.set("sers", "quantity.supply_voltage", 40.0)  # below U_L: a drive error
        runtime.advance(0.5)
        assert node.sdo[0x6041].raw & 0x4F == 0x08
        assert drive.emcy(0x3220)  # DC link undervoltage
        runtime.set("sers", "quantity.supply_voltage", 68.0)
        node.sdo[0x6040].raw = 0x80
        assert node.sdo[0x6041].raw & 0x4F == 0x40
    finally:
        drive.close()


def test_switch_on_and_enable_operation_in_one_controlword() -> None:
    """CiA 402-2's command coding "switch on + enable operation": 0x0F sent in Ready to switch on
    makes transitions 3 and 4 at once, over a real bus (the SERS's power stage on, as by 0x07,
    0x0F)."""
    drive = Drive("sers", 2, name="sers", ready=True)
    runtime, node = drive.runtime, drive.node
    try:
        node.sdo[0x6040].raw = 0x06
        assert node.sdo[0x6041].raw & 0x6F == 0x21 and runtime.read("sers", "energized") is False
        node.sdo[0x6040].raw = 0x0F
        assert node.sdo[0x6041].raw & 0x6F == 0x27  # Operation enabled
        assert runtime.read("sers", "energized") is True
    finally:
        drive.close()


def test_the_poselesta_x_axis_as_a_402_drive() -> None:
    """The CNC's X axis: enabled by the axis enable, a target as a Hand-Einzelsatz block started
    with NC-Start (G01 X10 F3000: 50 mm/s with 500 mm/s² ramps reach 10 mm after 10/50 + 50/500 =
    0.3 s), a jog as the X+ key, a following-error alarm as EMCY 8611h and the Fault state until
    the alarm ends."""
    drive = Drive("poselesta", 4, name="cnc", ready=True)
    runtime, device, node = drive.runtime, drive.device, drive.node
    try:
        for word, state in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):
            node.sdo[0x6040].raw = word
            assert node.sdo[0x6041].raw & 0x6F == state
        assert device.read("input.axis_enable") is True
        node.sdo[0x6060].raw = 1
        node.sdo[0x607A].raw = 10_000  # increments of 1 µm
        node.sdo[0x6081].raw = 50_000  # 50 mm/s = F3000
        start = runtime.now()
        node.sdo[0x6040].raw = 0x1F
        assert device.read("panel.mode") == "MANUAL_SINGLE_BLOCK"
        assert device.read("panel.mdi") == "N1 G90 G01 X10.000 F3000"
        runtime.advance(0.29)
        assert node.sdo[0x6064].raw < 10_000 and not node.sdo[0x6041].raw & 0x0400
        runtime.advance(0.02)
        assert device.events[-1] == (pytest.approx(start + 0.3), "position_reached")
        assert node.sdo[0x6064].raw == 10_000 and node.sdo[0x6041].raw & 0x0400
        runtime.run_until(lambda: device.read("program.state") == "END", 5.0)
        node.sdo[0x6060].raw = 3
        node.sdo[0x60FF].raw = 1
        node.sdo[0x6040].raw = 0x0F
        assert device.read("panel.mode") == "MANUAL" and device.read("output.travel_x") is True
        runtime.advance(1.0)
        assert node.sdo[0x606C].raw > 0 and node.sdo[0x6064].raw > 10_000
        node.sdo[0x60FF].raw = 0
        runtime.advance(1.0)
        assert node.sdo[0x606C].raw == 0
        runtime.fault("cnc", "following_error", True)
        assert node.sdo[0x6041].raw & 0x4F == 0x08
        assert drive.emcy(0x8611)
        node.sdo[0x6040].raw = 0x80
        assert node.sdo[0x6041].raw & 0x4F == 0x08  # the alarm is still there
        runtime.fault("cnc", "following_error", False)
        node.sdo[0x6040].raw = 0x00
        node.sdo[0x6040].raw = 0x80  # a fault reset is bit 7's rising edge
        assert node.sdo[0x6041].raw & 0x4F == 0x40
    finally:
        drive.close()


def test_pdos_carry_the_controlword_and_the_statusword(drive: Drive) -> None:
    """The master maps RPDO1 = controlword and TPDO1 = statusword + position actual value on every
    SYNC, starts the node, and drives the state machine by PDO alone."""
    node = drive.node
    node.tpdo.read()
    node.rpdo.read()
    tpdo = mapped(node.tpdo[1], 0x6041, 0x6064, trans_type=1)
    rpdo = mapped(node.rpdo[1], 0x6040, trans_type=255)
    node.tpdo.save()
    node.rpdo.save()
    arrived: queue.Queue[tuple[int, int]] = queue.Queue()
    tpdo.add_callback(lambda m: arrived.put((m["Statusword"].raw, m["Position actual value"].raw)))
    node.nmt.state = "OPERATIONAL"

    def sync() -> tuple[int, int]:
        drive.master.sync.transmit()  # (frames on the bus are handled in order: the RPDOs before)
        return arrived.get(timeout=5)

    assert sync()[0] & 0x4F == 0x40
    for word, state in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):
        rpdo["Controlword"].raw = word
        rpdo.transmit()
        status, position = sync()
        assert status & 0x6F == state and position == 0


def test_a_gms96_following_error_is_an_emcy_and_the_fault_state() -> None:
    """The GMS96's blocked axis: the following error trips N20, IDXOFF: EMCY 8611h; the drive
    shows Switched on (the controller is off), not Operation enabled."""
    drive = Drive("gms96", 4, name="card", ready=True)
    runtime, device, node = drive.runtime, drive.device, drive.node
    try:
        for word in (0x06, 0x07, 0x0F):
            node.sdo[0x6040].raw = word
        assert node.sdo[0x6041].raw & 0x6F == 0x27
        node.sdo[0x607A].raw = 100_000
        node.sdo[0x6040].raw = 0x1F
        runtime.advance(0.2)
        runtime.fault("card", "blocked_axis", True)
        assert runtime.run_until(lambda: device.model.stage.idxoff, 10.0)
        assert drive.emcy(0x8611)
        assert node.sdo[0x6041].raw & 0x6F == 0x23  # the controller switched itself off
    finally:
        drive.close()


def event_timer_tpdo(drive: Drive, index: int, name: str) -> queue.Queue[int]:
    """TPDO2 mapping object ``index`` (``name`` in the EDS), transmission type 255 with an event
    timer of 100 ms; the values the master receives."""
    node = drive.node
    node.tpdo.read()
    tpdo = mapped(node.tpdo[2], index, trans_type=255, event_timer=100)
    node.tpdo.save()
    arrived: queue.Queue[int] = queue.Queue()
    tpdo.add_callback(lambda m: arrived.put(m[name].raw))
    return arrived


def test_an_event_driven_tpdo_goes_out_every_event_timer_period(drive: Drive) -> None:
    """TPDO2 with transmission type 255 and an event timer of 100 ms: one every 100 ms of device
    time (virtual here), with the position as it moves."""
    node = drive.node
    arrived = event_timer_tpdo(drive, 0x6064, "Position actual value")
    node.nmt.state = "OPERATIONAL"
    assert drive.node.sdo[0x1017].raw == 0  # (an SDO round trip: the NMT command was handled before it)
    drive.runtime.advance(0.35)
    assert [arrived.get(timeout=5) for _ in range(3)] == [0, 0, 0]
    node.nmt.state = "PRE-OPERATIONAL"
    assert drive.node.sdo[0x1017].raw == 0
    drive.runtime.advance(0.5)
    assert drive.node.sdo[0x1017].raw == 0  # (a round trip after any TPDO the advance could have sent)
    assert arrived.empty()  # stopped with OPERATIONAL


def test_a_bus_that_goes_down_loses_messages_and_the_drive_goes_on(drive: Drive,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """The node's CAN controller cannot transmit (a SocketCAN interface down, bus-off: python-can
    raises ``CanError``; here its bus is shut): its TPDOs and the EMCY of a following error are
    lost and counted, the drive goes into its fault all the same, and the event-driven TPDO goes
    out again once the node is on a bus again."""
    import can

    node = drive.node
    arrived = event_timer_tpdo(drive, 0x6041, "Statusword")
    enable(drive)
    node.sdo[0x607A].raw = 100_000
    node.sdo[0x6081].raw = 50_000  # a move of 6.34 s (test_profile_position_move_at_the_closed_form_time)
    drive.control(0x1F)
    drive.control(0x0F)
    node.nmt.state = "OPERATIONAL"
    assert node.sdo[0x1017].raw == 0  # (a round trip: the NMT command was handled before it)
    drive.runtime.advance(0.35)
    moving = [arrived.get(timeout=5) for _ in range(3)]  # every 100 ms, the statusword standing
    assert len(set(moving)) == 1 and moving[0] & 0x6F == 0x27
    channel = drive.slave.bus.channel_id
    drive.slave.notifier.stop()  # (its reader first: one reading a closed bus ends with an error)
    drive.slave.bus.shutdown()  # the node's controller is off the bus
    drive.runtime.advance(0.5)  # five TPDOs lost
    drive.runtime.fault("pcd", "blocked_1", True)
    assert drive.runtime.run_until(lambda: drive.runtime.read("pcd", "axis.1.ExcPEr"), 3.0)  # its EMCY: lost
    assert drive.facade.lost >= 7 and arrived.empty()  # (and the statusword's change to Fault)
    # On a bus again: a new bus, and a reader for it.
    drive.slave.bus = can.Bus(interface="virtual", channel=channel)
    drive.slave.notifier = can.Notifier(drive.slave.bus, drive.slave.listeners, NOTIFIER_CYCLE)
    drive.runtime.advance(0.35)
    fault = [arrived.get(timeout=5) for _ in range(3)]  # the event timer ran on
    assert fault[0] & 0x4F == 0x08 and len(set(fault)) == 1
    assert capsys.readouterr().err.splitlines() == [
        "devsim: pcd.canopen: the bus refused a message (Cannot operate on a closed bus); messages are lost until"
        " it takes them again", f"devsim: pcd.canopen: the bus takes messages again ({drive.facade.lost} lost so far)"]


def test_an_event_driven_tpdo_goes_out_when_its_values_change(drive: Drive) -> None:
    """TPDO3 with transmission type 254, no event timer and an inhibit time of 50 ms (500 × 100 µs):
    nothing while the drive stands, the statusword as soon as it changes, then the position at
    most every 50 ms of device time while the axis moves, and silence again after it stopped."""
    node = drive.node
    node.tpdo.read()
    tpdo = mapped(node.tpdo[3], 0x6041, 0x6064, trans_type=254, inhibit_time=500, event_timer=0)
    node.tpdo.save()
    arrived: queue.Queue[tuple[int, int]] = queue.Queue()
    tpdo.add_callback(lambda m: arrived.put((m["Statusword"].raw, m["Position actual value"].raw)))
    node.nmt.state = "OPERATIONAL"
    assert node.sdo[0x1017].raw == 0  # (a round trip: the NMT command was handled before it)
    drive.runtime.advance(1.0)
    assert node.sdo[0x1017].raw == 0
    assert arrived.empty()  # no change, no TPDO
    enable(drive)
    drive.runtime.advance(0.05)
    assert arrived.get(timeout=5)[0] & 0x6F == 0x27  # the statusword changed to Operation enabled
    node.sdo[0x6060].raw = 1
    node.sdo[0x607A].raw = 20_000
    node.sdo[0x6081].raw = 10_000
    start = drive.runtime.now()
    node.sdo[0x6040].raw = 0x1F
    assert drive.runtime.run_until(lambda: not drive.device.drive.moving(drive.device.model), 30.0)
    moved = drive.runtime.now() - start
    drive.runtime.advance(1.0)  # the loop hunts about its target for up to about 0.8 s after the profile ends
    assert node.sdo[0x1017].raw == 0
    seen = []
    while not arrived.empty():
        seen.append(arrived.get())
    positions = [position for _, position in seen]
    assert positions[-1] == node.sdo[0x6064].raw  # the last change (the settled loop) went out
    assert any(1_000 < position < 19_000 for position in positions)  # and changes along the way
    assert moved > 1.0 and 10 <= len(seen) <= (moved + 1.0) / 0.05 + 1  # each 50 ms apart at least
    drive.runtime.advance(1.0)
    assert node.sdo[0x1017].raw == 0
    assert arrived.empty()  # standing again: silent


def test_halt_stops_a_profile_position_move_short_of_its_target(drive: Drive) -> None:
    """CiA 402-2 §12, controlword bit 8 (halt) in profile position mode: the axis is stopped with
    the ramp, in Operation enabled; the statusword's bit 10 then says it stands."""
    enable(drive)
    drive.node.sdo[0x607A].raw = 100_000
    drive.node.sdo[0x6081].raw = 50_000
    drive.control(0x1F)
    drive.runtime.advance(1.0)
    drive.control(0x11F)  # halt
    assert drive.runtime.run_until(lambda: drive.device.read("axis.1.status") & 0x04, 5.0)  # trajectory complete
    drive.runtime.advance(0.5)
    stopped = drive.node.sdo[0x6064].raw
    assert 0 < stopped < 60_000  # (1 s into the 6.34 s move; the triangle's half is 50 000)
    assert drive.status & 0x6F == 0x27 and drive.status & 0x0400  # Operation enabled, standing
    drive.runtime.advance(2.0)
    assert drive.node.sdo[0x6064].raw == stopped


def test_a_fault_reset_that_clears_the_fault_sends_the_error_reset_emcy(drive: Drive) -> None:
    """CiA 301 §7.2.7 (the EMCY producer's states error free / error occurred): when the errors
    are gone the node sends an EMCY with error code 0000h ("error reset or no error") and the
    error register as it is then; a fault reset that leaves the fault sends none."""
    into_a_following_error(drive)
    assert drive.emcy(0x8611)
    drive.control(0x0F)
    drive.control(0x80)  # fault reset, the blockage still there: the fault is cleared by FResSF
    assert drive.status & 0x4F == 0x40
    resets = drive.emcy(0x0000)
    assert len(resets) == 1 and resets[0].register == 0x00
    assert [e.code for e in drive.node.emcy.log] == [0x8611, 0x0000]
    drive.control(0x00)
    drive.control(0x80)  # a fault reset with no fault: no EMCY
    assert drive.node.sdo[0x6041].raw & 0x4F == 0x40 and len(drive.node.emcy.log) == 2


def test_a_synchronous_acyclic_tpdo_goes_out_at_the_sync_after_a_change(drive: Drive) -> None:
    """CiA 301 §7.5.2.35, TPDO transmission type 0 (synchronous, acyclic): sent at a SYNC when its
    values changed since it was last sent, not at the SYNCs between."""
    node = drive.node
    node.tpdo.read()
    tpdo = mapped(node.tpdo[1], 0x6041, trans_type=0)
    node.tpdo.save()
    arrived: queue.Queue[int] = queue.Queue()
    tpdo.add_callback(lambda m: arrived.put(m["Statusword"].raw))
    node.nmt.state = "OPERATIONAL"

    def syncs(count: int) -> list[int]:
        for _ in range(count):
            drive.master.sync.transmit()
        assert node.sdo[0x1017].raw == 0  # (a round trip: the SYNCs were handled before it)
        seen = []
        while not arrived.empty():
            seen.append(arrived.get())
        return seen

    assert syncs(3) == []  # no change
    drive.control(0x06)
    assert [word & 0x6F for word in syncs(3)] == [0x21]  # once, at the first SYNC after the change
    assert syncs(2) == []


@pytest.mark.parametrize("trans_type", [241, 245, 251, 252, 253])
def test_a_transmission_type_the_node_does_not_serve_is_refused(drive: Drive, trans_type: int) -> None:
    """CiA 301 §7.5.2.35: 241 … 251 are reserved, 252/253 (RTR only) need remote frames the node does
    not serve; writing one into a TPDO's sub-index 02h is aborted 0609 0030h (value range exceeded)
    and the type stays, rather than a PDO that never goes out."""
    with pytest.raises(canopen.SdoAbortedError) as refused:
        drive.node.sdo[0x1800][2].raw = trans_type
    assert refused.value.code == 0x06090030
    assert drive.node.sdo[0x1800][2].raw == 0xFF
    if trans_type <= 251:
        with pytest.raises(canopen.SdoAbortedError):
            drive.node.sdo[0x1400][2].raw = trans_type
