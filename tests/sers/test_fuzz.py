"""Fuzzing the pure SERS codec and parser, and the device behind them (no I/O needed)."""

from __future__ import annotations

import hypothesis.strategies as hs
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devsim.core.clock import VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers import SersDevice, codec
from devsim.devices.sers.statements import parse
from tests.sers.framer_oracle import framer_events
from tests.sers.lines import share_line

ALPHABET = "#*?=<>!:.,;-+/&|^\" \t\r\n0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
COMMANDS = ["#ON", "#OFF", "#E", "#S", "#H", "#W=360", "#V=1000", "#P11?", "#P12=0", "#RS", "#LS",
            "#IF I1=1 O1=1", "#X=V*ADC+100", "#LIST", "#LISTP 0.1", "#VER", "#P1017=2", "#P1017=1"]


@given(st.text(alphabet=ALPHABET, max_size=80), st.booleans())
def test_parser_never_raises_and_is_prefix_stable(text: str, final: bool) -> None:
    result = parse(text, final)
    assert result.errno is None or 1 <= result.errno <= 125
    ends = [end for _stmt, end in result.statements]
    assert ends == sorted(ends) and all(0 < end <= len(text) for end in ends)
    if not final:
        # what is complete now stays complete, unchanged, when more text arrives
        longer = parse(text + "X", False)
        assert [s for s, _ in longer.statements[: len(result.statements)]] == [
            s for s, _ in result.statements
        ]


#: Lines of 55 to 65 characters (``#``, an address, text), around the limit of §4.1.
LINES_AT_THE_LIMIT = hs.builds(
    lambda length, address, text, end: b"#" + address + text[: length - 1 - len(address)] + end,
    hs.integers(min_value=55, max_value=65),
    hs.sampled_from([b"", b"1", b"12", b"*", b"007"]),
    hs.binary(min_size=70, max_size=70).map(lambda b: bytes(0x41 + x % 26 for x in b)),
    hs.sampled_from([b"\r", b"\n", b"\r\n", b"\n\r", b"#\r", b""]))
#: Bytes that matter to the framer, and some that do not.
FRAMER_BYTES = hs.lists(hs.one_of(hs.sampled_from([b"#", b"*", b"\r", b"\n", b"1", b"0", b"A", b"?", b"\xb2"]),
                                  hs.binary(max_size=70), LINES_AT_THE_LIMIT), max_size=30).map(b"".join)


@pytest.mark.manual("§4.1", "at most 60 characters in a line")
@given(hs.one_of(hs.binary(max_size=200), FRAMER_BYTES))
def test_framer_accepts_any_bytes(data: bytes) -> None:
    """Any bytes: the events the manual's rules give (tests/sers/framer_oracle.py), byte by byte."""
    framer = codec.Framer()
    assert [framer.feed(byte) for byte in data] == framer_events(data)


def _device() -> tuple[SersDevice, VirtualClock, bytearray, NonVolatileMemory]:
    clock = VirtualClock()
    nvram = NonVolatileMemory(None)
    device = SersDevice(clock=clock, config={"boot_time": 0}, nvram=nvram)
    out = bytearray()
    device.attach(out.extend)
    device.feed(b"#P1019=45 PSAVE\r#NEW\r#ON\r#W=360 E\r#QUIT\r")
    return device, clock, out, nvram


def _answers(stream: bytes, size: int, *names: str) -> tuple[object, ...]:
    """What a fresh drive answers (and then reads for ``names``) when ``stream`` arrives in
    chunks of ``size`` bytes."""
    device, clock, out, _nvram = _device()
    for start in range(0, len(stream), size):
        device.feed(stream[start : start + size])
    clock.advance(0.01)
    return (bytes(out), *(device.read(name) for name in names))


@settings(max_examples=150, deadline=None)
@given(st.lists(st.one_of(st.binary(max_size=40), st.sampled_from([c + "\r" for c in COMMANDS]).map(str.encode)),
                max_size=25),
       st.lists(st.floats(min_value=0, max_value=2), max_size=25))
