"""The PCD4.H3's control names and faults, declared once (spec pcd4h3.md §4.2–§4.5, §5.4, §8,
§9.5).

``R.<n>``, ``F.<n>``, ``I.<n>`` and ``O.<n>`` are the PLC's media as S-Bus shows them;
``axis.<n>.<symbol>`` is a register or flag of axis n's block by its H3DEF symbol
(``axis.1.DestP``, ``axis.1.FStart``); ``axis.<n>.*`` further show the chip and the motor: what
the spec's scenarios inject (``axis.<n>.position`` sets the actual position, ``axis.<n>.load`` a
load torque, ``axis.<n>.bus_errors`` disturbed transfers) and check (``axis.<n>.trace``: the
chip transfers in the spec's notation).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, DriveActions, Fault, FaultTable, SignalDef, Table, signal_points
from devsim.core.points import BadValue, Family, Point, PointTable
from devsim.core.words import signed32
from devsim.devices.pcd4h3.drive import axis_signals
from devsim.devices.pcd4h3.lm628 import POSITION_RANGE, notation
from devsim.devices.pcd4h3.model import HALT, MEDIA_SIZE, RUN, STOP, Pcd4
from devsim.devices.pcd4h3.registers import AxisRegisters
from devsim.devices.pcd4h3.services import bus_input, read, write
from devsim.devices.pcd4h3.tables import FLAG_FIELD, REGISTERS

__all__ = ["DRIVE", "FAULTS", "POINTS", "SIGNALS"]

INT32 = 1 << 31

STATIC_AXES = (1, 2)  # declared in the table; further axes are reached through the families
SIGNALS = tuple(SignalDef(name, kind, initial, doc, "§2.6")  # type: ignore[arg-type]
                for n in STATIC_AXES for name, kind, initial, doc in axis_signals(n))


def _on(n: int, get: Callable[[Pcd4, int], Any]) -> Callable[[Pcd4], Any]:
    """A getter of axis n (None where the installation has no axis n)."""
    def getter(m: Pcd4) -> Any:
        if n > len(m.axes):
            return None
        m.catch_up()
        return get(m, n - 1)

    return getter


def _put_on(n: int, put: Callable[[Pcd4, int, Any], None]) -> Callable[[Pcd4, Any], None]:
    def setter(m: Pcd4, value: Any) -> None:
        if n > len(m.axes):
            raise BadValue(f"the installation has {len(m.axes)} axes")
        m.catch_up()
        put(m, n - 1, value)
        m.drives[n - 1].poke()
        m.wake()

    return setter


def _set_actual(m: Pcd4, i: int, value: int) -> None:
    m.drives[i].chip.set_actual(int(value))


def _set_load(m: Pcd4, i: int, value: float) -> None:
    m.drives[i].motor.load = float(value)


def _set_bus_errors(m: Pcd4, i: int, value: int) -> None:
    m.drives[i].chip.bus_errors = int(value)


def _clear_trace(m: Pcd4, i: int, value: Any) -> None:
    if value not in ([], None):
        raise BadValue("set the trace to [] to clear it")
    m.axes[i].trace.clear()


def _volts(m: Pcd4, i: int) -> float:
    chip = m.drives[i].chip
    if chip.motor_off:
        return 0.0
    return chip.filter.volts if chip.filter.dac_bits == 12 else chip.filter.volts * 10.0


def _axis_points(n: int) -> list[Point]:
    return [
        Point(f"axis.{n}.position", "int", f"axis {n} actual position (RDRP), counts; setting it redefines the "
              "count without motion (a test's injection)", "§5.1", "counts",
              get=_on(n, lambda m, i: m.drives[i].chip.actual), put=_put_on(n, _set_actual), in_state=True),
        Point(f"axis.{n}.set_position", "int", f"axis {n} set position of the profile generator (RDDP)", "§5.2",
              "counts", get=_on(n, lambda m, i: m.drives[i].chip.desired)),
        Point(f"axis.{n}.velocity", "float", f"axis {n} actual velocity as the encoder counts it", "§5.1",
              "counts/s", get=_on(n, lambda m, i: m.drives[i].chip.encoder_sign * m.drives[i].motor.velocity)),
        Point(f"axis.{n}.mechanical_position", "float", f"axis {n} where the motor is (the shared axis, counts "
              "from power-on)", "§5.4", "counts", get=_on(n, lambda m, i: m.drives[i].axis.position())),
        Point(f"axis.{n}.following_error", "int", f"axis {n} set position − actual position", "§5.5", "counts",
              get=_on(n, lambda m, i: m.drives[i].chip.profile.desired - m.drives[i].chip.unwrapped_actual)),
        Point(f"axis.{n}.output_volts", "float", f"axis {n} set-point output (±10 V, or PWM duty × 10 V)", "§5.11",
              "V", get=_on(n, _volts)),
        Point(f"axis.{n}.status", "int", f"axis {n} chip status byte (RDSTAT)", "§4.8",
              get=_on(n, lambda m, i: m.drives[i].chip.status), in_state=True),
        Point(f"axis.{n}.signals", "int", f"axis {n} chip signals register (RDSIGS)", "§4.5",
              get=_on(n, lambda m, i: m.drives[i].chip.signals)),
        Point(f"axis.{n}.motor_off", "bool", f"axis {n} control switched off", "§4.10",
              get=_on(n, lambda m, i: m.drives[i].chip.motor_off), in_state=True),
        Point(f"axis.{n}.display", "json", f"axis {n} PCA2.D14 display [top, bottom] (DP14 as configured)", "§3.4",
              get=_on(n, lambda m, i: list(m.screens[i + 1]) if i + 1 in m.screens else None)),
        Point(f"axis.{n}.trace", "json", f"axis {n} chip transfers, oldest first, as the spec writes them "
              "(C:1F D:00 02 …); set [] to clear", "§6",
              get=_on(n, lambda m, i: [notation(name, words) for name, words in m.axes[i].trace]),
              put=_put_on(n, _clear_trace)),
        Point(f"axis.{n}.comers", "int", f"axis {n} ComErS calls since start-up", "§3.7",
              get=_on(n, lambda m, i: m.axes[i].comers_calls)),
        Point(f"axis.{n}.load", "float", f"axis {n} load torque, as the volts that would hold it", "§8 S21", "V",
              get=_on(n, lambda m, i: m.drives[i].motor.load), put=_put_on(n, _set_load), minimum=-10, maximum=10),
        Point(f"axis.{n}.bus_errors", "int", f"axis {n} chip transfers still to be disturbed on the bus", "§3.7",
              get=_on(n, lambda m, i: m.drives[i].chip.bus_errors), put=_put_on(n, _set_bus_errors),
              minimum=0, maximum=1000),
    ]


def _medium(prefix: str, medium: str, settable: bool) -> Callable[[str], Point | None]:
    """``R.<n>``, ``F.<n>``, ``I.<n>``, ``O.<n>``: n in ASCII digits, as the PCD's addresses are
    written (§9.5; without re.ASCII, \\d also took the Arabic-Indic ٣ and the full-width ３ as 3)."""

    def make(name: str) -> Point | None:
        match = re.fullmatch(rf"{prefix}\.(\d{{1,4}})", name, re.ASCII)
        if match is None or int(match[1]) >= MEDIA_SIZE[medium]:
            return None
        address = int(match[1])
        kind = "int" if medium == "register" else "bool"

        def get(m: Pcd4) -> Any:
            m.catch_up()
            value = read(m, medium, address)
            return value if kind == "int" else bool(value)

        def put(m: Pcd4, value: Any) -> None:
            m.catch_up()  # the cycles before the change (skipped while the axes only move) see the old value
            if medium == "input":
                if bus_input(m, address) is not None:
                    raise BadValue(f"I {address} is an H3 module's own input: set its switch (input.LS1_n, "
                                   "input.LS2_n, input.REF_n)")
                m.inputs[address] = int(bool(value))
                m.wake()
            elif not write(m, medium, address, [signed32(int(value)) if kind == "int" else int(bool(value))]):
                raise BadValue(f"{name} is the simulator's read-only diagnostics block")

        return Point(name, kind, f"{medium} {address} of the PCD", "§9.5", get=get,  # type: ignore[arg-type]
                     put=put if settable else None)

    return make


#: The H3DEF symbols by their lower-case spelling: the PCD assembler does not tell upper from lower
#: case, so a user program may write them either way (manual §7.1.5); so may a point name.
_SYMBOLS = ({r.name.lower(): (r.name, "register") for r in REGISTERS}
            | {f.name.lower(): (f.name, "flag") for f in FLAG_FIELD})


def _axis_family(name: str) -> Point | None:
    match = re.fullmatch(r"axis\.(\d{1,2})\.(\w+)", name, re.ASCII)
    if match is None or not 1 <= int(match[1]) <= 32:
        return None
    n = int(match[1])
    if n not in STATIC_AXES:
        found = next((p for p in _axis_points(n) if p.name == name), None)
        if found is not None:
            return found
    if match[2].lower() not in _SYMBOLS:
        return None
    symbol, medium = _SYMBOLS[match[2].lower()]
    name = f"axis.{n}.{symbol}"  # the manual's spelling, whatever the caller's

    def address(m: Pcd4) -> int:
        if n > len(m.axes):
            raise BadValue(f"the installation has {len(m.axes)} axes")
        return m.layout.register(n, symbol) if medium == "register" else m.layout.flag(n, symbol)

    def get(m: Pcd4) -> Any:
        store = m.registers if medium == "register" else m.flags
        value = store.get(address(m), 0)
        return value if medium == "register" else bool(value)

    def put(m: Pcd4, value: Any) -> None:
        store = m.registers if medium == "register" else m.flags
        store[address(m)] = signed32(int(value)) if medium == "register" else int(bool(value))
        m.wake()

    kind = "int" if medium == "register" else "bool"
    return Point(name, kind, f"axis {n} {medium} {symbol}", "§4.2" if medium == "register" else "§4.3",  # type: ignore[arg-type]
                 get=get, put=put)


#: What setting ``plc.status`` does, by the status letter S-Bus reads (§9.6.2).
PLC_STATUS: Table[Callable[[Pcd4], None]] = Table([
    Command(RUN, Pcd4.run, "§9.6.2", "run, as S-Bus 'run' (2Fh)"),
    Command(HALT, Pcd4.halt, "§9.6.2", "halt, as ComErS does with comers_action: halt"),
    Command(STOP, Pcd4.stop, "§9.6.2", "stop, as S-Bus 'stop' (43h)"),
])


POINTS = PointTable.of(
    *(_axis_points(n) for n in STATIC_AXES),
    [
        Point("plc.status", "str", "PCD status: R run, H halt (ComErS), S stop; set R or S as S-Bus run/stop do",
              "§9.6.2", get=lambda m: m.status, put=lambda m, v: PLC_STATUS[v](m), choices=tuple(PLC_STATUS.rows),
              in_state=True),
        Point("plc.restart", "bool", "a cold restart: AxInit for every axis with the registers as they are (S-Bus "
              "38h)", "§9.6.1", put=lambda m, v: m.restart() if v else None, example=True),
    ],
    signal_points(SIGNALS),
    families=[
        Family("axis.<n>.<symbol>", "int", "a register (KProp … RSigB) or flag (OnDest … FBackw) of axis n's "
               "block by its H3DEF symbol, in any case (axis.1.destp is axis.1.DestP); also axis.<n>.* beyond axis 2", "§4.2, §4.3", _axis_family),
        Family("R.<n>", "int", "register n (0 … 4095) as S-Bus reads it", "§9.5", _medium("R", "register", True),
               modbus=(("holding", "input"), 4096)),
        Family("F.<n>", "bool", "flag n (0 … 8191)", "§9.5", _medium("F", "flag", True), modbus=(("coil",), 8192)),
        Family("I.<n>", "bool", "input n (0 … 1023); the H3 modules' own inputs follow their switches", "§9.5",
               _medium("I", "input", True), modbus=(("discrete",), 1024)),
        Family("O.<n>", "bool", "output n (0 … 1023)", "§9.5", _medium("O", "output", False), access="r"),
    ],
)


def _fault(n: int, what: str) -> Callable[[Pcd4, bool], None]:
    def apply(m: Pcd4, active: bool) -> None:
        if n > len(m.axes):
            raise BadValue(f"the installation has {len(m.axes)} axes")
        m.catch_up()
        drive = m.drives[n - 1]
        if what == "blocked":
            drive.motor.blocked = active
        else:
            count = drive.chip.actual  # the count stays where it is when the wiring changes
            drive.chip.encoder_sign = -1 if active else 1
            drive.chip.set_actual(count)
        drive.poke()
        m.wake()

    return apply


FAULTS = FaultTable([
    *(Fault(f"blocked_{n}", f"axis {n}: the rotor is blocked (the motor does not turn)", "§5.2, §6.6 E11",
            _fault(n, "blocked")) for n in STATIC_AXES),
    *(Fault(f"encoder_reversed_{n}", f"axis {n}: one phase inversion jumper wrong: the decoder counts backwards "
            "(runaway, S20)", "§2.5", _fault(n, "reversed")) for n in STATIC_AXES),
])


# -- axis 1 as a drive (CiA 402 facade): the library's functions, run at once --------------------
def _run(m: Pcd4, *symbols: str) -> None:
    m.catch_up()
    axis = m.axes[0]
    for symbol in symbols:
        axis.run(symbol)
    m.drives[0].poke()
    m.wake()


def _registers(m: Pcd4) -> AxisRegisters:
    return m.axes[0].registers


def _user(m: Pcd4, counts: float, what: str) -> int:
    """``counts`` in the user unit of MCFac, as a PCD register holds it (signed 32 bits); a value
    the register cannot hold is refused before anything is written (a PCD register would wrap it
    and the axis would go elsewhere)."""
    k = m.axes[0].k
    value = round(counts / k) if k and math.isfinite(counts) else 0
    if not -INT32 <= value < INT32:
        raise BadValue(f"{what} {counts:g} counts is {value} in MCFac's unit: more than a 32-bit PCD register holds")
    return value


def _target(m: Pcd4, counts: float) -> int:
    """A target position in DestP's unit; beyond the LM628's position range (−2^30 … 2^30 − 1
    counts, manual §7.4 FLdDA) the chip would refuse it with a command error: refused here."""
    if not -POSITION_RANGE <= counts < POSITION_RANGE:
        raise BadValue(f"target {counts:g} counts is beyond the LM628's position range −2^30 … 2^30 − 1")
    return _user(m, counts, "target")


def _enable(m: Pcd4, on: bool) -> None:
    if on:  # hold where the axis stands
        m.catch_up()
        _registers(m).destination = _target(m, m.drives[0].chip.actual)
        _run(m, "FLdDA", "FStart")
    else:
        _run(m, "FMotOff")


def _move_to(m: Pcd4, target: float, speed: float) -> None:
    destination = _target(m, target)
    if speed > 0:
        _registers(m).velocity = _user(m, speed, "speed")
        _run(m, "FLdVA")
    _registers(m).destination = destination
    _run(m, "FLdDA", "FStart")


def _jog(m: Pcd4, velocity: float) -> None:
    if velocity == 0:
        _stop(m, 0x0400)
    else:
        _registers(m).velocity = _user(m, abs(velocity), "speed")
        _run(m, "FLdVA", "FForw" if velocity > 0 else "FBackw")


def _stop(m: Pcd4, bits: int) -> None:
    """FStop with MCW's stop bits 8 … 10 set to ``bits`` (0400h smooth, 0200h abrupt)."""
    registers = _registers(m)
    registers.control_word = (registers.control_word & ~0x0700) | bits
    _run(m, "FStop")


