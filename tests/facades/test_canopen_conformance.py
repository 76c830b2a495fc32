"""A CANopen node that conforms (issue 29), checked with canopen as the master on python-can's
virtual bus: CiA 402's modes of operation (6060h takes only a mode 6502h lists, 6061h never shows
another), CiA 301's NMT resets (reset communication restores 1000h … 1FFFh, reset node the 402
objects too, one boot-up each), and SDO aborts that name the request they answer."""

from __future__ import annotations

import queue
import struct
from collections.abc import Callable
from pathlib import Path

import canopen
import pytest

from tests.facades.test_cia402 import Drive, mapped

ROOT = Path(__file__).resolve().parents[2]
VALUE_RANGE_EXCEEDED = 0x06090030  # CiA 301 SDO abort: value range of parameter exceeded

#: CiA 402-2, 6502h "supported drive modes": the bit of each mode of operation (6060h value).
MODE_BITS = {1: 0, 2: 1, 3: 2, 4: 3, 6: 5, 7: 6, 8: 7, 9: 8, 10: 9}


def test_6060h_takes_only_the_modes_6502h_lists_and_6061h_shows_no_other(drive: Drive) -> None:
    node = drive.node
    supported = node.sdo[0x6502].raw
    assert supported & (1 << MODE_BITS[1]) and supported & (1 << MODE_BITS[3])  # pp and pv: every drive here
    assert not supported & (1 << MODE_BITS[6])  # no homing mode
    shown = node.sdo[0x6061].raw
    for mode in (-1, 0, *range(1, 11), 127):
        bit = MODE_BITS.get(mode)
        if bit is not None and supported >> bit & 1:
            node.sdo[0x6060].raw = mode
            shown = mode
        else:
            with pytest.raises(canopen.SdoAbortedError) as refused:
                node.sdo[0x6060].raw = mode
            assert refused.value.code == VALUE_RANGE_EXCEEDED, mode
        assert node.sdo[0x6061].raw == shown, mode
    node.sdo[0x6060].raw = 1
    # an RPDO carrying an unsupported mode changes nothing either
    node.rpdo.read()
    rpdo = mapped(node.rpdo[1], 0x6060, trans_type=255)
    node.rpdo.save()
    node.nmt.state = "OPERATIONAL"
    rpdo["Modes of operation"].raw = 3
    rpdo.transmit()
    assert node.sdo[0x6061].raw == 3  # (frames on the bus are handled in order: the RPDO before the SDO)
    rpdo["Modes of operation"].raw = 6
    rpdo.transmit()
    assert node.sdo[0x6061].raw == 3
    assert node.sdo[0x6060].raw == 3


class Bootups:
    """The boot-up messages (CiA 301: COB-ID 700h + node id, one data byte 00h) the master sees from
    node ``node_id``; heartbeats (the NMT state, never 00h) are counted apart."""

    def __init__(self, drive: Drive, node_id: int = 3) -> None:
        self.frames: queue.Queue[bytes] = queue.Queue()
        drive.master.subscribe(0x700 + node_id, lambda can_id, data, timestamp: self.frames.put(bytes(data)))
        assert drive.node.sdo[0x1000].raw  # (a round trip: the boot-up of the attach went by before it)
        self.count()

    def count(self) -> int:
        """Boot-ups since the last count (after an SDO round trip, everything the node sent before
        it has been handled)."""
        seen = []
        while not self.frames.empty():
            seen.append(self.frames.get())
        return seen.count(b"\x00")


def configure(drive: Drive) -> None:
    """What a master writes during start-up: a heartbeat, TPDO1 = statusword on every SYNC, RPDO1 =
    controlword, and the 402 objects away from their power-on values, the drive enabled."""
    node = drive.node
    node.sdo[0x1017].raw = 20
    node.rpdo.read()
    mapped(node.rpdo[1], 0x6040, trans_type=255)
    node.rpdo.save()
    node.tpdo.read()
    mapped(node.tpdo[1], 0x6041, trans_type=1)
    node.tpdo.save()
    node.sdo[0x6060].raw = 3
    node.sdo[0x607A].raw = 1234
    node.sdo[0x6081].raw = 777
    node.sdo[0x60FF].raw = 5
    for word in (0x06, 0x07, 0x0F):
        node.sdo[0x6040].raw = word
    assert node.sdo[0x6041].raw & 0x6F == 0x27  # Operation enabled
    assert node.sdo[0x1A00][0].raw == 1 and node.sdo[0x1800][2].raw == 1


