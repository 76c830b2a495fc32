"""GMS96 through a real pty under virtual time: spec §6.1 session, §3.7 reply rules, §3.9
E/S-version, multidrop, framing, motion timing, reference run, faults and persistence."""

from __future__ import annotations

import math
from typing import Any

import pytest

from devsim.devices.gms96 import codec
from tests.gms96.conftest import Plant
from tests.support.memory import refused_memory

T0 = "68 06 06 68 53 03 54 00 00 00 AA 16"
STATUS = "10 01 03 04 16"
A10000 = "68 06 06 68 53 03 41 10 27 00 CE 16"
A30000 = "68 06 06 68 53 03 41 30 75 00 3C 16"


@pytest.mark.manual("§2.3", "commands go in the Langsatz as <address><command>[P1[P2[P3]]]")
def test_session_6_1_byte_exact(card: Plant) -> None:
    """Spec §6.1: commissioning and first move, every byte."""
    host = card.host
    assert host.ask(STATUS) == "10 40 03 43 16"
    assert host.ask("68 09 09 68 53 03 54 01 00 00 00 00 00 AB 16") == "68 05 05 68 08 03 56 94 01 F6 16"
    assert host.ask("68 09 09 68 53 03 54 03 00 00 00 00 00 AD 16") == "68 03 03 68 08 03 08 13 16"
    assert host.ask("68 0C 0C 68 53 03 54 01 00 00 03 00 00 00 00 00 AE 16") == "68 05 05 68 08 03 49 B0 04 08 16"
    for frame in (
        "68 06 06 68 53 03 42 32 00 00 CA 16",  # B50
        "68 06 06 68 53 03 4D 20 4E 00 11 16",  # M20000
        "68 06 06 68 53 03 66 10 27 00 F3 16",  # f10000
        "68 06 06 68 53 03 53 C8 00 00 71 16",  # S200
        "68 06 06 68 53 03 51 00 00 00 A7 16",  # Q0
    ):
        assert host.ask(frame) == "E5"
    assert host.ask(STATUS) == "10 D0 03 D3 16"
    card.idle()
    assert host.ask(STATUS) == "10 00 03 03 16"
    assert card.read("position_counter") == 0
    assert host.ask(A10000) == "E5"
    start = card.now()
    assert host.ask(STATUS) == "10 90 03 93 16"
    card.advance(0.5)
    mid = host.ask(T0)
    assert mid.startswith("68 06 06 68 08 03 40") and mid != "68 06 06 68 08 03 40 10 27 00 82 16"
    card.idle()
    assert host.ask(STATUS) == "10 00 03 03 16"
    assert host.ask(T0) == "68 06 06 68 08 03 40 10 27 00 82 16"
    # closed form (spec §6.1 check): sin² ramps, a = 50000, V = 10000 -> 1.314 s
    move_end = [t for t, e in card.device().events if e == "move_end"][-1]
    ramp = math.pi / 2 * 10000 / 50000  # T = pi/2 * V / a
    assert move_end - start == pytest.approx(ramp + 10000 / 10000, abs=1e-6)


