"""The LM628/LM629 motion controller chip of one PCD4.H3 axis (spec pcd4h3.md §3.5, §4.5, §4.8,
§5.2–§5.9; National Semiconductor LM628 datasheet): its commands, its status byte and signals
register, and one sample of its work (profile generator, filter, motor, the checks).

Pure and stepped: :meth:`Lm628.sample` advances one sample period (2048 / 6 MHz); the caller
decides when.  Commands take the words the host port carries (§3.5.3).
"""

from __future__ import annotations

from devsim.core.words import signed32
from devsim.devices.pcd4h3.pid import Coefficients, Filter, Motor, sat
from devsim.devices.pcd4h3.trajectory import Profile, Trajectory
from devsim.devices.pcd4h3.units import CHIP_SAMPLE

__all__ = ["Lm628", "MOTOR_OFF", "BREAKPOINT", "POSITION_ERROR", "WRAPAROUND", "INDEX", "COMPLETE", "COMMAND_ERROR"]

MOTOR_OFF, BREAKPOINT, POSITION_ERROR, WRAPAROUND, INDEX, COMPLETE, COMMAND_ERROR = 0x80, 0x40, 0x20, 0x10, 0x08, 0x04, 0x02
INTERRUPTS = BREAKPOINT | POSITION_ERROR | WRAPAROUND | INDEX | COMPLETE | COMMAND_ERROR
POSITION_RANGE = 1 << 30


