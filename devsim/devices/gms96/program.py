"""The ``p`` command of the command executor: PLC start/stop, CNC programs, markers, the analog
output and the PLC direct commands ``p10;OpCode;Operand`` (manual §2.3.1 p, §2.4.3, §2.5; spec
§3.8.13, §4.9, §4.10.4).

Each is a row of a :class:`~devsim.core.kit.Table`: :data:`P_FUNCTIONS` by ``P1;P2`` (or ``P1``),
:data:`DIRECT_COMMANDS` by OpCode.  A handler returns True when the command is complete at once,
False while the executor waits (WOSI … STVO, WAIT).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from devsim.core.kit import Command, Table
from devsim.devices.gms96.executor import Cmd, Executor
from devsim.devices.gms96.flash import Flash
from devsim.devices.gms96.image import ProcessImage
from devsim.devices.gms96.io import OUTPUT_BITS, Outputs
from devsim.devices.gms96.plc import Plc

__all__ = ["DIRECT_COMMANDS", "P_FUNCTIONS", "ProgramControl", "input_name"]

#: Program nesting: a program started from a program nests ("Schachtelung bis 8 möglich", manual
#: §2.5); a deeper call aborts the programs (the manual is silent; spec §4.9 [R]).
MAX_PROGRAM_DEPTH = 8
OUTPUT_OPERANDS = range(OUTPUT_BITS)  # A0.0..A1.2 (spec §4.10.4)


def input_name(operand: int) -> str | None:
    """p10 operand numbering of inputs: 0..7 = E0.x, 8..15 = E1.x, 16 = E2.0, 17 = E2.1."""
    if 0 <= operand <= 17:
        return f"E{operand // 8}.{operand % 8}"
    return None


class ProgramControl:
    """``p`` (manual §2.3.1 p, §2.4.3, §2.5): the queued programming functions and direct commands."""

    def __init__(
        self,
        *,
        executor: Executor,
        flash: Flash,
        image: ProcessImage,
        outputs: Outputs,
        plc: Plc,
        marker_byte: Callable[[int], int],
        motion_changes_at: Callable[[], float | None],
        write_marker_byte: Callable[[int, int], None],
    ) -> None:
        self.executor = executor
        self.flash = flash
        self.image = image
        self.outputs = outputs
        self.plc = plc
        self.marker_byte = marker_byte  # the card's: MB0/MB1/MB3 with the firmware's live status bits
        self.motion_changes_at = motion_changes_at  # the next instant the motion's status bits may change
        self.write_marker_byte = write_marker_byte  # the card's, with the effects of MB0/MB1
        self.stvo_edge = False  # STVO: a 0→1 edge on E0.1 since the wait began

    def run(self, cmd: Cmd) -> bool:
        """``p P1;P2;P3``: looked up by ``P1;P2``, then by ``P1``; anything else is accepted."""
        handler = P_FUNCTIONS.get(f"{cmd.p1};{cmd.p2}") or P_FUNCTIONS.get(str(cmd.p1))
        return True if handler is None else handler(self, cmd)

    # -- the PLC (§2.4) ---------------------------------------------------------------------------
    def plc_start(self, cmd: Cmd) -> bool:
        self.plc.start()
        return True

    def plc_stop(self, cmd: Cmd) -> bool:
        self.plc.stop()
        return True

    def marker_byte(self, cmd: Cmd) -> bool:
        """``p11;offset;value`` inside a program: MB(offset) := value."""
        self.write_marker_byte(cmd.p2, cmd.p3)
        return True

    def analog_output(self, cmd: Cmd) -> bool:
        """``p12;value``: the analog output AB2 (0..255 → 0..10 V)."""
        self.image.outputs[2] = max(0, min(255, cmd.p2))
        return True

    # -- CNC programs (§2.5) ------------------------------------------------------------------------
    def program_start(self, cmd: Cmd) -> bool:
        """``p3;1;pnr``: the program's commands go to the front of the queue (nested up to 8)."""
        ex = self.executor
        program = self.flash.programs.get(cmd.p3)
        if program is None:
            if ex.program_depth == 0:
                self.image.set_marker(0, 2, False)  # M0.2 start request of a missing program ends
            return True
        if ex.program_depth >= MAX_PROGRAM_DEPTH:
            self._abort_programs()
            return True
        ex.program_depth += 1
        img = self.image
        img.markers[2] = cmd.p3 & 0xFF
        img.set_marker(0, 2, True)
        img.set_marker(1, 0, False)
        cmds = [Cmd(*row, program=cmd.p3) for row in program] + [Cmd("_end", program=cmd.p3)]
        ex.queue.extendleft(reversed(cmds))
        return True

    def program_stop(self, cmd: Cmd) -> bool:
        """``p3;2`` inside a program: drop the rest of the running program.  Outside one ("Kann
        sinnvoller Weise nur innerhalb eines Ablauf-Programms vorkommen") there is nothing to stop:
        the host's queued commands stay."""
        queue = self.executor.queue
        while queue and self.executor.program_depth:
            item = queue.popleft()
            if item.letter == "_end":
                queue.appendleft(Cmd("_end", program=-1))
                return True
        return True

    def _abort_programs(self) -> None:
        """A call deeper than :data:`MAX_PROGRAM_DEPTH`: the manual says only "Schachtelung bis 8
        möglich" (§2.5); as spec §4.9 [R] has it, the program is aborted -- every nesting level's
        rows and ends are dropped (the host's queued commands stay), M0.2 = 0 and M1.0 stays 0;
        no message code (the spec defines none)."""
        ex = self.executor
        ex.queue = deque(c for c in ex.queue if c.program is None)
        ex.program_depth = 0
        self.image.set_marker(0, 2, False)

    def program_end(self, cmd: Cmd) -> bool:
        """The end of a program's commands (M0.2 off; M1.0 on when it ran to its end)."""
        ex = self.executor
        ex.program_depth = max(0, ex.program_depth - 1)
        if ex.program_depth == 0:
            self.image.set_marker(0, 2, False)
            if cmd.program is not None and cmd.program >= 0:
                self.image.set_marker(1, 0, True)
        return True

    # -- PLC direct commands p10 (§2.4.3) -----------------------------------------------------------
    def direct(self, cmd: Cmd) -> bool:
        """``p10;OpCode;Operand``, looked up in :data:`DIRECT_COMMANDS`; unknown opcodes: ignored."""
        handler = DIRECT_COMMANDS.get(str(cmd.p2))
        return True if handler is None else handler(self, cmd.p3)

    def _wait_input(self, operand: int, want: bool) -> bool:
        """WOSI/WORI: input ``operand`` as the image shows it (manual §2.4.2, §2.4.3)."""
        if input_name(operand) is None:
            return True
        byte, bit = divmod(operand, 8)
        outputs = self.outputs
        return self.executor.wait("WOSI" if want else "WORI", lambda: outputs.input_bit(byte, bit) == want)

    def wosi(self, operand: int) -> bool:
        return self._wait_input(operand, True)

    def wori(self, operand: int) -> bool:
        return self._wait_input(operand, False)

    def _wait_output(self, operand: int, want: bool) -> bool:
        """WOSO/WORO: output ``operand`` 0..10 (manual §2.4.3); beyond them nothing to wait for,
        as for WOSI/WORI beyond E2.1 and SETO beyond A1.2."""
        if operand not in OUTPUT_OPERANDS:
            return True
        return self.executor.wait("WOSO" if want else "WORO", lambda: self.outputs.output_bit(operand) == want)

    def woso(self, operand: int) -> bool:
        return self._wait_output(operand, True)

    def woro(self, operand: int) -> bool:
        return self._wait_output(operand, False)

    def _wait_marker(self, operand: int, want: bool) -> bool:
        """WOSF/WORF: marker bit ``operand`` (byte operand // 8, bit operand % 8) as the PLC sees
        it, the status bits of MB0/MB1/MB3 included (manual §2.4.1, §2.4.3)."""
        byte, mask = operand // 8 % 256, 1 << (operand % 8)
        return self.executor.wait(
            "WOSF" if want else "WORF", lambda: bool(self.marker_byte(byte) & mask) == want, self.motion_changes_at
        )

    def wosf(self, operand: int) -> bool:
        return self._wait_marker(operand, True)

    def worf(self, operand: int) -> bool:
        return self._wait_marker(operand, False)

    def wait_time(self, operand: int) -> bool:
        return self.executor.after(operand / 10.0, "WAIT") if operand > 0 else True

    def _output(self, operand: int, value: Callable[[bool], bool]) -> bool:
        if operand in OUTPUT_OPERANDS:
            self.outputs.write_output(operand, value(self.outputs.output_bit(operand)))
        return True

    def seto(self, operand: int) -> bool:
        return self._output(operand, lambda _old: True)

    def reso(self, operand: int) -> bool:
        return self._output(operand, lambda _old: False)

    def invo(self, operand: int) -> bool:
        return self._output(operand, lambda old: not old)

    def clao(self, operand: int) -> bool:
        for n in OUTPUT_OPERANDS:
            self.outputs.write_output(n, False)
        return True

    def sndf(self, operand: int) -> bool:
        self.image.post_error(operand)
        return True

    def sndm(self, operand: int) -> bool:
        self.image.post_message(operand)
        return True

    def stvo(self, operand: int) -> bool:
        self.stvo_edge = False
        return self.executor.wait("STVO", lambda: self.stvo_edge)

    def input_edge(self, name: str, value: bool) -> None:
        """An input changed: STVO waits for a 0→1 edge on E0.1."""
        if name == "E0.1" and value:
            self.stvo_edge = True


