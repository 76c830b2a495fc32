"""The statements of a command line as the SERS runs them interactively (manual §4.1, §4.2,
§4.6.1, §4.7; spec §3.2.4, §3.3, G-LIST, G-TRACE).

A statement runs as soon as it is complete (one that answers, with the next character,
§3.2.4a).  The line answers queries, listings and the version itself (:data:`INTERACTIVE`),
steers its own IF … THEN … ELSE … END (:data:`SKIPPING`), and in programming mode stores what
is typed (:data:`~.program.PROGRAMMING` names what runs instead); everything else the drive executes.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, Table
from devsim.devices.sers import statements as st
from devsim.devices.sers.access import address_number
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.line import CommandLine, answers
from devsim.devices.sers.model import SersDrive
from devsim.devices.sers.program import PROGRAMMING, editing_token

__all__ = ["INTERACTIVE", "SKIPPING", "LineStatements"]

Answer = Callable[[CommandLine, str], None]
Error = Callable[[CommandLine, int, str], None]


class LineStatements:
    """Runs the statements of the lines one SERS executes (§4.2, §3.2.4a)."""

    def __init__(self, model: SersDrive, answer: Answer, error: Error) -> None:
        self.model = model
        self._answer = answer  # a text the line answers (at once, or at its end)
        self._error = error  # an error message of the line

    def progress(self, line: CommandLine, final: bool) -> None:
        """Run the statements of ``line`` completed so far (all of them at its end)."""
        if line.error or not line.execute:
            return
        result = st.parse(line.text, final)
        for stmt, end in result.statements[line.executed :]:
            if not final and end == len(line.text) and answers(stmt):
                break  # §3.2.4a: a statement with an answer completes with the next character
            line.executed += 1
            try:
                self.statement(line, stmt)
            except SersError as exc:
                self._error(line, exc.errno, exc.detail)
                return
            finally:
                self.model.interpreter.poke()
        if result.errno is not None and line.executed == len(result.statements):
            self._error(line, result.errno, "")

    def statement(self, line: CommandLine, stmt: st.Statement) -> None:
        program = self.model.program
        if program.editing:
            instead = PROGRAMMING.get(editing_token(stmt))
            if instead is None:
                line.store.append(stmt.text)  # stored when the line ends without an error
                return
            if instead(program, stmt):
                return
        if line.skip_block:
            skip = _SKIPPING.get(type(stmt).__name__)
            if skip is not None:
                skip(line, stmt)
            return
        if line.skip_next:
            line.skip_next = False
            return
        self.run(line, stmt)

    def run(self, line: CommandLine, stmt: st.Statement) -> bool:
        """A statement the line answers itself, or the drive executes (execution.STATEMENTS)."""
        handler = _INTERACTIVE.get(stmt.name if isinstance(stmt, st.Command) else type(stmt).__name__)
        if handler is None or not handler(self, line, stmt):
            self.model.execution.execute(stmt)
        return True

    # -- statements with an answer or line state (the table INTERACTIVE) ---------------------
    def if_(self, line: CommandLine, stmt: st.If) -> bool:
        true = self.model.operands.evaluate(stmt.cond)
        if stmt.then:
            if not true:
                line.skip_block = 1
        else:
            line.skip_next = not true
        return True

    def else_(self, line: CommandLine, stmt: st.Else) -> bool:
        line.skip_block = 1  # the THEN part ran: skip to END
        return True

    def query(self, line: CommandLine, stmt: st.Query) -> bool:
        self._answer(line, self.model.answers.query_text(stmt) + "\n\r")
        return True

    def listing(self, line: CommandLine, stmt: st.ListCmd) -> bool:
        model = self.model
        if stmt.params:
            rows = model.answers.list_parameters(stmt.arg)
        else:
            rows = model.program.listing(model.answers.list_options, model.answers.render_statement, stmt.arg)
        self._answer(line, "".join(f"{row}\n\r" for row in rows))
        return True

    def master_query(self, line: CommandLine, stmt: st.Assign) -> bool:
        """``P2=n`` / ``P3=n`` from a master (IF/WAIT, read): answer the value (§4.8.5.5,
        G-MASTER); any other assignment is the drive's."""
        if stmt.target.kind not in ("P", "alias"):
            return False
        try:
            number = address_number(stmt.target)
        except SersError:
            return False
        if number not in (2, 3):
            return False
        model = self.model
        asked = int(model.operands.operand_value(stmt.value)) if not isinstance(stmt.value, str) else 0
        model.params.values[number] = asked
        self._answer(line, f"P{number}={model.access.plain_value(asked)}\n\r")
        return True

    def version(self, line: CommandLine, stmt: st.Command) -> bool:
        self._answer(line, f"P1133={self.model.access.firmware}\n\r")
        return True

    def trace(self, line: CommandLine, stmt: st.Trace) -> bool:
        interpreter = self.model.interpreter
        if stmt.query:
            self._answer(line, f"TR={int(interpreter.trace_mode)}\n\r")
            return True
        # TR: one program step; the executed statement is shown like a LIST row (G-TRACE)
        interpreter.trace_mode = True
        shown = interpreter.trace_step()
        if shown is not None:
            self._answer(line, shown + "\n\r")
        return True


#: Statements the line answers itself (a value, a listing, the version) or that steer the line
#: (IF/ELSE/END); a handler returning False leaves the statement to the drive.
INTERACTIVE: Table[Callable[[LineStatements, CommandLine, Any], bool]] = Table(
    [
        Command("If", LineStatements.if_, "§4.6.1", "IF condition [THEN … ELSE … END]"),
        Command("Else", LineStatements.else_, "§4.6.1", "ELSE: skip to END"),
        Command("End", lambda statements, line, stmt: True, "§4.6.1", "END of an IF block"),
        Command("Query", LineStatements.query, "§4.7", "P<n>? / P<n>?? / alias?: the value or the name"),
        Command("ListCmd", LineStatements.listing, "§4.2", "LIST / LISTP: the program or the parameters"),
        Command("Assign", LineStatements.master_query, "§4.8.5.5", "P2=/P3= from a master: answer the value"),
        Command("VER", LineStatements.version, "§4.8.2.5", "VER: the firmware version"),
        Command("Trace", LineStatements.trace, "§4.5.4", "TR? / TR: trace mode, one step"),
    ]
)
_INTERACTIVE = {row.token: row.handler for row in INTERACTIVE}

def _skip_if(line: CommandLine, stmt: st.If) -> None:
    if stmt.then:
        line.skip_block += 1


def _skip_end(line: CommandLine, stmt: st.End) -> None:
    line.skip_block -= 1


def _skip_else(line: CommandLine, stmt: st.Else) -> None:
    if line.skip_block == 1:
        line.skip_block = 0


#: Inside a false IF … THEN block the line only counts the blocks (§4.6.1).
SKIPPING: Table[Callable[[CommandLine, Any], None]] = Table(
    [
        Command("If", _skip_if, "§4.6.1", "a nested IF … THEN block"),
        Command("End", _skip_end, "§4.6.1", "the end of a block"),
        Command("Else", _skip_else, "§4.6.1", "the ELSE of the false block: run from here"),
    ]
)
_SKIPPING = {row.token: row.handler for row in SKIPPING}
