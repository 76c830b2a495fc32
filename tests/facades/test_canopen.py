"""A device as a CANopen node (issue 13): the EDS devsim generates per kind (shipped
in docs/eds/, read by canopen), NMT boot-up and heartbeat, identity and every point over SDO with
the device's validation; canopen's remote node as the master on python-can's virtual bus."""

from __future__ import annotations

import logging
import struct
import threading
import uuid
from collections.abc import Iterator
from pathlib import Path

import canopen
import pytest
from click.testing import CliRunner

from devsim.cli import cli
from devsim.core.clock import VirtualClock
from devsim.core.registry import device_class, kinds
from devsim.facades.canopen_node import READ_ONLY, VALUE_RANGE_EXCEEDED, CanopenFacade, load_od
from devsim.facades.canopen_od import DEVICE_TYPE, eds
from devsim.facades.canopen_sdo import LENGTH_MISMATCH
from tests.support.can import network as can_network

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = tuple(sorted(kinds()))  # every registered kind ships its EDS under docs/eds/


@pytest.mark.parametrize("kind", SHIPPED)
def test_the_shipped_eds_is_current_and_canopen_reads_it(kind: str) -> None:
    cls = device_class(kind)
    text = eds(kind, cls.description, cls.points, drive=cls.drive is not None,
               homing=cls.drive is not None and cls.drive.homing is not None)
    assert (ROOT / "docs" / "eds" / f"{kind}.eds").read_text(encoding="utf-8") == text + "\n", (
        f"run `devsim doc {kind} --eds > docs/eds/{kind}.eds`")
    od = canopen.import_od(str(ROOT / "docs" / "eds" / f"{kind}.eds"))
    assert od[0x1000].default == DEVICE_TYPE and od[0x1018][1].default == 0
    assert CliRunner().invoke(cli, ["doc", kind, "--eds"]).output == text + "\n"


class Bus:
    """A sers device as node 5 and canopen's remote node as the master, on one virtual CAN bus."""

    def __init__(self) -> None:
        channel = f"devsim-{uuid.uuid4().hex}"
        self.device = device_class("sers")(clock=VirtualClock(), config={})
        self.slave, self.master = can_network(), can_network()
        self.slave.connect(interface="virtual", channel=channel)
        self.master.connect(interface="virtual", channel=channel)
        self.facade = CanopenFacade(self.device, 5)
        self.remote = canopen.RemoteNode(5, load_od(eds("sers", self.device.description, self.device.points), 5))
        self.master.add_node(self.remote)

    def index(self, name: str) -> int:
        return next(i for i, p in self.facade.objects.items() if p.name == name)

    def close(self) -> None:
        self.slave.disconnect()
        self.master.disconnect()
        self.device.close()


@pytest.fixture
def bus() -> Iterator[Bus]:
    b = Bus()
    try:
        yield b
    finally:
        b.close()


def test_boot_up_heartbeat_and_identity(bus: Bus) -> None:
    bus.facade.attach(bus.slave)
    bus.remote.nmt.wait_for_bootup(5)
    assert bus.remote.sdo[0x1000].raw == DEVICE_TYPE
    assert bus.remote.sdo[0x1008].raw == "devsim sers"
    assert bus.remote.sdo[0x1018][2].raw == bus.remote.object_dictionary[0x1018][2].default
    bus.remote.sdo[0x1017].raw = 50  # heartbeat every 50 ms
    assert bus.remote.nmt.wait_for_heartbeat(5) == "PRE-OPERATIONAL"
    bus.remote.nmt.state = "OPERATIONAL"
    assert bus.remote.nmt.wait_for_heartbeat(5) == "OPERATIONAL"


def test_points_over_sdo_with_the_device_validation(bus: Bus) -> None:
    bus.facade.attach(bus.slave)
    supply = bus.remote.sdo[bus.index("quantity.supply_voltage")]
    assert supply.raw == 68.0
    supply.raw = 50.0
    assert bus.device.read("quantity.supply_voltage") == 50.0
    with pytest.raises(canopen.SdoAbortedError) as refused:
        supply.raw = -1.0
    assert refused.value.code == VALUE_RANGE_EXCEEDED and bus.device.read("quantity.supply_voltage") == 50.0
    with pytest.raises(canopen.SdoAbortedError) as read_only:
        bus.remote.sdo[bus.index("axis.position")].raw = 5.0
    assert read_only.value.code == READ_ONLY
    bus.remote.sdo[bus.index("input.I1")].raw = True
    assert bus.device.read("input.I1") is True
    assert bus.remote.sdo[bus.index("input.I1")].raw is True