def test_reply_rules(card: Plant) -> None:
    """Spec §3.7: E5 for c/N/queued/unknown, data for T, E5 for unsupported T, K for #1."""
    host = card.host
    assert host.ask("68 09 09 68 53 03 63 40 E2 01 02 00 00 DE 16") == "E5"  # c123456;2
    assert host.ask("68 0C 0C 68 53 03 54 01 00 00 06 00 00 08 00 00 B9 16") == "68 06 06 68 08 03 44 40 E2 01 72 16"
    assert host.ask("68 09 09 68 53 03 63 FF FF FF 02 00 00 B8 16") == "E5"  # c-1;2
    assert host.ask("68 0C 0C 68 53 03 54 01 00 00 06 00 00 08 00 00 B9 16") == "68 06 06 68 08 03 44 FF FF FF 4C 16"
    assert host.ask("68 09 09 68 53 03 4E 2C 01 00 0A 00 00 DB 16") == "E5"  # N300;10
    assert host.ask("68 09 09 68 53 03 54 05 00 00 0A 00 00 B9 16") == "68 06 06 68 08 03 4E 2C 01 00 86 16"
    assert host.ask("68 0C 0C 68 53 03 70 0B 00 00 0D 00 00 01 00 00 DF 16") == "E5"  # p11;13;1
    assert host.ask("68 0C 0C 68 53 03 54 01 00 00 03 00 00 0D 00 00 BB 16") == "68 05 05 68 08 03 49 01 00 55 16"
    assert host.ask("68 0C 0C 68 53 03 72 00 00 00 00 00 00 00 00 00 C8 16") == "E5"  # r0;0;0
    assert host.ask("68 09 09 68 53 03 54 05 00 00 0F 00 00 BE 16") == "68 06 06 68 08 03 4E 54 00 00 AD 16"
    assert host.ask("68 09 09 68 53 03 54 03 00 00 04 00 00 B1 16") == "68 03 03 68 08 03 02 0D 16"  # T3;4
    assert host.ask("68 09 09 68 53 03 54 02 00 00 00 00 00 AC 16") == "E5"  # T2;0 unsupported
    assert host.ask("68 03 03 68 53 03 7A D0 16") == "E5"  # unknown letter 'z'
    assert host.ask("68 03 03 68 53 03 71 C7 16") == "E5"  # q
    assert card.read("marker.M3.1") is True
    assert host.ask("10 00 03 03 16") == "E5"  # #0
    assert host.ask("10 0A 03 DC 05 EE 16") == "E5"  # #8 1500 rpm
    assert host.ask("10 0B 03 50 5E 16") == "E5"  # #9 80 %
    assert card.read("override") == 80
    assert host.ask("10 05 03 08 16") == "E5"  # undefined short command
    # m58;0: BUSY until the PLC resets M7.0; T1;3;6 shows MB6/MB7 (spec §6 E13)
    assert host.ask("68 09 09 68 53 03 6D 3A 00 00 00 00 00 FD 16") == "E5"
    assert host.ask("68 0C 0C 68 53 03 54 01 00 00 03 00 00 06 00 00 B4 16") == "68 05 05 68 08 03 49 00 01 55 16"
    assert host.ask(STATUS) == "10 C0 03 C3 16"
    card.set("marker.M7.0", False)
    assert host.ask(STATUS) == "10 40 03 43 16"


def test_message_fetch_and_t3(card: Plant) -> None:
    """Spec §6 E6/E7: T1;3;4 test-reads MB4, #1 fetches and clears it."""
    host = card.host
    card.set("message", 23)
    assert host.ask("68 0C 0C 68 53 03 54 01 00 00 03 00 00 04 00 00 B2 16") == "68 05 05 68 08 03 49 17 00 6B 16"
    assert host.ask(STATUS) == "10 42 03 17 5C 16"
    assert host.ask(STATUS) == "10 40 03 43 16"


def test_link_errors_no_reply(card: Plant) -> None:
    """Spec §3.10 / §8 link_errors_no_reply: every broken frame is silently discarded."""
    host = card.host
    for frame in (
        "68 06 06 68 53 03 41 10 27 00 CF 16",  # bad checksum
        "68 06 07 68 53 03 41 10 27 00 CE 16",  # L != L
        "68 06 06 68 53 03 41 10 27 00 CE 17",  # bad stop char
        "68 06 06 68 53 04 41 10 27 00 CF 16",  # other address
        "68 04 04 68 53 03 41 10 AA 16 FF",  # malformed parameter count
    ):
        assert host.silent(frame)
        card.advance(0.01)  # line idle >= 33 bit times before the next frame (R4)
    assert card.read("rejected_moves") == 0 and card.read("queue_length") == 0
    assert host.ask(STATUS) == "10 40 03 43 16"


def test_partial_frame_discarded_after_timeout(card: Plant) -> None:
    host = card.host
    before = card.bytes_in()
    host.send("10 01")
    card.wait_received(before + 2)
    card.advance(0.1)  # longer than the 50 ms inter-character timeout
    assert host.silent("03 04 16")  # the rest alone is no frame: never glued
    assert card.read("link_errors").get("timeout") == 1
    card.advance(0.01)  # "03 04 16" was garbage: line idle before the next frame (R4)
    assert host.ask(STATUS) == "10 40 03 43 16"


