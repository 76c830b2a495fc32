"""The queued letter commands as the command executor carries them out (manual §2.3.1; spec §3.8,
§4.2.1).

:data:`QUEUED_COMMANDS` maps each letter to a :class:`QueuedCommands` method; the letters with
sub-functions look those up in their own tables: :data:`G_FUNCTIONS` (``G`` P1),
:data:`H_FUNCTIONS`, :data:`M_FUNCTIONS`, :data:`Q_TYPES`, :data:`RESET_FUNCTIONS` and the ``p``
functions of :mod:`.program`.  A handler returns True when the command is complete at once, False
while the executor waits or a move runs.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from devsim.core.kit import Command, Table
from devsim.devices.gms96 import tables
from devsim.devices.gms96.coordinates import Coordinates
from devsim.devices.gms96.counter import CounterInput
from devsim.devices.gms96.executor import Cmd, Executor
from devsim.devices.gms96.feed import Feed
from devsim.devices.gms96.i2t import I2t
from devsim.devices.gms96.image import STATIC_BYTES, ProcessImage
from devsim.devices.gms96.io import Outputs
from devsim.devices.gms96.memory import Memory
from devsim.devices.gms96.motion import Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.program import ProgramControl
from devsim.devices.gms96.reference import References
from devsim.devices.gms96.spindle import Spindle
from devsim.devices.gms96.stage import PowerStage

__all__ = [
    "G_FUNCTIONS",
    "H_FUNCTIONS",
    "M_FUNCTIONS",
    "PROGRAM_END",
    "QUEUED_COMMANDS",
    "Q_TYPES",
    "RESET_FUNCTIONS",
    "QueuedCommands",
]

Handler = Callable[["QueuedCommands", Cmd], bool]


def g_key(p1: int) -> str:
    """The :data:`G_FUNCTIONS` row of ``G P1``: the extended zero-point selection ``0x000n36``
    (n = 1..15) is G54's row (spec §3.8.6)."""
    return "54" if p1 & 0xFF == 54 and 0 < (p1 >> 8) & 0xFF <= 15 else str(p1)


def m_key(p1: int) -> str:
    """The :data:`M_FUNCTIONS` row of ``m P1``: M50..M89 share one."""
    return "50..89" if 50 <= p1 <= 89 else str(p1)


def zero_point(p1: int) -> int:
    """The zero point G54..G69 that ``G P1`` names."""
    return 54 + ((p1 >> 8) & 0xFF) if g_key(p1) == "54" and p1 != 54 else p1


class CommandCard(Protocol):
    """What the queued commands ask of their card (spec §4.2.4, §5.6)."""

    def can_move(self) -> bool: ...
    def activate_controller(self) -> None: ...
    def changed(self) -> None: ...
    def record_event(self, name: str) -> None: ...


