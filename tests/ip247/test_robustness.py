"""The IP247's PG port against broken hosts (issue 11): garbage and broken AS511 transactions
(lost DLE ACK, a host that vanishes mid-transaction, doubled DLE at every position) never crash
it or touch the stored records, and kill -9 during a record write leaves them intact."""

from __future__ import annotations

import signal
import struct
from pathlib import Path

import hypothesis.strategies as hs
import pytest
import serial
from hypothesis import example, given, settings

from devsim.core.clock import VirtualClock
from devsim.devices.ip247 import Ip247Device
from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.client import PgClient
from devsim.runtime.client import ControlClient
from tests.ip247.test_machine_data import COM247, words
from tests.test_cli import Sim

PROGRAM = "%  5 KEEP\nN1 X10 F1000\nN2 M02\n"
OBSERVE = bytes.fromhex("02 62 1006 1006 01 1004 1006 1006 1006")  # a whole OBSERVE, PG side
FRAGMENTS = [b"\x02", b"\x10", b"\x10\x06", b"\x10\x15", b"\x10\x04", b"\x10\x03", b"\x10\x10", b"\x61", b"\x62",
             b"\x64", b"\x01\x14\x7b\x00", b"\x04\x45\x05\x00", OBSERVE, OBSERVE[:5], OBSERVE[:9]]


def _module() -> tuple[Ip247Device, VirtualClock, bytearray]:
    clock = VirtualClock()
    device = Ip247Device(clock=clock, config={"sys_id": {"module": 11}})
    clock.advance(1.0)  # the module runs after its 1 s start (spec §5.16)
    device.set("input.ANF1", True)
    device.set("input.END1", True)
    device.set("axis.1.machine_data", words(COM247))
    device.set("program.5", PROGRAM)
    out = bytearray()
    device.port("pg").attach(out.extend)
    return device, clock, out


def _records(device: Ip247Device) -> tuple[object, ...]:
    return device.read("axis.1.machine_data"), device.read("program.5"), device.read("programs"), device.read("sys_id")


def _observe_works(device: Ip247Device, clock: VirtualClock, out: bytearray) -> None:
    # whatever was half-way is abandoned after 500 ms of silence, which begins when the module's
    # last character has left the wire (9600 8E1: 11 bits a character; at most all it sent so far)
    clock.advance(0.6 + len(out) * 11 / 9600)
    out.clear()
    device.port("pg").feed(OBSERVE)
    assert out.startswith(bytes.fromhex("1006 02 161003 1006 02")), out.hex(" ")
    assert out.endswith(bytes.fromhex("1003 02 121003"))


@settings(max_examples=300, deadline=None)
@given(hs.lists(hs.tuples(hs.one_of(hs.binary(max_size=24).map(lambda b: b.replace(b"\x63", b"").replace(b"\x65", b"")),
                                    hs.sampled_from(FRAGMENTS)),
                          hs.sampled_from([0.0, 0.0, 0.1, 0.6])), max_size=40))
@example([(OBSERVE, 0.0), (b"\x00", 0.0), (OBSERVE, 0.0), (b"\x00", 0.0), (OBSERVE, 0.0)])  # its answers
def test_garbage_and_broken_transactions_leave_the_records_alone(chunks: list[tuple[bytes, float]]) -> None:
    """Random bytes and pieces of transactions (no write or delete function code among them),
    with pauses around the 500 ms timeout: nothing raises, the records stay, and a clean OBSERVE
    is answered afterwards."""
    device, clock, out = _module()
    before = _records(device)
    for data, pause in chunks:
        device.port("pg").feed(data)
        clock.advance(pause)
    assert _records(device) == before
    _observe_works(device, clock, out)


def test_lost_ack_vanished_host_and_doubled_dle_at_every_position() -> None:
    device, clock, out = _module()
    before = _records(device)
    request = bytes.fromhex("02 64 1006 1006 04 45 05 00 1004 1006 1006 1006")  # BA69 program 5
    for cut in range(1, len(request)):
        device.port("pg").feed(request[:cut])  # the PG stops acknowledging here
        clock.advance(0.6)
        device.port("pg").feed(request[:cut])
        device.port("pg").host_disconnected()  # ... or goes away
        doubled = request[:cut] + b"\x10" + request[cut:]
        device.port("pg").feed(doubled)  # a stray DLE at this position
        clock.advance(0.6)
        assert _records(device) == before, cut
    _observe_works(device, clock, out)