def test_split_frame_within_timeout_is_answered(card: Plant) -> None:
    host = card.host
    before = card.bytes_in()
    host.send("68 09 09 68 53")
    card.wait_received(before + 5)
    card.advance(0.01)
    assert host.ask("03 54 01 00 00 00 00 00 AB 16") == "68 05 05 68 08 03 56 94 01 F6 16"


def test_garbage_never_crashes_nor_loses_parameters(plant_factory: Any, tmp_path: Any) -> None:
    import random

    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    assert host.ask("68 09 09 68 53 03 4E 2C 01 00 0A 00 00 DB 16") == "E5"  # N300;10
    assert host.ask("68 09 09 68 53 03 73 55 00 00 AA 00 00 C8 16") == "E5"  # s85;170
    plant.idle()
    rng = random.Random(96)
    for _ in range(40):
        blob = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40)))
        host.send(blob)
        host.reply(0.005)
        plant.advance(0.06)
    host.reply(0.05)
    plant.advance(0.2)
    assert host.ask("68 09 09 68 53 03 54 05 00 00 0A 00 00 B9 16") == "68 06 06 68 08 03 4E 2C 01 00 86 16"
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    assert host.ask("68 09 09 68 53 03 54 05 00 00 0A 00 00 B9 16") == "68 06 06 68 08 03 4E 2C 01 00 86 16"


@pytest.mark.manual("§2.3.1 p", "after the start of a CNC/PLC download the card does not answer for 2 to 5 seconds (a flash sector is erased)")
def test_boot_silence_and_flash_erase(plant_factory: Any) -> None:
    plant = plant_factory({}, boot=False)
    host = plant.host
    assert host.silent(STATUS)
    plant.advance(0.6)
    assert host.ask(STATUS) == "10 40 03 43 16"
    assert host.ask("68 0C 0C 68 53 03 70 03 00 00 64 00 00 05 00 00 32 16") == "E5"  # p3;100;5
    assert host.silent(STATUS)
    plant.advance(3.1)
    assert host.ask(STATUS) == "10 40 03 43 16"


@pytest.mark.manual("§4.4", "19244 E-version, selected by DIL switch 7")
def test_e_version_duplicate_suppressed(plant_factory: Any) -> None:
    """Spec §3.11 duplicate example: the repeated +1000 (FCB=1) is acknowledged, not executed."""
    plant = plant_factory({"dil": {"protocol": "E"}})
    host = plant.host
    assert host.ask("68 06 06 68 53 03 51 00 00 00 A7 16") == "E5"  # Q0 (FCB 0)
    plant.idle()
    assert host.ask("68 06 06 68 73 03 2B E8 03 00 8C 16") == "E5"  # +1000, FCB=1
    assert host.ask("68 06 06 68 73 03 2B E8 03 00 8C 16") == "E5"  # repeat
    plant.idle()
    assert plant.read("position_setpoint") == 1000
    assert host.ask("68 06 06 68 53 03 2B E8 03 00 6C 16") == "E5"  # +1000, FCB=0
    plant.idle()
    assert plant.read("position_setpoint") == 2000
    # a repeated T is answered with the identical bytes
    first = host.ask("68 06 06 68 73 03 54 00 00 00 CA 16")
    assert first == "68 06 06 68 08 03 40 D0 07 00 22 16"
    assert host.ask("68 06 06 68 73 03 54 00 00 00 CA 16") == first
    # ACD when a message waits (spec §3.11 T3;0 E-version)
    plant.set("message", 5)
    reply = host.ask("68 09 09 68 53 03 54 03 00 00 00 00 00 AD 16")
    assert reply.split()[4] == "28"


def test_s_version_repeat_executes_twice(referenced: Plant) -> None:
    host = referenced.host
    assert host.ask("68 06 06 68 73 03 2B E8 03 00 8C 16") == "E5"
    assert host.ask("68 06 06 68 73 03 2B E8 03 00 8C 16") == "E5"
    referenced.idle()
    assert referenced.read("position_setpoint") == 2000


def test_client_against_card(card: Plant) -> None:
    client = card.client(3)
    assert client.status()[0] == 0x40
    ident, value, _raw = client.read(1, 0)
    assert (ident, value) == (0x56, 404)