def test_device_survives_any_input_and_keeps_its_memory(chunks: list[bytes], pauses: list[float]) -> None:
    device, clock, out, nvram = _device()
    stored = (nvram.get("params"), nvram.get("program"))
    for i, chunk in enumerate(chunks):
        device.feed(chunk)
        if i < len(pauses):
            clock.advance(pauses[i])
    clock.advance(5)
    # still answering, and nothing stored was damaged by the input (only PSAVE/NEW may change it)
    out.clear()
    device.feed(b"\r#1\r#QUIT\r#P1017=1\r")
    out.clear()
    device.feed(b"#P1019?\r")
    assert b"P1019=" in bytes(out) and bytes(out).endswith(b"\n\r")
    writers = (b"PSAVE", b"NEW", b"PGM", b"P1004", b"P0")
    if not any(w in b"".join(chunks).upper() for w in writers):
        assert (nvram.get("params"), nvram.get("program")) == stored


def test_program_survives_a_flood_of_garbage() -> None:
    device, clock, out, nvram = _device()
    program = nvram.get("program")
    device.feed(bytes(range(256)) * 20)
    device.feed(b"#" + b"A" * 5000 + b"\r")
    assert nvram.get("program") == program
    out.clear()
    device.feed(b"#\r#P1019?\r")
    assert b"P1019=45U/min" in bytes(out)


def test_unicode_digits_are_not_numbers() -> None:
    """Found by the fuzzer: '²' (0xB2 in latin-1) is a digit to str.isdigit() but not to the SERS."""
    device, clock, out, nvram = _device()
    out.clear()
    device.feed(b"#\xb2\r#V=\xb2\r#P\xb91?\r")
    device.feed(b"#1 P11?\r")
    assert bytes(out).endswith(b"P11=0\n\r\nok3\n\r")


@settings(max_examples=300, deadline=None)
@given(
    data=hs.lists(
        hs.sampled_from(
            [b"#", b"#1", b"#2", b"\r", b"\n", b"\r\n", b"ON", b" ", b"V=100", b"P11?", b"LIST", b"X", b"\x00", b"E",
             b"W=360", b"?", b"NEW", b"QUIT", b"PGM", b"L1", b"GOTO 1", b"#*", b"P1017=2", b"P1017=1", b"VER",
             b"P11??", b"IF X>0 THEN", b"END", b"TR?", b"A" * 30]
        ),
        max_size=60,
    ),
    cut=hs.integers(min_value=1, max_value=64),
)
def test_chunks_and_single_bytes_give_the_same_answers(data: list[bytes], cut: int) -> None:
    """The face's fast paths (noise between lines, text nobody executes, runs of text, whole
    lines) answer exactly as byte-by-byte handling does, wherever the host's chunks are cut."""
    stream = b"".join(data)
    assert _answers(stream, 1, "program", "P11") == _answers(stream, cut, "program", "P11")


@pytest.mark.parametrize(
    "stream",
    [
        b"#1\r",  # an address alone (the whole-line pattern must not read '1' as text)
        b"#*\r#*P11?\r",  # a broadcast executes but never answers
        b"#P11?\r",  # the poll: one query, answered after the echo of CR
        b"#P11? \r",  # ... after the echo of the space
        b"#P11? P12?\r#P11?P12?\n",  # two queries: the first answers mid-line
        b"#P1017=2 P11?\r#P11?\r#P1017=1\r",  # answers deferred to the line end (mode 2)
        b"#W=360E\r#E W=3\r#X=1 #2P11?\r#1P11?\r",  # statements run before the line end
        b"#" + b"P11?" * 16 + b"\r",  # beyond 60 characters
        b"#P11\x00?\r#Q?\r",  # errors
        # not selected: other drives' lines are skipped in one step up to the next address
        b"#2\r#" + b"A" * 70 + b"#1\r#1P11?\r",  # ... counting the line's length across a restart
        b"#2\r#" + b"A" * 59 + b"##1\r#1P11?\r",  # ... where a '#' beyond 60 is no overflow
        b"#2\rX\r\n#Q\r#\n#\r\n#*E\r#1P11?\r\n",  # ... line ends, pairs, a broadcast
    ],
)
def test_whole_lines_answer_as_bytes_do(stream: bytes) -> None:
    bytewise = _answers(stream, 1)
    assert bytewise == _answers(stream, len(stream))
    assert bytewise[0]


