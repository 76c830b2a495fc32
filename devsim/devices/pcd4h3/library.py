"""The PCD9.H3E1 library on one axis (spec pcd4h3.md §3.2–§3.4, §3.7, §4.2–§4.9): AxInit, and
AxHndlg running the function command flags in offset order against the LM628, converting with the
machine factor, and copying the chip's status into the status flags at the end.

Every chip transfer is checked for the command error (§3.7): the FB clears it (RSTI with bit 1 =
0), repeats the transfer at most twice, and after the third failure calls ComErS
(:attr:`H3Axis.on_comers`) and goes on with the next chip command.  What the FB itself cannot
convert (a conversion out of range, k = 0 on a read, SampI beyond 255, an MCW reaction that is
neither 1Ah nor 1Bh) fails the same way without reaching the chip.

The axis's registers are its :class:`~devsim.devices.pcd4h3.registers.AxisRegisters` (a named
view of its block in the PLC's register medium), its flags the PLC's flag medium (flag address →
value) the caller owns; the chip is a :class:`~devsim.devices.pcd4h3.lm628.Lm628`.  The
functions are :data:`FUNCTIONS`, the table of the command flags (§3.2) whose handlers AxHndlg
runs.  Every chip command the functions issue is appended to :attr:`H3Axis.trace` as the spec
writes its chip traces (§6.2).
"""

from __future__ import annotations

from collections.abc import Callable, MutableMapping

from devsim.core.kit import Command, Table
from devsim.devices.pcd4h3.layout import Layout
from devsim.devices.pcd4h3.lm628 import COMMAND_ERROR, NO_DATA, WRITE_BYTES, Lm628
from devsim.devices.pcd4h3.registers import AxisRegisters
from devsim.devices.pcd4h3.tables import command_flags, flag_row
from devsim.devices.pcd4h3.units import (
    FB_SAMPLE,
    acceleration_register,
    ffp_decode,
    round_half_away,
    velocity_register,
)

__all__ = ["FUNCTIONS", "H3Axis", "STATUS_FLAGS", "TIMES"]

STATUS_FLAGS = ("OnDest", "IPuls", "WrapOc", "ExcPEr", "BrkPos")  # status bits 2 … 6
TIMES = {row.name: float(row.extra["time_ms"]) for row in command_flags()}  # §10.1
FORWARD_END, BACKWARD_END = 0x3FFF_FFFF, 0xC000_0000
INT32 = 1 << 31
ATTEMPTS = 3  # the transfer and at most two repeats (§3.7)
TRACE_KEPT = 1024  # chip transfers kept in the trace


class Refused(Exception):
    """The FB cannot build the transfer (a command error without the chip, §3.7)."""