class Lm628:
    """One chip: its buffers, working registers, flags and the motor behind its output."""

    def __init__(self, motor: Motor | None = None) -> None:
        self.motor = motor if motor is not None else Motor()
        self.profile = Profile()
        self.filter = Filter(dac_bits=8)
        self.buffer = Trajectory()
        self.flags = 0  # interrupt flags (status bits 1 … 6)
        self.mask = 0
        self.motor_off = True
        self.stop_on_error = False
        self.error_threshold = 0x7FFF
        self.breakpoint: int | None = None
        self.accel_loaded = False
        self.home = 0.0  # motor position of count 0
        self._stop = 0  # the stop bits (8 … 10) of the last LTRJ, acting at the next STT
        self.on_target = False  # signals bit 10: the generator finished a profile since the last STT

    # -- initialisation and interrupts (§3.5.3) -------------------------------------------------
    def reset(self) -> None:
        """RESET: coefficients, trajectory and output to zero, 8-bit port, home here; only the
        breakpoint interrupt stays masked."""
        self.profile, self.buffer = Profile(), Trajectory()
        self.filter = Filter(dac_bits=8)
        self.flags, self.mask, self.motor_off, self.stop_on_error = 0, INTERRUPTS & ~BREAKPOINT, True, False
        self.breakpoint, self.accel_loaded, self.on_target = None, False, False
        self.define_home()

    def port(self, bits: int) -> None:
        """PORT8 / PORT12."""
        self.filter.dac_bits = bits

    def define_home(self) -> None:
        """DFH: the actual position becomes 0."""
        self.home = self.motor.position
        self.profile.set_home()
        self.profile.position = 0
        self.profile.target = 0

    def position_error(self, threshold: int, stop: bool) -> None:
        """LPEI (flag only) / LPES (flag and motor off)."""
        self.error_threshold, self.stop_on_error = threshold & 0x7FFF, stop

    def set_breakpoint(self, position: int, relative: bool = False) -> None:
        """SBPA / SBPR (relative to the current target)."""
        base = self.profile.target >> 16 if relative else 0
        self.breakpoint = base + signed32(position)

    def reset_interrupts(self, word: int) -> None:
        """RSTI: a 0 bit resets that flag."""
        self.flags &= word | ~INTERRUPTS

    # -- filter and trajectory ---------------------------------------------------------------------
    def load_filter(self, control: int, words: list[int]) -> None:
        """LFIL: the control word (ds in bits 15…8, which values follow) and kp, ki, kd, il."""
        values = iter(words)
        c = self.filter.buffer
        kp, ki, kd, il = c.kp, c.ki, c.kd, c.il
        if control & 8:
            kp = next(values) & 0x7FFF
        if control & 4:
            ki = next(values) & 0x7FFF
        if control & 2:
            kd = next(values) & 0x7FFF
        if control & 1:
            il = next(values) & 0x7FFF
        self.filter.buffer = Coefficients(kp, ki, kd, il, control >> 8 & 0xFF)

    def update_filter(self) -> None:
        """UDF."""
        self.filter.update()

    def load_trajectory(self, control: int, values: list[int]) -> None:
        """LTRJ: the control word (§3.5.4) and acceleration, velocity, position as loaded."""
        items = iter(values)
        b = self.buffer
        acceleration, velocity, position = b.acceleration, b.velocity, b.position
        if control & 0x20:
            value = next(items)
            acceleration = acceleration + signed32(value) if control & 0x10 else value & 0x3FFF_FFFF
            self.accel_loaded = True
        if control & 0x08:
            value = next(items)
            velocity = velocity + signed32(value) if control & 0x04 else value & 0x3FFF_FFFF
        if control & 0x02:
            value = signed32(next(items))
            position = (self.profile.target >> 16) + value if control & 0x01 else value
        self.buffer = Trajectory(acceleration, velocity, position, bool(control & 0x0800), bool(control & 0x1000))
        self._stop = control & 0x0700

    def start(self) -> None:
        """STT: take over the buffers; a stop in the control word acts now."""
        stop = self._stop
        if self.accel_loaded and not self.profile.complete and not self.motor_off and self.profile.velocity:
            self.flags |= COMMAND_ERROR  # acceleration changed while moving (§3.5.3)
            return
        self._stop = 0
        if stop & 0x0100:
            self.motor_off = True
            self.profile.stop_abruptly()
            self.flags |= COMPLETE
            return
        if stop & 0x0200:
            self.profile.stop_abruptly()
            self.flags |= COMPLETE
            return
        if stop & 0x0400:
            self.profile.stop_smoothly()
            return
        self.motor_off, self.accel_loaded, self.on_target = False, False, False
        self.flags &= ~COMPLETE
        self.profile.start(self.buffer)
        if self.profile.complete:
            self.flags |= COMPLETE
            self.on_target = True

    # -- reports (§4.5, §4.8) ----------------------------------------------------------------------
    @property
    def actual(self) -> int:
        """RDRP: the encoder count relative to home."""
        return int((self.motor.position - self.home) // 1)

    @property
    def status(self) -> int:
        """RDSTAT (bit 0 busy is never seen: commands complete at once)."""
        return self.flags | (MOTOR_OFF if self.motor_off else 0) | (COMPLETE if self.motor_off else 0)

    @property
    def signals(self) -> int:
        """RDSIGS (§4.5)."""
        t = self.buffer
        return ((self.status & INTERRUPTS) | int(self.motor_off) << 7 | int(self.filter.dac_bits == 8) << 8
                | int(self.stop_on_error) << 9 | int(self.on_target) << 10 | int(t.velocity_mode) << 11
                | int(t.forward) << 12 | int(self.accel_loaded) << 14)

    # -- one sample --------------------------------------------------------------------------------
    def sample(self) -> None:
        before = self.actual
        was_complete = self.profile.complete
        self.profile.sample()
        if self.profile.complete and not was_complete:
            self.flags |= COMPLETE
            self.on_target = True
        if self.motor_off:
            self.filter.output = 0
        else:
            self.filter.sample(self.profile.desired, self.actual)
        self.motor.step(self.filter.volts if self.filter.dac_bits == 12 else self.filter.volts * 10.0, CHIP_SAMPLE)
        after = self.actual
        if abs(sat(self.profile.desired - after, 32)) > self.error_threshold:
            self.flags |= POSITION_ERROR
            if self.stop_on_error:
                self.motor_off = True
        if self.breakpoint is not None and (before - self.breakpoint) * (after - self.breakpoint) <= 0 \
                and before != after:
            self.flags |= BREAKPOINT
            self.breakpoint = None
