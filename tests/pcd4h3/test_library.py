"""The PCD9.H3E1 library on one axis: AxInit and AxHndlg with the manual's Example 1 (spec
pcd4h3.md §3.3, §6.2, §6.3)."""

from __future__ import annotations

import pytest

from devsim.devices.pcd4h3.layout import Layout
from devsim.devices.pcd4h3.library import FUNCTIONS, H3Axis
from devsim.devices.pcd4h3.lm628 import Lm628
from devsim.devices.pcd4h3.pid import Motor
from devsim.devices.pcd4h3.registers import AxisRegisters, RegisterBlock
from devsim.devices.pcd4h3.tables import command_flags
from devsim.devices.pcd4h3.units import CHIP_SAMPLE

EXAMPLE_1 = {212: 0x41B, 206: 2000, 200: 150, 201: 50, 202: 50, 203: 500, 204: 15, 205: 0xC8000047 - (1 << 32),
             209: 500, 210: 100}


def example_axis() -> tuple[H3Axis, dict[int, int]]:
    registers: dict[int, int] = dict(EXAMPLE_1)
    flags: dict[int, int] = {}
    layout = Layout(bar=200, baf=200, axes=1)
    block = AxisRegisters(RegisterBlock(registers, layout.block(1)))
    return H3Axis(1, layout, Lm628(Motor()), block, flags), registers


def test_the_functions_are_the_command_flags_in_their_order() -> None:
    """§3.2: one library function per command flag of the flag field, in the field's order."""
    assert [row.token for row in FUNCTIONS] == [row.name for row in command_flags()]


def test_axinit_issues_the_chip_trace_of_example_1() -> None:
    """§6.2: RESET, PORT12, LTRJ 0000h, LPEI 2000, LFIL 0F0Fh 150 50 50 500, UDF, motor off +
    STT, acceleration 76, velocity 1 117 389; then status 84h, RSigB 4084h, OnDest 1."""
    axis, _ = example_axis()
    axis.flags[207] = 1  # a command flag left over: cleared by AxInit
    axis.init(6)
    assert axis.trace == [
        ("RESET", ()), ("PORT12", ()), ("LTRJ", (0x0000,)), ("LPEI", (2000,)),
        ("LFIL", (0x0F0F, 150, 50, 50, 500)), ("UDF", ()), ("LTRJ", (0x0100,)), ("STT", ()),
        ("LTRJ", (0x0020, 76)), ("LTRJ", (0x0008, 1_117_389)),
    ]
    assert axis.chip.signals & 0x2000  # UDF executed: bit 13 for the sample after it
    axis.chip.sample()  # (AxInit takes milliseconds: the chip samples meanwhile)
    assert axis.chip.status == 0x84 and axis.chip.signals == 0x4084
    assert axis.flags[200] == 1 and axis.flags[207] == 0 and axis.chip.actual == 0


def test_example_1_motion_program_through_the_flags() -> None:
    """§6.3: DestP 1000 (100 mm) + FLdDA + FStart: LTRJ 0002h 000186A0h, STT; flags read back 0,
    OnDest 0; after ≈ 6.34 s OnDest 1 at 100 000 counts, FRdAP gives R 213 = 1000."""
    axis, registers = example_axis()
    axis.init(6)
    axis.trace.clear()
    registers[207] = 1000
    axis.flags[207] = axis.flags[228] = 1
    assert axis.handle() == pytest.approx(0.5 + 4.1 + 1.0)  # base time and the two functions (§10.1)
    assert axis.trace == [("LTRJ", (0x0002, 100_000)), ("STT", ())]
    assert axis.flags[207] == axis.flags[228] == 0 and axis.flags[200] == 0
    samples = 0
    while not axis.flags[200]:
        for _ in range(29):  # one 10 ms PLC cycle
            axis.chip.sample()
        samples += 29
        axis.handle()
    assert samples * CHIP_SAMPLE == pytest.approx(6.34, rel=0.02)
    axis.flags[221] = 1  # FRdAP
    axis.handle()
    assert registers[213] == pytest.approx(1000, abs=1)