def test_a_kind_that_is_no_drive_has_no_cia402_objects() -> None:
    """Every shipped kind is a drive; the EDS of one that is not lists no 6040h … 6502h (issue 35)."""
    from devsim.facades.canopen_od import DRIVE_OBJECTS
    from devsim.facades.canopen_od import eds as make_eds

    plain, drive = make_eds("x", "d", [], drive=False), make_eds("x", "d", [], drive=True)
    for index, *_ in DRIVE_OBJECTS:
        assert f"=0x{index:04X}" not in plain and f"[{index:04X}]" not in plain
        assert f"=0x{index:04X}" in drive and f"[{index:04X}]" in drive
    assert "SupportedObjects=20" in plain  # 1005h, 1008h, 1014h, 1017h and the 16 PDO records


def test_the_emcy_cob_id_object_names_the_emcy_it_sends(bus: Bus) -> None:
    """CiA 301 1014h "COB-ID EMCY" (conditional: mandatory where EMCY is supported; here read-only,
    80h + node id, 11-bit, valid): the EDS declares it and the node answers it."""
    od = canopen.import_od(str(ROOT / "docs" / "eds" / "sers.eds"), 5)
    assert 0x1014 in od and od[0x1014].default == 0x80 + 5 and not od[0x1014].writable
    bus.facade.attach(bus.slave)
    assert bus.remote.sdo[0x1014].raw == 0x85
    bus.facade._emergency(1, 0x8611)
    assert bus.remote.emcy.wait(0x8611, timeout=5) is not None  # on 85h: what canopen's consumer listens to


def _exchange(bus: Bus, request: bytes) -> bytes:
    """One raw SDO request on the bus (the master's own client would not send it) and its answer."""
    answers: list[bytes] = []
    answered = threading.Event()

    def heard(_id: int, data: bytes, _ts: float) -> None:
        answers.append(bytes(data))
        answered.set()

    bus.master.subscribe(0x585, heard)
    try:
        bus.master.send_message(0x605, request)
        answered.wait(5)
    finally:
        bus.master.unsubscribe(0x585, heard)  # (the master's SDO client listens there too)
    assert answers, f"no answer to {request.hex()}"
    return answers[0]


def test_a_boolean_object_takes_one_byte(bus: Bus, caplog: pytest.LogCaptureFixture) -> None:
    """A BOOLEAN is one byte on the bus (CiA 301); canopen checks the length of its number
    types only.  Found by fuzzing: two bytes for input.I1 (expedited, or a segmented download that
    ends with two) were the server's own fault, logged, answered 0800 0000h; they are a length that
    does not match, 0607 0010h, and the point keeps its value.  An expedited download
    that does not say its size (e = 1, s = 0) takes the one byte the type has."""
    bus.facade.attach(bus.slave)
    i1 = bus.index("input.I1")
    mux = struct.pack("<HB", i1, 0)
    mismatch = bytes((0x80,)) + mux + struct.pack("<L", LENGTH_MISMATCH)
    with caplog.at_level(logging.ERROR):
        with pytest.raises(canopen.SdoAbortedError) as expedited:
            bus.remote.sdo.download(i1, 0, b"\x01\x00")
        assert expedited.value.code == LENGTH_MISMATCH
        assert _exchange(bus, bytes((0x21,)) + mux + bytes(4)) == bytes((0x60,)) + mux + bytes(4)
        assert _exchange(bus, bytes((0x0B,)) + b"\x01\x01" + bytes(5)) == mismatch  # the last segment: 2 bytes
        assert bus.device.read("input.I1") is False
        assert _exchange(bus, bytes((0x22,)) + mux + b"\x01\xee\xee\xee") == bytes((0x60,)) + mux + bytes(4)
    assert bus.device.read("input.I1") is True
    assert bus.remote.sdo[i1].raw is True
    assert not [r for r in caplog.records if r.levelno >= logging.ERROR]
