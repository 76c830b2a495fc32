"""What the PCD answers over S-Bus (spec pcd4h3.md §9.4, §9.5, §9.6.2, §9.6.3): reads and writes
of its media, its status, station number and firmware, run, stop and cold restart.

The media a host sees: registers R 0 … 4095 (the axis blocks among them, and the simulator's
read-only diagnostics block), flags F 0 … 8191 (the axis fields, the diagnostics flags), inputs
I 0 … 1023 (each H3 module's limit and reference inputs at FMAH3 + 16m + 9/10/11 and 13/14/15,
the user's keys elsewhere), outputs O 0 … 1023 (the FBs' own: read only), counters and timers.
:data:`SERVICES` is the station's table of S-Bus commands by code (``06h``): each row's
:class:`Service` lays out the telegram and carries it out; :func:`serve` turns one request into
the reply data, an ACK/NAK code, or nothing.  How many elements one telegram reads or writes
at most is the row's (§9.4: 32 registers, counters or timers, 128 flags, inputs or outputs), in
both directions; beyond it the station answers NAK and writes nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import msgspec

from devsim.core.kit import Command, Table
from devsim.core.words import signed32
from devsim.devices.pcd4h3.layout import DIAG_FLAGS, DIAG_REGISTERS
from devsim.devices.pcd4h3.model import BUS_INPUTS, MEDIA_SIZE, Pcd4
from devsim.devices.pcd4h3.sbus import (
    ACK,
    BROADCAST,
    NAK,
    Bad,
    NoParameters,
    Read,
    Reads,
    Request,
    Simple,
    Telegram,
    Write,
    Writes,
    pack_bits,
)

__all__ = [
    "DIAG_FLAGS", "DIAG_REGISTERS", "SERVICES", "Answer", "Service", "bus_input", "read", "serve", "telegram", "write",
]

Answer = bytes | int | None  # reply data, an ACK/NAK code, or no answer (broadcast)


def serve(plc: Pcd4, request: Request) -> Answer:
    """The answer to one request addressed to this station (or broadcast: executed, no answer);
    a command the station does not know gets NAK (§9.2)."""
    service = SERVICES.get(_token(request.command))
    if service is None:
        plc.record_event(f"nak: command {_token(request.command)} is not supported")
        answer: Answer = NAK
    else:
        answer = service(plc, request)
    return None if request.station == BROADCAST else answer


def telegram(code: int) -> Telegram | None:
    """How command ``code``'s parameters are laid out (the receivers' :data:`~devsim.devices.pcd4h3.sbus.Telegrams`)."""
    service = SERVICES.get(_token(code))
    return None if service is None else service.telegram


def _token(code: int) -> str:
    return f"{code:02X}h"


def _read(plc: Pcd4, command: Read) -> Answer:
    if command.address + command.count > MEDIA_SIZE[command.medium]:
        return NAK
    plc.catch_up()
    values = [read(plc, command.medium, command.address + i) for i in range(command.count)]
    if command.medium in ("flag", "input", "output"):
        return pack_bits(values)
    return b"".join((v & 0xFFFF_FFFF).to_bytes(4, "big") for v in values)


def _write(plc: Pcd4, command: Write) -> Answer:
    return ACK if write(plc, command.medium, command.address, command.values) else NAK


def write(plc: Pcd4, medium: str, first: int, values: tuple[int, ...] | list[int]) -> bool:
    """Write consecutive elements of a medium as a host does (registers as signed 32-bit values,
    flags 0/1); False, and nothing written, where the host may not: beyond the medium, the
    outputs (the FBs' own), the diagnostics block.  The seam for other host links (the Modbus
    mirror of spec §9.8 maps its coils and holding registers onto this and :func:`read`)."""
    if first < 0 or first + len(values) > MEDIA_SIZE[medium] or medium not in ("register", "flag"):
        return False
    plc.catch_up()  # the cycles before the write (skipped while the axes only move) see the old values
    if medium == "register":
        if any(_diagnostic_register(plc, first + i) is not None for i in range(len(values))):
            return False
        for i, value in enumerate(values):
            plc.registers[first + i] = signed32(value)
        plc.wake()  # the next cycle's DP14 shows the new value even when nothing moves (manual §9.2)
        return True
    if any(_diagnostic_flag(plc, first + i) is not None for i in range(len(values))):
        return False
    for i, value in enumerate(values):
        plc.flags[first + i] = 1 if value else 0
    plc.wake()
    return True


# -- reading one element --------------------------------------------------------------------------
def read(plc: Pcd4, medium: str, address: int) -> int:
    """One element of a medium as the host reads it (bring the chips to now first:
    ``plc.catch_up()``)."""
    return MEDIA[medium](plc, address)


def _register(plc: Pcd4, address: int) -> int:
    diag = _diagnostic_register(plc, address)
    return diag if diag is not None else plc.registers.get(address, 0)


def _flag(plc: Pcd4, address: int) -> int:
    diag = _diagnostic_flag(plc, address)
    return diag if diag is not None else plc.flags.get(address, 0)


def _input(plc: Pcd4, address: int) -> int:
    bus = bus_input(plc, address)
    return bus if bus is not None else plc.inputs.get(address, 0)


MEDIA: Table[Callable[[Pcd4, int], int]] = Table([
    Command("register", _register, "§9.5, §9.6.3", "R n: the axis blocks, the diagnostics block, the user's"),
    Command("flag", _flag, "§9.5, §9.6.3", "F n: the axis fields, the diagnostics flags, the user's"),
    Command("input", _input, "§2.2, §9.5", "I n: the H3 modules' limit and reference inputs, the user's keys"),
    Command("output", lambda plc, address: plc.outputs.get(address, 0), "§9.5", "O n: the FBs' own"),
    Command("counter", lambda plc, address: plc.counters.get(address, 0), "§9.5", "C n"),
    Command("timer", lambda plc, address: plc.timers.value(address), "§9.5", "T n, in tenths of a second"),
])
"""How the host reads one element of each medium, by the medium's name."""


