"""GMS96 scripted PLC through a real pty under virtual time (spec §4.10, §4.11, §3.8.9, §3.8.13,
§3.8.24): start/stop and memory status, download framing, M-function handshake with and without
auto-acknowledge, the built-in convenience rules, markers through ``T1;3``, I/O through the
control API."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.devices.gms96 import codec
from tests.gms96.conftest import Plant

STATUS = "10 01 03 04 16"
T3_4 = "68 09 09 68 53 03 54 03 00 00 04 00 00 B1 16"
FAST = {"cycle_ms": 20}


def frame(cmd: str, *params: int) -> str:
    """A host Langsatz (F = 53h) for card 3 as spaced hex."""
    return codec.encode(codec.LongFrame(0x53, 3, codec.letter(cmd, *params))).hex(" ").upper()


def raw_a(data: bytes) -> str:
    """An ``a`` download frame carrying ``data`` opaquely."""
    return codec.encode(codec.LongFrame(0x53, 3, b"a" + data)).hex(" ").upper()


def t_reply(identifier: int, value: bytes) -> str:
    return codec.encode(codec.t_reply(3, identifier, value)).hex(" ").upper()


def memory_status(plant: Plant) -> int:
    reply = plant.host.ask(T3_4)
    assert reply.startswith("68 03 03 68 08 03"), reply
    return int(reply.split()[6], 16)


def markers(plant: Plant, byte: int) -> tuple[int, int]:
    """``T1;3;byte``: MB(byte), MB(byte+1)."""
    reply = plant.host.ask(frame("T", 1, 3, byte)).split()
    assert reply[:7] == ["68", "05", "05", "68", "08", "03", "49"], reply
    return int(reply[7], 16), int(reply[8], 16)


def image(plant: Plant, p2: int, byte: int = 0) -> tuple[int, int]:
    """``T1;1;byte`` (inputs) / ``T1;2;byte`` (outputs)."""
    reply = plant.host.ask(frame("T", 1, p2, byte)).split()
    return int(reply[7], 16), int(reply[8], 16)


def ok(plant: Plant, cmd: str, *params: int) -> None:
    assert plant.host.ask(frame(cmd, *params)) == "E5"


def reference(plant: Plant) -> None:
    ok(plant, "Q", 0)
    plant.idle()
    assert plant.read("idxoff") is False


# -- run state, cycle time, memory status (spec §4.3.2, §4.10.2, §3.8.13) ------------------------


def test_no_plc_program_by_default(card: Plant) -> None:
    assert memory_status(card) == 0x02  # I.1: PLC not running
    ok(card, "p", 1, 1, 0)  # p1;1 without a program: nothing to start
    assert memory_status(card) == 0x02
    assert card.read("plc.loaded") is False and card.read("plc.cycles") == 0


def test_start_stop_status_bits_and_cycles(plant_factory: Any) -> None:
    plant = plant_factory({"plc": {**FAST, "auto_ack_m_functions_ms": 0}})
    assert memory_status(plant) == 0x00  # the scripted program is "in FLASH": started at power-on
    before = plant.read("plc.cycles")
    plant.advance(0.2)
    assert plant.read("plc.cycles") - before == 10  # 20 ms cycle on the device clock
    ok(plant, "p", 1, 2, 0)  # p1;2 stop
    assert memory_status(plant) == 0x02
    frozen = plant.read("plc.cycles")
    ok(plant, "m", 58, 0)
    plant.advance(0.5)
    assert plant.read("plc.cycles") == frozen
    assert plant.host.ask(STATUS) == "10 C0 03 C3 16"  # nobody acknowledges M58
    ok(plant, "p", 1, 1, 0)  # p1;1 start: queued behind the waiting m58 (spec §3.8.13)
    assert memory_status(plant) == 0x02
    ok(plant, "p", 11, 7, 0)  # the host acknowledges M58 itself (p11 is immediate)
    assert memory_status(plant) == 0x00  # now p1;1 ran
    plant.advance(0.05)
    assert plant.host.ask(STATUS) == "10 40 03 43 16"


@pytest.mark.manual("§6", "PLC run time for 1000 instructions per variant (87 ms, KS4/KS8 72 ms)")
@pytest.mark.parametrize(
    ("config", "cycle_ms"),
    [
        ({}, 87 * 230 / 1000),  # KSA15-2R: 87 ms per 1000 instructions (manual §6)
        ({"variant": "KS4"}, 72 * 230 / 1000),
        ({"variant": "KD8", "plc": {"instructions": 500}}, 88 * 500 / 1000),
        ({"plc": {"cycle_ms": 5}}, 5.0),
    ],
)
def test_cycle_time_from_variant_or_config(
    plant_factory: Any, config: dict[str, Any], cycle_ms: float
) -> None:
    plant = plant_factory(config)
    assert plant.read("plc.cycle_ms") == pytest.approx(cycle_ms)


@pytest.mark.manual("§4.4", "under an interpolation card (DIL 6) the GMS loses its PLC")
def test_interpolation_mode_has_no_plc(plant_factory: Any) -> None:
    plant = plant_factory({"dil": {"interpolation": True}, "plc": {"auto_ack_m_functions_ms": 0}})
    assert memory_status(plant) == 0x02
    ok(plant, "p", 1, 1, 0)
    assert memory_status(plant) == 0x02


# -- download framing (spec §3.8.24, §4.8) ---------------------------------------------------------


@pytest.mark.manual("§2.3.1 p", "p1;100 begins a PLC download (a frames), p1;101 ends it; p1;1 starts, p1;2 stops the PLC")
@pytest.mark.manual("§2.4", "a PLC program in the FLASH at power-on is started automatically")
@pytest.mark.manual("§2.3.1 T", "T3;4 I.1: PLC not running")
def test_download_stores_a_frames_opaquely(plant_factory: Any, tmp_path: Any) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    blobs = [b"", b"\x01\x02\x03\x04\x05", bytes(range(250))]
    assert host.ask(raw_a(b"\xaa\xbb")) == "E5"  # outside a download: ignored
    assert plant.read("plc.image") is None
    assert host.ask(frame("p", 1, 100, 0)) == "E5"  # begin: flash erase, 2..5 s silent
    assert host.silent(STATUS)
    plant.advance(3.1)
    for blob in blobs:
        assert host.ask(raw_a(blob)) == "E5"
    assert host.ask(frame("T", 1, 3, 0)).startswith("68 05 05 68 08 03 49")  # immediate T answered
    assert host.ask(frame("p", 1, 101, 0)) == "E5"
    assert plant.read("plc.image") == b"".join(blobs).hex()
    assert plant.read("plc.frames") == [0, 5, 250]
    assert memory_status(plant) == 0x02  # loaded, not started yet
    ok(plant, "p", 1, 1, 0)
    assert memory_status(plant) == 0x00
    ok(plant, "p", 1, 2, 0)
    assert memory_status(plant) == 0x02
    # in FLASH: starts by itself at power-on
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    assert memory_status(plant) == 0x00
    assert plant.read("plc.image") == b"".join(blobs).hex()
    assert plant.read("plc.frames") == [0, 5, 250]
    # a new download erases the old program; an aborted one leaves none
    assert host.ask(frame("p", 1, 100, 0)) == "E5"
    plant.advance(3.1)
    assert host.ask(raw_a(b"\x10\x20")) == "E5"
    assert host.ask("10 00 03 03 16") == "E5"  # #0 aborts the download
    assert host.ask(frame("p", 1, 101, 0)) == "E5"
    assert plant.read("plc.image") is None
    assert memory_status(plant) == 0x02
    ok(plant, "p", 1, 1, 0)
    assert memory_status(plant) == 0x02


@pytest.mark.manual("§2.3.1 T", "T3;4 I.0: PLC program storage error (e.g. too long)")
@pytest.mark.manual("§2.3.1 T", "T3;4 I.0: always 0 under interpolation")
@pytest.mark.parametrize(("interpolation", "status"), [(False, 0x03), (True, 0x02)])
def test_download_too_long_is_a_storage_error(plant_factory: Any, interpolation: bool, status: int) -> None:
    plant = plant_factory({"plc": {"flash_bytes": 8}, "dil": {"interpolation": interpolation}})
    host = plant.host
    assert host.ask(frame("p", 1, 100, 0)) == "E5"
    plant.advance(3.1)
    assert host.ask(raw_a(bytes(6))) == "E5"
    assert host.ask(raw_a(bytes(6))) == "E5"
    assert host.ask(frame("p", 1, 101, 0)) == "E5"
    assert memory_status(plant) == status  # I.0 storage error (not under interpolation) + I.1 not running
    assert plant.read("plc.image") is None


# -- M-function handshake (spec §3.8.9, §4.10.3) ----------------------------------------------------


@pytest.mark.manual("§2.3.1 m", "m waits until the PLC program resets the M bit")
def test_m_function_handshake_without_auto_ack(card: Plant) -> None:
    ok(card, "m", 58, 7)
    assert markers(card, 6) == (0x00, 0x01)  # M58 = M7.0
    assert markers(card, 10) == (0x00, 0x07)  # MB11 = extended M datum
    card.advance(2.0)
    assert card.host.ask(STATUS) == "10 C0 03 C3 16"  # BUSY until someone resets M7.0
    ok(card, "p", 11, 7, 0)  # the host plays PLC: p11;7;0
    assert card.host.ask(STATUS) == "10 40 03 43 16"


def test_m_function_auto_ack_after_delay(plant_factory: Any) -> None:
    plant = plant_factory({"plc": {**FAST, "auto_ack_m_functions_ms": 100}})
    ok(plant, "m", 89, 3)
    start = plant.now()
    assert markers(plant, 10) == (0x80, 0x03)  # M89 = M10.7, MB11 = 3
    assert plant.host.ask(STATUS) == "10 C0 03 C3 16"
    plant.advance(0.09)
    assert plant.read("busy") is True
    plant.run_until(lambda d: not d.busy(), timeout=1.0)
    waited = plant.now() - start
    assert 0.1 <= waited <= 0.1 + 2 * 0.02 + 1e-9  # a PLC timer: N ms from the cycle that saw it
    assert markers(plant, 10) == (0x00, 0x03)
    # S function: MB15 = spindle number | M15.7, MW16 = speed (Step5: MB16 high byte)
    ok(plant, "m", 100, 2, 1500)
    assert markers(plant, 15) == (0x82, 0x05) and markers(plant, 17)[0] == 0xDC
    plant.run_until(lambda d: not d.busy(), timeout=1.0)
    assert markers(plant, 15)[0] == 0x02
    # T function: MB18 = tool | M18.7, MB19 = D number
    ok(plant, "m", 101, 5, 9)
    assert markers(plant, 18) == (0x85, 0x09)
    plant.run_until(lambda d: not d.busy(), timeout=1.0)
    assert markers(plant, 18) == (0x05, 0x09)


def test_auto_ack_also_resets_bits_the_host_sets(plant_factory: Any) -> None:
    plant = plant_factory({"plc": {**FAST, "auto_ack_m_functions_ms": 0}})
    ok(plant, "p", 11, 8, 0x81)  # M8.0 and M8.7 by p11
    ok(plant, "p", 11, 40, 0x81)  # a free marker byte: not an M-function bit
    plant.advance(0.03)
    assert markers(plant, 8)[0] == 0x00
    assert markers(plant, 40)[0] == 0x81


# -- limit switches (spec §4.10.3, §5.11) ------------------------------------------------------------


def test_limit_switch_stop_holds_the_move(plant_factory: Any) -> None:
    plant = plant_factory(
        {
            "axis": {"limit_switches": [{"input": "E0.3", "low": 5000}]},  # physical: machine 21384 after Q0
            "plc": {
                **FAST,
                "limit_switches": [{"input": "E0.3", "action": "stop", "message": 41, "direction": "+"}],
            },
        }
    )
    reference(plant)
    ok(plant, "A", 30000)
    plant.run_until(lambda d: d.signals.get("E0.3"), timeout=30)
    plant.run_until(lambda d: not d.axis.moving, timeout=5)
    assert plant.read("busy") is True  # decelerated, not aborted
    stopped = plant.read("position_setpoint")
    assert 21384 < stopped < 30000
    assert markers(plant, 0)[0] & 0x01  # M0.0 STOP
    assert image(plant, 1)[0] & 0x08  # E0.3 in the PAE
    client = plant.client()
    k, mb4 = client.status()
    assert mb4 == 41 and k & 0x80  # BUSY, message 41
    plant.advance(0.5)
    assert plant.read("position_setpoint") == stopped
    # the host aborts and drives back out: moving away the STOP is released
    assert plant.host.ask("10 00 03 03 16") == "E5"
    plant.advance(0.05)
    assert not markers(plant, 0)[0] & 0x01
    ok(plant, "A", 10000)
    plant.idle()
    assert plant.read("position_setpoint") == 10000
    assert plant.read("input.E0.3") is False


def test_limit_switch_abort(plant_factory: Any) -> None:
    plant = plant_factory(
        {
            "axis": {"limit_switches": [{"input": "E1.0", "low": 5000}]},  # physical: machine 21384 after Q0
            "plc": {
                **FAST,
                "limit_switches": [{"input": "E1.0", "action": "abort", "message": 42, "direction": "+"}],
            },
        }
    )
    reference(plant)
    ok(plant, "A", 30000)
    ok(plant, "A", 35000)  # queued: discarded by the abort
    plant.idle()
    end = plant.read("position_setpoint")
    assert 21384 < end < 30000
    assert plant.read("queue_length") == 0
    assert not markers(plant, 0)[0] & 0x02  # M0.1 is a pulse
    assert plant.client().status()[1] == 42
    ok(plant, "+", 1000)  # further into the switch: aborted again within a cycle
    plant.idle(timeout=1.0)
    assert plant.read("position_setpoint") < end + 1000
    ok(plant, "A", 15000)  # out of the switch: allowed
    plant.idle()
    assert plant.read("position_setpoint") == 15000


def test_limit_switch_normally_closed(plant_factory: Any) -> None:
    plant = plant_factory(
        {"plc": {**FAST, "limit_switches": [{"input": "E0.6", "action": "stop", "active_low": True}]}}
    )
    plant.advance(0.05)
    assert markers(plant, 0)[0] & 0x01  # wire broken / switch open at 0 V: STOP
    plant.set("input.E0.6", True)
    plant.advance(0.05)
    assert not markers(plant, 0)[0] & 0x01


# -- messages on faults and the message query q (spec §4.10.3, §3.8.15) -------------------------------


def test_message_on_fault(plant_factory: Any) -> None:
    plant = plant_factory(
        {"plc": {**FAST, "message_on_fault": {"following_error": 51, "monitoring": 52, "emergency_stop": 53}}}
    )
    client = plant.client()
    plant.advance(0.05)
    assert client.status()[1] is None  # no fault at power-on (IDXOFF alone is none)
    reference(plant)
    # following error: the blocked axis
    ok(plant, "A", 30000)
    plant.advance(0.3)
    plant.set("quantity.blocked", True)
    plant.run_until(lambda d: d.stage.idxoff, timeout=5)
    plant.advance(0.05)
    assert client.status()[1] == 51
    assert client.status()[1] is None
    # q: the PLC re-reports what is still pending and resets M3.1
    assert plant.host.ask("68 03 03 68 53 03 71 C7 16") == "E5"
    plant.advance(0.05)
    assert client.status()[1] == 51
    assert not markers(plant, 3)[0] & 0x02
    plant.set("quantity.blocked", False)
    ok(plant, "Q", 3)
    plant.advance(0.05)
    assert client.status()[1] is None
    # monitoring: message 52, and no following-error message when it clears
    plant.set("quantity.monitoring", "dc_undervoltage")
    plant.advance(0.05)
    assert client.status()[1] == 52
    plant.set("quantity.monitoring", "")
    plant.advance(0.05)
    assert client.status()[1] is None
    ok(plant, "Q", 3)
    # emergency stop
    plant.set("input.emergency_stop", True)
    plant.advance(0.05)
    k, mb4 = client.status()
    assert mb4 == 53 and k & 0x08


def test_q_without_rules_is_left_to_a_running_plc(plant_factory: Any) -> None:
    plant = plant_factory({"plc": {**FAST, "loaded": True}})  # an (empty) scripted program runs
    assert plant.host.ask("68 03 03 68 53 03 71 C7 16") == "E5"
    plant.advance(0.05)
    assert not markers(plant, 3)[0] & 0x02


# -- start a CNC program on an input (spec §4.10.3, §4.9) ---------------------------------------------


def test_start_program_on_input(plant_factory: Any) -> None:
    plant = plant_factory({"plc": {**FAST, "start_program_on_input": [{"input": "E0.2", "program": 4}]}})
    host = plant.host
    assert host.ask(frame("p", 3, 100, 4)) == "E5"
    plant.advance(3.1)
    ok(plant, "p", 10, 16, 3)  # SETO A0.3 (recorded)
    ok(plant, "p", 10, 14, 2)  # WAIT 0.2 s (recorded)
    ok(plant, "p", 10, 17, 3)  # RESO A0.3 (recorded)
    ok(plant, "p", 3, 101, 4)
    assert plant.read("programs") == {4: 3}
    plant.set("input.E0.2", True)  # rising edge
    plant.advance(0.05)
    assert markers(plant, 0)[0] & 0x04  # M0.2: program running
    assert markers(plant, 2)[0] == 4  # MB2
    assert plant.read("output.A0.3") is True
    assert image(plant, 2) == (0x09, 0x00)  # T1;2;0 (A0.0 = brake released, N21 = 1)
    plant.advance(0.3)
    assert plant.read("output.A0.3") is False
    assert markers(plant, 0)[0] & 0x04 == 0
    assert markers(plant, 1)[0] & 0x01  # M1.0 finished successfully
    # holding the input does not restart; the falling edge does nothing; the next rising does
    plant.set("input.E0.2", False)
    plant.advance(0.05)
    assert plant.read("output.A0.3") is False
    plant.set("input.E0.2", True)
    plant.advance(0.05)
    assert plant.read("output.A0.3") is True


def test_start_request_for_a_missing_program_ends(plant_factory: Any) -> None:
    plant = plant_factory({"plc": {**FAST, "start_program_on_input": [{"input": "E0.2", "program": 9}]}})
    plant.set("input.E0.2", True)
    plant.advance(0.05)
    assert markers(plant, 0)[0] & 0x04 == 0
    assert markers(plant, 2)[0] == 9


# -- I/O and markers through the PLC, T reads and the control API (spec §4.11) -------------------------


def test_copy_bits_inputs_outputs_markers(plant_factory: Any) -> None:
    plant = plant_factory(
        {
            "plc": {
                **FAST,
                "copy_bits": [
                    {"from": "E0.4", "to": "A0.5"},
                    {"from": "M40.0", "to": "A1.2", "invert": True},
                    {"from": "E1.1", "to": "M41.3"},
                ],
            }
        }
    )
    plant.advance(0.05)
    assert plant.read("output.A1.2") is True  # NOT M40.0
    assert image(plant, 2) == (0x01, 0x04)  # A0.0 = brake output (N21 = 1)
    plant.set("input.E0.4", True)
    plant.set("input.E1.1", True)
    assert image(plant, 1) == (0x10, 0x02)  # T1;1;0: EB0, EB1
    assert plant.read("output.A0.5") is False  # not before the next cycle
    plant.advance(0.025)
    assert plant.read("output.A0.5") is True
    assert image(plant, 2) == (0x21, 0x04)
    assert markers(plant, 40) == (0x00, 0x08)  # M41.3 from E1.1
    assert plant.read("marker.M41.3") is True
    ok(plant, "p", 11, 40, 1)
    plant.advance(0.025)
    assert plant.read("output.A1.2") is False
    plant.set("input.E0.4", False)
    plant.advance(0.025)
    assert image(plant, 2) == (0x01, 0x00)


def hook_counter(plc: Any) -> None:
    """A Python PLC hook (tests the ``plc.hook`` setting): count cycles in MB50, echo E0.7 to A0.7
    and post message 77 when M60.0 rises."""
    plc.set_marker_byte(50, (plc.marker_byte(50) + 1) & 0xFF)
    plc.set_bit("A0.7", plc.bit("E0.7"))
    if plc.bit("M60.0") and not plc.bit("M60.1"):
        plc.message(77)
        plc.set_bit("M60.1", True)


def test_python_hook(plant_factory: Any) -> None:
    plant = plant_factory({"plc": {**FAST, "hook": "tests.gms96.test_plc:hook_counter"}})
    assert memory_status(plant) == 0x00
    before = markers(plant, 50)[0]
    plant.advance(0.1)
    assert markers(plant, 50)[0] - before == 5
    plant.set("input.E0.7", True)
    plant.advance(0.02)
    assert plant.read("output.A0.7") is True
    ok(plant, "p", 11, 60, 1)
    plant.advance(0.02)
    assert plant.client().status()[1] == 77
    ok(plant, "p", 1, 2, 0)  # stopped: the hook no longer runs
    frozen = markers(plant, 50)[0]
    plant.advance(0.1)
    assert markers(plant, 50)[0] == frozen


def test_brake_output_is_not_the_plcs(plant_factory: Any) -> None:
    plant = plant_factory(
        {"params": {"N21": 1}, "plc": {**FAST, "copy_bits": [{"from": "M40.0", "to": "A0.0"}]}}
    )
    plant.advance(0.05)
    assert plant.read("output.A0.0") is True  # brake released: controller active


# -- counter input as set-point source, electronic gear (spec §5.10, manual §2.6) ----------------------


@pytest.mark.manual("§2.6", "M < 2 saved with s85;170 and a restart: the counter input is the set-point source")
@pytest.mark.manual("§2.6", "N23: each counted increment is worth v set-point increments (1..8)")
def test_counter_input_mode_after_save_and_restart(plant_factory: Any, tmp_path: Any) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    ok(plant, "M", 0)  # M < 2: counter input (takes effect only after s85;170 + restart)
    ok(plant, "N", 4, 23)  # N23 = 4: every counted increment = 4 set-point increments
    ok(plant, "s", 85, 170)
    plant.idle()
    assert plant.read("counter.mode") is False
    plant.set("counter.pulses", 100)
    assert plant.read("position_setpoint") == 0
    plant.set("input.emergency_stop", True)  # emergency stop + release = restart
    plant.set("input.emergency_stop", False)
    plant.advance(0.6)
    assert plant.read("counter.mode") is True
    plant.set("counter.pulses", 100)
    assert host.ask(frame("T", 0)) == t_reply(0x40, codec.to_s24(400))
    plant.set("counter.pulses", -30)
    assert plant.read("position_setpoint") == 280
    assert plant.read("counter.count") == 70
    ok(plant, "A", 10000)  # the indexer is not the set-point source: rejected
    plant.advance(0.1)
    assert plant.read("rejected_moves") == 1 and plant.read("position_setpoint") == 280
    # a pulse stream: the set-point runs at rate x N23, status "motion running"
    plant.set("counter.rate_hz", 500)
    plant.advance(0.5)
    assert plant.read("position_setpoint") == pytest.approx(280 + 1000, abs=2)
    k, _mb4 = plant.client().status()
    assert k & 0x10  # K.4 motion running
    plant.set("counter.rate_hz", 0)
    plant.advance(0.01)
    assert plant.read("motion") is False
    assert plant.read("counter.count") == pytest.approx(70 + 250, abs=1)
    # back to the indexer: M > 1, save, restart
    ok(plant, "M", 2000)
    ok(plant, "s", 85, 170)
    plant.idle()
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    assert plant.read("counter.mode") is False


def hook_that_fails(plc: Any) -> None:
    """A hook that breaks on its third cycle."""
    plc.calls = getattr(plc, "calls", 0) + 1
    if plc.calls == 3:
        raise ZeroDivisionError("division by zero in the user's hook")


def test_a_hook_that_raises_stops_the_plc_visibly(plant_factory: Any) -> None:
    plant = plant_factory({"plc": {**FAST, "hook": "tests.gms96.test_plc:hook_that_fails"}})
    plant.advance(0.2)
    assert plant.read("plc.running") is False  # not "running" while it never cycles again
    assert plant.read("plc.fault") == "ZeroDivisionError: division by zero in the user's hook"
    assert plant.read("plc.cycles") == 3  # the failing cycle was the last
    plant.advance(0.2)
    assert plant.read("plc.cycles") == 3
    ok(plant, "p", 1, 1, 0)  # p1;1 starts it again (and it fails again on its own count)
    assert plant.read("plc.fault") is None


def test_a_hook_that_cannot_be_loaded_is_one_line(tmp_path: Any) -> None:
    from devsim.core.config import ConfigError, load_config
    from devsim.devices.gms96.config import Gms96Config

    path = tmp_path / "card.yaml"
    path.write_text("plc:\n  hook: no_such_module_here:fn\n")
    with pytest.raises(ConfigError) as info:
        load_config(path, Gms96Config)
    assert "card.yaml:2: plc.hook: PLC hook 'no_such_module_here:fn' cannot be loaded: ModuleNotFoundError" in str(
        info.value
    )
    assert "\n" not in str(info.value)


@pytest.mark.manual("§2.3.1 T", "T3;4 I.2: 'Programmier-/Löschfehler des Flash-Speichers (z.B. nach Download)'")
def test_a_plc_download_into_a_defective_flash_is_a_flash_error(plant_factory: Any) -> None:
    plant = plant_factory({})
    host = plant.host
    assert host.ask(frame("p", 1, 100, 0)) == "E5"
    plant.advance(3.1)
    assert host.ask(raw_a(b"\x01\x02")) == "E5"
    assert host.ask(frame("p", 1, 101, 0)) == "E5"
    assert plant.read("plc.image") == "0102" and memory_status(plant) == 0x02
    plant.runtime.fault(plant.name, "flash_error", True)
    assert host.ask(frame("p", 1, 100, 0)) == "E5"  # the erase fails
    plant.advance(3.1)
    assert memory_status(plant) == 0x06  # I.2 FLASH error + I.1 PLC not running
    assert host.ask(raw_a(b"\x03")) == "E5"
    assert host.ask(frame("p", 1, 101, 0)) == "E5"  # and so does the write
    assert memory_status(plant) == 0x06
    assert plant.read("plc.image") == "0102"  # the FLASH stays as it was
    plant.runtime.fault(plant.name, "flash_error", False)
    assert host.ask(frame("p", 1, 100, 0)) == "E5"
    plant.advance(3.1)
    assert host.ask(raw_a(b"\x03")) == "E5"
    assert host.ask(frame("p", 1, 101, 0)) == "E5"
    assert plant.read("plc.image") == "03" and memory_status(plant) == 0x02