class H3Axis:
    """Axis ``axis`` of an installation: its registers and flags in the media, its chip.

    ``on_comers`` is called with the function's flag offset when ComErS runs (the PLC's
    reaction, §3.7); ``on_write`` after each command sent to the chip (a report command, §3.5.3,
    changes nothing in it: the drive keeps a settled chip at rest); ``rsigb_bit12_inverted`` is
    the G-5 option, ``velocity_readback_unsigned`` G-11's, ``literal_mcw_command`` G-8's;
    ``fb_sample`` (seconds) the sample time the conversions assume (G-6, §5.1)."""

    def __init__(self, axis: int, layout: Layout, chip: Lm628, registers: AxisRegisters,
                 flags: MutableMapping[int, int], *, on_comers: Callable[[int], None] | None = None,
                 on_write: Callable[[], None] | None = None, rsigb_bit12_inverted: bool = False,
                 velocity_readback_unsigned: bool = False, literal_mcw_command: bool = False,
                 fb_sample: float = FB_SAMPLE) -> None:
        self.axis, self.layout, self.chip = axis, layout, chip
        self.registers, self.flags = registers, flags
        #: (symbol, flag address) of the command flags in AxHndlg's order, and the status flags' addresses
        self.command_flags = tuple((symbol, layout.flag(axis, symbol)) for symbol in layout.command_order)
        self.status_flags = tuple(layout.flag(axis, symbol) for symbol in STATUS_FLAGS)
        self.on_comers, self.on_write = on_comers, on_write
        self.rsigb_bit12_inverted = rsigb_bit12_inverted
        self.velocity_readback = abs if velocity_readback_unsigned else int
        self.literal_mcw_command, self.fb_sample = literal_mcw_command, fb_sample
        self.mode = 0  # LTRJ bits 11/12 from the last FSelOM
        self.trace: list[tuple[str, tuple[int, ...]]] = []
        self.comers_calls = 0
        self.last_comers = -1  # flag offset of the function that last called ComErS
        self.warnings = 0  # FStop with a doubtful MCW, a single step while moving, IMode 5 on a ±10 V module (G-10, E10, G-26)
        self.transfers = 0  # chip transfers since start-up
        self.ran: list[str] = []  # the functions the last AxHndlg call ran
        self._function = ""
        self._attempts = 1  # the most attempts one transfer of the running function took

    # -- media ------------------------------------------------------------------------------------
    def flag(self, symbol: str) -> int:
        return self.flags.get(self.layout.flag(self.axis, symbol), 0)

    def set_flag(self, symbol: str, value: int) -> None:
        self.flags[self.layout.flag(self.axis, symbol)] = value

    @property
    def k(self) -> float:
        return ffp_decode(self.registers.machine_factor)

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
            self._wrote()
            if not chip.status & COMMAND_ERROR:
                self._attempts = max(self._attempts, attempt)
                return True
            self._clear_error()
        self._comers()
        return False

    def _wrote(self) -> None:
        if self.on_write is not None:
            self.on_write()

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
        self._wrote()
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
        off), velocity, command flags cleared.  IMode 5 on a ±10 V module (manual §7.1.3: H310,
        311, 320 and 321 take 6) is sent as PORT8 and taken: the DAC gets 8 bits only, a warning
        (spec G-26); IMode 6 on a PWM module is the LM629's command error."""
        self._function = "AxInit"
        self._send("RESET")
        self._send("PORT12" if imode == 6 else "PORT8")
        if imode != 6 and not self.chip.lm629:
            self.warnings += 1  # G-26: a coarse output
        self.mode = 0
        for symbol in ("FSelOM", "FSetPE", "FLdRP", "FUpDRP", "FLdAA", "FLdVA"):
            self._run(symbol)
        for row in command_flags():
            self.set_flag(row.name, 0)
        self._status()

    def handle(self, before: Callable[[float], None] | None = None) -> float:
        """AxHndlg: every set command flag in offset order, then the status flags.  ``before``
        is told, before each function, how many ms of this call have passed (so the chip acts
        at the right sample); returns the call's duration in ms (§3.3.2: base 0.5 ms, each
        function its §10.1 time, each repeat the time again)."""
        elapsed = 0.5
        self.ran = []
        flags = self.flags
        for symbol, address in self.command_flags:
            if flags.get(address, 0):
                if before is not None:
                    before(elapsed)
                self.ran.append(symbol)
                try:
                    attempts = self._run(symbol)
                finally:
                    flags[address] = 0  # in any case (§3.7), even when ComErS halts the PCD
                elapsed += TIMES[symbol] * attempts
        self._status()
        return elapsed

    def repeat(self, transfers: list[tuple[str, tuple[int, ...]]], times: int) -> None:
        """Count and trace ``transfers`` ``times`` over, as AxHndlg calls that ran the same
        functions with the same outcome would (skipped PLC cycles that only read, issue 31)."""
        for _ in range(times):
            for name, words in transfers:
                self._log(name, words)

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
        status, flags = self.chip.status, self.flags
        for bit, address in enumerate(self.status_flags, start=2):
            flags[address] = status >> bit & 1

    # -- conversions (§3.4, §5.1) ------------------------------------------------------------------
    def _refuse(self) -> None:
        self._comers()
        raise Refused(self._function)

    def _word16(self, value: int) -> int:
        """A register as one data word of the chip, or a refusal when it is no 16-bit word (§7.4:
        a value outside the range is a command error; 65 636 loaded 100, -65 536 loaded 0).  The
        chip refuses what is above 7FFFh itself."""
        if not 0 <= value <= 0xFFFF:
            self._refuse()
        return value

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
        self._ltrj(self.mode | (0x0003 if relative else 0x0002), self._word32(self.registers.destination * self.k))

    def _velocity(self, relative: bool) -> None:
        word = self._word32(velocity_register(self.registers.velocity, self.k, self.fb_sample))
        self._ltrj(self.mode | (0x000C if relative else 0x0008), word)

    def _acceleration(self, relative: bool) -> None:
        word = self._word32(acceleration_register(self.registers.acceleration, self.k, self.fb_sample))
        self._ltrj(self.mode | 0x0100)  # the acceleration changes only with the motor off
        self._stt()
        self._ltrj(self.mode | (0x0030 if relative else 0x0020), word)

    def _breakpoint(self, relative: bool) -> None:
        self._send("SBPR" if relative else "SBPA", self._word32(self.registers.break_position * self.k))

    def _step(self, direction: int) -> None:
        if not self.chip.profile.complete:
            self.warnings += 1  # not allowed during motion, but the FB does not check (E10)
        self._ltrj(0x0003, direction & 0xFFFF_FFFF)
        self._stt()

    def _run_to(self, end: int) -> None:
        self._ltrj(0x0002, end)
        self._stt()

    def _read_position(self, report: str) -> int:
        return self._to_user(self._read(report))

    def _read_velocity(self, report: str, scale: float) -> int:
        """[SIM-CHOICE] Signed, as the chip reports it: negative backwards (§7.4 FRdAV, FRdSV print 0 … ;
        docs Deviations); without the sign with the G-11 option ``velocity_readback_unsigned``."""
        return self.velocity_readback(self._to_user(self._read(report) / (scale * self.fb_sample)))

    def load_destination_relative(self) -> None:
        """FLdDR: LTRJ mode | 0003h with DestP · k."""
        self._position(True)

    def load_destination_absolute(self) -> None:
        """FLdDA: LTRJ mode | 0002h with DestP · k."""
        self._position(False)

    def load_velocity_relative(self) -> None:
        """FLdVR: LTRJ mode | 000Ch with the velocity register of Veloc."""
        self._velocity(True)

    def load_velocity_absolute(self) -> None:
        """FLdVA: LTRJ mode | 0008h with the velocity register of Veloc."""
        self._velocity(False)

    def load_acceleration_relative(self) -> None:
        """FLdAR: motor off (LTRJ 0100h, STT), then LTRJ mode | 0030h with Accel's register."""
        self._acceleration(True)

    def load_acceleration_absolute(self) -> None:
        """FLdAA: motor off (LTRJ 0100h, STT), then LTRJ mode | 0020h with Accel's register."""
        self._acceleration(False)

    def load_regulator(self) -> None:
        """FLdRP: LFIL (SampI << 8) | 000Fh, KProp, KInt, KDer, IntL."""
        registers = self.registers
        sample = registers.sample_interval
        if not 0 <= sample <= 255:
            self._refuse()
        words = [self._word16(value) for value in (registers.proportional, registers.integral, registers.derivative,
                                                   registers.integration_limit)]
        self._send("LFIL", sample << 8 | 0x000F, *words)

    def update_regulator(self) -> None:
        """FUpDRP: UDF."""
        self._send("UDF")

    def select_mode(self) -> None:
        """FSelOM: LTRJ with MCW bits 11, 12 (kept for the later LTRJs)."""
        self.mode = self.registers.control_word & 0x1800
        self._ltrj(self.mode)

    def set_position_error(self) -> None:
        """FSetPE: LPES (MCW low byte 1Ah) or LPEI (1Bh) with PosEr; anything else refused (G-8), or
        with ``literal_mcw_command`` (the G-8 option: the FB writes the byte as the chip's command
        byte, spec §3.4 FSetPE "command byte = MCW & FFh") sent as that command: a write command with
        data words gets PosEr, one without none (00h RESETs the chip); [SIM-CHOICE] a report
        command's byte or one the chip does not know is still refused."""
        reaction = self.registers.control_word & 0xFF
        limit = self._word16(self.registers.position_error_limit)
        if reaction in (0x1A, 0x1B):
            self._send("LPES" if reaction == 0x1A else "LPEI", limit)
            return
        mnemonic = WRITE_BYTES.get(reaction) if self.literal_mcw_command else None
        if mnemonic is None:
            self._refuse()  # G-8
        self._send(mnemonic, *(() if mnemonic in NO_DATA else (limit,)))

    def reset_status_flags(self) -> None:
        """FResSF: RSTI with StaFRR."""
        self._send("RSTI", self.registers.status_reset & 0xFFFF)

    def load_break_position_relative(self) -> None:
        """FLdBPR: SBPR with BrkP · k."""
        self._breakpoint(True)

    def load_break_position_absolute(self) -> None:
        """FLdBPA: SBPA with BrkP · k."""
        self._breakpoint(False)

    def set_index_position(self) -> None:
        """FSetIP: SIP."""
        self._send("SIP")

    def set_zero_position(self) -> None:
        """FSetZP: DFH."""
        self._send("DFH")

    def read_actual_position(self) -> None:
        """FRdAP: RDRP / k into RActP."""
        self.registers.actual_position = self._read_position("RDRP")

    def read_set_position(self) -> None:
        """FRdSP: RDDP / k into RSetP."""
        self.registers.set_position = self._read_position("RDDP")

    def read_actual_velocity(self) -> None:
        """FRdAV: RDRV / (T · k) into RActV."""
        self.registers.actual_velocity = self._read_velocity("RDRV", 1.0)

    def read_set_velocity(self) -> None:
        """FRdSV: RDDV / (65536 · T · k) into RSetV."""
        self.registers.set_velocity = self._read_velocity("RDDV", 65536.0)

    def read_integration_sum(self) -> None:
        """FRdITS: RDSUM into RIntTS."""
        self.registers.integration_sum = self._read("RDSUM")

    def read_index_position(self) -> None:
        """FRdIP: RDIP / k into RIndP."""
        self.registers.index_position = self._read_position("RDIP")

    def read_signal_register(self) -> None:
        """FRdSR: RDSIGS into RSigB (bit 12 inverted with the G-5 option)."""
        value = self._read("RDSIGS")
        self.registers.signal_register = value ^ 0x1000 if self.rsigb_bit12_inverted else value

    def start(self) -> None:
        """FStart: STT."""
        self._stt()

    def stop(self) -> None:
        """FStop: LTRJ mode | MCW bits 8 … 10, STT; several bits by priority, none: no stop (G-10)."""
        bits = self.registers.control_word & 0x0700
        if bits not in (0x0100, 0x0200, 0x0400):
            self.warnings += 1  # G-10: several bits by priority 8 > 9 > 10; none: no stop at all
            bits = bits & -bits
        self._ltrj(self.mode | bits)
        self._stt()

    def motor_off(self) -> None:
        """FMotOff: LTRJ mode | 0100h, STT."""
        self._ltrj(self.mode | 0x0100)
        self._stt()

    def step_forward(self) -> None:
        """FSStepF: LTRJ 0003h +1, STT."""
        self._step(1)

    def step_backward(self) -> None:
        """FSStepB: LTRJ 0003h −1, STT."""
        self._step(-1)

    def forward(self) -> None:
        """FForw: LTRJ 0002h to 3FFFFFFFh, STT."""
        self._run_to(FORWARD_END)

    def backward(self) -> None:
        """FBackw: LTRJ 0002h to C0000000h, STT."""
        self._run_to(BACKWARD_END)


