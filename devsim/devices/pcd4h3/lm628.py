"""The LM628/LM629 motion controller chip of one PCD4.H3 axis (spec pcd4h3.md §3.5, §3.7, §4.5,
§4.8, §5.2–§5.9; National Semiconductor LM628 datasheet): its commands with the command error
they raise on bad data, its status byte and signals register, and one sample of its work
(profile generator, filter, motor, encoder with index and wrap-around, the checks).

Pure and stepped: :meth:`Lm628.sample` advances one sample period (2048 / 6 MHz); the caller
decides when.  Commands take the words the host port carries (§3.5.3); :meth:`Lm628.command` and
:meth:`Lm628.read` are the host port itself, where a disturbed bus (``bus_errors``) or a chip that
is not fitted (``present``) turns every transfer into a command error (§3.7, G-27).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from devsim.core.kit import Command, Table
from devsim.core.words import signed32
from devsim.devices.pcd4h3.pid import Coefficients, Filter, Motor, sat
from devsim.devices.pcd4h3.trajectory import Profile, Trajectory
from devsim.devices.pcd4h3.units import CHIP_SAMPLE

__all__ = ["BREAKPOINT", "COMMAND_ERROR", "COMPLETE", "INDEX", "Lm628", "MOTOR_OFF", "NO_DATA", "POSITION_ERROR",
           "POSITION_RANGE", "WRAPAROUND", "WRITE_BYTES"]

MOTOR_OFF, BREAKPOINT, POSITION_ERROR, WRAPAROUND, INDEX, COMPLETE, COMMAND_ERROR = 0x80, 0x40, 0x20, 0x10, 0x08, 0x04, 0x02
INTERRUPTS = BREAKPOINT | POSITION_ERROR | WRAPAROUND | INDEX | COMPLETE | COMMAND_ERROR
POSITION_RANGE = 1 << 30  # positions run from −2^30 to 2^30 − 1 (C0000000h … 3FFFFFFFh)
VALUE_MAX = 0x3FFF_FFFF  # velocity and acceleration words


def wrap(count: int) -> int:
    """A count in the chip's position range, as its 31-bit counter wraps (§5.7)."""
    return (count + POSITION_RANGE) % (2 * POSITION_RANGE) - POSITION_RANGE


def _in_range(position: int) -> bool:
    return -POSITION_RANGE <= position < POSITION_RANGE


def _sign(value: int) -> int:
    return (value > 0) - (value < 0)


def moved_flags(before: int, after: int, home: int, breakpoint: int | None) -> int:
    """WRAPAROUND and BREAKPOINT for an encoder that counted from ``before`` to ``after`` (raw
    counts) in one sample (§5.7: the 31-bit counter wraps; the breakpoint is reached or passed)."""
    flags = 0
    if (before - home + POSITION_RANGE) >> 31 != (after - home + POSITION_RANGE) >> 31:
        flags |= WRAPAROUND
    if breakpoint is not None:
        was, now = _sign(wrap(before - home) - breakpoint), _sign(wrap(after - home) - breakpoint)
        if was != now and was != 0 and now * was <= 0:
            flags |= BREAKPOINT
    return flags