def test_reset_communication_restores_the_communication_objects_and_boots_once(drive: Drive) -> None:
    """CiA 301: reset communication sets 1000h … 1FFFh to their power-on values (the EDS's
    defaults: no heartbeat, the predefined PDO set unmapped) and boots (one boot-up message,
    then PRE-OPERATIONAL); the application (the 402 objects, the enabled drive) is untouched."""
    node = drive.node
    od = canopen.import_od(str(ROOT / "docs" / "eds" / "pcd4h3.eds"), 3)
    bootups = Bootups(drive)
    configure(drive)
    assert node.nmt.wait_for_heartbeat(5) == "PRE-OPERATIONAL"
    node.nmt.state = "OPERATIONAL"
    for word, state in ((0x07, 0x23), (0x0F, 0x27)):  # RPDO1 is taken in OPERATIONAL
        node.rpdo[1]["Controlword"].raw = word
        node.rpdo[1].transmit()
        assert node.sdo[0x6041].raw & 0x6F == state
    node.nmt.send_command(0x82)  # reset communication
    assert node.sdo[0x1017].raw == od[0x1017].default == 0
    assert bootups.count() == 1
    for index, sub in ((0x1800, 1), (0x1800, 2), (0x1800, 5), (0x1A00, 0), (0x1A00, 1)):
        assert node.sdo[index][sub].raw == od[index][sub].default, (hex(index), sub)
    assert node.sdo[0x6061].raw == 3 and node.sdo[0x607A].raw == 1234  # the application objects stay
    assert node.sdo[0x6041].raw & 0x6F == 0x27
    node.rpdo[1]["Controlword"].raw = 0x00  # disable voltage, by a PDO the reset unmapped
    node.rpdo[1].transmit()
    assert node.sdo[0x6041].raw & 0x6F == 0x27  # not taken
    node.sdo[0x1017].raw = 20
    assert node.nmt.wait_for_heartbeat(5) == "PRE-OPERATIONAL"
    drive.master.send_message(0, [0x82, 0])  # reset communication of all nodes
    assert node.sdo[0x1017].raw == 0 and bootups.count() == 1


def test_reset_node_also_restores_the_402_objects_and_disables_the_drive(drive: Drive) -> None:
    """CiA 301: reset node resets the application (2000h … 9FFFh: here the 402 objects to the
    EDS's power-on values, the drive disabled, the state machine in Switch on disabled) and then
    the communication, with one boot-up message."""
    node = drive.node
    od = canopen.import_od(str(ROOT / "docs" / "eds" / "pcd4h3.eds"), 3)
    bootups = Bootups(drive)
    configure(drive)
    assert drive.runtime.read("pcd", "axis.1.motor_off") is False
    node.nmt.state = "OPERATIONAL"
    node.nmt.send_command(0x81)  # reset node
    assert node.sdo[0x6041].raw & 0x4F == 0x40  # Switch on disabled
    assert bootups.count() == 1
    assert drive.runtime.read("pcd", "axis.1.motor_off") is True
    for index in (0x6040, 0x6060, 0x607A, 0x6081, 0x60FF):
        assert node.sdo[index].raw == od[index].default, hex(index)
    assert node.sdo[0x6061].raw == od[0x6060].default
    assert node.sdo[0x1017].raw == 0 and node.sdo[0x1A00][0].raw == od[0x1A00][0].default
    node.sdo[0x1017].raw = 20
    assert node.nmt.wait_for_heartbeat(5) == "PRE-OPERATIONAL"
    for word, state in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):  # and it runs the 402 flow again
        node.sdo[0x6040].raw = word
        assert node.sdo[0x6041].raw & 0x6F == state
    node.nmt.send_command(0x81)
    assert node.sdo[0x6041].raw & 0x4F == 0x40 and bootups.count() == 1