@pytest.mark.manual("§1", "up to 32 axes are served from one host on the serial line; only the addressed card answers")
def test_multidrop_only_addressed_card_answers(plant_factory: Any) -> None:
    plant = plant_factory({"dil": {"address": 1}}, {"dil": {"address": 2}}, {"dil": {"address": 3}})
    host = plant.host
    for addr in (1, 2, 3):
        frame = codec.encode(codec.short_command(1, addr)).hex(" ")
        reply = host.ask(frame)
        assert reply == codec.encode(codec.ShortFrame(0x40, addr)).hex(" ").upper()
    assert host.silent("10 01 05 06 16")
    assert host.ask("68 06 06 68 53 02 41 10 27 00 CD 16") == "E5"  # A10000 to card 2 only
    assert plant.read("rejected_moves", "gms96_2") == 1
    assert plant.read("rejected_moves", "gms96_1") == 0
    assert plant.read("rejected_moves", "gms96_3") == 0


@pytest.mark.manual("§2.3.1 T", "IDXOFF = 1 (state after power-on): moves are not executable")
def test_move_rejected_before_reference(card: Plant) -> None:
    assert card.host.ask(A10000) == "E5"
    card.advance(0.2)
    assert card.read("position_setpoint") == 0
    assert card.read("rejected_moves") == 1
    assert card.read("busy") is False


def test_reference_run_q0(card: Plant) -> None:
    host = card.host
    assert host.ask("68 06 06 68 53 03 51 00 00 00 A7 16") == "E5"
    assert host.ask(STATUS) == "10 D0 03 D3 16"
    card.idle()
    dev = card.device()
    assert card.read("idxoff") is False
    assert card.read("position_counter") == 0
    period = dev.cfg.axis.index_period
    assert dev.axis.position() % period == pytest.approx(0.0, abs=1e-6)  # on an index mark
    # cam found at -15000, driven off at -15000 (S, positive), next mark below: -16384
    assert dev.axis.position() == pytest.approx(-4 * period)
    assert host.ask(A10000) == "E5"
    card.idle()
    assert host.ask(T0) == "68 06 06 68 08 03 40 10 27 00 82 16"


def test_reference_distance_limit(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"cam": None}})
    host = plant.host
    assert host.ask("68 0C 0C 68 53 03 51 00 00 00 00 00 00 50 C3 00 BA 16") == "E5"  # Q0;0;50000
    plant.idle()
    assert plant.read("idxoff") is True
    assert abs(plant.device().axis.position()) <= 50000 + 2000


@pytest.mark.manual("§2.3.1 Q", "message 23 when the distance limit P3 is exceeded with P2.6")
def test_reference_limit_message_23(referenced: Plant) -> None:
    referenced.device().cfg.axis.cam = None
    dev = referenced.device()
    for sw in dev.switches:
        sw.cancel()
    dev.signals.signal("E2.1").value = False
    host = referenced.host
    assert host.ask("68 0C 0C 68 53 03 51 00 00 00 40 00 00 50 C3 00 FA 16") == "E5"  # Q0;64;50000
    referenced.idle()
    assert host.ask(STATUS) == "10 02 03 17 1C 16"
    assert host.ask(STATUS) == "10 00 03 03 16"


@pytest.mark.manual("§2.4.3", "SETO, RESO, SNDF, SNDM between moves do not disturb the chaining (synchronous commands)")
def test_blending_and_output_on_the_fly(referenced: Plant) -> None:
    host = referenced.host
    dev = referenced.device()
    seen: list[float] = []
    dev.signals.subscribe("A0.2", lambda *_: seen.append(dev.axis.position() - dev.coordinates.origin))
    assert host.ask(A10000) == "E5"
    assert host.ask("68 0C 0C 68 53 03 70 0A 00 00 10 00 00 02 00 00 E2 16") == "E5"  # SETO A0.2
    assert host.ask("68 06 06 68 53 03 41 20 4E 00 05 16") == "E5"  # A20000
    referenced.idle()
    assert referenced.read("position_setpoint") == 20000
    assert seen and seen[0] == pytest.approx(10000, abs=1)
    assert abs(dev.axis.velocity(dev.events[-1][0] - 0.0)) == 0
    speeds = [abs(dev.axis.velocity(t)) for t, e in dev.events if e == "move_end"]
    assert speeds[0] > 0  # no stop at the junction


