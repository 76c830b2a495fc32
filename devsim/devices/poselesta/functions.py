"""The G and M functions and the address letters F, M, S, T of a block (manual §2.3.15–§2.3.19,
§2.4.7, §2.4.8; spec poselesta.md §4.4.5–§4.4.9, §4.12.1, §4.12.2).

Each is a row of a :class:`~devsim.core.kit.Table` whose handler does what the function does:
the G words of a block, looked up as ``G00`` … ``G91`` when the block starts, set the modal
functions in force (motion, plane, compensation, dimensions) or mark what the block does at its
end (dwell, exact stop, subroutine flow, G25); an M function, looked up as ``M00`` … ``M11`` when
it goes on the data bus, sets and resets the decoded outputs V15 and notes what the block does
next (stop, end, wait for a handshake).  A G function without a row is stored and runs as a no-op
with the event ``unsupported_g``; an M function without a row (M15, M07, the free codes) only goes
out on the bus.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.kit import Command, Table
from devsim.core.signals import SignalBank
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.tape import Block

__all__ = ["ADDRESSES", "DECODED", "G_CODES", "M_CODES", "BlockFunctions", "block_end_function"]

#: The decoded M outputs V15/1–8 (§2.4.7): reset block-wise in Hand-Einzelsatz.
DECODED = ("m00", "m01", "m02", "m03", "m04", "m06", "m08", "m10")
_FIXED = frozenset((*range(12), 13, 14, 15, 30))


def block_end_function(m: int) -> bool:
    """M00, M01, M02, M05, M09, M11, M15 and the odd free codes act at the end of the block
    (§2.4.8; spec §4.4.5); the others at its start."""
    return m in (0, 1, 2, 5, 9, 11, 15) or (m not in _FIXED and m % 2 == 1)


class BlockFunctions:
    """The modal functions in force and what the running block's G and M functions ask for
    (spec §4.12.1, §4.12.2).  Decoded M outputs are set on ``signals``; events go to ``screen``."""

    def __init__(self, signals: SignalBank, screen: Screen) -> None:
        self._signals = signals
        self._screen = screen
        # modal (spec §4.12.1: "Modality")
        self.motion = 0  # G00 … G03
        self.plane = 17  # G17 / G18 / G19
        self.compensation = 40  # G40 / G41 / G42 (no offset: spec §5.8 phase 1)
        self.absolute = True  # G90 / G91
        self.feed = 0  # F, mm/min
        self.tool = 0  # the last T programmed
        # the running block
        self.dwell = False  # G04: L ms at the block end
        self.exact_stop = False  # G09, G60 (and G04): the contour ends at rest in this block
        self.flow: set[int] = set()  # G11 / G12 / G13: where the program goes on
        self.full_circle = False  # G25
        self.tool_change = False  # M06 output: wait for the acknowledge
        self.m10_waits = False  # M10 output while its acknowledge was H: wait for the pulse
        self.program_stop = False  # M00
        self.optional_stop = False  # M01
        self.program_end = False  # M02

    def begin(self, block: Block) -> None:
        """A block starts: its G words take effect (spec §4.12.1), in their order."""
        self.dwell = self.exact_stop = self.full_circle = False
        self.flow = set()
        self.tool_change = self.m10_waits = False
        self.program_stop = self.optional_stop = self.program_end = False
        for g in block.values("G"):
            handler = G_CODES.get(f"G{g:02d}")
            if handler is None:
                self.unsupported(g)  # stored and run as no-op (spec §4.12.1)
            else:
                handler(self, g)

    def unsupported(self, g: int) -> None:
        self._screen.record("unsupported_g")
        self._screen.report("program", "unsupported_g", g)

    @property
    def contour_ends(self) -> bool:
        """G04, G09, G60, G11, G12 or G13: the contour does not go on into the next block."""
        return self.dwell or self.exact_stop or bool(self.flow)

    # -- G functions (spec §4.12.1) ------------------------------------------------------------------
    def _motion(self, g: int) -> None:
        self.motion = g

    def _plane(self, g: int) -> None:
        self.plane = g

    def _compensation(self, g: int) -> None:
        if g != self.compensation:
            self.compensation = g  # recorded, no path offset (spec §5.8, phase 1)
            self._screen.record("compensation")
            self._screen.report("program", "compensation", f"G{g}")

    def _dimensions(self, g: int) -> None:
        self.absolute = g == 90

    def _dwell(self, _g: int) -> None:
        self.dwell = True

    def _exact_stop(self, _g: int) -> None:
        self.exact_stop = True

    def _label(self, _g: int) -> None:
        """G10 marks the first block of a subroutine; executed, it does nothing."""

    def _flow(self, g: int) -> None:
        self.flow.add(g)

    def _full_circle(self, _g: int) -> None:
        self.full_circle = True

    def block_over(self, manual_single_block: bool) -> None:
        """The block is over: done, ended by M02, or given up (a mode key, Not-Stop).  §2.4.7: "In
        der Betriebsart Hand-Einzelsatz wirken alle dekodierten M-Funktionen satzweise": there
        what it set on V15 ends with it."""
        if manual_single_block:
            for output in DECODED:
                self._signals.set(output, False)

    # -- M functions on the bus (spec §4.12.2) --------------------------------------------------------
    def put(self, kind: str, value: int) -> None:
        """A function goes on the data bus (:class:`~devsim.devices.poselesta.mst.MstBus`)."""
        if kind != "M":
            return
        handler = M_CODES.get(f"M{value:02d}")
        if handler is not None:
            handler(self, value)

    def _switch(self, on: str | None, *off: str) -> None:
        for output in off:
            self._signals.set(output, False)
        if on is not None:
            self._signals.set(on, True)

    def _stop(self, _m: int) -> None:
        self._switch("m00")
        self.program_stop = True

    def _optional_stop(self, _m: int) -> None:
        self._switch("m01")
        self.optional_stop = True

    def _end(self, _m: int) -> None:
        self._switch("m02")
        self.program_end = True

    def _spindle_cw(self, _m: int) -> None:
        self._switch("m03", "m04")

    def _spindle_ccw(self, _m: int) -> None:
        self._switch("m04", "m03")

    def _spindle_stop(self, _m: int) -> None:
        self._switch(None, "m03", "m04")

    def _tool_change(self, _m: int) -> None:
        self._switch("m06")
        self.tool_change = True

    def _coolant_on(self, _m: int) -> None:
        self._switch("m08")

    def _coolant_off(self, _m: int) -> None:
        self._switch(None, "m08")

    def _clamp(self, _m: int) -> None:
        self._switch("m10")
        self.m10_waits = bool(self._signals.get("m10_ack"))  # H at output: not self-holding (§2.3.18)

    def _unclamp(self, _m: int) -> None:
        self._switch(None, "m10")


GHandler = Callable[[BlockFunctions, int], None]
MHandler = Callable[[BlockFunctions, int], None]

#: The G functions with a meaning here (spec §4.12.1), looked up when a block starts.
G_CODES: Table[GHandler] = Table([
    Command("G00", BlockFunctions._motion, "§2.3.15", "positioning at rapid, each axis on its own (modal)"),
    Command("G01", BlockFunctions._motion, "§2.3.15", "linear interpolation at F × override (modal)"),
    Command("G02", BlockFunctions._motion, "§2.3.15", "circular interpolation clockwise, centre I/J/K (modal)"),
    Command("G03", BlockFunctions._motion, "§2.3.15", "circular interpolation counter-clockwise (modal)"),
    Command("G04", BlockFunctions._dwell, "§2.4.2", "dwell: L seconds at the block end"),
    Command("G09", BlockFunctions._exact_stop, "§2.4.3", "exact stop: the contour ends at rest in this block"),
    Command("G10", BlockFunctions._label, "§2.4.2", "start of a subroutine (a label: no-op when executed)"),
    Command("G11", BlockFunctions._flow, "§2.4.2", "end of a subroutine: back to the block after the call"),
    Command("G12", BlockFunctions._flow, "§2.4.2", "subroutine call L a.bbb: the subroutine at N bbb, a times"),
    Command("G13", BlockFunctions._flow, "§2.4.2", "repeat L a.bbb: back to N bbb, a more times"),
    Command("G17", BlockFunctions._plane, "§2.3.15", "plane XY (I/J) (modal)"),
    Command("G18", BlockFunctions._plane, "§2.3.15", "plane ZX (K/I; G02 clockwise seen from +Y) (modal)"),
    Command("G19", BlockFunctions._plane, "§2.3.15", "plane YZ (J/K) (modal)"),
    Command("G25", BlockFunctions._full_circle, "§2.4.2", "unknown (I/J-only blocks): no motion, event "
            "unsupported_g; a full circle with g25_full_circle"),
    Command("G40", BlockFunctions._compensation, "§2.3.15", "cutter compensation off (modal)"),
    Command("G41", BlockFunctions._compensation, "§2.3.15", "cutter compensation left: recorded, no offset"),
    Command("G42", BlockFunctions._compensation, "§2.3.15", "cutter compensation right: recorded, no offset"),
    Command("G60", BlockFunctions._exact_stop, "§2.4.3", "exact stop (modal in DIN 66025; here per block)"),
    Command("G90", BlockFunctions._dimensions, "§2.3.15", "absolute dimensions (modal)"),
    Command("G91", BlockFunctions._dimensions, "§2.3.15", "incremental dimensions (modal)"),
])

#: The M functions with an effect beyond the data bus (spec §4.12.2), looked up when they go out.
M_CODES: Table[MHandler] = Table([
    Command("M00", BlockFunctions._stop, "§2.4.7", "programmed stop (V15/1): NC-Start continues"),
    Command("M01", BlockFunctions._optional_stop, "§2.4.7", "optional stop (V15/2), with V21/10 H"),
    Command("M02", BlockFunctions._end, "§2.4.7", "program end (V15/3): back to the first block"),
    Command("M03", BlockFunctions._spindle_cw, "§2.4.7", "spindle clockwise (V15/4; resets M04)"),
    Command("M04", BlockFunctions._spindle_ccw, "§2.4.7", "spindle counter-clockwise (V15/5; resets M03)"),
    Command("M05", BlockFunctions._spindle_stop, "§2.4.7", "spindle stop: resets V15/4 and V15/5"),
    Command("M06", BlockFunctions._tool_change, "§2.3.17", "tool change (V15/6): waits for the acknowledge V22/5"),
    Command("M08", BlockFunctions._coolant_on, "§2.4.7", "coolant on (V15/7)"),
    Command("M09", BlockFunctions._coolant_off, "§2.4.7", "coolant off: resets V15/7"),
    Command("M10", BlockFunctions._clamp, "§2.3.18", "clamping (V15/8): not self-holding while V22/6 is H, "
            "then waits for its negative pulse"),
    Command("M11", BlockFunctions._unclamp, "§2.4.7", "clamping off: resets V15/8"),
])


def _feed(functions: BlockFunctions, block: Block, _out: list[tuple[str, int]]) -> None:
    feed = block.value("F")
    if feed is not None:
        functions.feed = feed


def _start_m(_functions: BlockFunctions, block: Block, out: list[tuple[str, int]]) -> None:
    out += [("M", m) for m in sorted(block.values("M")) if not block_end_function(m) and m != 30]


def _speed(_functions: BlockFunctions, block: Block, out: list[tuple[str, int]]) -> None:
    speed = block.value("S")
    if speed is not None:
        out += [("S1", speed % 100), ("S2", speed // 100 % 100)]  # units and tens first


def _tool(functions: BlockFunctions, block: Block, out: list[tuple[str, int]]) -> None:
    tool = block.value("T")
    if tool is not None:
        out.append(("T", tool))
        functions.tool = tool


AddressHandler = Callable[[BlockFunctions, Block, list[tuple[str, int]]], None]

#: The words a block starts with, in the order their functions go on the bus (§2.4.8): F, the
#: block-start M functions, S as S1 and S2, T.
ADDRESSES: Table[AddressHandler] = Table([
    Command("F", _feed, "§2.3.22", "feed in mm/min (inch/min with V22/2 H), modal"),
    Command("M", _start_m, "§2.4.8", "the block-start M functions, ascending, on the bus with strobe M"),
    Command("S", _speed, "§2.4.8", "spindle speed: S1 (units, tens) and S2 (hundreds, thousands) on the bus"),
    Command("T", _tool, "§2.4.8", "tool number on the bus with strobe T"),
])