class QueuedCommands:
    """The queued commands of one card (manual §2.3.1): what the executor runs for each letter."""

    def __init__(
        self,
        *,
        card: CommandCard,
        executor: Executor,
        program: ProgramControl,
        references: References,
        indexer: Indexer,
        feed: Feed,
        coordinates: Coordinates,
        params: NParameters,
        stage: PowerStage,
        i2t: I2t,
        counter: CounterInput,
        spindle: Spindle,
        outputs: Outputs,
        image: ProcessImage,
        memory: Memory,
        eeprom_write_s: float,
    ) -> None:
        self.card = card
        self.executor = executor
        self.program = program
        self.references = references
        self.indexer = indexer
        self.feed = feed
        self.coordinates = coordinates
        self.params = params
        self.stage = stage
        self.i2t = i2t
        self.counter = counter
        self.spindle = spindle
        self.outputs = outputs
        self.image = image
        self.memory = memory
        self.eeprom_write_s = eeprom_write_s  # s85;170 keeps BUSY this long

    def run(self, cmd: Cmd) -> bool:
        """Carry out ``cmd`` (its row in :data:`QUEUED_COMMANDS`, or the program end marker); a
        letter without a row (a stored program of another version) only re-plans."""
        handler = QUEUED_COMMANDS.get(cmd.letter) or PROGRAM_END.get(cmd.letter) or QueuedCommands.other
        return handler(self, cmd)

    def _settled(self) -> bool:
        """A setting took effect: the running plan follows it, waits re-check."""
        self.indexer.replan()
        self.card.changed()
        return True

    def other(self, cmd: Cmd) -> bool:
        return self._settled()

    # -- moves (spec §4.2.4, §5.4) ---------------------------------------------------------------
    def move(self, cmd: Cmd) -> bool:
        return self.executor.move(cmd)

    def velocity_move(self, cmd: Cmd) -> bool:
        return self.executor.move(cmd, blend=False)

    def feed_move(self, cmd: Cmd) -> bool:
        """``w``: the position counter is zeroed at the start, then a ``v`` move by P1."""
        if not self.card.can_move():
            self.executor.rejected_moves += 1
            return True
        self.coordinates.set_counter_here(0)
        return self.executor.move(Cmd("v", cmd.p1), blend=False)

    # -- settings (spec §4.7) ----------------------------------------------------------------------
    def acceleration(self, cmd: Cmd) -> bool:
        self.feed.B = tables.clamp_setting("B", cmd.p1)
        return self._settled()

    def max_speed(self, cmd: Cmd) -> bool:
        self.feed.M = tables.clamp_setting("M", cmd.p1)
        return self._settled()

    def search_speed(self, cmd: Cmd) -> bool:
        self.feed.S = tables.clamp_setting("S", cmd.p1)
        return self._settled()

    def feed(self, cmd: Cmd) -> bool:
        self.feed.set_feed(cmd.p1, cmd.p2)
        return self._settled()

    def set_origin(self, cmd: Cmd) -> bool:
        """``O``: the position counter (work coordinates) := P1, no motion (spec §3.8.11)."""
        self.coordinates.set_work_position(cmd.p1)
        return self._settled()

    def override(self, cmd: Cmd) -> bool:
        if cmd.p1 in (0, 1):
            self.feed.set_override_active(bool(cmd.p1))
        return self._settled()

    def data_word(self, cmd: Cmd) -> bool:
        """``d``: a data word from byte P2 (DW0..DW79 are static)."""
        if 0 <= cmd.p2 <= 254:
            self.image.write_word(cmd.p2, cmd.p1)
            if cmd.p2 < STATIC_BYTES:
                self.memory.save_static()
        return self._settled()

    def reset(self, cmd: Cmd) -> bool:
        """``r``: :data:`RESET_FUNCTIONS` by P3."""
        handler = RESET_FUNCTIONS.get(str(cmd.p3))
        if handler is not None:
            handler(self, cmd)
        return self._settled()

    def defaults(self, cmd: Cmd) -> bool:
        self.params.defaults()
        self.feed.defaults()
        return True

    def erase_eeprom(self, cmd: Cmd) -> bool:
        self.memory.erase_eeprom()
        return True

    def save(self, cmd: Cmd) -> bool:
        """``s85;170``: save to the EEPROM (BUSY for ``eeprom_write_s``); any other key: nothing."""
        if (cmd.p1, cmd.p2) != tables.SAVE_KEY:
            return True
        self.memory.save_eeprom()
        if self.eeprom_write_s <= 0:
            return True
        return self.executor.after(self.eeprom_write_s, "eeprom")

    # -- G functions (spec §3.8.6, §5.9) -------------------------------------------------------------
    def g(self, cmd: Cmd) -> bool:
        handler = G_FUNCTIONS.get(g_key(cmd.p1))
        return self._settled() if handler is None else handler(self, cmd)

    def rapid(self, cmd: Cmd) -> bool:
        self.feed.f = self.feed.M
        return self._settled()

    def g53(self, cmd: Cmd) -> bool:
        """Deselect the zero offset (P2 = 1: and the tool offset); P3 = 1: enter the machine zero."""
        c = self.coordinates
        if cmd.p3 == 1:
            c.machine_zero = cmd.p2
            c.save()
        else:
            c.deselect(without_tool=cmd.p2 == 1)
        return self._settled()

    def zero_offset(self, cmd: Cmd) -> bool:
        """G54..G57 (and the extended G54..G69): select; P3 = 1: enter; P2 = 1: re-select."""
        c = self.coordinates
        zp = zero_point(cmd.p1)
        if cmd.p3 == 1:
            c.zero_table[zp] = cmd.p2
            c.save()
        elif cmd.p2 == 1:
            c.reselect()
        else:
            c.active_zero = zp
        return self._settled()

    def absolute(self, cmd: Cmd) -> bool:
        self.coordinates.g_relative = False
        return self._settled()

    def relative(self, cmd: Cmd) -> bool:
        self.coordinates.g_relative = True
        return self._settled()

    def speed_limit(self, cmd: Cmd) -> bool:
        self.coordinates.g92 = cmd.p2
        return self._settled()

    def feed_mode(self, cmd: Cmd) -> bool:
        self.feed.feed_mode = cmd.p1
        return self._settled()

    def cutting_speed(self, cmd: Cmd) -> bool:
        """G96 constant cutting speed (spec §3.8.6, §5.2; manual: "V-version", "further information
        on request").  Modelled [R] as far as the sources go: the card computes the desired spindle
        speed ``n = C / r`` [rpm] continuously from the cutting-speed value ``C`` (P2, with P3 as its
        upper 24 bits; unit inc/min/2π, so that v = 2π·r·n) and the distance ``r`` of the set-point
        to the active zero point (work coordinates, at least 1 inc), limited by G92 (P2 = rpm
        limit, 0 = none).  Where the real card sends that speed is not documented, so it only shows
        in the control API (``g96_rpm``); motion is not affected."""
        self.coordinates.g96 = ((cmd.p3 & 0xFFFFFF) << 24) | (cmd.p2 & 0xFFFFFF)
        self.card.changed()
        return True

    def cutting_speed_off(self, cmd: Cmd) -> bool:
        self.coordinates.g96 = None
        self.card.changed()
        return True

    # -- reference runs (spec §3.8.14, §5.6, §5.12) ----------------------------------------------------
    def reference(self, cmd: Cmd) -> bool:
        """``Q``: not while the power stage cannot go into control (emergency stop, monitoring, the
        NV error of T3;4 I.5: "Endstufe geht nicht in Regelung", manual §2.3.1 T), nor (but Q3) in
        counter-input mode (spec §5.10); then :data:`Q_TYPES` by P1 (any other type: a run that fails)."""
        if self.stage.faulted() or (self.counter.active and cmd.p1 != 3):
            self.executor.rejected_moves += 1
            return True
        handler = Q_TYPES.get(str(cmd.p1)) or QueuedCommands.reference_run
        return handler(self, cmd)

    def spindle(self, cmd: Cmd) -> bool:
        self.spindle.run(cmd.p2 & 0xFF, cmd.p3)
        return True

    def controller_on(self, cmd: Cmd) -> bool:
        """Q3: the position controller on, no motion (``Q3;64``: the resolver's absolute position)."""
        self.card.activate_controller()
        if cmd.p2 & 0x40 and cmd.p3 == 0:
            self.coordinates.set_counter_here(self.references.resolver_position())
        self.stage.idxoff = False
        self.i2t.latched = False
        return True

    def reference_run(self, cmd: Cmd) -> bool:
        ex = self.executor
        stage = self.stage
        self.card.activate_controller()
        p1, p2, p3 = cmd.p1, cmd.p2 & 0xFF, cmd.p3
        ref_p2 = (self.params.reference_type >> 8) & 0xFF if p1 == -1 else p2  # P2 from N19 (spec §5.6)
        if not (ref_p2 & 0x40 and not stage.idxoff):
            stage.idxoff = True

        def done(success: bool) -> None:
            ex.reference = None
            if success:
                self.i2t.latched = False
            if ex.current is not None and ex.current.letter == "Q":
                ex.complete()

        # P2.5: the index mark from the counter input's reference track (spec §3.8.14)
        ex.reference = self.references.run(p1, p2, p3, done, counter_track=bool(ref_p2 & 0x20))
        ex.reference.start()
        return ex.reference is None or ex.reference.finished

    # -- H functions (spec §3.8.7, §5.5) -------------------------------------------------------------------
    def h(self, cmd: Cmd) -> bool:
        handler = H_FUNCTIONS.get(str(cmd.p1))
        return True if handler is None else handler(self, cmd)

    def wait_in_position(self, cmd: Cmd) -> bool:
        """H2 (spec §5.5): in position (|e| <= |N27| for N28 ms after the set-point stopped); with
        N27 = 0 or on a stepper card as soon as the set-point is finished.  The device re-checks
        (changed() -> poke) when the set-point stops and N28 later."""
        if self.outputs.in_position():
            return True
        self.executor.waiting_in_position = True
        return self.executor.wait("H2", self.outputs.in_position)

    def torque_abort(self, cmd: Cmd) -> bool:
        self.executor.h7_level = max(0, min(100, cmd.p2))
        return True

    def measurement(self, cmd: Cmd) -> bool:
        """H22;1 / H22;0: the counter input's min/max measurement (spec §3.8.7, counter.py)."""
        if cmd.p2:
            self.counter.h22_start()
        else:
            self.counter.h22_stop()
        return True

    # -- M functions (spec §3.8.9) -----------------------------------------------------------------------
    def m(self, cmd: Cmd) -> bool:
        handler = M_FUNCTIONS.get(m_key(cmd.p1))
        return True if handler is None else handler(self, cmd)  # unknown: accepted, no action

    def _m_wait(self, cmd: Cmd, byte: int, bit: int) -> bool:
        """Set the function's marker bit and wait until the PLC resets it (the PLC's
        ``auto_ack_m_functions_ms`` or a scripted rule)."""
        img = self.image
        img.set_marker(byte, bit, True)
        self.card.changed()
        return self.executor.wait(f"m{cmd.p1}", lambda: not img.marker(byte, bit))

    def m_function(self, cmd: Cmd) -> bool:
        """M50..M89: M6.0..M10.7, MB11 := P2."""
        byte, bit = tables.m_function_marker(cmd.p1)
        self.image.markers[11] = cmd.p2 & 0xFF
        return self._m_wait(cmd, byte, bit)

    def s_function(self, cmd: Cmd) -> bool:
        """m100: MB15 := P2 (M15.7 kept), MW16 := P3, M15.7."""
        img = self.image
        img.markers[15] = (img.markers[15] & 0x80) | (cmd.p2 & 0x7F)
        img.markers[16] = (cmd.p3 >> 8) & 0xFF
        img.markers[17] = cmd.p3 & 0xFF
        return self._m_wait(cmd, 15, 7)

    def t_function(self, cmd: Cmd) -> bool:
        """m101: MB18 := P2 (non-volatile), MB19 := P3, M18.7."""
        img = self.image
        img.markers[18] = (img.markers[18] & 0x80) | (cmd.p2 & 0x7F)
        img.markers[19] = cmd.p3 & 0xFF
        self.memory.save_static()
        return self._m_wait(cmd, 18, 7)

    def sync_run(self, cmd: Cmd) -> bool:
        """``m49``: synchronous run to the counter input until #0 / M0.1 / a fault (counter.py)."""
        counter = self.counter
        if counter.active:
            return True
        if not counter.start_sync():
            self.executor.rejected_moves += 1
            self.card.record_event("move_rejected")
            return True
        return self.executor.wait("m49", lambda: not counter.sync)

    # -- p (spec §3.8.13) ------------------------------------------------------------------------------
    def p(self, cmd: Cmd) -> bool:
        return self.program.run(cmd)

    def program_end(self, cmd: Cmd) -> bool:
        return self.program.program_end(cmd)