def test_a_power_cycle_of_the_device_boots_the_node_out_of_its_fault() -> None:
    """A drive switched off and on boots as a node does at power-on: one boot-up message, the
    communication and 402 objects at their power-on values, Switch on disabled (not the Fault it
    was in before: the device's fault went with the power), and the 402 flow enables it again."""
    drive = Drive("sers", 3, name="sers", ready=True)
    runtime, node = drive.runtime, drive.node
    try:
        bootups = Bootups(drive)
        node.sdo[0x1017].raw = 20
        runtime.set("sers", "quantity.supply_voltage", 40.0)  # below U_L: a drive error
        runtime.advance(0.5)
        assert node.sdo[0x6041].raw & 0x4F == 0x08  # Fault
        runtime.set("sers", "quantity.supply_voltage", 68.0)
        runtime.power_cycle("sers")
        assert node.sdo[0x1017].raw == 0 and node.sdo[0x6041].raw & 0x4F == 0x40  # Switch on disabled
        assert bootups.count() == 1  # (counted after the SDO round trips: it came before their answers)
        runtime.advance(3.0)  # the SERS's 2 s power-on
        runtime.call(drive.device.apply_state, drive.device.drive_setup)
        for word, state in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):
            node.sdo[0x6040].raw = word
            assert node.sdo[0x6041].raw & 0x6F == state, hex(word)
    finally:
        drive.close()


@pytest.mark.parametrize("kind", ["gms96", "ip247", "pcd4h3", "poselesta", "sers"])
def test_every_kind_boots_its_node_when_it_powers_up(kind: str) -> None:
    """The model announces its power-up (a power cycle; the end of a ``power`` fault, where the
    kind declares one): the node sends one boot-up message each time and drops what the master
    wrote into its communication objects."""
    drive = Drive(kind, 3, name="dev")
    try:
        bootups = Bootups(drive)
        drive.node.sdo[0x1017].raw = 20
        drive.runtime.power_cycle("dev")
        assert drive.node.sdo[0x1017].raw == 0 and bootups.count() == 1
        if "power" in drive.device.faults.names():
            drive.node.sdo[0x1017].raw = 20
            drive.runtime.fault("dev", "power", True)
            drive.runtime.fault("dev", "power", False)
            assert drive.node.sdo[0x1017].raw == 0 and bootups.count() == 1
    finally:
        drive.close()