@pytest.mark.parametrize("size", [1, 7, 200])
def test_a_line_for_another_drive_counts_its_length_into_a_restart_for_this_one(size: int) -> None:
    """§4.1: 60 characters per line, counted from the line's first '#' across restarts; the
    skip over other drives' lines (drive not selected) counts as byte-by-byte framing does:
    text beyond 60 is an overflow, a '#' beyond it is not."""
    over = _answers(b"#2\r#" + b"A" * 70 + b"#1\r", size)[0]
    assert over.endswith(b"#1\r\n*RS232 Puffer\xfcberlauf\n\r")
    hashes = _answers(b"#2\r#" + b"A" * 59 + b"##1\r", size)[0]
    assert hashes.endswith(b"#1\r\nok1\n\r")


@settings(max_examples=300, deadline=None)
@given(
    data=hs.lists(hs.one_of(hs.binary(max_size=12), hs.sampled_from([b"#", b"#1", b"#2", b"\r", b"\n", b"P11?",
                                                                     b"Q", b"\x8f", b"A" * 70])), max_size=40),
    cut=hs.integers(min_value=2, max_value=300),
)
def test_random_noise_in_chunks_answers_as_bytes_do(data: list[bytes], cut: int) -> None:
    """Random noise (what benchmarks/noise.py --raw pours in): the one-step paths for another
    drive's line and for a line failing at its first statement answer exactly as byte-by-byte
    handling does."""
    stream = b"".join(data)
    assert _answers(stream, 1, "P11", "P12") == _answers(stream, cut, "P11", "P12")


POLLS = [b"#P11?\r", b"#1P11?\r", b"#2P11?\r", b"#*P11?\r", b"#P11?\n", b"#1 P11?\r", b"#P11??\r", b"#P51?\r",
         b"#V?\r", b"#O1?\r", b"#I3?\r", b"#P9999?\r", b"#P1?\r", b"#Z?\r", b"#TR?\r", b"#1" + b" " * 54 + b"P11?\r",
         b"#P1017?\r", b"#P265?\r", b"#P336?\r"]  # plain values that the states change (answers kept per value)
STATES = [b"#P1017=0\r", b"#P1017=1\r", b"#P1017=2\r", b"#2\r", b"#1\r", b"#Q\r", b"#P1019=0\r", b"#PGM\r",
          b"#QUIT\r", b"#ON W=360 E\r", b"#P1=*\r", b"#P1=1\r", b"#P265=1\r", b"#P265=0\r", b"#RS\r", b"#OFF\r",
          b"\n", b"\r", b"#1P11?\r#"]  # the second half of a line end pair; a line begun in the chunk


def _line_by_line(lines: list[bytes], bytewise: bool, pauses: list[float], shared: bool) -> tuple[object, ...]:
    device, clock, out, _nvram = _device()
    share_line(device, shared)
    answers = []
    for i, line in enumerate(lines):
        for piece in ([line[k : k + 1] for k in range(len(line))] if bytewise else [line]):
            device.feed(piece)
        answers.append(bytes(out))
        out.clear()
        clock.advance(pauses[i] if i < len(pauses) else 0.0)
    return answers, device.read("P11"), device.read("program")


@settings(max_examples=300, deadline=None)
@given(lines=hs.lists(hs.sampled_from(POLLS + STATES), max_size=30),
       pauses=hs.lists(hs.sampled_from([0.0, 0.001, 0.3, 2.0]), max_size=30), shared=hs.booleans())
def test_polls_line_by_line_answer_as_bytes_do(lines: list[bytes], pauses: list[float], shared: bool) -> None:
    """A chunk that is one whole query line (a host's poll) is answered in one step
    (``face._answer_poll``): in every echo mode, selected or not, on a shared line, in
    programming mode, with errors and warnings pending and while the axis moves, exactly as the
    same line taken byte by byte."""
    assert _line_by_line(lines, False, pauses, shared) == _line_by_line(lines, True, pauses, shared)


