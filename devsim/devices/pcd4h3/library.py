"""The PCD9.H3E1 library on one axis (spec pcd4h3.md §3.2–§3.4, §4.2–§4.9): AxInit, and AxHndlg
running the function command flags in offset order against the LM628, converting with the
machine factor, and copying the chip's status into the status flags at the end.

The PLC media are plain mappings (register and flag address → value) the caller owns; the chip
is a :class:`~devsim.devices.pcd4h3.lm628.Lm628`.  Every chip command the functions issue is
appended to :attr:`H3Axis.trace` as the spec writes its chip traces (§6.2).  Command-error
handling (retries, ComErS, §3.7) is not here yet.
"""

from __future__ import annotations

from collections.abc import Callable, MutableMapping

from devsim.devices.pcd4h3.layout import FLAGS, Layout
from devsim.devices.pcd4h3.lm628 import Lm628
from devsim.devices.pcd4h3.units import (
    CHIP_SAMPLE,
    FB_SAMPLE,
    acceleration_register,
    counts,
    ffp_decode,
    round_half_away,
    velocity_register,
)

__all__ = ["FUNCTIONS", "H3Axis"]

COMMAND_FLAGS = tuple(f.symbol for f in FLAGS if f.kind == "command")
STATUS_FLAGS = ("OnDest", "IPuls", "WrapOc", "ExcPEr", "BrkPos")  # status bits 2 … 6
FORWARD_END, BACKWARD_END = 0x3FFF_FFFF, 0xC000_0000


class H3Axis:
    """Axis ``axis`` of an installation: its registers and flags in the media, its chip."""

    def __init__(self, axis: int, layout: Layout, chip: Lm628, registers: MutableMapping[int, int],
                 flags: MutableMapping[int, int]) -> None:
        self.axis, self.layout, self.chip = axis, layout, chip
        self.registers, self.flags = registers, flags
        self.mode = 0  # LTRJ bits 11/12 from the last FSelOM
        self.trace: list[tuple[str, tuple[int, ...]]] = []

    # -- media ------------------------------------------------------------------------------------
    def reg(self, symbol: str) -> int:
        return self.registers.get(self.layout.register(self.axis, symbol), 0)

    def put(self, symbol: str, value: int) -> None:
        self.registers[self.layout.register(self.axis, symbol)] = value

    def flag(self, symbol: str) -> int:
        return self.flags.get(self.layout.flag(self.axis, symbol), 0)

    def set_flag(self, symbol: str, value: int) -> None:
        self.flags[self.layout.flag(self.axis, symbol)] = value

    @property
    def k(self) -> float:
        return ffp_decode(self.reg("MCFac"))

    # -- the chip, traced ----------------------------------------------------------------------------
    def _ltrj(self, control: int, *values: int) -> None:
        self.trace.append(("LTRJ", (control, *values)))
        self.chip.load_trajectory(control, list(values))

    def _stt(self) -> None:
        self.trace.append(("STT", ()))
        self.chip.start()

    def _cmd(self, name: str, *data: int) -> None:
        self.trace.append((name, data))

    # -- AxInit, AxHndlg (§3.3) -----------------------------------------------------------------------
    def init(self, imode: int = 6) -> None:
        """AxInit: reset, output port, mode, position error, filter, acceleration (with motor
        off), velocity, command flags cleared."""
        self._cmd("RESET")
        self.chip.reset()
        self._cmd("PORT12" if imode == 6 else "PORT8")
        self.chip.port(12 if imode == 6 else 8)
        for symbol in ("FSelOM", "FSetPE", "FLdRP", "FUpDRP", "FLdAA", "FLdVA"):
            FUNCTIONS[symbol](self)
        for symbol in COMMAND_FLAGS:
            self.set_flag(symbol, 0)
        self._status()

    def handle(self) -> list[str]:
        """AxHndlg: every set command flag in offset order, then the status flags; returns the
        functions run."""
        ran = []
        for symbol in COMMAND_FLAGS:
            if self.flag(symbol):
                FUNCTIONS[symbol](self)
                self.set_flag(symbol, 0)
                ran.append(symbol)
        self._status()
        return ran

    def _status(self) -> None:
        status = self.chip.status
        for bit, symbol in enumerate(STATUS_FLAGS, start=2):
            self.set_flag(symbol, status >> bit & 1)

    # -- the functions (§3.4) --------------------------------------------------------------------------
    def _position(self, relative: bool) -> None:
        self._ltrj(self.mode | (0x0003 if relative else 0x0002), counts(self.reg("DestP"), self.k) & 0xFFFF_FFFF)

    def _velocity(self, relative: bool) -> None:
        self._ltrj(self.mode | (0x000C if relative else 0x0008), velocity_register(self.reg("Veloc"), self.k) & 0xFFFF_FFFF)

    def _acceleration(self, relative: bool) -> None:
        self._ltrj(self.mode | 0x0100)  # the acceleration changes only with the motor off
        self._stt()
        self._ltrj(self.mode | (0x0030 if relative else 0x0020),
                   acceleration_register(self.reg("Accel"), self.k) & 0xFFFF_FFFF)

    def _regulator(self) -> None:
        words = [self.reg(s) & 0x7FFF for s in ("KProp", "KInt", "KDer", "IntL")]
        control = (self.reg("SampI") & 0xFF) << 8 | 0x000F
        self._cmd("LFIL", control, *words)
        self.chip.load_filter(control, words)

    def _update(self) -> None:
        self._cmd("UDF")
        self.chip.update_filter()

    def _select_mode(self) -> None:
        self.mode = self.reg("MCW") & 0x1800
        self._ltrj(self.mode)

    def _position_error(self) -> None:
        stop = self.reg("MCW") & 0xFF == 0x1A
        self._cmd("LPES" if stop else "LPEI", self.reg("PosEr") & 0x7FFF)
        self.chip.position_error(self.reg("PosEr"), stop)

    def _reset_status(self) -> None:
        word = self.reg("StaFRR") & 0xFFFF
        self._cmd("RSTI", word)
        self.chip.reset_interrupts(word)

    def _breakpoint(self, relative: bool) -> None:
        value = counts(self.reg("BrkP"), self.k)
        self._cmd("SBPR" if relative else "SBPA", value & 0xFFFF_FFFF)
        self.chip.set_breakpoint(value, relative)

    def _zero(self) -> None:
        self._cmd("DFH")
        self.chip.define_home()

    def _read(self, symbol: str, value: int) -> None:
        self.put(symbol, value)

    def _to_user(self, value: float) -> int:
        k = self.k
        return round_half_away(value / k) if k else 0

    def _stop(self) -> None:
        self._ltrj(self.mode | (self.reg("MCW") & 0x0700))
        self._stt()

    def _motor_off(self) -> None:
        self._ltrj(self.mode | 0x0100)
        self._stt()

    def _step(self, direction: int) -> None:
        if not self.chip.profile.complete:
            return  # not during motion (§3.2)
        self._ltrj(0x0003, direction & 0xFFFF_FFFF)
        self._stt()

    def _run_to(self, end: int) -> None:
        self._ltrj(0x0002, end)
        self._stt()


