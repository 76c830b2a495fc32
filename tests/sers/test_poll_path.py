"""A host's poll answered from what the face kept of the same poll before (issue 31) changes
nothing: a drive fed each line as one chunk (the poll path, and for a repeated poll the kept
one) answers, at every step, exactly what a drive fed the same lines in pieces (no poll path)
answers, and ends in the same state, whatever happens between the polls: lines for it and for
others, echo modes (P1017), programming mode, power cycles, moves, writes through the points and
a running program that changes P1017 and the values polled while nobody sends a line."""

from __future__ import annotations

import hypothesis.strategies as hs
from hypothesis import given, settings

from devsim.core.changes import CHANGES
from devsim.core.clock import VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers import SersDevice, codec
from devsim.devices.sers.line import KeptPoll
from tests.sers.lines import share_line

POLLS = [b"#P11?\r", b"#1P11?\r", b"#P12?\r", b"#P11?\n", b"#1 P11?\r", b"#P336?\r", b"#P1017?\r", b"#C1?\r",
         b"#P51?\r", b"#V?\r", b"#P1?\r", b"#Z?\r", b"#P9999?\r", b"#P11??\r", b"#O1?\r", b"#P0?\r", b"#2P11?\r",
         b"#*P11?\r", b"#P1050?\r", b"#P1133?\r", b"#P265?\r", b"#200P11?\r", b"#1P12?\n", b"#P12?\r\n",
         b"#P1013?\n"]
LINES = [b"#P1017=0\r", b"#P1017=1\r", b"#P1017=2\r", b"#2\r", b"#1\r", b"#Q\r", b"#P1019=0\r", b"#PGM\r",
         b"#QUIT\r", b"#ON W=360 E\r", b"#P1=*\r", b"#P1=1\r", b"#P265=1\r", b"#P265=0\r", b"#RS\r", b"#OFF\r",
         b"\n", b"\r", b"#1P11?\r#", b"#C1=3\r", b"#P11=0 P12=0\r", b"#RUN\r", b"#S\r", b"#P76=2\r", b"#P1029=3\r",
         b"#P76=0\r"]
#: A program that changes what a poll answers, and how, while no line arrives (I1 drives it).
PROGRAM = ["L1", "WAIT I1=1", "P1017=2", "C1=1", "O1=1", "WAIT I1=0", "P1017=0", "C1=2", "WAIT I1=1",
           "P1017=1", "C1=3", "O1=0", "WAIT I1=0", "GT1"]
#: A program parked on a WAIT whose condition no signal announces (a point writes C1): a poll's
#: answer pokes it (the poll path looks at the WAIT again, as a line's statements do).
WAIT_PROGRAM = ["L1", "WAIT C1=9", "O1=1", "C1=0", "WAIT C1=9", "O1=0", "C1=0", "GT1"]
#: A master's program (DIP address 0): it waits for its slave's answer, and takes the host's
#: bytes for it meanwhile (§3.6.2).
MASTER_PROGRAM = ["L1", "Z=1", "ON", "X=V", "Z=0", "WAIT I1=1", "GT1"]
SETS = [("param.P1017", 0), ("param.P1017", 2), ("param.P1017", 1), ("param.P100", 9), ("input.I1", True),
        ("input.I1", False), ("dip.service_switch", True), ("dip.service_switch", False), ("param.P265", 1),
        ("input.stop", True), ("input.stop", False), ("input.limit_right", True), ("input.limit_right", False),
        ("param.P0", 2), ("param.P0", 0)]

STEPS = hs.lists(hs.one_of(
    hs.tuples(hs.just("poll"), hs.integers(0, len(POLLS) - 1), hs.integers(1, 4)),  # a poll, repeated
    hs.tuples(hs.just("line"), hs.integers(0, len(LINES) - 1), hs.just(1)),
    hs.tuples(hs.just("advance"), hs.sampled_from([0.0, 0.001, 0.05, 0.3, 2.0]), hs.just(1)),
    hs.tuples(hs.just("set"), hs.integers(0, len(SETS) - 1), hs.just(1)),
    hs.tuples(hs.just("power"), hs.sampled_from([0, 1]), hs.just(1)),  # a power cycle; the supply off and on
    hs.tuples(hs.just("supply"), hs.sampled_from([0, 1]), hs.just(1)),  # the supply off, or on
    hs.tuples(hs.just("share"), hs.sampled_from([0, 1]), hs.just(1)),  # the line shared now, or not (a bus)
), max_size=40)
#: (DIP address, program, boot time)
SETUPS = hs.tuples(hs.sampled_from([1, 1, 0]), hs.sampled_from([None, PROGRAM, MASTER_PROGRAM, WAIT_PROGRAM]),
                   hs.sampled_from([0, 0, 0.2]))