def test_every_sdo_abort_names_the_request_it_answers(drive: Drive) -> None:
    """CiA 301: an abort transfer request carries the multiplexer (index, sub-index) of the
    transfer it ends.  Each case follows a successful upload of 1000h, so an abort that named the
    last object used instead would show 1000h/00h."""
    node = drive.node
    answers: queue.Queue[bytes] = queue.Queue()
    drive.master.subscribe(0x583, lambda can_id, data, timestamp: answers.put(bytes(data)))
    write_only = next(i for i, p in drive.facade.objects.items() if p.settable and not p.readable)

    def aborted(request: Callable[[], object]) -> tuple[int, int, int]:
        assert node.sdo.upload(0x1000, 0) and answers.get(timeout=5)[0] == 0x43
        with pytest.raises(canopen.SdoAbortedError) as refused:
            request()
        while (frame := answers.get(timeout=5))[0] != 0x80:  # (the segments before the abort)
            pass
        _, index, subindex, code = struct.unpack("<BHBL", frame)
        assert code == refused.value.code
        return index, subindex, code

    raw = node.sdo.request_response
    cases: list[tuple[Callable[[], object], tuple[int, int, int]]] = [
        (lambda: node.sdo.upload(0x5FFF, 0), (0x5FFF, 0, 0x06020000)),  # object does not exist
        (lambda: node.sdo.download(0x5FFF, 0, b"\0\0\0\0"), (0x5FFF, 0, 0x06020000)),
        (lambda: node.sdo.upload(0x1018, 7), (0x1018, 7, 0x06090011)),  # sub-index does not exist
        (lambda: node.sdo.download(0x1800, 9, b"\0"), (0x1800, 9, 0x06090011)),
        (lambda: node.sdo.upload(write_only, 0), (write_only, 0, 0x06010001)),  # write-only
        (lambda: node.sdo.download(0x1000, 0, b"\1\2\3\4"), (0x1000, 0, 0x06010002)),  # read-only
        (lambda: node.sdo.download(0x1008, 0, b"a longer name", force_segment=True), (0x1008, 0, 0x06010002)),
        (lambda: node.sdo.download(0x6081, 0, b"\1\2"), (0x6081, 0, 0x06070010)),  # length
        (lambda: node.sdo.download(0x607A, 0, b"\1\2\3\4\5\6", force_segment=True), (0x607A, 0, 0x06070010)),
        (lambda: node.sdo.download(0x6060, 0, b"\x06"), (0x6060, 0, VALUE_RANGE_EXCEEDED)),  # value
        (lambda: node.sdo.download(0x6060, 0, b"\x06", force_segment=True), (0x6060, 0, VALUE_RANGE_EXCEEDED)),
        (lambda: raw(bytes((0xE0, 0x34, 0x12, 0x05, 0, 0, 0, 0))), (0x1234, 5, 0x05040001)),  # no such command
        (lambda: raw(bytes((0xA4, 0x41, 0x60, 0x00, 0x7F, 0, 0, 0))), (0x6041, 0, 0x05040001)),  # block upload
        (lambda: raw(bytes((0xC6, 0x7A, 0x60, 0x00, 4, 0, 0, 0))), (0x607A, 0, 0x05040001)),  # block download
        (lambda: raw(bytes((0x60, 0x34, 0x12, 0x05, 0, 0, 0, 0))), (0, 0, 0x05040001)),  # a segment, no transfer
    ]
    for request, expected in cases:
        assert aborted(request) == expected
    # a toggle error ends the segmented upload of 1008h it interrupts
    assert raw(bytes((0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0)))[0] == 0x41 and answers.get(timeout=5)
    assert raw(bytes((0x60, 0, 0, 0, 0, 0, 0, 0)))[0] == 0x00 and answers.get(timeout=5)  # toggle 0
    with pytest.raises(canopen.SdoAbortedError) as refused:
        raw(bytes((0x60, 0, 0, 0, 0, 0, 0, 0)))  # toggle 0 again
    assert refused.value.code == 0x05030000
    assert struct.unpack("<BHBL", answers.get(timeout=5)) == (0x80, 0x1008, 0, 0x05030000)
    assert node.sdo[0x1008].raw == "devsim pcd4h3"  # and the server goes on


def heartbeat(node: canopen.RemoteNode, state: str) -> bool:
    """A heartbeat showing ``state`` comes within a few (one sent before the command may be on its way)."""
    return any(node.nmt.wait_for_heartbeat(5) == state for _ in range(5))


def test_a_stopped_node_answers_no_sdo_and_sends_no_emcy(drive: Drive) -> None:
    """CiA 301 §7.3.2.2 (the NMT states and the communication objects each one serves): in
    STOPPED only NMT and the error control (heartbeat) work; SDO and EMCY are served in
    PRE-OPERATIONAL and OPERATIONAL.  A request sent while stopped gets no answer (the answers
    counted after a round trip in PRE-OPERATIONAL, which frames on the bus are handled in order
    before), and a fault announced while stopped sends no EMCY."""
    node = drive.node
    answers: queue.Queue[bytes] = queue.Queue()
    emcys: queue.Queue[bytes] = queue.Queue()
    drive.master.subscribe(0x583, lambda can_id, data, timestamp: answers.put(bytes(data)))
    drive.master.subscribe(0x83, lambda can_id, data, timestamp: emcys.put(bytes(data)))
    node.sdo[0x1017].raw = 20
    assert answers.get(timeout=5)[0] == 0x60
    node.nmt.state = "STOPPED"
    assert heartbeat(node, "STOPPED")
    drive.master.send_message(0x603, bytes((0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0)))  # upload 1000h
    drive.master.send_message(0x603, bytes((0x2B, 0x17, 0x10, 0x00, 50, 0, 0, 0)))  # download 1017h
    drive.runtime.call(drive.facade._emergency, 1, 0x8611)  # the model announces a fault
    node.nmt.state = "PRE-OPERATIONAL"
    assert heartbeat(node, "PRE-OPERATIONAL")
    assert node.sdo[0x1017].raw == 20  # the download while stopped was not carried out
    seen = []
    while not answers.empty():
        seen.append(answers.get())
    assert [frame[0] for frame in seen] == [0x4B]  # the round trip's answer alone
    assert emcys.empty()
    drive.runtime.call(drive.facade._emergency, 1, 0x8611)  # in PRE-OPERATIONAL it goes out
    assert drive.emcy(0x8611)


