"""A running sequence program and the jog functions of the inputs I1..I6: "Stop bei Handfahren"
P1093 (manual §4.8.6.3; spec §4.4 ``INTERRUPTED_BY_JOG``).

"Wenn eine Handfahrfunktion über einen digitalen Eingang (I 1 bis I 6) aktiviert wird und ein
E²Prom-Ablaufprogramm aktiv ist" the program is, with P1093=0, interrupted and continued once
the input is released; with P1093=1 it is aborted and not continued.  The jog commands of the
serial line (LS, RS, LF, RF, P1031) and a program's own jogs leave the program alone.
"""

from __future__ import annotations

from devsim.devices.sers import statements as st
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.interpreter import Interpreter
from devsim.devices.sers.motion import Motion
from devsim.devices.sers.params import SersParameters

__all__ = ["JogInterruption"]


class JogInterruption:
    """What a jog input does to the running program, by P1093 (§4.8.6.3).

    P1093=0: the program is interrupted: it stays active (P0 reads 1, [SIM-CHOICE]: the manual
    names no other value and the program is not ended) but does not advance; what it waited for
    (a D, a WAIT, a positioning) is kept, a D's time and a D2 timer run on, a D2 jump and a WAIT
    condition that hold meanwhile take effect when it continues.  It continues once no input
    I1..I6 with its manual function is active any more and the drive stands (the jog stops when
    its input drops; a homing run of I5 ends on its own) [SIM-CHOICE, the manual: "Nach
    Deaktivieren des Eingangs"].  A positioning ``E`` the jog interrupted is continued to its
    setpoint, as P1033=1 continues an interrupted positioning (§4.8.6.2: "Fortsetzen des
    Positioniervorgangs"), and the program waits for it as before; a ``:`` jog or a ``POSR`` the
    jog took over is executed again.

    P1093=1: the program is aborted as after a program error, without L65 and without the
    continuation of P1033 (which the manual gives for a stop command and the STOP input): a
    start begins at line 1 [SIM-CHOICE].

    A manual function the drive refuses (errno 70 while homing, 78 at a limit switch …) leaves
    the program alone [SIM-CHOICE: it was not "aktiviert"].
    """

    __slots__ = ("interpreter", "motion", "params", "_released")  # (one per drive: no instance dictionary)

    __slots__ = ("interpreter", "motion", "params", "held", "_released")  # (one per drive: no instance dictionary)

    def __init__(self, interpreter: Interpreter, motion: Motion, params: SersParameters) -> None:
        self.interpreter = interpreter
        self.motion = motion
        self.params = params
        self.held: str | None = None  # what the interrupted program waited for (waiting "jog")
        self._released = False  # the inputs are released: continue once the drive stands

    def activated(self) -> None:
        """A jog function of I1..I6 was carried out (after it, so it may take over the motion)."""
        interpreter = self.interpreter
        if not interpreter.running:
            return
        if int(self.params.stop_on_jog) == 1:
            interpreter.abort()
            return
        self._released = False
        if interpreter.waiting != "jog":
            self.held, interpreter.waiting = interpreter.waiting, "jog"

    def released(self) -> None:
        """No input I1..I6 with its manual function is active any more."""
        if self.interpreter.waiting != "jog":
            return
        self._released = True
        if self.motion.kind is None:
            self._continue()

    def came(self, what: str) -> None:
        """What the program waited for came during the interruption: it goes on when it continues."""
        if self.held == what:
            self.held = None

    def motion_ended(self) -> None:
        if self._released:
            self._continue()

    def restore(self) -> None:
        """A stop (S, the STOP input, I7) comes: it finds the program waiting as it was (P1033)."""
        interpreter = self.interpreter
        self._released = False
        if interpreter.waiting == "jog":
            interpreter.waiting, self.held = self.held, None

    def _continue(self) -> None:
        interpreter = self.interpreter
        self._released = False
        if not interpreter.running or interpreter.waiting != "jog":
            return  # (ended, stopped or jumped to L65 meanwhile)
        held, self.held = self.held, None
        blocks = held == "position" and int(self.params.wait_until_positioned) == 1
        if interpreter.d2_pending and not blocks:
            held = None  # the D2 jump due meanwhile aborts a D or WAIT (§4.8.5.1): at the next cycle
        interpreter.waiting = held
        if held is None:
            interpreter.continue_cycle()
        elif held == "wait":
            interpreter.poke()
        elif held == "position":
            self._continue_motion()
        # ("delay", "segment", "master": what they wait for is still to come)

    def _continue_motion(self) -> None:
        """The program waited for a motion the jog took over (pc is past its statement)."""
        interpreter = self.interpreter
        index = interpreter.pc - 1
        stmt = interpreter.program.statements[index] if 0 <= index < len(interpreter.program.statements) else None
        if isinstance(stmt, st.Command) and stmt.name == "E":
            try:
                if not self.motion.continue_positioning():
                    interpreter.on_motion_end()  # (it stands at the setpoint already)
            except SersError as exc:
                interpreter.program_error(exc.errno)
            return
        interpreter.pc = index  # a ':' jog, POSR …: executed again
        interpreter.waiting = None
        interpreter.continue_cycle()