Setup = tuple[int, list[str] | None, float]


def _run(steps: list[tuple[str, float, int]], whole: bool, shared: bool, setup: Setup) -> tuple[object, ...]:
    """What a drive answers at each step and where it ends; ``whole``: each line fed as one chunk
    (a poll taken by the poll path), else in two pieces (``#``, the rest: no poll path)."""
    address, program, boot_time = setup
    clock = VirtualClock()
    device = SersDevice(clock=clock, config={"boot_time": boot_time, "address": address},
                        nvram=NonVolatileMemory(None))
    share_line(device, shared)
    model = device.model
    out = bytearray()
    device.attach(out.extend)
    if program:
        device.set("program", program)
        clock.advance(boot_time)
        device.feed(b"#200RUN\r" if address == 0 else b"#RUN\r")
    answers = []
    for kind, value, repeat in steps:
        for _ in range(repeat):
            if kind in ("poll", "line"):
                line = (POLLS if kind == "poll" else LINES)[int(value)]
                for piece in ([line] if whole or len(line) < 2 else [line[:1], line[1:]]):
                    device.feed(piece)
            elif kind == "advance":
                clock.advance(value)
            elif kind == "set":
                name, setting = SETS[int(value)]
                try:
                    device.set(name, setting)
                except Exception as exc:  # (a write the drive refuses: refused on both)
                    answers.append(type(exc).__name__)
            elif kind == "supply":  # (the doors a plant's control goes through: devsim.core.changes)
                device.fault("power", not value)
            elif kind == "share":
                share_line(device, bool(value))  # (what a bus does, counted as a bus counts it)
                CHANGES.count += 1
            elif value:
                device.fault("power", True)
                clock.advance(0.01)
                device.fault("power", False)
            else:
                device.power_cycle()
            answers.append(bytes(out))
            out.clear()
            face = device.face()  # (what the kept poll answered at once relies on: no check of its own)
            assert face.polls.kept is None or (face.line is None and not face._spontaneous and face._last_replied)
    face = device.face()
    line = face.line
    return (answers, device.state(), dict(model.params.values), model.power_stage.errno, model.power_stage.warnings,
            model.addressed, model.interpreter.waiting, bytes(model.master._buffer), model.master.sent, model.interpreter.pc,
            face.framer.in_line, face.framer.idle,
            face._last_replied, None if line is None else (line.execute, line.reply, line.error, bytes(line.held)))


@settings(max_examples=400, deadline=None)
@given(steps=STEPS, shared=hs.booleans(), setup=SETUPS)
def test_a_kept_poll_answers_as_a_line_in_pieces_does(steps: list[tuple[str, float, int]], shared: bool,
                                                      setup: Setup) -> None:
    assert _run(steps, True, shared, setup) == _run(steps, False, shared, setup)