MAPPING_ERRORS = {
    "no object": 0x06020000,  # object does not exist in the object dictionary
    "cannot be mapped": 0x06040041,  # object cannot be mapped to the PDO
    "too long": 0x06040042,  # the number and length of the objects to be mapped would exceed PDO length
}


def test_a_pdo_mapping_takes_only_what_the_eds_lets_be_mapped(drive: Drive) -> None:
    """CiA 301 §7.5.2.36 / §7.5.2.38 (RPDO / TPDO mapping parameter, the re-mapping procedure): an
    entry naming an object that does not exist is aborted 0602 0000h, one that cannot be mapped
    (PDOMapping=0 in the EDS, a length other than the object's, a read-only object in an RPDO)
    0604 0041h, and enabling a mapping (sub-index 00h) whose objects exceed the PDO's 64 bits or its
    8 entries 0604 0042h; nothing refused is kept, and a mapping that is accepted works."""
    node = drive.node

    def refused(index: int, subindex: int, value: int, size: int = 4) -> int:
        with pytest.raises(canopen.SdoAbortedError) as aborted:
            node.sdo.download(index, subindex, value.to_bytes(size, "little"))
        return aborted.value.code

    node.sdo[0x1800][1].raw = 0x80000183  # TPDO1 not valid
    node.sdo[0x1A00][0].raw = 0  # mapping disabled
    assert refused(0x1A00, 1, 0x5FFF0010) == MAPPING_ERRORS["no object"]
    assert refused(0x1A00, 1, 0x10170010) == MAPPING_ERRORS["cannot be mapped"]  # heartbeat time: PDOMapping=0
    assert refused(0x1A00, 1, 0x65020020) == MAPPING_ERRORS["cannot be mapped"]  # 6502h: PDOMapping=0
    assert refused(0x1A00, 1, 0x60410020) == MAPPING_ERRORS["cannot be mapped"]  # statusword is 16 bits
    assert refused(0x1600, 1, 0x60410010) == MAPPING_ERRORS["cannot be mapped"]  # read-only into an RPDO
    assert node.sdo[0x1A00][1].raw == 0 and node.sdo[0x1600][1].raw == 0
    for sub, entry in ((1, 0x60410010), (2, 0x60640020), (3, 0x606C0020)):
        node.sdo[0x1A00][sub].raw = entry
    assert refused(0x1A00, 0, 3, 1) == MAPPING_ERRORS["too long"]  # 80 bits
    assert refused(0x1A00, 0, 9, 1) == MAPPING_ERRORS["too long"]  # 8 entries at most
    assert node.sdo[0x1A00][0].raw == 0
    node.sdo[0x1A00][0].raw = 2  # 48 bits
    node.sdo[0x1800][2].raw = 1
    node.sdo[0x1800][1].raw = 0x183
    node.tpdo.read()
    node.nmt.state = "OPERATIONAL"
    assert [v.index for v in node.tpdo[1].map] == [0x6041, 0x6064]
    frames: queue.Queue[bytes] = queue.Queue()
    drive.master.subscribe(0x183, lambda can_id, data, timestamp: frames.put(bytes(data)))
    drive.master.send_message(0x80, b"")  # SYNC
    assert len(frames.get(timeout=5)) == 6


def test_a_pdo_mapping_entry_names_a_sub_index_its_object_has(drive: Drive) -> None:
    """An object of one value (VAR) is its sub-index 00h alone: a mapping entry naming another
    sub-index of it names an object the node does not have (0602 0000h), as one naming a record's
    missing sub-index does, and nothing refused is kept."""
    node = drive.node
    node.sdo[0x1800][1].raw = 0x80000183  # TPDO1 not valid
    node.sdo[0x1A00][0].raw = 0  # mapping disabled
    node.sdo[0x1400][1].raw = 0x80000203  # RPDO1 not valid
    node.sdo[0x1600][0].raw = 0
    for index, entry in ((0x1A00, 0x60410110), (0x1A00, 0x10180920), (0x1600, 0x60400110)):
        with pytest.raises(canopen.SdoAbortedError) as aborted:
            node.sdo.download(index, 1, entry.to_bytes(4, "little"))
        assert aborted.value.code == MAPPING_ERRORS["no object"]
    assert node.sdo[0x1A00][1].raw == 0 and node.sdo[0x1600][1].raw == 0


