"""The simulated PCD4 CPU around the H3 modules (spec pcd4h3.md §3.3.3, §4.1, §9.5, §9.6): its
media (registers, flags, inputs, outputs, counters, timers), the cold start that runs AxInit for
every axis (XOB 16), and the cyclic part that calls AxHndlg for every axis once per PLC cycle,
with the cyclic read functions and the DP14 display the manual's examples program.

The cycle runs on the device clock only while there is something to do (a command flag set, a
chip moving, a cyclic read to refresh): an idle PLC costs no CPU, and what a host sees is what an
always-cycling PLC would show.  Inside a cycle each function acts on its chip at the moment the
FBs' execution times (§10.1) put it, so two axes started in one cycle start about 1 ms apart.

The kind's model: it builds its parts and hands each its collaborators: per axis a drive
(:class:`~devsim.devices.pcd4h3.drive.H3Drive`: chip, motor, switches) and the library on it
(:class:`~devsim.devices.pcd4h3.library.H3Axis`, with its register block as
:class:`~devsim.devices.pcd4h3.registers.AxisRegisters`), the timers, and the user program's
:class:`~devsim.devices.pcd4h3.programs.Sequence`.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Mapping
from typing import Any

from devsim.core.clock import Clock, Timer
from devsim.core.model import Model
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.pcd4h3 import display
from devsim.devices.pcd4h3.config import AXIS, Pcd4h3Config
from devsim.devices.pcd4h3.drive import H3Drive, axis_signals
from devsim.devices.pcd4h3.layout import Layout
from devsim.devices.pcd4h3.library import STATUS_FLAGS, TIMES, H3Axis
from devsim.devices.pcd4h3.lookahead import FIRST_HORIZON, HORIZON, Moments, quiet_cycles, switch_near
from devsim.devices.pcd4h3.programs import PROGRAMS, Sequence
from devsim.devices.pcd4h3.registers import AxisRegisters, RegisterBlock
from devsim.devices.pcd4h3.timers import Timers
from devsim.devices.pcd4h3.units import CHIP_SAMPLE, CHIP_SAMPLE_US

__all__ = ["Halted", "Pcd4"]

RUN, HALT, STOP = "R", "H", "S"
MEDIA_SIZE = {"register": 4096, "flag": 8192, "input": 1024, "output": 1024, "counter": 1600, "timer": 32}
MOTION_FUNCTIONS = ("FStart", "FStop", "FMotOff", "FSStepF", "FSStepB", "FForw", "FBackw")
BUS_INPUTS = {"X": (9, 10, 11), "Y": (13, 14, 15)}  # LS1, LS2, In/Ref at module address + offset (§2.2)


class Halted(Exception):
    """ComErS halted the CPU (``comers_action: halt``)."""


class Pcd4(Model):
    """One PCD4 with ``modules`` H3 modules and ``mna`` axes."""

    #: The cycle's own bookkeeping in slots, the rest in the instance dictionary: that one shares
    #: its keys among the devices while it holds 29 or fewer (see :class:`devsim.core.model.Model`).
    __slots__ = ("_skipped", "_coast_end", "_coast_reads", "_horizon", "_seen", "_last_cycle", "_calls_before",
                 "_running_since")

    def __init__(self, *, clock: Clock, config: Mapping[str, Any] | None = None,
                 nvram: NonVolatileMemory | None = None, name: str = "") -> None:
        super().__init__(clock=clock, config=config, nvram=nvram, name=name)
        s = self.settings = Pcd4h3Config.parse(self.config).dump()
        h = s["h3def"]
        variant = s["variant"]
        self.per_module, self.pwm, self.rs422 = int(variant[2]), variant[3] in "67", variant[3] in "17"
        self.imode = h["imode"] or (5 if self.pwm else 6)
        self.fmah3, self.station = h["fmah3"], s["station"]
        self.layout = Layout(h["bar"], h["baf"], h["mna"], s["flag_map"])
        self.cycle_time = s["plc_cycle_ms"] / 1000
        self.diag_registers, self.diag_flags = s["diagnostics"]
        self.registers: dict[int, int] = {}
        self.flags: dict[int, int] = {}
        self.inputs: dict[int, int] = {}  # inputs that are not an H3 module's (the user's keys)
        self.outputs: dict[int, int] = {}
        self.counters: dict[int, int] = {}
        self.timers = Timers(clock)
        self.drives: list[H3Drive] = []
        self.axes: list[H3Axis] = []
        self.signals.declare(row for n in range(1, max(2, h["mna"]) + 1)  # one shared layout per kind
                             for row in axis_signals(n))  # type: ignore[arg-type]
        chip_sample = CHIP_SAMPLE * (s["chip_sample_time_us"] / CHIP_SAMPLE_US)  # the default: CHIP_SAMPLE exactly
        for n in range(1, h["mna"] + 1):
            module, y = (n - 1) // 2, n % 2 == 0
            present = module < s["modules"] and (not y or self.per_module == 2)
            drive = H3Drive(n, clock, self.signals, s["axes"].get(n) or _axis_defaults(), lm629=self.pwm,
                            rs422=self.rs422, present=present, jumpers=s["jumpers"],
                            host_interrupt=s["emulate_host_interrupt"], sample_time=chip_sample)
            registers = AxisRegisters(RegisterBlock(self.registers, self.layout.block(n)))
            registers.reset()  # G-16: the registers start with Example 1's values
            axis = H3Axis(n, self.layout, drive.chip, registers, self.flags, on_comers=self._comers,
                          on_write=drive.poke, rsigb_bit12_inverted=s["rsigb_bit12_inverted"],
                          velocity_readback_unsigned=s["velocity_readback_unsigned"],
                          literal_mcw_command=s["literal_mcw_command"], fb_sample=s["fb_sample_time_us"] / 1e6)
            self.drives.append(drive)
            self.axes.append(axis)
            self.signals.subscribe(f"LS1_{n}", lambda _n, old, new, n=n: self._limit(n, old, new))
            self.signals.subscribe(f"LS2_{n}", lambda _n, old, new, n=n: self._limit(n, old, new))
        program = PROGRAMS.get(s["user_program"] or "")
        self.sequence = (Sequence(program, self.axes[0], self.inputs, self.counters, self.timers)
                         if program is not None and self.axes else None)
        displayed = dict(s["display"])
        if program is not None and program.display:
            displayed.setdefault(1, {"reg1": "RActP", "reg2": "RSetV"})
        self.displayed = displayed
        self.screens = {n: display.BLANK for n in displayed}
        self.status = RUN
        self.initialised = [False] * len(self.axes)
        self._timer: Timer | None = None
        self._skipped: list[float] = []  # the cycles the timer skips (issue 31), run late if they read
        self._coast_end: float | None = None  # the cycle after the skipped ones
        self._coast_reads = False  # the skipped cycles read the chips (run late, at the next look)
        self._horizon = FIRST_HORIZON  # how far the next look-ahead reaches (doubles while nothing ends it early)
        self._seen: dict[tuple[int, str], int] = {}  # status flags at the last look (events)
        self._last_cycle = -math.inf
        self._calls_before, self._running_since = 0, clock.now()  # AxHndlg calls (one per axis per cycle)
        self.cold_start()

    # -- cold start (XOB 16, §9.6.1) -------------------------------------------------------------
    def cold_start(self) -> None:
        """Load the configured registers, run AxInit for every axis, start the cycle."""
        self._materialize(self.clock.now())
        for n, values in self.settings["init"].items():
            if n > len(self.axes):
                continue
            for symbol, value in values.items():
                self.axes[n - 1].registers.load(symbol, value)
        self._fold_calls()
        self.status = RUN
        if self.sequence is not None:
            self.sequence.restart()
        for index, (axis, drive) in enumerate(zip(self.axes, self.drives, strict=True)):
            drive.catch_up()
            try:
                axis.init(self.imode)
            except Halted:
                break
            finally:
                drive.poke()
            self.initialised[index] = True
        self.wake()

    def restart(self) -> None:
        """S-Bus 'restart cold' (38h)."""
        self.cold_start()

    def run(self) -> None:
        """S-Bus 'run' (2Fh)."""
        self._materialize(self.clock.now())
        if self.status != RUN:
            self.status = RUN
            self._running_since = self.clock.now()
            self.wake()

    def stop(self) -> None:
        """S-Bus 'stop' (43h): AxHndlg no longer runs; the chips finish what they do."""
        self._materialize(self.clock.now())
        if self.status == RUN:
            self._fold_calls()
        self.status = STOP

    def halt(self) -> None:
        """The CPU halts (as ComErS does with ``comers_action: halt``)."""
        self._materialize(self.clock.now())
        if self.status == RUN:
            self._fold_calls()
        self.status = HALT

    def power_cycle(self, *, wipe: bool = False) -> None:
        """Off and on: the chips are reset and the motors stand; the PLC's registers stay (R2
        memory, G-16), AxInit runs again: the actual position is 0 (§4.11)."""
        super().power_cycle(wipe=wipe)
        for drive in self.drives:
            drive.catch_up()
            drive.motor.velocity = 0.0
            drive.chip.reset()
            drive.poke()
        self.cold_start()
        self.announce("power_on")

    # -- the cycle (§3.3.2, §9.6.1) ---------------------------------------------------------------
    def wake(self) -> None:
        """Something may need the cycle: make sure the next one is scheduled (on the cycle grid)."""
        if self._timer is not None:
            if self._coast_end is not None:
                self._resume()
            return
        now = self.clock.now()
        due = max(now, self._last_cycle + self.cycle_time)
        self._timer = self.clock.call_at(due, self._cycle)

    def _resume(self) -> None:
        """Skip no further cycle: the next one on the grid from now runs."""
        now = self.clock.now()
        self._materialize(now)
        skipped, self._skipped, self._coast_end = self._skipped, [], None
        if skipped:  # what was computed ahead is dropped: look less far ahead for a while
            self._horizon = FIRST_HORIZON
        if skipped and self._timer is not None:  # (all after now)
            self._timer.cancel()
            self._timer = self.clock.call_at(skipped[0], self._cycle)

    def _materialize(self, until: float) -> None:
        """Run the skipped cycles up to ``until`` that read the chips (cyclic reads, the
        display), as they would have run: each chip back at that cycle's moments; the shared
        axes follow at the next look, not in the past.  Only the first and the last run; those
        between only count and trace the first one's transfers (the same reads, which cannot fail
        and change no chip, of the same status: the last leaves registers and display as all would)."""
        skipped = self._skipped
        due = bisect_right(skipped, until)
        if not due:
            return
        starts, self._skipped = skipped[:due], skipped[due:]
        if not self._coast_reads or self.status != RUN:  # (without reads they would change nothing)
            return
        before = self._run_late(starts[0])
        if len(starts) > 1:
            # every skipped cycle sets the same flags, whose reads cannot fail and change no chip,
            # and finds the same status: the ones between transfer what the first did, and the
            # last leaves the registers and the display as they all would
            transfers = [axis.trace[len(axis.trace) - (axis.transfers - count):]
                         for axis, count in zip(self.axes, before, strict=True)]
            for axis, cycle in zip(self.axes, transfers, strict=True):
                axis.repeat(cycle, len(starts) - 2)
            self._run_late(starts[-1])

    def _run_late(self, start: float) -> list[int]:
        """A skipped cycle that reads, run late: each chip back at its moments; returns each
        axis's count of transfers before it."""
        before = [axis.transfers for axis in self.axes]
        for drive in self.drives:
            drive.catch_up(start, follow=False)
        self._run_axes(start, follow=False)
        return before

    def _cycle(self) -> None:
        self._timer = None
        start = self.clock.now()
        self._materialize(start)
        self._skipped, self._coast_end = [], None
        self._last_cycle = start
        for drive in self.drives:
            drive.catch_up()
            drive.stepper.present()
        elapsed = self._run_axes(start) if self.status == RUN else 0.0
        if self._busy():
            due = start + max(self.cycle_time, elapsed)
            if self._only_moving():
                moments, work = self._quiet_work()
                step = max(self.cycle_time, work)
                skipped = quiet_cycles(self.drives, due, step, moments, self._horizon)
                self._horizon = min(HORIZON, 2 * self._horizon)
                while skipped and not self.timers.none_runs_out(skipped[-1]):  # (that cycle would see it)
                    skipped.pop()
                if skipped:
                    self._skipped, due = skipped, skipped[-1] + step
                    self._coast_end = due
                    self._coast_reads = self._reading()
            self._timer = self.clock.call_at(due, self._cycle)

    def _run_axes(self, start: float, *, follow: bool = True) -> float:
        """AxHndlg for every axis, the user program and the display: a cycle's work (§3.3.2,
        §9.6.1); returns its duration in seconds."""
        elapsed = 0.0
        if self.sequence is not None:
            self.sequence.before_handling()
        try:
            for axis, drive in zip(self.axes, self.drives, strict=True):
                for symbol in self.settings["cyclic_reads"]:
                    axis.set_flag(symbol, 1)
                offset = elapsed

                def before(ms: float, drive: H3Drive = drive, offset: float = offset) -> None:
                    drive.catch_up(start + offset + ms / 1000, follow=follow)

                elapsed += axis.handle(before) / 1000  # (a command pokes the drive at once; a read does not)
                self._note(axis)
            if self.sequence is not None:
                self.sequence.cycle(start)  # (its timers as they count at the cycle's start)
        except Halted:
            pass
        self._display()
        return elapsed

    def _reads(self, index: int) -> set[str]:
        reads = set(self.settings["cyclic_reads"])
        if index == 0 and self.sequence is not None:
            reads.update(self.sequence.program.cyclic_reads)
        return reads

    def _reading(self) -> bool:
        return any(self._reads(index) for index in range(len(self.axes)))

    def _quiet_work(self) -> tuple[list[Moments], float]:
        """When a cycle with nothing but its cyclic reads looks at each chip (its start, each
        read, as ``(offset, ms)`` the way :meth:`_run_axes` adds them) and how long it lasts:
        AxHndlg's base time per axis and the reads' times (§3.3.2, §10.1)."""
        moments: list[Moments] = []
        elapsed = 0.0
        running = self.status == RUN
        for index, axis in enumerate(self.axes):
            reads, ms, seen = self._reads(index) if running else set(), 0.5, [(0.0, 0.0)]
            for symbol, _ in axis.command_flags:
                if symbol in reads:
                    seen.append((elapsed, ms))
                    ms += TIMES[symbol]
            moments.append(tuple(seen))
            if running:
                elapsed += ms / 1000
        return moments, elapsed

    def _only_moving(self) -> bool:
        """The next cycles have nothing to do but copy the chips' status (while it stays) and
        read the chips as configured: no command flag, no step of the user program whose
        condition holds (one waiting on a timer waits: the cycles skipped end before it runs
        out), and reads that cannot fail (every chip fitted, no disturbed transfer, a ComErS
        that only counts)."""
        if self.status != RUN:
            return True
        sequence = self.sequence
        if sequence is not None and sequence.busy:
            return False
        if self._reading() and (
                self.settings["comers_action"] != "continue"
                or any(not drive.chip.present or drive.chip.bus_errors for drive in self.drives)):
            return False
        flags = self.flags
        return not any(flags.get(address, 0) for axis in self.axes for _, address in axis.command_flags)

    def _note(self, axis: H3Axis) -> None:
        """Events for timing expectations: a motion function run (``axis1.FStart`` …) and a
        status flag rising (``axis1.OnDest`` …)."""
        for symbol in axis.ran:
            if symbol in MOTION_FUNCTIONS:
                self.record_event(f"axis{axis.axis}.{symbol}")
        flags = self.flags
        for symbol, address in zip(STATUS_FLAGS, axis.status_flags, strict=True):
            value = flags.get(address, 0)
            key = (axis.axis, symbol)
            if value and not self._seen.get(key):
                self.record_event(f"axis{axis.axis}.{symbol}")
                if symbol == "ExcPEr":
                    self.announce("fault", axis.axis, 0x8611)  # CiA 402's "following error" (EMCY)
            self._seen[key] = value

    def _busy(self) -> bool:
        if any(not drive.settled for drive in self.drives):
            return True
        if self.status != RUN:
            return False
        if self._reading():  # the cyclic reads go on while the chips rest (each cycle transfers)
            return True
        if self.sequence is not None and (self.sequence.busy or self.timers.running()):
            return True
        flags = self.flags
        return any(flags.get(address, 0) for axis in self.axes for _, address in axis.command_flags)

    def _display(self) -> None:
        for n, view in self.displayed.items():
            if n > len(self.axes):
                continue
            axis = self.axes[n - 1]
            first, second = axis.registers.named(view["reg1"]), axis.registers.named(view["reg2"])
            if axis.flag("DplM"):
                self.screens[n] = (display.six_digits(first), display.six_digits(second))
            else:
                self.screens[n] = display.ten_digits(first)

    def _comers(self, offset: int) -> None:
        if self.settings["comers_action"] != "continue":
            self._fold_calls()
            self.status = HALT
            raise Halted

    def _limit(self, n: int, old: Any, new: Any) -> None:
        """A limit switch opened: a user program would stop the axis (optional, §5.10)."""
        if old and not new and self.settings["emulate_user_limit_stop"]:
            self._materialize(self.clock.now())
            self.axes[n - 1].set_flag("FStop", 1)
            self.wake()

    def _fold_calls(self) -> None:
        now = self.clock.now()
        if self.status == RUN:
            self._calls_before += self._cycles_since(now)
        self._running_since = now

    def _cycles_since(self, now: float) -> int:
        return max(0, math.floor((now - self._running_since) / self.cycle_time + 1e-9))

    def handler_calls(self) -> int:
        """AxHndlg calls of each axis since start-up: one per cycle while the PCD runs."""
        running = self._cycles_since(self.clock.now()) if self.status == RUN else 0
        return self._calls_before + running

    def catch_up(self) -> None:
        """Bring every chip to now (before the host looks).  While cycles are skipped, the
        shared axis now follows the motor from here; where that could reach a switch before the
        next cycle, the skipping ends."""
        now = self.clock.now()
        self._materialize(now)
        for drive in self.drives:
            drive.catch_up()
        if self._coast_end is not None:
            following = self._coast_end
            if any(switch_near(drive, drive.axis.position(now), drive.axis.position(following))
                   for drive in self.drives if drive.switches):
                self._resume()

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        for drive in self.drives:
            drive.close()


def _axis_defaults() -> dict[str, Any]:
    return AXIS.parse({}).dump()