def _read_velocity(axis: H3Axis, register: int, scale: float) -> int:
    k = axis.k
    return round_half_away(register / (k * scale * FB_SAMPLE)) if k else 0


FUNCTIONS: dict[str, Callable[[H3Axis], None]] = {
    "FLdDR": lambda a: a._position(True),
    "FLdDA": lambda a: a._position(False),
    "FLdVR": lambda a: a._velocity(True),
    "FLdVA": lambda a: a._velocity(False),
    "FLdAR": lambda a: a._acceleration(True),
    "FLdAA": lambda a: a._acceleration(False),
    "FLdRP": H3Axis._regulator,
    "FUpDRP": H3Axis._update,
    "FSelOM": H3Axis._select_mode,
    "FSetPE": H3Axis._position_error,
    "FResSF": H3Axis._reset_status,
    "FLdBPR": lambda a: a._breakpoint(True),
    "FLdBPA": lambda a: a._breakpoint(False),
    "FSetIP": lambda a: a._cmd("SIP"),
    "FSetZP": H3Axis._zero,
    "FRdAP": lambda a: a._read("RActP", a._to_user(a.chip.actual)),
    "FRdSP": lambda a: a._read("RSetP", a._to_user(a.chip.profile.desired)),
    "FRdAV": lambda a: a._read("RActV", _read_velocity(a, round(a.chip.motor.velocity * CHIP_SAMPLE), 1.0)),
    "FRdSV": lambda a: a._read("RSetV", _read_velocity(a, a.chip.profile.velocity, 65536.0)),
    "FRdITS": lambda a: a._read("RIntTS", a.chip.filter.integral),
    "FRdIP": lambda a: a._read("RIndP", 0),
    "FRdSR": lambda a: a._read("RSigB", a.chip.signals),
    "FStart": H3Axis._stt,
    "FStop": H3Axis._stop,
    "FMotOff": H3Axis._motor_off,
    "FSStepF": lambda a: a._step(1),
    "FSStepB": lambda a: a._step(-1),
    "FForw": lambda a: a._run_to(FORWARD_END),
    "FBackw": lambda a: a._run_to(BACKWARD_END),
}