#: Letter commands the executor carries out in order (spec §4.2.1, §3.8).
QUEUED_COMMANDS: Table[Handler] = Table(
    [
        Command("A", QueuedCommands.move, "§2.3.1 A", "absolute move"),
        Command("B", QueuedCommands.acceleration, "§2.3.1 B", "acceleration"),
        Command("d", QueuedCommands.data_word, "§2.3.1 d", "write a data word"),
        Command("f", QueuedCommands.feed, "§2.3.1 f", "feed rate"),
        Command("G", QueuedCommands.g, "§2.3.1 G", "G functions (G53-G57 offsets, G90/91, G92, G94/95)"),
        Command("H", QueuedCommands.h, "§2.3.1 H", "H functions (in-position, torque abort, measurement ...)"),
        Command("M", QueuedCommands.max_speed, "§2.3.1 M", "maximum speed"),
        Command("m", QueuedCommands.m, "§2.3.1 m", "M functions (outputs, electronic gear m49 ...)"),
        Command("O", QueuedCommands.set_origin, "§2.3.1 O", "set the origin (actual position := value)"),
        Command("o", QueuedCommands.override, "§2.3.1 o", "override on/off"),
        Command("Q", QueuedCommands.reference, "§2.3.1 Q", "reference run Q0/1/2/3/6/8/-1"),
        Command("r", QueuedCommands.reset, "§2.3.1 r", "defaults (r0) / erase the EEPROM (r1)"),
        Command("S", QueuedCommands.search_speed, "§2.3.1 S", "S function"),
        Command("s", QueuedCommands.save, "§2.3.1 s", "save to the EEPROM (s85;170)"),
        Command("v", QueuedCommands.velocity_move, "§2.3.1 v", "positioning with velocity optimisation (the profile "
                "planned before the move; not blended)"),
        Command("w", QueuedCommands.feed_move, "§2.3.1 w", "feed (Vorschub): the position counter zeroed (O0), then "
                "a v move by P1"),
        Command("+", QueuedCommands.move, "§2.3.1 +", "relative move"),
        Command("p", QueuedCommands.p, "§2.3.1 p", "program and PLC control (p1, p3)"),
        Command("a", QueuedCommands.other, "§2.3.1 a", "a PLC download line"),
    ]
)

