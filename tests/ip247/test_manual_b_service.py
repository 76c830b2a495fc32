"""The manual's hardware chapter and the service parts of chapter 7 walked (manual §3 Hardware:
pages, X21, X7, X8; §7.1 Projektierung und Inbetriebnahme, §7.2.3 PG-Schnittstellenfehler, §7.3
Ergänzende Hinweise), driven through the PG port (AS511 on a real pty) or the PLC endpoint."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import pytest
import serial

from devsim.core.config import ConfigError
from devsim.devices.ip247.client import AgClient, As511Error, PgClient
from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, Make, Module, record
from tests.ip247.test_machine_data import COM247, words


def position(mod: Module, page: int = 1) -> int:
    return struct.unpack(">i", mod.call(0x62, bytes((page,)))[8:12])[0]


@pytest.mark.manual("§3.3.2", "the four pages of a module are four consecutive numbers from the base address set "
                    "with S2: one per axis, the fourth for the programs; the next module starts 4 higher")
def test_the_four_pages_from_the_base_address(devsim_device: Any) -> None:
    module = devsim_device("ip247", {"base_page": 84}, transport="tcp")
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    md = words(COM247)
    md[3] = 0x0002  # module 0, axis 2
    module.set("input.ANF2", True)
    module.set("input.END2", True)
    with AgClient(host, int(port)) as plc:
        assert plc.write_record(85, 20, 9, md)[:2] == bytes((0, 85))  # the second page: axis 2
        assert module.read("axis.2.md_error") == 0
        assert plc.read_record(87, 65)[0] == 0 and plc.write_record(87, 24, 0, [0, 0, 0])[0] == 0  # data channel
        for page in (83, 88):  # the module before, the next module
            assert plc.read_record(page, 70)[0] == 0x80


@pytest.mark.manual("§3.3.2", "the page address is set in steps of 4 in the range 0 … 252")
@pytest.mark.parametrize("base_page", [5, 254, 256])
def test_a_base_page_off_the_steps_of_4_is_refused(devsim_plant: Any, tmp_path: Path, base_page: int) -> None:
    plant = "devices:\n  - name: ip\n    kind: ip247\n    config: {base_page: %d}\n"
    (tmp_path / "bad.yaml").write_text(plant % base_page)
    with pytest.raises(ConfigError, match="base_page"):
        devsim_plant(tmp_path / "bad.yaml")
    (tmp_path / "good.yaml").write_text(plant % 252)
    devsim_plant(tmp_path / "good.yaml")


@pytest.mark.manual("§3.3.2", "jumper X21 1-2: the digital outputs cannot be disabled; 2-3: BASP disables them")
@pytest.mark.parametrize(("x21", "disabled"), [("2-3", True), ("1-2", False)])
def test_basp_and_the_jumper_x21(make: Make, x21: str, disabled: bool) -> None:
    mod = make({"x21": x21})
    mod.ready()
    mod.operate(1, 7, FORWARD, w=1000, dd=1_000)
    mod.clock.advance(5)
    assert mod.device.read("output.PE1") is True
    mod.device.set("input.BASP", True)
    mod.clock.advance(0.1)
    assert mod.device.read("output.PE1") is not disabled
    assert (mod.device.read("axis.1.error") == 55) is disabled


@pytest.mark.manual("§3.3.4", "front connector X7: per axis the inputs limit switch ANF, reference switch BERO, "
                    "limit switch END and external start/stop, and the output 'Position erreicht' PE")
def test_each_axis_has_its_own_inputs_and_output(make: Make) -> None:
    mod = make({"axes": {2: {"end": 5_000.0}}})
    for axis in (1, 2, 3):
        mod.ready(axis)
    mod.device.set("input.START3", True)
    for axis in (1, 2, 3):
        mod.operate(axis, 7, FORWARD, w=1000, dd=10_000)
    mod.clock.advance(10)
    assert [mod.device.read(f"axis.{n}.error") for n in (1, 2, 3)] == [0, 26, 6]
    assert [mod.device.read(f"output.PE{n}") for n in (1, 2, 3)] == [True, False, False]
    assert [position(mod, n) for n in (1, 3)] == [11_000, 1_000]


@pytest.mark.manual("§3.3.5", "the PG interface X8 runs at 9600 bit/s (the PG's cable sets the rate)")
@pytest.mark.manual("§7.1.5.3", "online, the PG shows the SYS-ID with the firmware state ('IP247', 'A02.1')")
def test_the_pg_port_at_9600(mod: Module) -> None:
    assert mod.port.baudrate == 9600 and mod.port.parity == serial.PARITY_EVEN
    assert mod.call(0x64, bytes((4, 70, 0, 0)))[8:20] == b"IP247 A02.1 "


@pytest.mark.manual("§7.2.3", "F53H 'Zeitfehler Baugruppe': no connection to the module, e.g. when it has no "
                    "supply; the PG gets no answer")
def test_a_module_without_supply_does_not_answer(mod: Module) -> None:
    # with supply it answers; and so the pty has heard the fixture's open at 8E1 before the second
    # open below asks for parity again (two requests with no gap at all may fail: docs/connect.md)
    assert mod.call(0x64, bytes((4, 70, 0, 0)))[8:14] == b"IP247 "
    mod.device.fault("power", True)
    with serial.serial_for_url(mod.device.port_url("pg"), baudrate=9600, parity="E", timeout=0.5) as port:
        with pytest.raises(As511Error):
            PgClient(port).read_record(4, 70)
    mod.device.fault("power", False)
    mod.clock.advance(2)  # the start-up second (LEDs blinking) is over
    assert mod.call(0x64, bytes((4, 70, 0, 0)))[8:14] == b"IP247 "


@pytest.mark.manual("§7.3.1", "commands are executed in the order they arrive: a Stopp only after the commands "
                    "before it; a start entered after the Stopp makes the drive move off again at once")
def test_commands_in_arrival_order(mod: Module) -> None:
    mod.ready()
    for cmd in (FORWARD, BACKWARD, FORWARD, STOP, FORWARD):
        mod.operate(1, 1, cmd, w=1000)
    mod.clock.advance(3)
    assert mod.device.read("axis.1.running") is True and mod.device.read("axis.1.velocity") > 0
    mod.operate(1, 1, STOP)
    mod.clock.advance(3)
    assert mod.device.read("axis.1.running") is False


@pytest.mark.manual("§7.3.3", "after every restart the reference point is deleted, 'Achse aus' (BA4) is preset and "
                    "a running job is no longer active")
@pytest.mark.manual("§7.3.3", "with the battery intact the machine data stay valid and the actual value reported is "
                    "the reference point's coordinate")
@pytest.mark.manual("§3.1.1", "while the module stays in a buffered rack, machine data and programs survive a "
                    "power failure; a failure of the 5 V supply resets the module")
def test_restart_with_the_battery(mod: Module) -> None:
    mod.ready()
    mod.store(5, "%  5\nN1 X100 F1000\nN2 M02\n")
    mod.operate(1, 8, START, b=5)
    mod.clock.advance(1)
    mod.device.fault("power", True)
    mod.device.fault("power", False)
    mod.clock.advance(2)
    answer = mod.call(0x62, b"\x01")
    assert answer[5] == 4 and answer[6] & 0xA0 == 0xA0  # BA4; reference missing, fertig
    assert struct.unpack(">i", answer[8:12])[0] == 1_000  # x_ref of COM247's machine data
    mod.clock.advance(60)
    assert position(mod) == 1_000 and mod.device.read("axis.1.md_error") == 0
    assert mod.device.read("program.5") == "%  5\nN1 X100 F1000\nN2 M02\n"
    assert mod.operate(1, 6, START, w=1000, dd=0)[4] == 10


@pytest.mark.manual("§7.3.3", "when the battery buffering failed (module pulled) all machine data and programs are "
                    "lost, zero offsets and tool offsets deleted")
def test_restart_without_the_battery(mod: Module) -> None:
    mod.ready()
    mod.store(5, "%  5\nN1 X100 F1000\nN2 M02\n")
    mod.operate(1, 13, FORWARD, dd=2_000)
    mod.operate(1, 15, FORWARD, dd=3_000)
    mod.device.fault("battery_failed", True)
    mod.device.fault("power", True)
    mod.device.fault("power", False)
    mod.device.fault("battery_failed", False)
    mod.clock.advance(2)
    assert mod.call(0x64, bytes((4, 64, 0, 0)))[8:] == bytes(12)
    assert mod.call(0x64, bytes((4, 65, 0, 0)))[8:] == b""
    assert mod.load_md()[8] == 0 and mod.operate(1, 5, START, b=1)[4] == 0
    assert position(mod) == 1_000  # no zero offset, no tool offset left


@pytest.mark.manual("§7.1.5.3", "after power-on the LEDs blink alternately for a moment, then the green LED is lit")
@pytest.mark.manual("§7.1.5.3", "after a machine-data set is transferred its power unit automatically gets an "
                    "initialising pulse (RS)")
@pytest.mark.manual("§3.3.3", "the module gives each axis's power unit a high-active reset pulse (RS)")
def test_commissioning_leds_and_the_reset_pulse(mod: Module) -> None:
    mod.device.fault("power", True)
    mod.device.fault("power", False)
    seen = set()
    for _ in range(4):
        seen.add((mod.device.read("output.led_green"), mod.device.read("output.led_red")))
        mod.clock.advance(0.25)
    assert {(True, False), (False, True)} <= seen
    mod.clock.advance(1)
    assert mod.device.read("output.led_green") is True
    assert mod.load_md()[8] == 0
    assert mod.device.read("output.RS1") is True
    mod.clock.advance(0.2)
    assert mod.device.read("output.RS1") is False


@pytest.mark.manual("§7.1.5.3", "software limits: braking begins only when the software limit switch is reached")
def test_braking_begins_at_the_software_limit(mod: Module) -> None:
    mod.ready()  # COM247's MD: software limit end +500 mm
    mod.operate(1, 6, START, w=6000, dd=490_000)
    mod.clock.advance(30)
    mod.operate(1, 1, FORWARD, w=6000)
    mod.clock.advance(10)
    assert mod.device.read("axis.1.error") == 29 and position(mod) > 500_000


@pytest.mark.manual("§7.1.5.3", "BA4 'Achse aus': a running mode is aborted (the aborted mode stays shown, §4.2.2)")
def test_axis_off_aborts_the_running_mode(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 7, FORWARD, w=1000, dd=200_000)
    mod.clock.advance(1)
    assert mod.operate(1, 4, START)[4] == 0
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is False and position(mod) < 50_000
    observed = mod.call(0x62, b"\x01")
    assert observed[5] == 7 and observed[20] == STOP  # BTR: the aborted BA7; last command: Stopp


@pytest.mark.manual("§7.1.3", "the pulse frequency is the velocity divided by the resolution: "
                    "f = v [mm/min] / (k [µm/pulse] · 60)")
def test_velocity_and_pulse_frequency(mod: Module) -> None:
    mod.ready()  # k = 1.1 µm per pulse
    mod.operate(1, 1, FORWARD, w=3300)
    mod.clock.advance(3)
    frequency = mod.device.read("axis.1.velocity") / 1.1  # pulses per second
    assert frequency == pytest.approx(3300 * 1000 / (1.1 * 60))


@pytest.mark.manual("§3.3.3", "the polarity of clock and direction level is programmable (machine data)")
def test_the_direction_level_follows_the_polarity(mod: Module) -> None:
    mod.ready(1)  # COM247's MD: positive edge (40H)
    assert mod.load_md(axis=2, record=record(pulse_polarity=0x00))[8] == 0
    mod.operate(2, 5, START, b=1)
    for axis in (1, 2):
        mod.operate(axis, 1, FORWARD, w=1000)
    mod.clock.advance(1)
    assert (mod.device.read("output.RP1"), mod.device.read("output.RP2")) == (True, False)
    for axis in (1, 2):
        mod.operate(axis, 1, STOP)
    mod.clock.advance(2)
    for axis in (1, 2):
        mod.operate(axis, 1, BACKWARD, w=1000)
    mod.clock.advance(1)
    assert (mod.device.read("output.RP1"), mod.device.read("output.RP2")) == (False, True)
