"""Program storage of the SERS in simulated EEPROM (manual §4.2, §4.3, §4.4, §4.5.3; spec §4.9).

The program is a sequence of statements, each with its own number (§4.3), grouped in the lines
the user typed (for LIST with P1028 bit 3).  It lives in the device's non-volatile memory
(section ``program``) and every change is written through at once, as the real drive writes
to its E²PROM; a line is stored only when it arrived complete and error-free, so a bad line
never damages what is stored.  Capacity follows the spec's cost model G-MEM (2 KB standard,
8 KB with option P8): ``EEPROM Speicher voll`` (errno 5) when full.

Editing (§4.2): ``NEW`` clears, ``PGM`` inserts after the current program position, which the
LIST forms move (``LIST0`` = before the first statement); ``DEL`` deletes the statement at the
position, ``C n`` changes the constant of the assignment there.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from devsim.core.console import warn
from devsim.core.kit import Command, Table
from devsim.core.nvram import NonVolatileMemory, stored_object
from devsim.devices.sers import statements as st
from devsim.devices.sers.codec import MAX_LINE
from devsim.devices.sers.errors import SersError, message

__all__ = ["PROGRAMMING", "PROGRAM_BYTES", "PROGRAM_BYTES_P8", "ProgramMemory", "defined_once", "editing_token",
           "refusal", "statement_cost"]

SECTION = "program"
#: the program memory: 2 KB standard, 8 KB with option P8 (§4.4; spec §4.9 G-MEM)
PROGRAM_BYTES, PROGRAM_BYTES_P8 = 2048, 8192


def _stored(section: object, capacity: int) -> tuple[list[str], list[bool]]:
    """The statements of a stored program section and where its lines begin, if the drive could
    have written it (``{"lines": [[text, ...], ...]}`` within ``capacity`` bytes); else ValueError."""
    lines = stored_object(section, "program", ("lines",))["lines"]
    if type(lines) is not list or not all(type(line) is list and line and all(type(t) is str for t in line)
                                          for line in lines):
        raise ValueError(f"the stored program lines {lines!r:.40} are no lines of statements the drive stores")
    statements = [text for line in lines for text in line]
    starts = [index == 0 for line in lines for index in range(len(line))]
    used = sum(statement_cost(text) for text in statements)
    if used > capacity:
        raise ValueError(f"the stored program of {used} bytes is longer than the drive's {capacity}-byte"
                         f" program memory (option P8: {PROGRAM_BYTES_P8})")
    for text in statements:  # (each as programming mode took it when it was typed, §4.2)
        if (problem := refusal(text)) is not None:
            raise ValueError(f"the stored statement {text!r:.40} is one the drive refuses when it is typed ({problem})")
    try:
        defined_once([], statements)
    except SersError as exc:
        raise ValueError(f"the stored program defines a label twice (errno 83: {message(83, detail=exc.detail)})") from None
    return statements, starts


def refusal(text: str) -> str | None:
    """Why programming mode would not have stored ``text`` as one statement, or None (§4.2): a
    line carries it (a byte of latin-1 each, no CR, LF or ``#``, within the 60-character line,
    §4.1), the statement reader takes it whole as one statement without an errno, and it is no
    statement programming mode runs instead of storing (:data:`PROGRAMMING`).  Label numbers
    defined twice are :func:`defined_once`'s, the memory's size :meth:`ProgramMemory.add_line`'s."""
    if len(text) >= MAX_LINE or max(text, default="") > "\xff" or "\r" in text or "\n" in text or "#" in text:
        return f"no line of {MAX_LINE} latin-1 characters carries it"
    result = st.parse(text, final=True)
    if result.errno is not None:
        return f"errno {result.errno}: {message(result.errno)}"
    if len(result.statements) != 1 or result.statements[0][0].text != text:
        return "it is not one statement as the drive stores it"
    if editing_token(result.statements[0][0]) in PROGRAMMING:
        return "programming mode does not store it"
    return None


def label_of(text: str) -> int | None:
    """The number of the label ``text`` defines (§4.6.2), or None."""
    result = st.parse(text, final=True)
    if result.errno is None and len(result.statements) == 1 and isinstance(result.statements[0][0], st.Label):
        return result.statements[0][0].number
    return None


def defined_once(stored: Sequence[str], texts: Sequence[str]) -> None:
    """errno 83 (§4.6.2 "Jede Labelnummer darf nur einmal im Programm definiert sein"): a label
    of ``texts`` that ``stored`` or an earlier one of ``texts`` defines already."""
    defined = {label_of(t) for t in stored} - {None}
    for text in texts:
        number = label_of(text)
        if number is not None:
            if number in defined:
                raise SersError(83, str(number))
            defined.add(number)


def statement_cost(text: str) -> int:
    """Bytes a statement occupies (spec §4.9 G-MEM)."""
    stripped = text.strip()
    if stripped.startswith('"'):
        return 2 + max(0, len(stripped) - 2)
    if stripped.startswith("//"):
        return 0
    if any(ch.isdigit() for ch in stripped):
        return 6
    return 2