def bus_input(plc: Pcd4, address: int) -> int | None:
    """An H3 module's input (§2.2), or None for an address outside the modules."""
    relative = address - plc.fmah3
    module, offset = divmod(relative, 16)
    if relative < 0 or module >= int(plc.settings["modules"]):
        return None
    for chip, offsets in BUS_INPUTS.items():
        if offset in offsets:
            n = 2 * module + (1 if chip == "X" else 2)
            name = f'{("LS1", "LS2", "REF")[offsets.index(offset)]}_{n}'
            return int(bool(plc.signals.get(name))) if name in plc.signals else 0
    return 0  # the chip data bus and the unused inputs read 0 without raw bus access


def _diagnostic_register(plc: Pcd4, address: int) -> int | None:
    index = address - plc.diag_registers
    if not 0 <= index < DIAG_REGISTERS * len(plc.axes):
        return None
    n, item = divmod(index, DIAG_REGISTERS)
    return DIAGNOSTICS[item](plc, n) if item < len(DIAGNOSTICS) else 0


def _diagnostic_flag(plc: Pcd4, address: int) -> int | None:
    index = address - plc.diag_flags
    if not 0 <= index < DIAG_FLAGS * len(plc.axes):
        return None
    n, item = divmod(index, DIAG_FLAGS)
    chip = plc.drives[n].chip
    moving = not chip.profile.complete or abs(chip.motor.velocity) > 1.0  # counts/s
    values = (plc.initialised[n], False, moving, plc.axes[n].warnings > 0)
    return int(values[item]) if item < len(values) else 0


def _text(plc: Pcd4, n: int, part: int) -> int:
    top, bottom = plc.screens.get(n + 1, ("", ""))
    data = (top.ljust(6) + bottom.ljust(6)).encode("ascii", "replace")
    return signed32(int.from_bytes(data[4 * part : 4 * part + 4], "big")) if top or bottom else 0


