"""The configurable readings of the spec's gaps (spec pcd4h3.md §10, G-rows marked as options), each
driven by a host over S-Bus on a real pty: with the option the answer differs from the default's,
and the default is the recommended reading."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from devsim.devices.pcd4h3.sbus import FS, crc16
from tests.pcd4h3.helpers import Station, load, reg, run

HOST_INTERRUPT, BREAKPOINT, COMPLETE = 1 << 15, 1 << 6, 1 << 2  # RSigB bits (§4.5)


def read(pcd: Station, function: str, register: str) -> int:
    run(pcd, function)
    return pcd.read_registers(reg(register))[0]


@pytest.mark.parametrize("unsigned", [False, True])
def test_velocity_readback_unsigned(make: Callable[..., Station], unsigned: bool) -> None:
    """G-11: FRdSV and FRdAV signed (negative backwards) by default, without the sign with the option."""
    pcd = make({"velocity_readback_unsigned": unsigned})
    load(pcd, Veloc=200)
    run(pcd, "FLdVA", "FBackw")
    pcd.sim.advance(3.0)
    sign = 1 if unsigned else -1
    assert read(pcd, "FRdSV", "RSetV") == sign * 200
    assert read(pcd, "FRdAV", "RActV") == pytest.approx(sign * 200, rel=0.05)


@pytest.mark.parametrize("emulate", [False, True])
def test_emulate_host_interrupt(make: Callable[..., Station], emulate: bool) -> None:
    """G-12: RSigB bit 15 is 0 by default; with the option it is 1 while a flag the mask enables is
    set: trajectory complete after AxInit, not the breakpoint's (masked after RESET)."""
    pcd = make({"emulate_host_interrupt": emulate})
    assert read(pcd, "FRdSR", "RSigB") & (HOST_INTERRUPT | COMPLETE) == (HOST_INTERRUPT if emulate else 0) | COMPLETE
    load(pcd, BrkP=10, DestP=100)
    run(pcd, "FLdBPA", "FLdDA", "FStart")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), 10.0)
    load(pcd, StaFRR=0xFFFF & ~COMPLETE)  # reset trajectory complete only: the breakpoint flag stays
    run(pcd, "FResSF")
    assert read(pcd, "FRdSR", "RSigB") & (HOST_INTERRUPT | BREAKPOINT | COMPLETE) == BREAKPOINT


@pytest.mark.parametrize("literal", [False, True])
def test_literal_mcw_command(make: Callable[..., Station], literal: bool) -> None:
    """G-8: an MCW low byte other than 1Ah/1Bh is FSetPE's command error (ComErS) by default; with the
    option it goes to the chip as its command byte: 02h = DFH, the actual position becomes 0."""
    pcd = make({"literal_mcw_command": literal})
    load(pcd, DestP=100)
    run(pcd, "FLdDA", "FStart")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), 10.0)
    pcd.sim.advance(0.5)
    load(pcd, MCW=0x0402)
    run(pcd, "FSetPE")
    assert pcd.sim.read("axis.1.comers") == (0 if literal else 1)
    assert read(pcd, "FRdAP", "RActP") == pytest.approx(0 if literal else 100, abs=1)


@pytest.mark.parametrize("excludes", [False, True])
def test_crc_excludes_fs(make: Callable[..., Station], excludes: bool) -> None:
    """§9.2 tolerance: a request whose CRC leaves FS out is dropped by default (CRC error, no reply),
    answered with the option; the CRC over FS … data is taken either way."""
    pcd = make({"crc_excludes_fs": excludes})
    body = bytes((FS, 0, 1, 0x06, 0)) + reg("Veloc").to_bytes(2, "big")
    pcd.send_raw(body + crc16(body[1:]).to_bytes(2, "big"))
    if excludes:
        assert pcd.receive(4)[2:-2] == (500).to_bytes(4, "big")
    assert pcd.read_registers(reg("Accel")) == [100]  # the next answer is this request's: the first got none


@pytest.mark.parametrize(("config", "counts_per_s"), [
    ({}, 19_980.469), ({"fb_sample_time_us": 2048 / 6}, 20_000.0), ({"chip_sample_time_us": 256.0}, 26_640.65)])
def test_sample_times(make: Callable[..., Station], config: dict, counts_per_s: float) -> None:
    """G-6, §5.1: the FBs convert with 341 µs (``fb_sample_time_us``), the chip samples every 341.333 µs
    (``chip_sample_time_us``), so 200 × k = 20 000 counts/s run 0.1 % slow by default, exactly with the
    chip's sample time in the FBs, a third faster on an 8 MHz chip (256 µs): the chip's profile velocity
    (diagnostics R 4004, counts/s × 1000) and the motor's; read back through the FBs' constants, FRdSV
    gives the commanded 200 in every case."""
    pcd = make(config)
    load(pcd, Veloc=200)
    run(pcd, "FLdVA", "FForw")
    pcd.sim.advance(3.0)
    assert pcd.read_registers(4004)[0] / 1000 == pytest.approx(counts_per_s, abs=0.5)
    assert pcd.sim.read("axis.1.velocity") == pytest.approx(counts_per_s, rel=0.01)
    assert read(pcd, "FRdSV", "RSetV") == 200
