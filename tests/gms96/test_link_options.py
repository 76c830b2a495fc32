"""GMS96 link-layer options through a real pty under virtual time: reply delay (spec §3.7),
command queue full (§4.2.5, §3.10), broadcast (§2.3), unknown commands (§3.7, §3.10) and the
FT1.2 line-idle rule R4 after a detected error (§3.2, §3.10)."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.devices.gms96 import codec
from devsim.runtime import Runtime
from tests.gms96.conftest import Plant

STATUS = "10 01 03 04 16"
K_IDLE = "10 40 03 43 16"  # #1 answer of an idle, unreferenced card at address 3
BAD_CHECKSUM = "68 06 06 68 53 03 41 10 27 00 CF 16"


def letter(cmd: str, *params: int, address: int = 3, control: int = 0x53) -> str:
    return codec.encode(codec.LongFrame(control, address, codec.letter(cmd, *params))).hex(" ")


def t_answer(address: int, identifier: int, value: int) -> str:
    return codec.encode(codec.t_reply(address, identifier, codec.to_s24(value))).hex(" ").upper()


def send(plant: Plant, frame: str) -> None:
    """Write a frame and wait until the card has all of it (before advancing virtual time)."""
    before = plant.bytes_in()
    plant.host.send(frame)
    plant.wait_received(before + len(bytes.fromhex(frame)))


def referenced(plant: Plant, delay: float = 0.0) -> Plant:
    send(plant, letter("Q", 0))
    plant.advance(delay)
    assert plant.host.reply() == b"\xe5"
    plant.idle()
    assert plant.read("idxoff") is False
    return plant


def sent_count(plant: Plant) -> int:
    return int(plant.runtime.call(lambda: plant.runtime.lines[plant.name].status()["bytes_out"]))


# -- reply timing (spec §3.7) ------------------------------------------------------------------
def test_response_delay_starts_reply_after_the_delay(plant_factory: Any) -> None:
    plant = plant_factory({"link": {"response_delay": 0.02}})
    host = plant.host
    send(plant, STATUS)
    assert host.reply(0.1) == b""  # virtual time stands still: no reply yet
    plant.advance(0.019)
    assert host.reply(0.1) == b""  # 19 ms < 20 ms
    plant.advance(0.002)
    assert host.reply().hex(" ").upper() == K_IDLE


def test_response_delay_zero_answers_at_once(card: Plant) -> None:
    before = card.now()
    assert card.host.ask(STATUS) == K_IDLE
    assert card.now() == before


# -- command queue full (spec §4.2.5, §3.10) ---------------------------------------------------
def _fill_queue(plant: Plant) -> None:
    """Capacity 1: A10000 runs, A20000 waits in the queue — the queue is full."""
    assert plant.host.ask(letter("A", 10000)) == "E5"
    assert plant.host.ask(letter("A", 20000)) == "E5"
    assert plant.read("queue_length") == 1


def test_queue_full_defer_releases_e5_when_a_slot_frees(plant_factory: Any) -> None:
    plant = referenced(plant_factory({"queue_capacity": 1}))
    _fill_queue(plant)
    assert plant.host.silent(letter("A", 30000))  # the E5h is held back
    plant.advance(0.1)
    assert plant.host.reply(0.1) == b""
    dev = plant.device()
    assert len(dev.executor.deferred) == 1
    plant.run_until(lambda d: not d.executor.deferred)
    assert plant.host.reply() == b"\xe5"  # released when A10000 ended and A20000 left the queue
    assert [e for _t, e in dev.events].count("move_end") >= 1
    plant.idle()
    assert plant.read("position_setpoint") == 30000  # the deferred command was executed


def test_queue_full_defer_with_response_delay(plant_factory: Any) -> None:
    plant = referenced(plant_factory({"queue_capacity": 1, "link": {"response_delay": 0.01}}), 0.011)
    host = plant.host
    for target in (10000, 20000):
        send(plant, letter("A", target))
        plant.advance(0.011)
        assert host.reply() == b"\xe5"
    assert host.silent(letter("A", 30000))
    plant.run_until(lambda d: not d.executor.deferred)
    assert host.reply(0.1) == b""  # the released E5h, too, waits the reply delay
    plant.advance(0.011)
    assert host.reply() == b"\xe5"


def test_queue_full_defer_e_version_repeat_gets_the_released_e5(plant_factory: Any) -> None:
    """E-version: the E5h released later is the reply a repetition (same FCB) gets again."""
    plant = referenced(plant_factory({"dil": {"protocol": "E"}, "queue_capacity": 1}))
    host = plant.host
    assert host.ask(letter("A", 10000, control=0x73)) == "E5"
    assert host.ask(letter("A", 20000, control=0x53)) == "E5"
    late = letter("A", 30000, control=0x73)
    assert host.silent(late)
    plant.run_until(lambda d: not d.executor.deferred)
    assert host.reply() == b"\xe5"
    assert host.ask(late) == "E5"  # the host missed it and repeats: not queued a second time
    assert [e for _t, e in plant.device().events].count("duplicate") == 1
    plant.idle()
    assert plant.read("position_setpoint") == 30000


def test_queue_full_defer_e_version_a_released_e5_is_no_reply_to_a_later_frame(plant_factory: Any) -> None:
    """E-version: the E5h released for a queued frame is not what a repetition of a frame the
    host sent after it gets (spec §3.9: the previous reply, byte for byte)."""
    plant = referenced(plant_factory({"dil": {"protocol": "E"}, "queue_capacity": 1}))
    host = plant.host
    assert host.ask(letter("A", 10000, control=0x73)) == "E5"
    assert host.ask(letter("A", 20000, control=0x53)) == "E5"
    assert host.silent(letter("A", 30000, control=0x73))  # the queue is full: its E5h waits
    status = letter("T", 1, 0, control=0x53)  # answered at once, queue full or not
    answer = host.ask(status)
    assert answer.startswith("68")
    plant.run_until(lambda d: not d.executor.deferred)
    assert host.reply() == b"\xe5"  # A 30000's, released
    assert host.ask(status) == answer  # the host missed T's answer and repeats: the same bytes
    assert [e for _t, e in plant.device().events].count("duplicate") == 1


def test_queue_full_drop_gives_no_reply_and_forgets_the_command(plant_factory: Any) -> None:
    plant = referenced(plant_factory({"queue_capacity": 1, "link": {"on_queue_full": "drop"}}))
    _fill_queue(plant)
    assert plant.host.silent(letter("A", 30000))
    out = sent_count(plant)
    plant.idle()
    assert plant.host.reply(0.1) == b""
    assert sent_count(plant) == out  # nothing released later either
    assert plant.read("position_setpoint") == 20000


def test_queue_full_nack_is_the_fixed_frame_fc1(plant_factory: Any) -> None:
    plant = referenced(plant_factory({"queue_capacity": 1, "link": {"on_queue_full": "nack"}}))
    _fill_queue(plant)
    assert plant.host.ask(letter("A", 30000)) == "10 01 03 04 16"  # 10 01 A CS 16, CS = 01 + 03
    plant.idle()
    assert plant.read("position_setpoint") == 20000
    assert plant.host.ask(letter("A", 30000)) == "E5"  # room again
    plant.idle()
    assert plant.read("position_setpoint") == 30000


# -- broadcast (spec §2.3) ---------------------------------------------------------------------
def test_broadcast_executed_by_every_card_never_answered(plant_factory: Any) -> None:
    plant = plant_factory(*({"dil": {"address": a}, "link": {"broadcast_address": 255}} for a in (1, 2, 3)))
    host = plant.host
    out = sent_count(plant)
    assert host.silent(letter("N", 300, 10, address=255))  # N300;10 to everybody
    assert host.silent(letter("T", 5, 10, address=255))  # a request, too, gets no answer
    assert sent_count(plant) == out
    for a in (1, 2, 3):
        assert host.ask(letter("T", 5, 10, address=a)) == t_answer(a, 0x4E, 300)


def test_broadcast_disabled_by_default(plant_factory: Any) -> None:
    plant = plant_factory({"dil": {"address": 1}}, {"dil": {"address": 2}})
    host = plant.host
    assert host.ask(letter("T", 5, 10, address=1)) != t_answer(1, 0x4E, 300)
    assert host.silent(letter("N", 300, 10, address=255))
    for a in (1, 2):
        assert host.ask(letter("T", 5, 10, address=a)) != t_answer(a, 0x4E, 300)


def test_broadcast_short_frame_not_executed(plant_factory: Any) -> None:
    plant = plant_factory({"link": {"broadcast_address": 255}})
    assert plant.host.silent(codec.encode(codec.short_command(9, 255, bytes([50]))).hex(" "))
    assert plant.read("override") != 50


def test_broadcast_into_a_full_queue_never_sends_the_deferred_e5(plant_factory: Any) -> None:
    plant = referenced(plant_factory({"queue_capacity": 1, "link": {"broadcast_address": 255}}))
    _fill_queue(plant)
    out = sent_count(plant)
    assert plant.host.silent(letter("A", 30000, address=255))
    plant.idle()
    assert plant.host.reply(0.1) == b""
    assert sent_count(plant) == out  # executed in turn, but silently
    assert plant.read("position_setpoint") == 30000


# -- unknown commands (spec §3.7, §3.10) -------------------------------------------------------
def test_unknown_letter_and_short_command_ack_by_default(card: Plant) -> None:
    assert card.host.ask(letter("z")) == "E5"
    assert card.host.ask("10 05 03 08 16") == "E5"  # #5: not defined
    assert card.read("queue_length") == 0
    assert card.host.ask(STATUS) == K_IDLE


def test_unknown_letter_and_short_command_reply_none(plant_factory: Any) -> None:
    plant = plant_factory({"link": {"unknown_command_reply": "none", "unknown_short_command_reply": "none"}})
    host = plant.host
    assert host.silent(letter("z", 1))
    assert host.silent("10 05 03 08 16")
    assert host.ask(letter("B", 50)) == "E5"  # known commands still answered
    assert host.ask(STATUS) == K_IDLE
    assert plant.read("queue_length") == 0
    assert [e for _t, e in plant.device().events].count("unknown_command") == 1


# -- FT1.2 R4: line idle after a detected error (spec §3.2, §3.10) -----------------------------
def test_r4_frame_back_to_back_behind_an_error_is_discarded(card: Plant) -> None:
    host = card.host
    assert host.silent(BAD_CHECKSUM + " " + STATUS)  # one write: no idle in between
    assert card.read("link_errors").get("not_idle", 0) >= 1
    card.advance(0.01)
    assert host.ask(STATUS) == K_IDLE


def test_r4_needs_33_bit_times_measured_from_the_last_byte(card: Plant) -> None:
    host = card.host
    bit = 1 / 9600
    assert card.face().link.idle_after_error == pytest.approx(33 * bit)
    assert host.silent(BAD_CHECKSUM)
    card.advance(30 * bit)
    assert host.silent(STATUS)  # only 30 bit times idle: lost, and the line was busy again
    card.advance(30 * bit)  # 60 bit times after the error, but 30 after the lost frame
    assert host.silent(STATUS)
    card.advance(34 * bit)
    assert host.ask(STATUS) == K_IDLE


def test_r4_each_error_kind_arms_the_idle(card: Plant) -> None:
    host = card.host
    for broken in (
        BAD_CHECKSUM,
        "68 06 07 68 53 03 41 10 27 00 CE 16",  # L != L
        "68 06 06 68 53 03 41 10 27 00 CE 17",  # end byte
        "10 01 03 05 16",  # Kurzsatz checksum
        "FF",  # garbage, as a parity/framing error leaves it
    ):
        assert host.silent(f"{broken} {STATUS}"), broken
        card.advance(0.005)
        assert host.ask(STATUS) == K_IDLE, broken


def test_r4_good_frame_before_the_error_is_answered(card: Plant) -> None:
    assert card.host.ask(f"{STATUS} {BAD_CHECKSUM}") == K_IDLE
    assert card.host.reply(0.1) == b""


def test_r4_partial_frame_started_behind_an_error_is_discarded(card: Plant) -> None:
    """The first half of a frame glued to the error, the rest after the idle: still lost."""
    host = card.host
    before = card.bytes_in()
    host.send(BAD_CHECKSUM + " 10 01")
    card.wait_received(before + 14)
    card.advance(0.01)
    assert host.silent("03 04 16")  # alone, the tail is garbage (and arms R4 again)
    card.advance(0.01)
    assert host.ask(STATUS) == K_IDLE


def test_r4_timeout_of_a_partial_frame_needs_no_extra_idle(card: Plant) -> None:
    host = card.host
    before = card.bytes_in()
    host.send("10 01")
    card.wait_received(before + 2)
    card.advance(0.1)  # the 50 ms inter-character timeout is itself line idle
    assert host.ask(STATUS) == K_IDLE


@pytest.mark.manual("§2.2", "DIL switch 8: 9600 Bd off, 38400 Bd on")
def test_r4_at_38400_baud() -> None:
    runtime = Runtime(virtual=True).start()
    try:
        dev: Any = runtime.add_device("gms96", "fast", {"dil": {"baud": 38400}})
        assert dev.face().link.idle_after_error == pytest.approx(33 / 38400)
    finally:
        runtime.stop()


def test_r4_can_be_switched_off(plant_factory: Any) -> None:
    plant = plant_factory({"link": {"error_line_idle": False}})
    assert plant.host.ask(f"{BAD_CHECKSUM} {STATUS}") == K_IDLE
    assert plant.read("link_errors").get("not_idle", 0) == 0