def test_a_polls_kept_answer_line_is_the_answer_made_anew_for_every_parameter_and_value() -> None:
    """``Answers.parameter_line`` keeps a plain parameter's answer line per value: for every
    readable parameter, in several states and asked twice, it is what ``parameter_text`` makes
    (or the same error)."""
    from devsim.devices.sers.errors import SersError
    from devsim.devices.sers.parameters import PARAMETERS
    from devsim.devices.sers.statements import Address

    device, clock, _out, _nvram = _device()
    answers = device.model.answers

    def outcome(kept: bool, target: Address, number: int) -> str:
        try:
            if kept:
                return answers.parameter_line(target, number, "latin-1").decode("latin-1")
            return answers.parameter_text(target, number) + "\n\r"
        except SersError as exc:
            return f"error {exc.errno}"

    numbers = [n for n in sorted(PARAMETERS) if PARAMETERS[n].readable]
    for step in (b"", b"#P1017=1 P265=1 P1=*\r", b"#ON W=90 E\r", b"#P1017=0 P1=1 P11=0\r"):
        device.feed(step)
        clock.advance(0.05)
        for number in numbers:
            target = Address("P", number, f"P{number}")
            made = outcome(False, target, number)
            for _ in range(2):  # made, then kept
                assert outcome(True, target, number) == made, number


def test_the_poll_paths_are_taken() -> None:
    from devsim.devices.sers.line import poll_line as _poll_line

    assert _poll_line(b"#1P11?\r") is not None and _poll_line(b"#P51??\n") is not None
    for line in (b"#1P11?", b"#1P11?P12?\r", b"#1V=1\r", b"#1P11?\r#", b"P11?\r", b"#1" + b" " * 58 + b"P11?\r"):
        assert _poll_line(line) is None, line


@pytest.mark.manual("§4.2", "LIST: the program is listed (in pgm mode executed, not stored)")
def test_a_stored_constant_beyond_28_digits_is_listed() -> None:
    """Found by fuzzing: a program line ``W=2748332147483632147483639`` (stored as typed, range checks
    come when it runs) made ``#LIST`` raise decimal.InvalidOperation out of the port's feed: its fixed
    point rendering (4 decimals) needs 29 digits, more than the decimal module's default 28."""
    device, clock, out, nvram = _device()
    device.feed(b"#PGM")
    device.feed(b"W=2748332147483632147483639\r")
    clock.advance(0.01)
    kept = nvram.get("program")
    out.clear()
    device.feed(b"#LIST\r")
    clock.advance(0.01)
    assert b"W=2748332147483632" in bytes(out) and bytes(out).endswith(b"pgm\n\r")
    assert nvram.get("program") == kept


@pytest.mark.manual("§4.7", "P123 Vorschubkonstante: > 0; an invalid value gives an error message (errno 2 'zu klein')")
@pytest.mark.parametrize("value", [b".00001", b"0.00004"])
def test_a_feed_constant_that_rounds_to_zero_is_too_small(value: bytes) -> None:
    """Found by fuzzing: ``#P76=2P123=.00001=`` was taken (P123 > 0) and stored on the 4-decimal grid
    as 0.0000; from then on every command that weighs a position (P123?, P51?, W=..., LISTP) raised
    ValueError ("P121, P122 and P123 must be > 0") out of the port's feed.  The range is checked on
    the value the drive keeps: errno 2, P123 unchanged, the drive answers on."""
    device, clock, out, _nvram = _device()
    out.clear()
    device.feed(b"#P123=" + value + b"\r")
    clock.advance(0.01)
    assert b"*zu klein" in bytes(out)
    out.clear()
    device.feed(b"#P123?\r#P51?\r")
    clock.advance(0.01)
    assert b"P123=1mm" in bytes(out) and b"P51=" in bytes(out)
    device.feed(b"#P123=0.00005\r")  # rounds half up to 0.0001: taken
    clock.advance(0.01)
    assert device.model.params.values[123] == 0.0001