@pytest.mark.manual("§2.3.1 M", "M between two moves prevents chaining them")
def test_m_breaks_blending(referenced: Plant) -> None:
    host = referenced.host
    dev = referenced.device()
    assert host.ask(A10000) == "E5"
    assert host.ask("68 06 06 68 53 03 4D 20 4E 00 11 16") == "E5"  # M20000
    assert host.ask("68 06 06 68 53 03 41 20 4E 00 05 16") == "E5"
    referenced.idle()
    ends = [t for t, e in dev.events if e == "move_end"]
    assert abs(dev.axis.velocity(ends[0])) == pytest.approx(0.0, abs=1e-6)


@pytest.mark.manual("§1.1", "the maximum following error is programmable (N20); exceeding it switches the indexer off (IDXOFF)")
@pytest.mark.manual("§2.3.1 Q", "Q3: only (re-)activation of the position controller, no move")
def test_following_error_blocked_axis(referenced: Plant) -> None:
    host = referenced.host
    assert host.ask(A30000) == "E5"
    referenced.advance(0.3)
    referenced.set("quantity.blocked", True)
    referenced.run_until(lambda d: d.stage.idxoff, 5)
    assert host.ask(STATUS) == "10 40 03 43 16"
    assert referenced.read("controller") is False
    assert referenced.read("output.A0.0") is False
    referenced.set("quantity.blocked", False)
    assert host.ask("68 06 06 68 53 03 51 03 00 00 AA 16") == "E5"  # Q3
    referenced.run_until(lambda d: not d.stage.idxoff, 1)
    assert referenced.read("output.A0.0") is True


@pytest.mark.manual("§2.2", "the card reads the DIL switch only at power-on or after a reset (e.g. Notaus)")
def test_emergency_stop_is_a_reset(referenced: Plant) -> None:
    host = referenced.host
    referenced.set("input.emergency_stop", True)
    assert host.ask(STATUS) == "10 48 03 4B 16"
    referenced.set("dil.address", 5)
    assert host.ask(STATUS) == "10 48 03 4B 16"  # DIL read only at reset
    referenced.set("input.emergency_stop", False)
    referenced.advance(0.6)
    assert host.ask("10 01 05 06 16") == "10 40 05 45 16"
    assert host.silent(STATUS)


@pytest.mark.manual("§2.3.2 #0", "#0 aborts the running operation and discards the pending commands")
def test_abort_discards_queue(referenced: Plant) -> None:
    host = referenced.host
    assert host.ask(A30000) == "E5"
    assert host.ask("68 06 06 68 53 03 41 00 00 00 97 16") == "E5"
    referenced.advance(0.2)
    assert host.ask("10 00 03 03 16") == "E5"
    referenced.idle()
    assert referenced.read("queue_length") == 0
    assert 1 <= referenced.read("position_setpoint") <= 29999


@pytest.mark.manual("§2.3.1 G", "G95: speed in inc per revolution with the actual speed from Kurzsatz #8; f P2 adds 1/256 inc")
@pytest.mark.manual("§2.3.2 #9", "#9 override is acted on during a move")
def test_override_and_g95(referenced: Plant) -> None:
    host = referenced.host
    dev = referenced.device()
    assert host.ask("68 06 06 68 53 03 4D 20 4E 00 11 16") == "E5"  # M20000
    assert host.ask("68 06 06 68 53 03 66 10 27 00 F3 16") == "E5"  # f10000
    assert host.ask("10 0B 03 50 5E 16") == "E5"  # #9 80 %
    assert host.ask(A30000) == "E5"
    referenced.advance(1.0)
    assert abs(dev.axis.velocity()) == pytest.approx(8000)
    referenced.set("quantity.override_pot", 120)
    referenced.advance(0.5)
    assert abs(dev.axis.velocity()) == pytest.approx(8000)
    assert host.ask("68 06 06 68 53 03 6F 00 00 00 C5 16") == "E5"  # o0 is queued: after the move
    referenced.advance(0.5)
    assert abs(dev.axis.velocity()) == pytest.approx(8000)
    referenced.idle()
    assert referenced.read("override") == 100
    assert host.ask("68 06 06 68 53 03 4D 50 C3 00 B6 16") == "E5"  # M50000
    assert host.ask("68 06 06 68 53 03 47 5F 00 00 FC 16") == "E5"  # G95
    assert host.ask("68 09 09 68 53 03 66 E8 03 00 80 00 00 27 16") == "E5"  # f1000;128
    assert host.ask("10 0A 03 DC 05 EE 16") == "E5"  # 1500 rpm
    assert host.ask("68 06 06 68 53 03 41 00 00 00 97 16") == "E5"  # A0 (back from 30000)
    referenced.advance(0.9)  # sin² ramp to 25012 Hz takes pi/2 * 25012 / 50000 = 0.79 s
    assert abs(dev.axis.velocity()) == pytest.approx(25012, abs=50)  # 1000.5 * 1500 / 60
    assert host.ask("10 0A 03 EE 02 FD 16") == "E5"  # 750 rpm -> half speed
    referenced.advance(0.5)
    assert abs(dev.axis.velocity()) == pytest.approx(12506, abs=50)