class Lm628:
    """One chip: its buffers, working registers, flags, and the motor and encoder behind it."""

    #: (Slots: with the sample time and the interrupt option the chip has 31 attributes, and CPython
    #: stops sharing the keys of a class's instance dictionaries at 30: each chip's grew)
    __slots__ = ("motor", "sample_time", "host_interrupt", "lm629", "present", "bus_errors", "command_errors",
                 "encoder_sign", "index_period", "index_offset", "profile", "filter", "buffer", "flags", "mask",
                 "motor_off", "stop_on_error", "error_threshold", "breakpoint", "loaded", "started", "index_armed",
                 "index_position", "home", "_stop", "on_target", "udf_sample", "_raw", "rest_x", "rest_v", "rest_n")

    def __init__(self, motor: Motor | None = None, *, lm629: bool = False, present: bool = True,
                 encoder_sign: int = 1, index_period: int = 0, index_offset: int = 0,
                 host_interrupt: bool = False, sample_time: float = CHIP_SAMPLE) -> None:
        self.motor = motor if motor is not None else Motor()
        #: seconds between samples: 2048 clock periods (341.333 µs at 6 MHz; ``chip_sample_time_us``)
        self.sample_time = sample_time
        self.host_interrupt = host_interrupt  # RDSIGS bit 15 shows the HI output (spec G-12 option)
        self.lm629 = lm629  # the PWM types' chip: no 12-bit port (G-26)
        self.present = present  # False: a Y chip on a one-axis module, every transfer fails (G-27)
        self.bus_errors = 0  # transfers still to be disturbed on the PCD4 bus (§3.7 cause 5)
        self.command_errors = 0  # since start-up (diagnostics)
        self.encoder_sign = encoder_sign  # −1: phases A/B swapped by a wrong inversion jumper (§2.5)
        self.index_period = index_period  # counts between index marks (4 · lines), 0: no index reaches the decoder
        self.index_offset = index_offset
        self.profile = Profile()
        self.filter = Filter(dac_bits=8)
        self.buffer = Trajectory()
        self.flags = COMPLETE  # interrupt flags (status bits 1 … 6): 84h after power-on (§3.5.2)
        self.mask = 0
        self.motor_off = True
        self.stop_on_error = False
        self.error_threshold = 0x7FFF
        self.breakpoint: int | None = None
        #: What LTRJ loaded since the last start (its control word's bits 5, 3, 1: acceleration,
        #: velocity, position): the pending values a relative load adds to (G-30).
        self.loaded = 0
        self.started = False  # a real trajectory start since RESET (relative loads need one, G-4)
        self.index_armed = False
        self.index_position = 0
        self.home = 0  # raw encoder count of position 0
        self._stop = 0  # the stop bits (8 … 10) of the last LTRJ, acting at the next STT
        self.on_target = False  # signals bit 10: the generator finished a profile since the last STT
        self.udf_sample = False  # signals bit 13: for the sample after UDF
        #: The motor's position and velocity where the chip settled (batch.SETTLE samples without
        #: change) and the samples since: its lag dies away from there (batch.rest)
        self.rest_x, self.rest_v, self.rest_n = 0.0, 0.0, 0
        self._raw = self._encoder()

    # -- the host port (§3.5.2, §3.7) ------------------------------------------------------------
    def command(self, mnemonic: str, *words: int) -> None:
        """One command byte and its data words; a failed transfer sets the command error."""
        handler = COMMANDS.get(mnemonic)
        if handler is None or not self._transfer():
            self.error()
            return
        handler(self, list(words))

    def read(self, mnemonic: str) -> int | None:
        """A report command (RDRP, RDSIGS …): its value, or None when the transfer failed."""
        report = REPORTS.get(mnemonic)
        if report is None or not self._transfer():
            self.error()
            return None
        return report(self)

    def _transfer(self) -> bool:
        if not self.present:
            return False
        if self.bus_errors > 0:
            self.bus_errors -= 1
            return False
        return True

    def error(self) -> None:
        """The command error flag (status bit 1): the command is ignored."""
        self.flags |= COMMAND_ERROR
        self.command_errors += 1

    # -- initialisation and interrupts (§3.5.3) -------------------------------------------------
    def reset(self) -> None:
        """RESET: coefficients, trajectory and output to zero, 8-bit port, home here; only the
        breakpoint interrupt stays masked."""
        self.profile, self.buffer = Profile(), Trajectory()
        self.filter = Filter(dac_bits=8)
        self.flags, self.mask, self.motor_off, self.stop_on_error = COMPLETE, INTERRUPTS & ~BREAKPOINT, True, False
        self.error_threshold = 0x7FFF
        self.breakpoint, self.loaded, self.on_target, self.started = None, 0, False, False
        self.index_armed, self._stop = False, 0
        self.define_home()

    def port(self, bits: int) -> None:
        """PORT8 / PORT12 (the LM629 has no 12-bit port: command error)."""
        if bits == 12 and self.lm629:
            self.error()
            return
        self.filter.dac_bits = bits

    def define_home(self) -> None:
        """DFH: the actual position becomes 0; the desired position and the running target move
        with it, so a running move stops where it would have (§5.9)."""
        actual = self.unwrapped_actual
        self.home += actual
        self.profile.shift(-actual)

    def set_actual(self, position: int) -> None:
        """The actual position reads ``position`` from now (a test's injection, S07); the desired
        position moves with it."""
        shift = position - self.unwrapped_actual
        self.home -= shift
        self.profile.shift(shift)

    def arm_index(self) -> None:
        """SIP: the next index mark latches the actual position."""
        self.index_armed = True

    def position_error(self, threshold: int, stop: bool) -> None:
        """LPEI (flag only) / LPES (flag and motor off); the threshold is 0 … 7FFFh."""
        if not 0 <= threshold <= 0x7FFF:
            self.error()
            return
        self.error_threshold, self.stop_on_error = threshold, stop

    def set_breakpoint(self, position: int, relative: bool = False) -> None:
        """SBPA / SBPR (relative to the current target, only after a first start)."""
        if relative and not self.started:
            self.error()
            return
        value = (self.target if relative else 0) + signed32(position)
        if not _in_range(value):
            self.error()
            return
        self.breakpoint = value

    def reset_interrupts(self, word: int) -> None:
        """RSTI: a 0 bit resets that flag."""
        self.flags &= word | ~INTERRUPTS

    def mask_interrupts(self, word: int) -> None:
        """MSKI: which flags drive the host interrupt."""
        self.mask = word & INTERRUPTS

    # -- filter and trajectory ---------------------------------------------------------------------
    def load_filter(self, control: int, words: list[int]) -> None:
        """LFIL: the control word (ds in bits 15…8, which values follow) and kp, ki, kd, il."""
        wanted = bin(control & 0x0F).count("1")
        if len(words) != wanted or any(not 0 <= w <= 0x7FFF for w in words):
            self.error()
            return
        values = iter(words)
        c = self.filter.buffer
        kp, ki, kd, il = c.kp, c.ki, c.kd, c.il
        if control & 8:
            kp = next(values)
        if control & 4:
            ki = next(values)
        if control & 2:
            kd = next(values)
        if control & 1:
            il = next(values)
        self.filter.buffer = Coefficients(kp, ki, kd, il, control >> 8 & 0xFF)

    def update_filter(self) -> None:
        """UDF."""
        self.filter.update()
        self.udf_sample = True

    def load_trajectory(self, control: int, values: list[int]) -> None:
        """LTRJ: the control word (§3.5.4) and acceleration, velocity, position as loaded; bad
        data or a relative value before the first start reject the whole command (§3.7)."""
        wanted = bin(control & 0x2A).count("1")
        if len(values) != wanted or control & 0x15 and not self.started or control & ~0x1F3F & 0xFFFF:
            self.error()
            return
        items = iter(values)
        b, profile, loaded = self.buffer, self.profile, self.loaded
        acceleration, velocity, position = b.acceleration, b.velocity, b.position
        if control & 0x20:  # relative: to a value loaded since the start, else the working one (G-30)
            value = next(items)
            base = acceleration if loaded & 0x20 else profile.acceleration
            acceleration = base + signed32(value) if control & 0x10 else value & 0xFFFF_FFFF
        if control & 0x08:  # (§7.4 FLdVR: "bezogen auf die momentane Sollgeschwindigkeit")
            value = next(items)
            base = velocity if loaded & 0x08 else abs(profile.velocity)
            velocity = base + signed32(value) if control & 0x04 else value & 0xFFFF_FFFF
        if control & 0x02:  # (§7.4 FLdDR: "bezogen auf die momentane Zielposition")
            value = signed32(next(items))
            base = position if loaded & 0x02 else self.target
            position = base + value if control & 0x01 else value
        if not (0 <= acceleration <= VALUE_MAX and 0 <= velocity <= VALUE_MAX and _in_range(position)):
            self.error()
            return
        self.loaded = loaded | control & 0x2A
        self.buffer = Trajectory(acceleration, velocity, position, bool(control & 0x0800), bool(control & 0x1000))
        self._stop = control & 0x0700

    def start(self) -> None:
        """STT: take over the buffers; a stop in the control word acts now.  Every stop ends in
        "trajectory complete" (manual §7.4 FStop: "Das Statusflag OnDest wird nach einem
        ausgeführten Stop gesetzt"), a smooth one of a generator that already stands at once.
        [SIM-CHOICE] The stop stays in the control word until the next LTRJ: a second STT repeats it
        (§7.4 FStop: resume only after FSelOM; so FMotOff, FStart leaves the control off, docs
        Deviations §7.4 FRdSR, FMotOff)."""
        stop = self._stop
        if self.loaded & 0x20 and not self.profile.complete and not self.motor_off and self.profile.velocity:
            self.error()  # acceleration changed while moving (§3.5.3)
            return
        if stop & 0x0100:
            self.motor_off = True
            self.profile.stop_abruptly()
            self.flags |= COMPLETE
            return
        if stop & 0x0200:  # maximum deceleration: the set position becomes the actual one (§7.4 FStop bit 9)
            self.profile.stop_abruptly(self.unwrapped_actual)
            self.on_target = True
            self.flags |= COMPLETE
            return
        if stop & 0x0400:
            self.profile.stop_smoothly()
            if self.profile.complete:  # it stood already: the stop is done now, no sample will end it
                self.on_target = True
                self.flags |= COMPLETE
            return
        self.motor_off, self.loaded, self.on_target, self.started = False, 0, False, True
        self.flags &= ~COMPLETE
        self.profile.start(self.buffer, self.frame)
        if self.profile.complete:
            self.flags |= COMPLETE
            self.on_target = True

    # -- reports (§4.5, §4.8) ----------------------------------------------------------------------
    def _encoder(self) -> int:
        return math.floor(self.encoder_sign * self.motor.position)

    @property
    def unwrapped_actual(self) -> int:
        return self._encoder() - self.home

    @property
    def actual(self) -> int:
        """RDRP: the encoder count relative to home, in the chip's range."""
        return wrap(self._encoder() - self.home)

    @property
    def desired(self) -> int:
        """RDDP: the generator's desired position."""
        return wrap(self.profile.desired)

    @property
    def frame(self) -> int:
        """How far the generator's (unwrapped) counts lie from the chip's registers: a multiple of
        2^31 after a wrap-around in velocity mode (§5.7).  The registers hold the wrapped values, so
        a new target counts from the wrapped desired position (manual §7.4 FLdDA: "bezogen auf die
        Nullposition"), not back across the overflow."""
        return self.profile.desired - self.desired

    @property
    def target(self) -> int:
        """The target position register (what FLdDR, FLdBPR add to), in the chip's range."""
        return wrap(self.profile.target >> 16)

    @property
    def status(self) -> int:
        """RDSTAT (bit 0 busy is never seen: commands complete at once).  Bit 2 "trajectory
        complete" is an interrupt flag like bits 1 and 3 … 6: set when the generator finishes and
        when the motor is switched off (RESET, a motor-off stop, an LPES trip), reset by RSTI also
        while the motor stays off (84h after a reset, 80h after RSTI 0000h: §3.5.2; manual §7.4
        FResSF: OnDest is set by these events)."""
        return self.flags | (MOTOR_OFF if self.motor_off else 0)

    @property
    def signals(self) -> int:
        """RDSIGS (§4.5): bits 11 and 12 (velocity mode, forward) are the working trajectory's,
        taken over at STT, not the buffer's (manual §7.4 FSelOM, FRdSR: they change only with
        the next start).  Bit 15, the host interrupt (the HI pin is not wired on the H3, manual
        §7.4 FRdSR: "ohne Bedeutung"), is 0 unless ``host_interrupt`` (spec G-12 option): then 1
        while a flag MSKI's mask enables is set (RESET enables all but the breakpoint's)."""
        p = self.profile
        return ((self.status & INTERRUPTS) | int(self.index_armed) | int(self.motor_off) << 7
                | int(self.filter.dac_bits == 8) << 8 | int(self.stop_on_error) << 9 | int(self.on_target) << 10
                | int(p.velocity_mode) << 11 | int(p.forward) << 12 | int(self.udf_sample) << 13
                | int(bool(self.loaded & 0x20)) << 14 | int(self.host_interrupt and bool(self.flags & self.mask)) << 15)

    @property
    def real_velocity(self) -> int:
        """RDRV: whole counts per sample, the top 14 bits only (C000h … 3FFFh)."""
        return max(-0x4000, min(0x3FFF, math.floor(self.encoder_sign * self.motor.velocity * self.sample_time)))

    # -- one sample --------------------------------------------------------------------------------
    def sample(self) -> None:
        self.udf_sample = False
        before = self._raw
        was_complete = self.profile.complete
        if self.motor_off:  # the set position tracks the coasting axis, the integrator rests (G-21)
            self.profile.hold(self.unwrapped_actual)
            self.filter.reset()
        else:
            self.profile.sample()
            if self.profile.complete and not was_complete:
                self.flags |= COMPLETE
                self.on_target = True
            self.filter.sample(self.profile.desired, self.unwrapped_actual)
        volts = self.filter.volts if self.filter.dac_bits == 12 else self.filter.volts * 10.0
        self.motor.step(volts, self.sample_time)
        after = self._raw = self._encoder()
        if before != after:
            self._moved(before, after)
        if not self.motor_off and abs(sat(self.profile.desired - self.unwrapped_actual, 32)) > self.error_threshold:
            self.flags |= POSITION_ERROR
            if self.stop_on_error:
                self.motor_off = True
                self.flags |= COMPLETE  # switching the motor off completes the trajectory

    def _moved(self, before: int, after: int) -> None:
        """The encoder counted from ``before`` to ``after`` (raw counts) in this sample."""
        home = self.home
        self.flags |= moved_flags(before, after, home, self.breakpoint)
        if self.index_armed and self.index_period:
            period, offset = self.index_period, self.index_offset
            if after > before:  # the last mark at or below ``after``, passed if above ``before``
                mark = (after - offset) // period * period + offset
                passed = mark > before
            else:  # the first mark at or above ``after``, passed if below ``before``
                mark = -((offset - after) // period) * period + offset
                passed = mark < before
            if passed:
                self.index_position = wrap(mark - home)
                self.index_armed = False
                self.flags |= INDEX


Write = Callable[[Lm628, list[int]], None]
Report = Callable[[Lm628], int]


def _none(action: Callable[[Lm628], None]) -> Write:
    """A command without data words (any word is a command error)."""
    return lambda chip, words: action(chip) if not words else chip.error()


def _one(action: Callable[[Lm628, int], None]) -> Write:
    """A command with one data word."""
    return lambda chip, words: action(chip, words[0]) if len(words) == 1 else chip.error()


def _control(action: Callable[[Lm628, int, list[int]], None]) -> Write:
    """A command with a control word and the values it announces."""
    return lambda chip, words: action(chip, words[0], words[1:]) if words else chip.error()


COMMANDS: Table[Write] = Table([
    Command("RESET", _none(Lm628.reset), "§3.5.3", "reset chip"),
    Command("PORT8", _none(lambda c: c.port(8)), "§3.5.3", "output port 8 bits"),
    Command("PORT12", _none(lambda c: c.port(12)), "§3.5.3", "output port 12 bits (not on the LM629)"),
    Command("DFH", _none(Lm628.define_home), "§3.5.3", "define home: actual position := 0"),
    Command("SIP", _none(Lm628.arm_index), "§3.5.3", "set index position: capture at the next index pulse"),
    Command("LPEI", _one(lambda c, w: c.position_error(w, False)), "§3.5.3", "position error threshold (flag only)"),
    Command("LPES", _one(lambda c, w: c.position_error(w, True)), "§3.5.3",
            "position error threshold for stopping (flag and motor off)"),
    Command("SBPA", _one(lambda c, w: c.set_breakpoint(w, False)), "§3.5.3", "set breakpoint, absolute"),
    Command("SBPR", _one(lambda c, w: c.set_breakpoint(w, True)), "§3.5.3", "set breakpoint relative to the target"),
    Command("MSKI", _one(Lm628.mask_interrupts), "§3.5.3", "mask interrupts to the HI pin"),
    Command("RSTI", _one(Lm628.reset_interrupts), "§3.5.3", "reset interrupt flags (bit 0 resets)"),
    Command("LFIL", _control(Lm628.load_filter), "§3.5.3, §3.5.5", "load filter parameters into the buffers"),
    Command("UDF", _none(Lm628.update_filter), "§3.5.3", "update filter (buffers → working)"),
    Command("LTRJ", _control(Lm628.load_trajectory), "§3.5.3, §3.5.4", "load trajectory parameters into the buffers"),
    Command("STT", _none(Lm628.start), "§3.5.3", "start motion (take over the trajectory buffers)"),
])
"""The write commands of §3.5.3 by mnemonic (32-bit values as one word each)."""

REPORTS: Table[Report] = Table([
    Command("RDSTAT", lambda c: c.status, "§3.5.3, §4.8", "read status byte"),
    Command("RDSIGS", lambda c: c.signals, "§3.5.3, §4.5", "read signals register"),
    Command("RDIP", lambda c: c.index_position, "§3.5.3", "read index position"),
    Command("RDDP", lambda c: c.desired, "§3.5.3", "read desired (set) position"),
    Command("RDRP", lambda c: c.actual, "§3.5.3", "read real (actual) position"),
    Command("RDDV", lambda c: c.profile.velocity, "§3.5.3", "read desired velocity (× 2^16)"),
    Command("RDRV", lambda c: c.real_velocity, "§3.5.3", "read real velocity (counts per sample)"),
    Command("RDSUM", lambda c: c.filter.integral, "§3.5.3", "read integration-term sum"),
])
"""The report commands of §3.5.3 by mnemonic."""

CODES = {"RESET": 0x00, "STT": 0x01, "DFH": 0x02, "SIP": 0x03, "UDF": 0x04, "PORT8": 0x05, "PORT12": 0x06,
         "RDDV": 0x07, "RDDP": 0x08, "RDIP": 0x09, "RDRP": 0x0A, "RDRV": 0x0B, "RDSIGS": 0x0C, "RDSUM": 0x0D,
         "LPES": 0x1A, "LPEI": 0x1B, "MSKI": 0x1C, "RSTI": 0x1D, "LFIL": 0x1E, "LTRJ": 0x1F, "SBPA": 0x20, "SBPR": 0x21}
"""Command bytes (§3.5.3)."""
WRITE_BYTES = {code: mnemonic for mnemonic, code in CODES.items() if mnemonic in COMMANDS}
"""The write commands by their command byte (an FSetPE with the G-8 option sends MCW's low byte)."""
NO_DATA = frozenset(("RESET", "STT", "DFH", "SIP", "UDF", "PORT8", "PORT12"))
"""The write commands without data words (§3.5.3)."""
READ_BYTES = {"RDDV": 4, "RDDP": 4, "RDIP": 4, "RDRP": 4, "RDRV": 2, "RDSIGS": 2, "RDSUM": 2}


def notation(mnemonic: str, words: tuple[int, ...]) -> str:
    """One transfer as the spec writes chip traces (§6): ``C:1F D:00 02 D:00 01 D:86 A0``."""
    parts = [f"C:{CODES.get(mnemonic, 0xFF):02X}"]
    if mnemonic in READ_BYTES:
        return f"{parts[0]} R:{READ_BYTES[mnemonic]}"
    wide = {"LTRJ": range(1, len(words)), "SBPA": range(len(words)), "SBPR": range(len(words))}.get(mnemonic, ())
    for index, word in enumerate(words):
        halves = (word >> 16 & 0xFFFF, word & 0xFFFF) if index in wide else (word & 0xFFFF,)
        parts.extend(f"D:{h >> 8:02X} {h & 0xFF:02X}" for h in halves)
    return " ".join(parts)