def test_the_sync_cob_id_object_names_the_sync_the_node_consumes(drive: Drive) -> None:
    """CiA 301, 1005h COB-ID SYNC (UNSIGNED32, rw, 80h as the predefined connection set has it):
    the node, a SYNC consumer, sends its synchronous TPDOs at the SYNC with the CAN-ID 1005h names,
    and after the master writes another, at that one alone.  The node produces no SYNC, so bit 30
    (gen) is refused 0609 0030h, as are 29-bit frames (bit 29) and a CAN-ID CiA 301 restricts;
    reset communication brings back 80h."""
    node = drive.node
    entry = node.object_dictionary[0x1005]
    assert entry.data_type == 0x0007 and entry.writable and entry.default == 0x80
    assert node.sdo[0x1005].raw == 0x80
    node.tpdo.read()
    tpdo = mapped(node.tpdo[1], 0x6041, trans_type=1)
    node.tpdo.save()
    arrived: queue.Queue[int] = queue.Queue()
    tpdo.add_callback(lambda m: arrived.put(m["Statusword"].raw))
    node.nmt.state = "OPERATIONAL"

    def answered(can_id: int) -> int:
        """The TPDOs a SYNC with ``can_id`` brought (counted after an SDO round trip)."""
        drive.master.send_message(can_id, b"")
        assert node.sdo[0x1017].raw == 0  # (frames on the bus are handled in order)
        count = 0
        while not arrived.empty():
            arrived.get()
            count += 1
        return count

    assert answered(0x80) == 1 and answered(0x90) == 0
    node.sdo[0x1005].raw = 0x90
    assert node.sdo[0x1005].raw == 0x90
    assert answered(0x90) == 1 and answered(0x80) == 0
    node.sdo[0x1005].raw = 0x80000091  # bit 31 is "do not care" for a consumer
    assert answered(0x91) == 1 and answered(0x90) == 0
    for refused in (0x40000092, 0x20000092, 0x601, 0x703, 0x0, 0x1092):
        with pytest.raises(canopen.SdoAbortedError) as aborted:
            node.sdo[0x1005].raw = refused
        assert aborted.value.code == VALUE_RANGE_EXCEEDED, hex(refused)
        assert node.sdo[0x1005].raw == 0x80000091
    assert answered(0x91) == 1
    node.nmt.send_command(0x82)  # reset communication
    assert node.sdo[0x1005].raw == 0x80
    node.tpdo.read()
    mapped(node.tpdo[1], 0x6041, trans_type=1)
    node.tpdo.save()
    node.nmt.state = "OPERATIONAL"
    assert answered(0x91) == 0 and answered(0x80) == 1