@pytest.mark.manual("§4.6.9", "RS:expression: jog until the event occurs")
@pytest.mark.parametrize(("until", "answer"), [(b"I0", b"*unbekanntes if Ereignis"), (b"O17=1", b"*ung\xfcltiger Ausgang"),
                                               (b"P99999>1", b"*Parameter nicht vorhanden")])
def test_a_jog_until_an_operand_that_does_not_exist_does_not_start(until: bytes, answer: bytes) -> None:
    """Found by fuzzing: ``#ONP1035=0`` ``RS:I0`` ``\\r`` answered errno 13 but left the drive jogging
    with the condition armed; the next change of any input evaluated it again and raised SersError out
    of the input's point write (``input.I2``).  The condition is evaluated before the jog starts: the
    statement's error, no jog."""
    device, clock, out, _nvram = _device()
    out.clear()
    device.feed(b"#ONP1035=0")
    device.feed(b"RS:" + until)
    device.feed(b"\r")
    clock.advance(0.2)
    assert answer in bytes(out)
    device.set("input.I2", True)
    device.set("input.I2", False)
    clock.advance(0.2)
    assert device.model.motion.kind is None


@pytest.mark.manual("§4.8.3.1", "P11: a drive error brakes the drive with the acceleration of P1030, then the motor current is switched off")
@pytest.mark.parametrize(("point", "value"), [("input.limit_right", True), ("quantity.heatsink_temperature", 150)])
def test_a_drive_error_with_p1030_0_stops_the_axis_at_once(point: str, value: object) -> None:
    """Found by fuzzing: ``#P1030=0`` is taken (§4.8.4.4 gives P1030 no minimum); a drive error while
    the axis moved (the limit switch opening, overtemperature) then raised ValueError("decel must be
    positive") out of the point write.  With no ramp to brake on the drive switches the torque off at
    once, as on a short circuit [SIM-CHOICE], and reports the error as ever."""
    device, clock, out, _nvram = _device()
    device.feed(b"#P1030=0\r#ON\r#H\r")
    clock.advance(0.2)
    assert device.model.motion.kind is not None
    device.set(point, value)
    clock.advance(0.2)
    assert device.model.motion.kind is None and not device.model.motion.moving
    assert device.read("param.P11") != 0
    out.clear()
    device.feed(b"#VER\r")
    assert b"P1133=120901" in bytes(out)


#: Pieces of lines typed in programming mode: statements of every kind, what programming mode
#: runs instead of storing, and what it refuses.
PROGRAM_PIECES = ["ON", "W=360", "E", "L5", "L 7", "GT5", "GOSUB 7", "RT", "IF I1", "IF P12<>0 THEN", "ELSE", "END",
                  "WAIT !I2", "RS:I3", "\"Durchmesser\"", "// note", "LIST", "LIST0", "P12?", "V??", "C 5", "DEL",
                  "X=V*ADC+100", "+3", "NOT", "PE", ";", "QUIT", "PGM", "NEW", "P0=0", "TR", "XYZ", "L200", "IF I17",
                  " ", "O1=1"]
#: The characters of a line's text (no line end, no ``#``).
LINE_TEXT = "".join(ch for ch in ALPHABET if ch not in "#\r\n")


@settings(max_examples=150, deadline=None)
@given(st.lists(st.lists(st.one_of(st.sampled_from(PROGRAM_PIECES), st.text(alphabet=LINE_TEXT, max_size=6)),
                         max_size=6).map(" ".join), max_size=12))
def test_a_program_typed_in_programming_mode_always_loads_again(lines: list[str]) -> None:
    """Whatever programming mode stored of the lines typed (spec §4.2), the stored program loads
    again as the same statements: the check of a stored program (a statement the drive refuses
    when typed fails the program's checksum) never refuses one the drive wrote itself."""
    from devsim.devices.sers.program import PROGRAM_BYTES, ProgramMemory

    device, clock, _out, nvram = _device()
    device.feed(b"#NEW\r" + b"".join(b"#" + line.encode("latin-1") + b"\r" for line in lines) + b"#QUIT\r")
    clock.advance(0.1)
    assert ProgramMemory(nvram, PROGRAM_BYTES).lines() == device.read("program")
