"""The PCD9.H3E1 library on one axis (spec pcd4h3.md §3.2–§3.4, §3.7, §4.2–§4.9): AxInit, and
AxHndlg running the function command flags in offset order against the LM628, converting with the
machine factor, and copying the chip's status into the status flags at the end.

Every chip transfer is checked for the command error (§3.7): the FB clears it (RSTI with bit 1 =
0), repeats the transfer at most twice, and after the third failure calls ComErS
(:attr:`H3Axis.on_comers`) and goes on with the next chip command.  What the FB itself cannot
convert (a conversion out of range, k = 0 on a read, SampI beyond 255, an MCW reaction that is
neither 1Ah nor 1Bh) fails the same way without reaching the chip.

The PLC media are plain mappings (register and flag address → value) the caller owns; the chip
is a :class:`~devsim.devices.pcd4h3.lm628.Lm628`.  Every chip command the functions issue is
appended to :attr:`H3Axis.trace` as the spec writes its chip traces (§6.2).
"""

from __future__ import annotations

from collections.abc import Callable, MutableMapping

from devsim.devices.pcd4h3.layout import FLAGS, Layout
from devsim.devices.pcd4h3.lm628 import COMMAND_ERROR, Lm628
from devsim.devices.pcd4h3.units import (
    FB_SAMPLE,
    acceleration_register,
    ffp_decode,
    round_half_away,
    velocity_register,
)

__all__ = ["FUNCTIONS", "H3Axis", "TIMES"]

COMMAND_FLAGS = tuple(f.symbol for f in FLAGS if f.kind == "command")
STATUS_FLAGS = ("OnDest", "IPuls", "WrapOc", "ExcPEr", "BrkPos")  # status bits 2 … 6
TIMES = {f.symbol: f.time_ms for f in FLAGS if f.kind == "command"}  # §10.1
FORWARD_END, BACKWARD_END = 0x3FFF_FFFF, 0xC000_0000
INT32 = 1 << 31
ATTEMPTS = 3  # the transfer and at most two repeats (§3.7)
TRACE_KEPT = 1024  # chip transfers kept in the trace


class Refused(Exception):
    """The FB cannot build the transfer (a command error without the chip, §3.7)."""