#: The executor's own marker behind a program's commands (not a host command).
PROGRAM_END: Table[Handler] = Table(
    [Command("_end", QueuedCommands.program_end, "§2.5", "the end of a CNC program's commands")]
)

#: ``G P1`` (spec §3.8.6); any other P1 is ignored.
G_FUNCTIONS: Table[Handler] = Table(
    [
        Command("0", QueuedCommands.rapid, "§2.3.1 G", "G0: working speed := M (rapid)"),
        Command("53", QueuedCommands.g53, "§2.3.1 G", "G53: deselect the zero (;1: and tool) offset; P3=1: machine zero"),
        *(
            Command(str(n), QueuedCommands.zero_offset, "§2.3.1 G",
                    f"G{n}: select / enter (P3=1) / re-select (P2=1) a zero offset"
                    + (" (also the extended 0x000n36: G54..G69)" if n == 54 else ""))
            for n in range(54, 58)
        ),
        Command("90", QueuedCommands.absolute, "§2.3.1 G", "G90: absolute coordinates"),
        Command("91", QueuedCommands.relative, "§2.3.1 G", "G91: relative coordinates"),
        Command("92", QueuedCommands.speed_limit, "§2.3.1 G", "G92: speed limit of G96 (P2, rpm)"),
        Command("94", QueuedCommands.feed_mode, "§2.3.1 G", "G94: feed in increments per second"),
        Command("95", QueuedCommands.feed_mode, "§2.3.1 G", "G95: feed in increments per revolution (#8)"),
        Command("96", QueuedCommands.cutting_speed, "§2.3.1 G", "G96: constant cutting speed (g96_rpm)"),
        Command("97", QueuedCommands.cutting_speed_off, "§2.3.1 G", "G97: deselect G96"),
    ]
)