#: ``p`` functions executed in the command queue (spec §3.8.13); ``p1;100``/``101``, ``p3;100``/``101``
#: (downloads) and ``p11`` outside a program are the face's (carried out on receipt).
P_FUNCTIONS: Table[Callable[[ProgramControl, Cmd], bool]] = Table(
    [
        Command("1;1", ProgramControl.plc_start, "§2.3.1 p", "start the PLC program"),
        Command("1;2", ProgramControl.plc_stop, "§2.3.1 p", "stop the PLC"),
        Command("3;1", ProgramControl.program_start, "§2.3.1 p", "start CNC program P3 (nested up to 8)"),
        Command("3;2", ProgramControl.program_stop, "§2.3.1 p", "stop the running CNC program (inside a program)"),
        Command("10", ProgramControl.direct, "§2.4.3", "a PLC direct command p10;OpCode;Operand"),
        Command("11", ProgramControl.marker_byte, "§2.3.1 p", "MB(P2) := P3 (recorded in a CNC program)"),
        Command("12", ProgramControl.analog_output, "§2.3.1 p", "analog output AB2 := P2 (0..255 → 0..10 V)"),
    ]
)

#: PLC direct commands ``p10;OpCode;Operand`` (manual §2.4.3, spec §4.10.4), by OpCode.
DIRECT_COMMANDS: Table[Callable[[ProgramControl, int], bool]] = Table(
    [
        Command("2", ProgramControl.wosi, "§2.4.3", "WOSI: wait until input Operand is set"),
        Command("3", ProgramControl.wori, "§2.4.3", "WORI: wait until input Operand is reset"),
        Command("6", ProgramControl.woso, "§2.4.3", "WOSO: wait until output Operand is set"),
        Command("7", ProgramControl.woro, "§2.4.3", "WORO: wait until output Operand is reset"),
        Command("10", ProgramControl.wosf, "§2.4.3", "WOSF: wait until marker Operand is set"),
        Command("11", ProgramControl.worf, "§2.4.3", "WORF: wait until marker Operand is reset"),
        Command("14", ProgramControl.wait_time, "§2.4.3", "WAIT: wait Operand tenths of a second"),
        Command("16", ProgramControl.seto, "§2.4.3", "SETO: output Operand on (keeps blending)"),
        Command("17", ProgramControl.reso, "§2.4.3", "RESO: output Operand off (keeps blending)"),
        Command("24", ProgramControl.invo, "§2.4.3", "INVO: invert output Operand"),
        Command("26", ProgramControl.clao, "§2.4.3", "CLAO: reset all outputs"),
        Command("28", ProgramControl.sndf, "§2.4.3", "SNDF: Operand buffered into MB5 (keeps blending)"),
        Command("29", ProgramControl.sndm, "§2.4.3", "SNDM: Operand buffered into MB4 (keeps blending)"),
        Command("31", ProgramControl.stvo, "§2.4.3", "STVO: wait for a 0→1 edge on E0.1"),
    ]
)