class H3Axis:
    """Axis ``axis`` of an installation: its registers and flags in the media, its chip."""

    def __init__(self, axis: int, layout: Layout, chip: Lm628, registers: MutableMapping[int, int],
                 flags: MutableMapping[int, int]) -> None:
        self.axis, self.layout, self.chip = axis, layout, chip
        self.registers, self.flags = registers, flags
        self.mode = 0  # LTRJ bits 11/12 from the last FSelOM
        self.trace: list[tuple[str, tuple[int, ...]]] = []
        #: Called with the function's flag offset when ComErS runs (the PLC's reaction).
        self.on_comers: Callable[[int], None] | None = None
        self.comers_calls = 0
        self.last_comers = -1  # flag offset of the function that last called ComErS
        self.warnings = 0  # FStop with a doubtful MCW, a single step while moving (G-10, E10)
        self.rsigb_bit12_inverted = False  # G-5 option
        self.transfers = 0  # chip transfers since start-up
        self.ran: list[str] = []  # the functions the last AxHndlg call ran
        self._function = ""
        self._attempts = 1  # the most attempts one transfer of the running function took

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

    # -- the chip, checked and traced (§3.7) -------------------------------------------------------
    def _log(self, name: str, words: tuple[int, ...]) -> None:
        self.transfers += 1
        if len(self.trace) >= TRACE_KEPT:
            del self.trace[: TRACE_KEPT // 2]
        self.trace.append((name, words))

    def _send(self, name: str, *words: int) -> bool:
        chip = self.chip
        for attempt in range(1, ATTEMPTS + 1):
            self._log(name, words)
            chip.command(name, *words)
            if not chip.status & COMMAND_ERROR:
                self._attempts = max(self._attempts, attempt)
                return True
            self._clear_error()
        self._comers()
        return False

    def _read(self, name: str) -> int:
        chip = self.chip
        for attempt in range(1, ATTEMPTS + 1):
            self._log(name, ())
            value = chip.read(name)
            if value is not None and not chip.status & COMMAND_ERROR:
                self._attempts = max(self._attempts, attempt)
                return value
            self._clear_error()
        self._comers()
        raise Refused(name)

    def _clear_error(self) -> None:
        self._log("RSTI", (0xFFFD,))
        self.chip.command("RSTI", 0xFFFD)
        self.chip.flags &= ~COMMAND_ERROR  # the FB polls until the flag is gone

    def _comers(self) -> None:
        self._attempts = ATTEMPTS
        self.comers_calls += 1
        self.last_comers = self.layout.flag_offsets.get(self._function, -1)
        if self.on_comers is not None:
            self.on_comers(self.last_comers)

    def _ltrj(self, control: int, *values: int) -> bool:
        return self._send("LTRJ", control, *values)

    def _stt(self) -> bool:
        return self._send("STT")

    # -- AxInit, AxHndlg (§3.3) -----------------------------------------------------------------------
    def init(self, imode: int = 6) -> None:
        """AxInit: reset, output port, mode, position error, filter, acceleration (with motor
        off), velocity, command flags cleared."""
        self._function = "AxInit"
        self._send("RESET")
        self._send("PORT12" if imode == 6 else "PORT8")
        self.mode = 0
        for symbol in ("FSelOM", "FSetPE", "FLdRP", "FUpDRP", "FLdAA", "FLdVA"):
            self._run(symbol)
        for symbol in COMMAND_FLAGS:
            self.set_flag(symbol, 0)
        self._status()

    def handle(self, before: Callable[[float], None] | None = None) -> float:
        """AxHndlg: every set command flag in offset order, then the status flags.  ``before``
        is told, before each function, how many ms of this call have passed (so the chip acts
        at the right sample); returns the call's duration in ms (§3.3.2: base 0.5 ms, each
        function its §10.1 time, each repeat the time again)."""
        elapsed = 0.5
        self.ran = []
        for symbol in self.layout.command_order:
            if self.flags.get(self.layout.flag(self.axis, symbol), 0):
                if before is not None:
                    before(elapsed)
                self.ran.append(symbol)
                try:
                    attempts = self._run(symbol)
                finally:
                    self.set_flag(symbol, 0)  # in any case (§3.7), even when ComErS halts the PCD
                elapsed += TIMES[symbol] * attempts
        self._status()
        return elapsed

    def run(self, symbol: str) -> None:
        """Run one function now, as its flag would (tests, the PLC's cold start)."""
        self._run(symbol)

    def _run(self, symbol: str) -> int:
        self._function, self._attempts = symbol, 1
        try:
            FUNCTIONS[symbol](self)
        except Refused:
            pass
        return self._attempts

    def _status(self) -> None:
        status = self.chip.status
        for bit, symbol in enumerate(STATUS_FLAGS, start=2):
            self.set_flag(symbol, status >> bit & 1)

    # -- conversions (§3.4, §5.1) ------------------------------------------------------------------
    def _refuse(self) -> None:
        self._comers()
        raise Refused(self._function)

    def _word32(self, value: float) -> int:
        """A converted value as the FB's 32-bit result, or a refusal on overflow."""
        number = round_half_away(value)
        if not -INT32 <= number < INT32:
            self._refuse()
        return number & 0xFFFF_FFFF

    def _to_user(self, value: float) -> int:
        k = self.k
        if k == 0:
            self._refuse()  # division by zero (§6.6 E5)
        number = round_half_away(value / k)
        if not -INT32 <= number < INT32:
            self._refuse()
        return number

    # -- the functions (§3.4) --------------------------------------------------------------------------
    def _position(self, relative: bool) -> None:
        self._ltrj(self.mode | (0x0003 if relative else 0x0002), self._word32(self.reg("DestP") * self.k))

    def _velocity(self, relative: bool) -> None:
        word = self._word32(velocity_register(self.reg("Veloc"), self.k))
        self._ltrj(self.mode | (0x000C if relative else 0x0008), word)

    def _acceleration(self, relative: bool) -> None:
        word = self._word32(acceleration_register(self.reg("Accel"), self.k))
        self._ltrj(self.mode | 0x0100)  # the acceleration changes only with the motor off
        self._stt()
        self._ltrj(self.mode | (0x0030 if relative else 0x0020), word)

    def _regulator(self) -> None:
        sample = self.reg("SampI")
        if not 0 <= sample <= 255:
            self._refuse()
        words = [self.reg(s) & 0xFFFF for s in ("KProp", "KInt", "KDer", "IntL")]
        self._send("LFIL", sample << 8 | 0x000F, *words)

    def _select_mode(self) -> None:
        self.mode = self.reg("MCW") & 0x1800
        self._ltrj(self.mode)

    def _position_error(self) -> None:
        reaction = self.reg("MCW") & 0xFF
        if reaction not in (0x1A, 0x1B):
            self._refuse()  # G-8
        self._send("LPES" if reaction == 0x1A else "LPEI", self.reg("PosEr") & 0xFFFF)

    def _breakpoint(self, relative: bool) -> None:
        self._send("SBPR" if relative else "SBPA", self._word32(self.reg("BrkP") * self.k))

    def _stop(self) -> None:
        bits = self.reg("MCW") & 0x0700
        if bits not in (0x0100, 0x0200, 0x0400):
            self.warnings += 1  # G-10: several bits by priority 8 > 9 > 10; none: no stop at all
            bits = bits & -bits
        self._ltrj(self.mode | bits)
        self._stt()

    def _motor_off(self) -> None:
        self._ltrj(self.mode | 0x0100)
        self._stt()

    def _step(self, direction: int) -> None:
        if not self.chip.profile.complete:
            self.warnings += 1  # not allowed during motion, but the FB does not check (E10)
        self._ltrj(0x0003, direction & 0xFFFF_FFFF)
        self._stt()

    def _run_to(self, end: int) -> None:
        self._ltrj(0x0002, end)
        self._stt()

    def _read_position(self, register: str, report: str) -> None:
        self.put(register, self._to_user(self._read(report)))

    def _read_velocity(self, register: str, report: str, scale: float) -> None:
        self.put(register, self._to_user(self._read(report) / (scale * FB_SAMPLE)))

    def _read_signals(self) -> None:
        value = self._read("RDSIGS")
        self.put("RSigB", value ^ 0x1000 if self.rsigb_bit12_inverted else value)


FUNCTIONS: dict[str, Callable[[H3Axis], None]] = {
    "FLdDR": lambda a: a._position(True),
    "FLdDA": lambda a: a._position(False),
    "FLdVR": lambda a: a._velocity(True),
    "FLdVA": lambda a: a._velocity(False),
    "FLdAR": lambda a: a._acceleration(True),
    "FLdAA": lambda a: a._acceleration(False),
    "FLdRP": H3Axis._regulator,
    "FUpDRP": lambda a: a._send("UDF") and None,
    "FSelOM": H3Axis._select_mode,
    "FSetPE": H3Axis._position_error,
    "FResSF": lambda a: a._send("RSTI", a.reg("StaFRR") & 0xFFFF) and None,
    "FLdBPR": lambda a: a._breakpoint(True),
    "FLdBPA": lambda a: a._breakpoint(False),
    "FSetIP": lambda a: a._send("SIP") and None,
    "FSetZP": lambda a: a._send("DFH") and None,
    "FRdAP": lambda a: a._read_position("RActP", "RDRP"),
    "FRdSP": lambda a: a._read_position("RSetP", "RDDP"),
    "FRdAV": lambda a: a._read_velocity("RActV", "RDRV", 1.0),
    "FRdSV": lambda a: a._read_velocity("RSetV", "RDDV", 65536.0),
    "FRdITS": lambda a: a.put("RIntTS", a._read("RDSUM")),
    "FRdIP": lambda a: a._read_position("RIndP", "RDIP"),
    "FRdSR": H3Axis._read_signals,
    "FStart": lambda a: a._stt() and None,
    "FStop": H3Axis._stop,
    "FMotOff": H3Axis._motor_off,
    "FSStepF": lambda a: a._step(1),
    "FSStepB": lambda a: a._step(-1),
    "FForw": lambda a: a._run_to(FORWARD_END),
    "FBackw": lambda a: a._run_to(BACKWARD_END),
}
"""Each command flag's function (§3.2): the chip sequence it sends."""