def _function(symbol: str, handler: Callable[[H3Axis], None]) -> Command[Callable[[H3Axis], None]]:
    row = flag_row(symbol)
    doc = (f"flag offset {row.key}: {row.doc}; {row.extra['time_ms']} ms"
           + ("" if row.extra["in_motion"] else "; not during motion"))
    return Command(symbol, handler, "§3.2", doc)


FUNCTIONS: Table[Callable[[H3Axis], None]] = Table([
    _function("FLdDR", H3Axis.load_destination_relative),
    _function("FLdDA", H3Axis.load_destination_absolute),
    _function("FLdVR", H3Axis.load_velocity_relative),
    _function("FLdVA", H3Axis.load_velocity_absolute),
    _function("FLdAR", H3Axis.load_acceleration_relative),
    _function("FLdAA", H3Axis.load_acceleration_absolute),
    _function("FLdRP", H3Axis.load_regulator),
    _function("FUpDRP", H3Axis.update_regulator),
    _function("FSelOM", H3Axis.select_mode),
    _function("FSetPE", H3Axis.set_position_error),
    _function("FResSF", H3Axis.reset_status_flags),
    _function("FLdBPR", H3Axis.load_break_position_relative),
    _function("FLdBPA", H3Axis.load_break_position_absolute),
    _function("FSetIP", H3Axis.set_index_position),
    _function("FSetZP", H3Axis.set_zero_position),
    _function("FRdAP", H3Axis.read_actual_position),
    _function("FRdSP", H3Axis.read_set_position),
    _function("FRdAV", H3Axis.read_actual_velocity),
    _function("FRdSV", H3Axis.read_set_velocity),
    _function("FRdITS", H3Axis.read_integration_sum),
    _function("FRdIP", H3Axis.read_index_position),
    _function("FRdSR", H3Axis.read_signal_register),
    _function("FStart", H3Axis.start),
    _function("FStop", H3Axis.stop),
    _function("FMotOff", H3Axis.motor_off),
    _function("FSStepF", H3Axis.step_forward),
    _function("FSStepB", H3Axis.step_backward),
    _function("FForw", H3Axis.forward),
    _function("FBackw", H3Axis.backward),
])
"""The library functions by their command flag (§3.2), in the flag field's order: what AxHndlg
runs for a set flag, and what the reference lists."""