class ProgramMemory:
    """The one stored program: statement texts, and where the user's lines begin (§4.3, §4.5.3).
    (Slots: a host's repeated poll reads :attr:`editing`, one block of memory.)"""

    __slots__ = ("nvram", "capacity", "editing", "position", "_statements", "_starts", "_joined")

    def __init__(self, nvram: NonVolatileMemory, capacity: int = PROGRAM_BYTES) -> None:
        self.nvram = nvram
        self.capacity = capacity
        self.editing = False
        #: current program position: the number of the current statement (0 = before the first)
        self.position = 0
        self._statements: list[str] = []
        self._starts: list[bool] = []  # statement i begins a user line
        self._joined = False  # the last line typed ended with ';': the next one continues it (§4.2)
        self.reload()

    # -- persistence -----------------------------------------------------------------------
    def _store(self) -> None:
        self.nvram.put(SECTION, {"lines": self.lines()})

    def reload(self) -> None:
        """The program as the drive stored it: its lines, each of one or more statement texts
        programming mode took when they were typed (:func:`refusal`, :func:`defined_once`),
        within the memory (§4.4).  [SIM-CHOICE, as the kind's parameters: a stored value the
        drive never stores reads as a failed checksum, :class:`~devsim.devices.sers.memory.ParameterMemory`]
        Anything else (null, ``{}``, a number for a statement, a line the drive would refuse:
        ``XYZ 12``, ``LIST``, a label defined twice; a program longer than the memory: a file of a
        drive with option P8 on one without it) fails the program's checksum: the drive starts
        without a valid program (``RUN``: errno 69, spec §4.4 "valid program"), one line on
        stderr names the file, and the file keeps what it held until a program is written.
        Before, null, ``{}`` or ``[]`` read as no program without a word, a number as the
        statement ``'5'``, a program longer than the memory loaded, and so did a statement the
        drive refuses (passed over when it ran: ``XYZ 12``, ``LIST``; a second ``L5`` never
        jumped to)."""
        self._statements, self._starts = [], []  # (no program stored yet, or a wiped memory)
        if SECTION in self.nvram:
            try:
                self._statements, self._starts = _stored(self.nvram.get(SECTION), self.capacity)
            except ValueError as exc:
                warn(f"devsim: memory {self.nvram.path or 'memory'}: {exc}; the program fails its checksum"
                     " (no valid program)")
        self.editing = False
        self._joined = False
        self.position = min(self.position, len(self._statements))

    # -- queries ---------------------------------------------------------------------------
    def lines(self) -> list[list[str]]:
        lines: list[list[str]] = []
        for text, start in zip(self._statements, self._starts, strict=True):
            if start or not lines:
                lines.append([text])
            else:
                lines[-1].append(text)
        return lines

    def statements(self) -> list[str]:
        return list(self._statements)

    @property
    def valid(self) -> bool:
        return bool(self._statements)

    def used_bytes(self) -> int:
        return sum(statement_cost(s) for s in self._statements)

    def free_words(self) -> int:
        return max(0, self.capacity - self.used_bytes()) // 2

    # -- editing ---------------------------------------------------------------------------
    def new(self) -> None:
        self._statements, self._starts = [], []
        self._joined = False
        self.position = 0
        self.editing = True
        self._store()

    def edit(self) -> None:
        self.editing = True

    def quit(self) -> None:
        self.editing = False

    def add_line(self, texts: Sequence[str], *, joins_next: bool = False) -> None:
        """Store a complete line typed in programming mode at the current position; it continues
        the line before when that one ended with ';' ("Strichkomma verhindert einen
        Zeilenumbruch bei Programmeingabe in der aktuellen Zeile", §4.2), and ``joins_next`` says
        this one does."""
        joined, self._joined = self._joined, joins_next
        if not texts:
            return
        if self.used_bytes() + sum(statement_cost(t) for t in texts) > self.capacity:
            raise SersError(5)
        defined_once(self._statements, texts)
        at = self.position
        self._statements[at:at] = list(texts)
        self._starts[at:at] = [not (joined and at > 0)] + [False] * (len(texts) - 1)
        if at + len(texts) < len(self._starts):
            self._starts[at + len(texts)] = True  # what follows an inserted line starts a line
        self.position = at + len(texts)
        self._store()

    def add(self, text: str, new_line: bool) -> None:
        """Append one statement (initial state of a scenario, tests)."""
        if self.used_bytes() + statement_cost(text) > self.capacity:
            raise SersError(5)
        self._statements.append(text)
        self._starts.append(new_line or len(self._statements) == 1)
        self.position = len(self._statements)
        self._store()

    def delete(self) -> None:
        """DEL: delete the statement at the current position."""
        p = self.position
        if not 1 <= p <= len(self._statements):
            return
        starts = self._starts[p - 1]
        del self._statements[p - 1]
        del self._starts[p - 1]
        if starts and p - 1 < len(self._starts):
            self._starts[p - 1] = True
        self.position = p - 1
        self._store()

    def change(self, text: str) -> None:
        """C n: replace the statement at the current position by ``text``."""
        p = self.position
        if not 1 <= p <= len(self._statements):
            raise SersError(49)
        self._statements[p - 1] = text
        self._store()

    def current(self) -> str | None:
        p = self.position
        return self._statements[p - 1] if 1 <= p <= len(self._statements) else None

    # -- listing -----------------------------------------------------------------------------
    def select(self, arg: str) -> tuple[int, int]:
        """The statement numbers (first, last) a LIST argument names, moving the position
        (§4.2: every LIST form changes it)."""
        count = len(self._statements)
        arg = arg.strip()
        if not arg:
            return 1, count
        if arg == ".":
            return self.position, self.position
        if arg == "-":
            self.position = max(0, self.position - 1)
            return self.position, self.position
        if arg == "+":
            self.position = min(count, self.position + 1)
            return self.position, self.position
        if arg.startswith("-") and arg[1:].isdigit():
            n = min(int(arg[1:]), count)
            self.position = n
            return max(1, n - 19), n
        if "." in arg:
            first, _, tens = arg.partition(".")
            n = int(first or 0)
            self.position = min(n, count)
            return max(1, n), n + int(tens or 0) * 10 - 1
        n = min(int(arg), count)
        self.position = n
        return n, n

    def listing(self, options: int, render: Callable[[str], str] = str, arg: str = "") -> list[str]:
        """LIST output (spec G-LIST, manual §4.3, P1028): one statement per row, numbered
        ``n: `` with bit 0; with bit 3 the user's lines are kept, numbered by their first
        statement; with bit 2 labels start in column 1 and statements in column 4.
        ``render`` turns a stored statement into its listed form (full decimals, units)."""
        first, last = self.select(arg)
        rows: list[str] = []
        groups: list[tuple[int, list[str]]] = []
        for index, (text, start) in enumerate(zip(self._statements, self._starts, strict=True), start=1):
            if options & 8 and not start and groups:
                groups[-1][1].append(text)
            else:
                groups.append((index, [text]))
        for number, group in groups:
            if number + len(group) - 1 < first or number > last:
                continue
            text = " ".join(render(stmt) for stmt in group)
            if options & 4 and not _is_label(group[0]):
                text = "   " + text
            rows.append(f"{number}: {text}" if options & 1 else text)
        return rows


