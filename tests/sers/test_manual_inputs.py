"""Manual §3.3.1, §4.8.1.1, §4.8.6.3 and §4.8.6.14: the digital inputs' manual functions, through the
pty on virtual time."""

from __future__ import annotations

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import download


def _boot_with(plant_factory, config: dict, inputs: tuple[str, ...]) -> Plant:  # type: ignore[no-untyped-def]
    plant: Plant = plant_factory(config, boot=False)
    for name in inputs:
        plant.set(f"input.{name}", True)  # active from power-on
    plant.advance(2.0)  # the initialisation (display '-', §3.5)
    return plant


@pytest.mark.manual("§4.8.6.3", "P1095=0: at a power-on reset a jog function is activated when the signal is "
                    "present statically at its input")
@pytest.mark.manual("§4.5.1", "jogging through the inputs I1 to I4 energises the motor automatically")
def test_p1095_0_a_static_jog_input_starts_after_power_on(plant_factory) -> None:
    plant = _boot_with(plant_factory, {"params": {"P1021": 2, "P1095": 0}}, ("I2",))  # I2: right slow
    plant.advance(0.5)
    assert plant.read("motion.kind") == "jog"
    assert plant.read("energized") is True
    assert plant.read("axis.velocity") > 0


@pytest.mark.manual("§4.8.6.3", "P1095=1: at a power-on reset a jog function is activated only by an edge to '1'")
def test_p1095_1_needs_an_edge_after_power_on(plant_factory) -> None:
    plant = _boot_with(plant_factory, {"params": {"P1021": 2, "P1095": 1}}, ("I2",))
    plant.advance(0.5)
    assert plant.read("motion.kind") is None
    plant.set("input.I2", False)
    plant.set("input.I2", True)
    plant.advance(0.5)
    assert plant.read("motion.kind") == "jog"


@pytest.mark.manual("§4.5.1", "jogging with commands over the serial interface needs the motor energised before "
                    "(ON)")
def test_serial_jog_needs_on(sers: Plant) -> None:
    from tests.sers.test_programs import refused

    refused(sers.host, "#RS\r", 79)
    assert sers.read("motion.kind") is None
    sers.host.ask("#ON RS\r")
    assert sers.read("motion.kind") == "jog"


@pytest.mark.manual("§3.1.4", "service switch (DIP 1 bit 6) ON: all jog functions are available at the digital "
                    "inputs (without P1021)")
def test_service_switch_enables_the_jog_inputs(plant_factory) -> None:
    plant = plant_factory({"service_switch": True})
    plant.set("input.I4", True)  # right fast
    plant.advance(0.2)
    assert plant.read("motion.kind") == "jog"
    assert plant.read("axis.velocity") > 0


@pytest.mark.manual("§4.8.1.1", "P1022: an input also set in P1021 is blocked for parallel mode (P1022=3, "
                    "P1021=129: I1 jogs left and is no address bit, so I1 with the start edge calls L1)")
def test_an_input_enabled_in_p1021_is_no_address_bit(plant_factory) -> None:
    plant: Plant = plant_factory({"params": {"P1022": 3, "P1021": 129}})
    download(plant.host, "L1 O1=1 RT", "L2 O2=1 RT")
    assert plant.host.ask("#ON\r").endswith(b"ok1\n\r")
    plant.set("input.I1", True)
    plant.set("input.I8", True)  # the start edge
    plant.advance(0.05)
    assert (plant.read("output.O1"), plant.read("output.O2")) == (True, False)  # address 0, not 1
    assert plant.read("motion.kind") == "jog"  # I1 is the jog input it is enabled as