#: ``Q P1`` (spec §3.8.14).
Q_TYPES: Table[Handler] = Table(
    [
        Command("0", QueuedCommands.reference_run, "§2.3.1 Q", "Q0: cam, then index mark"),
        Command("1", QueuedCommands.reference_run, "§2.3.1 Q", "Q1: index mark"),
        Command("2", QueuedCommands.reference_run, "§2.3.1 Q", "Q2: cam"),
        Command("3", QueuedCommands.controller_on, "§2.3.1 Q", "Q3: position controller on (Q3;64: resolver position)"),
        Command("6", QueuedCommands.reference_run, "§2.3.1 Q", "Q6: search on a 24 V input"),
        Command("8", QueuedCommands.spindle, "§2.3.1 Q", "Q8: spindle simulation"),
        Command("-1", QueuedCommands.reference_run, "§2.3.1 Q", "Q-1: per N19, drive-off to N33"),
    ]
)

#: ``H P1`` (spec §3.8.7); any other P1 is ignored.
H_FUNCTIONS: Table[Handler] = Table(
    [
        Command("2", QueuedCommands.wait_in_position, "§2.3.1 H", "H2: wait until in position (N27/N28)"),
        Command("7", QueuedCommands.torque_abort, "§2.3.1 H", "H7: abort the next move at P2 % of Imax"),
        Command("22", QueuedCommands.measurement, "§2.3.1 H", "H22: counter-input min/max measurement on/off"),
    ]
)

#: ``m P1`` (spec §3.8.9); any other P1 is accepted without an action.
M_FUNCTIONS: Table[Handler] = Table(
    [
        Command("49", QueuedCommands.sync_run, "§2.3.1 m", "m49: synchronous run to the counter input"),
        Command("50..89", QueuedCommands.m_function, "§2.3.1 m", "M50..M89: marker M6.0..M10.7, MB11 := P2"),
        Command("100", QueuedCommands.s_function, "§2.3.1 m", "m100: S function (MB15, MW16, M15.7)"),
        Command("101", QueuedCommands.t_function, "§2.3.1 m", "m101: T function (MB18, MB19, M18.7)"),
    ]
)

#: ``r P3`` (spec §3.8.16); any other P3 does nothing.
RESET_FUNCTIONS: Table[Handler] = Table(
    [
        Command("0", QueuedCommands.defaults, "§2.3.1 r", "r0: defaults of the controller and indexer (RAM)"),
        Command("1", QueuedCommands.erase_eeprom, "§2.3.1 r", "r1: erase the EEPROM"),
    ]
)