def _is_label(text: str) -> bool:
    stripped = text.strip().upper()
    return stripped.startswith("L") and stripped[1:2].isdigit()


# -- programming mode (the table PROGRAMMING) -----------------------------------------------------
def editing_token(stmt: st.Statement) -> str:
    """A statement's row in :data:`PROGRAMMING`: a command by its keyword, ``P0=`` for an
    assignment to P0, anything else by its type."""
    if isinstance(stmt, st.Command):
        return stmt.name
    if isinstance(stmt, st.Assign) and stmt.target.kind == "P" and stmt.target.ref == 0:
        return "P0="
    return type(stmt).__name__


def _change(program: ProgramMemory, stmt: st.Change) -> bool:
    """C n (§4.2): the assignment at the current position with the constant n."""
    current = program.current()
    parsed = st.parse(current, final=True) if current is not None else None
    if parsed is None or parsed.errno is not None or len(parsed.statements) != 1:
        raise SersError(49)
    old = parsed.statements[0][0]
    if not isinstance(old, st.Assign) or not isinstance(old.value, st.Number):
        raise SersError(49)
    program.change(f"{old.target.text}={stmt.value.text}")
    return True


def _delete(program: ProgramMemory, stmt: st.Command) -> bool:
    program.delete()
    return True


def _runs(program: ProgramMemory, stmt: Any) -> bool:
    return False  # (runs as outside programming mode)


def _passed_over(program: ProgramMemory, stmt: Any) -> bool:
    return True  # (neither stored nor run)


#: Programming mode (§4.2 "Im Programmiermodus werden Anweisungen wie LIST, DEL, TR, C, nicht
#: gespeichert, sondern ausgeführt"): everything typed is stored in the program except these; a
#: handler returning False leaves the statement to run as outside programming mode.  A stored
#: program holding one of them is one the drive could not have written (:func:`refusal`).
PROGRAMMING: Table[Callable[[ProgramMemory, Any], bool]] = Table(
    [
        Command("Change", _change, "§4.2", "C n: the constant of the current statement"),
        Command("DEL", _delete, "§4.2", "delete the current statement"),
        Command("ListCmd", _runs, "§4.2", "LIST / LISTP run"),
        Command("Trace", _runs, "§4.5.4", "TR / TR? run"),
        Command("QUIT", _runs, "§4.2", "QUIT leaves programming mode"),
        Command("P0=", _runs, "§4.8.2.1", "P0=0 leaves programming mode"),
        Command("Comment", _passed_over, "§4.2", "// a comment is not stored"),
    ]
)