DIAGNOSTICS: tuple[Callable[[Pcd4, int], int], ...] = (
    lambda p, n: p.drives[n].chip.status,
    lambda p, n: p.drives[n].chip.signals,
    lambda p, n: p.drives[n].chip.actual,
    lambda p, n: p.drives[n].chip.desired,
    lambda p, n: round(p.drives[n].chip.profile.velocity / 65536 / p.drives[n].chip.sample_time * 1000),
    lambda p, n: round(p.drives[n].chip.encoder_sign * p.drives[n].motor.velocity * 1000),
    lambda p, n: p.drives[n].chip.filter.dac,
    lambda p, n: round(_volts(p, n) * 1000),
    lambda p, n: p.drives[n].chip.command_errors,
    lambda p, n: p.axes[n].comers_calls,
    lambda p, n: p.axes[n].last_comers,
    lambda p, n: p.handler_calls(),
    lambda p, n: _text(p, n, 0),
    lambda p, n: _text(p, n, 1),
    lambda p, n: _text(p, n, 2),
)
"""The diagnostics registers of one axis (§9.6.3), by offset."""


def _volts(plc: Pcd4, n: int) -> float:
    chip = plc.drives[n].chip
    if chip.motor_off:
        return 0.0
    return chip.filter.volts if chip.filter.dac_bits == 12 else chip.filter.volts * 10.0


def _status(plc: Pcd4, command: Simple) -> bytes:
    return plc.status.encode()


def _station(plc: Pcd4, command: Simple) -> bytes:
    return bytes((plc.station,))


def _firmware(plc: Pcd4, command: Simple) -> bytes:
    return str(plc.settings["firmware"]).encode("ascii", "replace")[:3].ljust(3)


def _restart(plc: Pcd4, command: Simple) -> int:
    plc.restart()
    return ACK


def _run(plc: Pcd4, command: Simple) -> int:
    plc.run()
    return ACK


def _stop(plc: Pcd4, command: Simple) -> int:
    plc.stop()
    return ACK


class Service(msgspec.Struct, frozen=True):
    """One S-Bus command of the station: its telegram (how the parameters are laid out) and what
    the PCD does with it; called with the PCD and the request, it returns the answer."""

    telegram: Reads | Writes | NoParameters
    run: Callable[[Pcd4, Any], Answer]

    def __call__(self, plc: Pcd4, request: Request) -> Answer:
        command = self.telegram.decode(request.parameters)
        if isinstance(command, Bad):
            plc.record_event(f"nak: {command.reason}")  # (why, for the watch and the logs)
            return NAK
        return self.run(plc, command)


def _reads(code: str, medium: str, most: int) -> Command[Service]:
    return Command(code, Service(Reads(medium, most), _read), "§9.4", f"read {medium}s (at most {most})")


def _writes(code: str, medium: str, most: int, note: str = "") -> Command[Service]:
    return Command(code, Service(Writes(medium, most), _write), "§9.4", f"write {medium}s (at most {most}){note}")


def _simple(code: str, name: str, run: Callable[[Pcd4, Simple], Answer]) -> Command[Service]:
    return Command(code, Service(NoParameters(name), run), "§9.4", name)


SERVICES: Table[Service] = Table([
    _reads("00h", "counter", 32),
    _reads("02h", "flag", 128),
    _reads("03h", "input", 128),
    _reads("05h", "output", 128),
    _reads("06h", "register", 32),
    _reads("07h", "timer", 32),
    _writes("0Bh", "flag", 128),
    _writes("0Dh", "output", 128, " (NAK: the outputs belong to the FBs)"),
    _writes("0Eh", "register", 32),
    _simple("1Bh", "read status", _status),
    _simple("1Dh", "read station", _station),
    _simple("20h", "read firmware", _firmware),
    _simple("2Fh", "run", _run),
    _simple("38h", "restart cold", _restart),
    _simple("43h", "stop", _stop),
])
"""The S-Bus commands the station carries out, by command code (§9.4)."""