def test_a_pdo_cob_id_takes_no_can_id_cia_301_restricts(drive: Drive) -> None:
    """CiA 301 §7.3.5 (restricted CAN-IDs: NMT 000h, 001h … 07Fh, 101h … 180h, the default SDOs
    581h … 5FFh and 601h … 67Fh, 6E0h … 6FFh, NMT error control 701h … 77Fh, 780h … 7FFh: no
    configurable communication object uses them): an RPDO's or TPDO's COB-ID (sub-index 01h of
    1400h … 1403h, 1800h … 1803h) that makes the PDO valid (bit 31 = 0) with one is aborted
    0609 0030h, as 1005h's is, and the COB-ID stays what it was.  A PDO not valid uses no CAN-ID:
    80000000h, as masters write to switch a PDO off, is taken (as CANopenNode takes it), and
    making that PDO valid as it is is refused.  CAN-IDs the table leaves free are taken."""
    node = drive.node
    for index in (0x1400, 0x1403, 0x1800, 0x1803):
        before = node.sdo[index][1].raw
        node.sdo[index][1].raw = 0x8000_0000 | before  # (not valid: a CAN-ID may be given)
        for can_id in (0x000, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x703, 0x77F, 0x7FF):
            for flags in (0x0, 0x4000_0000):  # (bit 30: no RTR)
                with pytest.raises(canopen.SdoAbortedError) as aborted:
                    node.sdo[index][1].raw = flags | can_id
                assert aborted.value.code == VALUE_RANGE_EXCEEDED, (hex(index), hex(flags | can_id))
                assert node.sdo[index][1].raw == 0x8000_0000 | before
        node.sdo[index][1].raw = 0x8000_0000  # switched off
        with pytest.raises(canopen.SdoAbortedError):
            node.sdo[index][1].raw = 0x0000_0000
        for free in (0x0081, 0x0100, 0x0481, 0x06DF):  # (EMCY, TIME, PDO, free ranges)
            node.sdo[index][1].raw = free
            assert node.sdo[index][1].raw == free
            node.sdo[index][1].raw = 0x8000_0000 | free
        node.sdo[index][1].raw = before
    node.tpdo.read()
    mapped(node.tpdo[1], 0x6041, trans_type=1)
    node.tpdo[1].cob_id = 0x1F3
    node.tpdo.save()
    frames: queue.Queue[bytes] = queue.Queue()
    drive.master.subscribe(0x1F3, lambda can_id, data, timestamp: frames.put(bytes(data)))
    node.nmt.state = "OPERATIONAL"
    drive.master.send_message(0x80, b"")  # SYNC: the TPDO goes out with the CAN-ID written
    assert len(frames.get(timeout=5)) == 2


def test_a_valid_pdo_keeps_its_can_id(drive: Drive) -> None:
    """CiA 301 §7.5.2.35 / §7.5.2.37 (PDO communication parameter, sub-index 01h): bits 0 … 29 of
    a PDO's COB-ID do not change while the PDO exists (bit 31 = 0); a write that would change them
    is aborted 0609 0030h.  The way to another CAN-ID is to make the PDO not valid first, as
    canopen's PdoMap.save() does."""
    node = drive.node
    for index, default in ((0x1400, 0x203), (0x1800, 0x183)):
        assert node.sdo[index][1].raw == default
        for changed in (default + 2, 0x4000_0000 | (default + 2)):
            with pytest.raises(canopen.SdoAbortedError) as aborted:
                node.sdo[index][1].raw = changed
            assert aborted.value.code == VALUE_RANGE_EXCEEDED, hex(changed)
            assert node.sdo[index][1].raw == default
        node.sdo[index][1].raw = 0x4000_0000 | default  # (bit 30 is not one of them)
        node.sdo[index][1].raw = default
        node.sdo[index][1].raw = 0x8000_0000 | default  # not valid …
        node.sdo[index][1].raw = default + 2  # … then valid with another CAN-ID
        assert node.sdo[index][1].raw == default + 2


def test_a_synchronous_rpdo_is_taken_at_the_next_sync(drive: Drive) -> None:
    """CiA 301 (PDO transmission types, 1400h sub-index 02h): an RPDO with a synchronous type
    (0 … 240) is taken at the next SYNC the node receives, not as it arrives; of two before one
    SYNC, the later one's data is what the SYNC actuates.  An RPDO with type 254/255 is taken as it
    arrives."""
    node = drive.node
    node.rpdo.read()
    synchronous = mapped(node.rpdo[1], 0x6040, trans_type=1)
    at_once = mapped(node.rpdo[2], 0x60FF, trans_type=255)
    node.rpdo.save()
    node.nmt.state = "OPERATIONAL"

    def state() -> int:
        return node.sdo[0x6041].raw & 0x6F  # (a round trip: the frames sent before it are handled)

    synchronous["Controlword"].raw = 0x06  # shutdown
    synchronous.transmit()
    assert state() & 0x4F == 0x40  # Switch on disabled until the SYNC
    drive.master.send_message(0x80, b"")
    assert state() == 0x21  # Ready to switch on
    for word in (0x00, 0x07):  # disable voltage, then switch on: the SYNC takes the switch on
        synchronous["Controlword"].raw = word
        synchronous.transmit()
    assert state() == 0x21
    drive.master.send_message(0x80, b"")
    assert state() == 0x23  # Switched on
    assert state() == 0x23  # (no second SYNC: nothing taken again)
    at_once["Target velocity"].raw = 1234
    at_once.transmit()
    assert node.sdo[0x60FF].raw == 1234