@pytest.mark.manual("§2.3.1 s", "s85;170 saves M, S, B and all N entries in the EEPROM; they are active at the next start")
def test_persistence_s85_170_power_cycle(plant_factory: Any, tmp_path: Any) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    assert host.ask("68 09 09 68 53 03 4E 2C 01 00 0A 00 00 DB 16") == "E5"  # N300;10
    assert host.ask("68 06 06 68 53 03 4D 20 4E 00 11 16") == "E5"  # M20000
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    assert host.ask("68 09 09 68 53 03 54 05 00 00 0A 00 00 B9 16") == "68 06 06 68 08 03 4E C8 00 00 21 16"
    assert host.ask("68 09 09 68 53 03 4E 2C 01 00 0A 00 00 DB 16") == "E5"
    assert host.ask("68 09 09 68 53 03 73 55 00 00 AA 00 00 C8 16") == "E5"  # s85;170
    plant.idle()
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    assert host.ask("68 09 09 68 53 03 54 05 00 00 0A 00 00 B9 16") == "68 06 06 68 08 03 4E 2C 01 00 86 16"


@pytest.mark.manual("§2.5", "commands after p3;100;pnr are recorded, not executed; p3;101 ends; p3;1;pnr runs the program")
def test_cnc_program_download_and_run(referenced: Plant) -> None:
    host = referenced.host
    assert host.ask("68 0C 0C 68 53 03 70 03 00 00 64 00 00 00 00 00 2D 16") == "E5"  # p3;100;0
    assert host.silent(STATUS)
    referenced.advance(5.0)
    assert host.ask("68 06 06 68 53 03 41 E8 03 00 82 16") == "E5"
    assert host.ask("68 0C 0C 68 53 03 70 0A 00 00 10 00 00 02 00 00 E2 16") == "E5"
    assert host.ask("68 06 06 68 53 03 41 00 00 00 97 16") == "E5"
    assert host.ask("68 0C 0C 68 53 03 70 03 00 00 65 00 00 00 00 00 2E 16") == "E5"
    assert referenced.read("position_setpoint") == 0
    assert referenced.read("programs") == {0: 3}
    assert host.ask("68 0C 0C 68 53 03 70 03 00 00 01 00 00 00 00 00 CA 16") == "E5"  # p3;1;0
    referenced.run_until(lambda d: d.marker_byte(1) & 1, 10)
    assert referenced.read("output.A0.2") is True


@pytest.mark.manual("§2.3.1 N", "N15: I²t current limit in % · 2.55 of Imax")
def test_i2t_limitation(referenced: Plant) -> None:
    host = referenced.host
    assert host.ask("68 09 09 68 53 03 4E 7F 00 00 0F 00 00 32 16") == "E5"  # N127;15
    referenced.set("quantity.load_pct", 100)
    referenced.advance(1.9)
    assert referenced.read("i2t_active") is False
    referenced.advance(0.2)
    reply = host.ask("68 09 09 68 53 03 54 03 00 00 00 00 00 AD 16")
    assert int(reply.split()[6], 16) & 0x60 == 0x60
    reply = host.ask("68 09 09 68 53 03 54 01 00 00 05 00 00 B0 16")
    assert abs(int(reply.split()[7], 16) - 126) <= 1