def test_kill_9_during_a_record_write_keeps_the_stored_records(tmp_path: Path) -> None:
    """Programs written one after the other over the PG port; kill -9 while one is in flight (its
    parameters sent, its answer not read): after a restart every acknowledged program is there
    in full, the one in flight is there in full or not at all, and the records before them too."""
    state, sock = tmp_path / "state", tmp_path / "ctl.sock"
    state.mkdir()

    def start() -> tuple[Sim, dict[str, str]]:
        sim = Sim("ip247", "--pty", "--state-dir", str(state), "--control", f"unix:{sock}")
        return sim, sim.read_until("ip247: ready")

    texts = {n: f"%{n:3d} KILL TEST {n}\n" + "".join(f"N{b} X{b} F1000\n" for b in range(1, 9)) + "N9 M02\n"
             for n in range(10, 40)}
    sim, seen = start()
    try:
        with ControlClient(f"unix:{sock}") as ctl:
            ctl.set("ip247", "program.5", PROGRAM)
        with serial.Serial(seen["ip247.pg"].split()[1], 9600, parity="E", timeout=5) as port:
            client = PgClient(port)
            for n in range(10, 30):
                record = lang.record_words(n, texts[n])
                assert client.transaction(0x63, bytes((4, 22, n, 0)) + struct.pack(f">{len(record)}H", *record))
            record = lang.record_words(30, texts[30])
            port.write(bytes.fromhex("02"))
            assert port.read(2) == b"\x10\x06"
            port.write(b"\x63")
            assert port.read(1) == b"\x02"
            port.write(b"\x10\x06")
            assert port.read(3) == b"\x16\x10\x03"
            port.write(b"\x10\x06" + (bytes((4, 22, 30, 0)) + struct.pack(f">{len(record)}H", *record)).replace(
                b"\x10", b"\x10\x10") + b"\x10\x04")
            sim.proc.send_signal(signal.SIGKILL)
            sim.proc.wait(timeout=15)
    finally:
        sim.stop()
    sim, _ = start()
    try:
        with ControlClient(f"unix:{sock}") as ctl:
            assert ctl.read("ip247", "program.5") == PROGRAM
            for n in range(10, 30):
                assert ctl.read("ip247", f"program.{n}") == texts[n]
            assert ctl.read("ip247", "program.30") in (None, texts[30])
            assert ctl.read("ip247", "channel.error") == 8
    finally:
        code, err = sim.stop()
    assert code == 0 and "Traceback" not in err


def test_a_long_boot_time_keeps_one_timer_not_one_per_blink() -> None:
    """(Fuzzed: ``boot_time: 1e9`` in the configuration made one timer per 0.25 s blink of the
    whole boot at power-up, 4·10^9 of them: ``devsim run ip247`` took all memory and was killed.)
    The LEDs blink the same, the module runs at the end of the boot."""
    clock = VirtualClock()
    device = Ip247Device(clock=clock, config={"boot_time": 1000.0})
    assert len(clock._heap) < 10
    seen = []
    for _ in range(4):
        seen.append((device.read("output.led_green"), device.read("output.led_red")))
        clock.advance(0.25)
    assert seen == [(True, False), (False, True), (True, False), (False, True)]
    clock.advance(1000.0 - 1.0 - 1e-6)
    assert device.booting and len(clock._heap) < 10
    clock.advance(2e-6)
    assert not device.booting and device.read("output.led_green") is True
    assert Ip247Device(clock=VirtualClock(), config={"boot_time": 1e308}).booting  # (int(inf) before)


def test_the_pg_port_is_silent_for_the_first_second_while_the_leds_blink() -> None:
    """§2.1/§5.16: after power-up both LEDs blink alternately and the module answers nothing;
    after 1 s the green LED stays on and the PG port answers."""
    clock = VirtualClock()
    device = Ip247Device(clock=clock, config={})
    out = bytearray()
    device.port("pg").attach(out.extend)
    device.port("pg").feed(b"\x02")
    seen = []
    for _ in range(4):
        seen.append((device.read("output.led_green"), device.read("output.led_red")))
        clock.advance(0.25)
    assert out == b"" and seen == [(True, False), (False, True), (True, False), (False, True)]
    assert device.read("output.led_green") is True and device.read("output.led_red") is False
    device.port("pg").feed(b"\x02")
    assert out == b"\x10\x06"


def test_a_program_name_s_number_is_ascii_digits() -> None:
    """'program.٣' (Arabic-Indic digits, which \\d and int() take) is no name of program 3."""
    from devsim.core.points import UnknownName

    device = Ip247Device(clock=VirtualClock(), config={"boot_time": 0})
    with pytest.raises(UnknownName):
        device.read("program.\u0663")


@pytest.mark.parametrize("key", ["\u0662", "+2", " 2", "\u00b2"])
def test_a_configured_axis_is_1_2_or_3_in_ascii(key: str) -> None:
    """The configuration's axes keys: int() also read the Arabic-Indic '٢', '+2' and ' 2' as axis 2,
    and '²' gave int()'s own message."""
    from devsim.core.typed import Invalid
    from devsim.devices.ip247.config import Ip247Config

    assert 2 in Ip247Config.parse({"axes": {2: {}}}).axes
    with pytest.raises(Invalid, match="an axis is 1, 2 or 3"):
        Ip247Config.parse({"axes": {key: {}}})