#: What a kept poll must not jump over, each after the same poll answered once.
HAZARDS = {
    "echo mode by a point": [("set", 1, 1), ("poll", 0, 2), ("set", 2, 1), ("poll", 0, 2)],
    "echo mode by the program": [("poll", 6, 2), ("set", 4, 1), ("advance", 0.05, 1), ("poll", 6, 2),
                                 ("set", 5, 1), ("advance", 0.05, 1), ("poll", 6, 2)],
    "a value by the program": [("poll", 7, 2), ("set", 4, 1), ("advance", 0.05, 1), ("poll", 7, 2)],
    "programming mode": [("poll", 0, 1), ("line", 7, 1), ("poll", 0, 2), ("line", 8, 1), ("poll", 0, 2)],
    "programming mode by a point": [("poll", 0, 2), ("set", 13, 1), ("poll", 0, 2), ("set", 14, 1), ("poll", 0, 2)],
    "another drive selected": [("poll", 0, 1), ("line", 3, 1), ("poll", 0, 2), ("poll", 1, 1), ("poll", 0, 1)],
    "power cycle": [("poll", 0, 1), ("power", 0, 1), ("poll", 0, 2), ("power", 1, 1), ("poll", 0, 2)],
    "a move": [("poll", 0, 1), ("line", 9, 1), ("poll", 0, 2), ("advance", 2.0, 1), ("poll", 0, 2)],
    "an error": [("poll", 0, 1), ("set", 11, 1), ("poll", 0, 2), ("line", 20, 1), ("poll", 0, 2)],
    "a line end pair": [("poll", 3, 1), ("line", 17, 1), ("poll", 3, 2), ("line", 16, 1), ("poll", 3, 1)],
    "a line begun": [("line", 18, 1), ("poll", 0, 2)],
    "the supply off": [("poll", 0, 2), ("supply", 0, 1), ("poll", 0, 2), ("supply", 1, 1), ("poll", 0, 2)],
    "a master waiting": [("poll", 0, 2), ("advance", 0.001, 1), ("poll", 0, 2), ("advance", 0.5, 1), ("poll", 0, 2)],
    "a line end pair after polls in turn": [("poll", 0, 1), ("poll", 22, 1), ("poll", 0, 1), ("line", 16, 1),
                                            ("poll", 22, 1), ("poll", 0, 1), ("poll", 22, 1), ("line", 17, 1)],
    "a WAIT the poll pokes": [("advance", 0.01, 1), ("poll", 0, 2), ("set", 3, 1), ("poll", 0, 2), ("advance", 0.05, 1), ("poll", 15, 2)],
    "a bus after the polls": [("poll", 0, 2), ("share", 1, 1), ("poll", 0, 2), ("power", 0, 1)],
    "a weighting changed under a kept position poll": [("poll", 8, 2), ("line", 25, 1), ("poll", 8, 2), ("line", 23, 1),
                                                      ("poll", 8, 2)],
    "a position polled while the axis moves": [("poll", 8, 1), ("line", 9, 1), ("advance", 0.05, 1), ("poll", 8, 1),
                                               ("advance", 0.05, 1), ("poll", 8, 2), ("poll", 5, 1), ("advance", 0.05, 1),
                                               ("poll", 8, 1)],
    "a standing reply after another answered at once": [("poll", 0, 2), ("poll", 24, 2), ("poll", 0, 1),
                                                        ("line", 16, 1), ("poll", 0, 1)],
    "a weighted value": [("poll", 8, 1), ("line", 23, 1), ("poll", 8, 1), ("line", 9, 1), ("advance", 0.05, 1),
                         ("poll", 8, 2)],
}


def test_a_kept_poll_jumps_over_nothing() -> None:
    setups: list[Setup] = [(1, None, 0), (1, PROGRAM, 0), (0, MASTER_PROGRAM, 0), (1, None, 0.2), (1, WAIT_PROGRAM, 0)]
    for name, steps in HAZARDS.items():
        for shared in (False, True):
            for setup in setups:
                assert _run(steps, True, shared, setup) == _run(steps, False, shared, setup), (name, setup)


def test_repeated_polls_are_answered_from_what_was_kept_and_forgotten_at_power_on() -> None:
    clock = VirtualClock()
    device = SersDevice(clock=clock, config={"boot_time": 0}, nvram=NonVolatileMemory(None))
    out = bytearray()
    device.attach(out.extend)
    face = device.face()
    device.feed(b"#P11?\r")
    kept = face.polls.polls[b"#P11?\r"]
    assert bytes(out) == b"#P11?\rP11=0\n\r\nok1\n\r"
    reply = kept.reply
    device.feed(b"#P11?\r")
    assert face.polls.polls[b"#P11?\r"] is kept and kept.reply is reply and bytes(out) == 2 * reply  # (sent as kept)
    device.feed(b"#1P12?\n")
    device.feed(b"#P11?\r")
    assert list(face.polls.polls) == [b"#P11?\r", b"#1P12?\n"] and face.polls.polls[b"#P11?\r"] is kept
    framer = codec.Framer()
    framer.whole_line(5, 13)  # (as the line #P11? CR leaves it)
    assert vars(face.framer) == vars(framer) and face.polls.kept is kept
    device.feed(b"\r")
    assert face.polls.kept is None and face.polls.polls[b"#P11?\r"] is kept  # (the line is checked again)
    device.feed(b"#P11?\r")
    assert face.polls.kept is kept
    for n in range(20):  # (a bounded number)
        device.feed(b"#P%d?\r" % n)
    assert 0 < len(face.polls.polls) <= KeptPoll.MOST
    device.model.power_cycle()
    assert face.polls.polls is None