def _reset_fault(m: Pcd4) -> None:
    _registers(m).status_reset = 0
    _run(m, "FResSF")


def _only_axis_1(m: Pcd4) -> Any:
    """Axis 1's drive as of now (the chips may have been computed ahead of the present)."""
    m.catch_up()
    return m.drives[0]


DRIVE = DriveActions(
    enable=_enable,
    move_to=_move_to,
    jog=_jog,
    quick_stop=lambda m: _stop(m, 0x0200),
    reset_fault=_reset_fault,
    position=lambda m: _only_axis_1(m).chip.actual,
    velocity=lambda m: (lambda drive: drive.chip.encoder_sign * drive.motor.velocity)(_only_axis_1(m)),
    enabled=lambda m: not _only_axis_1(m).chip.motor_off,
    fault=lambda m: bool(_only_axis_1(m).chip.status & 0x20),
    moving=lambda m: not _only_axis_1(m).chip.profile.complete,
    following_error=lambda m: (lambda chip: chip.profile.desired - chip.unwrapped_actual)(_only_axis_1(m).chip),
)
"""Axis 1 as a CiA 402 drive: positions in counts, speeds in counts/s; the functions run at once
as a host-side call of the FBs would; a quick stop is FStop with MCW's abrupt stop; a fault is an
excessive position error."""