@pytest.mark.manual("§3.1", "on a monitoring fault position and current control are switched off and the BREMSE output goes to 0 V")
@pytest.mark.manual("§3.1", "KSA: LEDs show the monitoring cause (yellow: undervoltage)")
def test_monitoring(referenced: Plant) -> None:
    host = referenced.host
    referenced.set("quantity.monitoring", "dc_undervoltage")
    assert host.ask("68 09 09 68 53 03 54 03 00 00 00 00 00 AD 16") == "68 03 03 68 08 03 0C 17 16"
    assert referenced.read("leds")["yellow"] is True
    assert referenced.read("output.A0.0") is False
    referenced.set("quantity.monitoring", "")
    assert host.ask("68 06 06 68 53 03 51 03 00 00 AA 16") == "E5"
    referenced.run_until(lambda d: d.status() == 0, 1)


def _card_with_eeprom(tmp_path: Any, n: dict[str, Any], n8: Any) -> Any:
    import json

    from devsim.runtime import Runtime

    (tmp_path / "gms96.nvram.json").write_text(json.dumps({"eeprom": {"B": 50, "M": 2000, "S": 100, "o": 1,
                                                                        "N": n, "N8": n8}}))
    return Runtime(virtual=True, state_dir=tmp_path).start()


def test_a_stored_n_parameter_out_of_its_range_is_clamped_as_a_write_is(tmp_path: Any) -> None:
    """(Fuzzed: a hand-edited EEPROM image loaded N39 = 10^30 and N8 = [-10^12, 10^12] as they
    were; a write of them is clamped, spec §3.8.10.)"""
    runtime = _card_with_eeprom(tmp_path, {"39": 10**30}, [-10**12, 10**12])
    try:
        runtime.add_device("gms96")
        assert runtime.read("gms96", "param.N39") == 100
        assert runtime.read("gms96", "param.N8") == -8388608
    finally:
        runtime.stop()


@pytest.mark.parametrize(("n", "n8"), [({}, "ab"), ({}, [1.5, "x"]), ({}, [1, 2, 3]), ({"39": "50"}, [0, 0]),
                                        ({"39": True}, [0, 0])])
def test_a_stored_n_parameter_that_is_no_whole_number_refuses_the_memory(tmp_path: Any, n: Any, n8: Any) -> None:
    """(Fuzzed: N8 "ab" loaded as ['a', 'b'] and every read of N8 failed with ValueError.)"""
    from devsim.core.nvram import UnfitMemory

    runtime = _card_with_eeprom(tmp_path, n, n8)
    try:
        with pytest.raises(UnfitMemory, match="this memory image does not fit the kind 'gms96'"):
            runtime.add_device("gms96")
    finally:
        runtime.stop()


@pytest.mark.parametrize("row", [None, 1.5, ["A"], ["A", "x", 0, 0, 1], ["#", 1, 0, 0, 1], [["A"], 1, 0, 0, 1],
                                 ["A", 1, 0, 0, 1, 9], ["m", 50, [1], 0, 1]])
def test_a_stored_program_row_no_download_makes_refuses_the_memory(tmp_path: Any, row: Any) -> None:
    """(Fuzzed: stored CNC program rows are run as they are; a row of the wrong shape or types
    loaded, and starting the program failed in the executor with TypeError: Cmd(*row), a move's
    target compared with a string, an M function's marker.)"""
    import json

    from devsim.runtime import Runtime

    def flash(rows: list[Any]) -> str:  # (as the card's save writes it: no PLC program)
        return json.dumps({"flash": {"programs": {"0": rows}, "plc": None, "plc_frames": []}})

    (tmp_path / "gms96.nvram.json").write_text(flash([["A", 10000, 0, 0, 1], row]))
    refused_memory(tmp_path, "gms96", match=r"\(ValueError: stored program row .* is no command the card queues\)")
    (tmp_path / "gms96.nvram.json").write_text(flash([["A", 10000, 0, 0, 1]]))
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("gms96")
        assert runtime.read("gms96", "programs") == {0: 1}
    finally:
        runtime.stop()
