"""Walk of manual §2.6 (traverse programs: header, blocks, N, L, G, X, F and M functions and the
syntax restrictions), driven through the PG port on a real pty: programs go in with BA22 (whose
result words are the syntax error and the faulty block) and run with BA8/BA9."""

from __future__ import annotations

import pytest

from devsim.devices.ip247.client import As511Error
from tests.ip247.helpers import START, TAKE_OVER, Make, Module, record
from tests.ip247.test_vectors import rotary

manual = pytest.mark.manual


def stored(mod: Module, number: int, text: str) -> tuple[int, int, int]:
    """BA22: (module error, program error, faulty block)."""
    answer = mod.store(number, text)
    return answer[4], int.from_bytes(answer[8:10], "big"), int.from_bytes(answer[10:12], "big")


def run(mod: Module, text: str, number: int = 1, seconds: float = 60) -> None:
    assert stored(mod, number, text) == (0, 0, 0)
    mod.operate(1, 8, START, b=number)
    mod.clock.advance(seconds)


def state(mod: Module) -> tuple[int, int, int]:
    """(error, actual value, M function) of axis 1."""
    read = mod.device.read
    return read("axis.1.error"), read("axis.1.position"), read("axis.1.m_function")


@pytest.fixture
def ready(mod: Module) -> Module:
    """COM247's machine data on axis 1 (x_A −10 mm, x_E 500 mm, reference 1 mm), reference set."""
    mod.ready()
    return mod


# -- §2.6.1 ------------------------------------------------------------------------------------------
@manual("§2.6.1", "traverse programs are independent of the axes: one program runs on several axes at once")
def test_one_program_on_two_axes_at_once(mod: Module) -> None:
    mod.ready(1)
    mod.ready(2)
    assert stored(mod, 5, "%  5\nN1 X20 F1000 M10\nN2 M02\n") == (0, 0, 0)
    mod.operate(1, 8, START, b=5)
    mod.operate(2, 8, START, b=5)
    mod.clock.advance(0.5)
    assert mod.device.read("axis.1.running") and mod.device.read("axis.2.running")
    mod.clock.advance(30)
    assert mod.device.read("axis.1.position") == mod.device.read("axis.2.position") == 20_000


@manual("§2.6.1", "a program holds at most 1023 ASCII characters including its header")
def test_a_program_longer_than_1023_characters_is_refused(ready: Module) -> None:
    body = "".join(f"N{n} G04 F1{' ' * 30}\n" for n in range(1, 28))
    text = "%  1\n" + body + "N99 M02\n"
    assert len(text) > 1023
    # (its record, 1126 parameter bytes, is longer than any request: DLE NAK, spec §3.6.5 and
    # test_block_limit.py; one within the block limit is stored marked faulty, test_manual_b_com247)
    with pytest.raises(As511Error, match="DLE NAK"):
        stored(ready, 1, text)
    assert ready.client.read_record(4, 65)[8:] == b""  # nothing stored


@manual("§2.6.1", "at most 6000 ASCII characters are stored on the IP247 in all: error 24 'Zu wenig Platz'")
def test_the_program_memory_holds_6000_characters(ready: Module) -> None:
    block = "N1 G04 F1" + " " * 39 + "\n"  # 49 characters with LF
    text = "%{:3d}\n" + block * 19 + "N2 M02\n"
    size = len(text.format(1))
    count = 6000 // size
    for number in range(1, count + 1):
        assert stored(ready, number, text.format(number))[0] == 0
    assert stored(ready, count + 1, text.format(count + 1))[0] == 24


@manual("§2.6.1", "loops and subprogram calls nest to a common depth of 5 (error 39 beyond)")
def test_nesting_deeper_than_5_is_error_39(ready: Module) -> None:
    for n in range(2, 8):
        assert stored(ready, n, f"L{n:3d}\nN1 L{n + 1}\nN2 M02\n")[0] == 0
    assert stored(ready, 8, "L  8\nN1 X2 F1000\nN2 M02\n")[0] == 0
    run(ready, "%  1\nN1 L2\nN2 M02\n")  # 1 → 2 → … → 8: six calls deep
    assert state(ready)[0] == 39 and ready.device.read("axis.1.position") == 1_000
    run(ready, "%  9\nN1 L4\nN2 M02\n", number=9)  # 9 → 4 → … → 8: five calls deep
    assert state(ready)[:2] == (0, 2_000)


# -- §2.6.2, §2.6.3, §2.6.4, §2.6.10: the syntax, checked at BA22 -------------------------------------------
SYNTAX = [
    pytest.param("N1 M02\n", 2, 0, marks=manual("§2.6.2", "a program begins with its header: % or L and the number")),
    pytest.param("%  1\nN1 X10 F100 M02\nN2 X1 F10 M02\n", 18, 2,
                 marks=manual("§2.6.3", "no block may follow the end block with M02")),
    pytest.param("%  1\nN1 X1 F10\n", 15, 1,
                 marks=manual("§2.6.3", "the end block with M02 is obligatory")),
    pytest.param("%  1\nX100 F10\nN2 M02\n", 2, 1, marks=manual("§2.6.3", "the N function is obligatory in a block")),
    pytest.param("%  1\nN1 M02", 8, 1, marks=manual("§2.6.3", "each block ends with a line feed")),
    pytest.param("%  1\nN1 F100 X10\nN2 M02\n", 9, 1,
                 marks=manual("§2.6.3", "the functions of a block appear in the order N, L, G, X, F, M")),
    pytest.param("%  1\nN1 X1 F10" + " " * 41 + "\nN2 M02\n", 19, 1,
                 marks=manual("§2.6.3", "a block is at most 50 characters long including its LF")),
    pytest.param("%  1\nN1000 M02\n", 3, 1, marks=manual("§2.6.4", "the block number is 0 … 999")),
    pytest.param("%  1\nN1 L256\nN2 M02\n", 4, 1, marks=manual("§2.6.1", "program numbers are 0 … 255")),
    pytest.param("%  1\nN1 G33\nN2 M02\n", 37, 1,
                 marks=manual("§2.6.6", "only the G functions listed are allowed (37 'G-Funktion nicht erlaubt')")),
    pytest.param("%  1\nN1 X123456 F10\nN2 M02\n", 10, 1, marks=manual("§2.6.7", "X ranges over ±99999.999")),
    pytest.param("%  1\nN1 X1.2345 F10\nN2 M02\n", 12, 1, marks=manual("§2.6.7", "X has at most three decimals")),
    pytest.param("%  1\nN1 X1 F65001\nN2 M02\n", 11, 1,
                 marks=manual("§2.6.8", "F as a velocity lies in 1 … 65000")),
    pytest.param("%  1\nN1 X1 F10 M123\nN2 M02\n", 17, 1, marks=manual("§2.6.9", "M is two digits, 00 … 99")),
    pytest.param("%  1\nN1 G00 F100\nN2 M02\n", 5, 1,
                 marks=manual("§2.6.10", "G00 must be followed by the X function")),
    pytest.param("%  1\nN1 G04 X10 F5\nN2 M02\n", 5, 1,
                 marks=manual("§2.6.10", "G04 is followed by F (the time), never by X")),
    pytest.param("%  1\nN1 X10\nN2 M02\n", 6, 1,
                 marks=manual("§2.6.10", "an X without G00 must be followed by the F function")),
    pytest.param("%  1\nN1 G24 F3 M10\nN2 G20\nN3 M02\n", 9, 1,
                 marks=manual("§2.6.6.4", "a G24 block holds no other function, not even an M function")),
    pytest.param("%  1\nN1 G24 F2\nN2 X1 F1\nN3 G20 M10\nN4 M02\n", 5, 3,
                 marks=manual("§2.6.6.4", "a G20 block holds no other function (5 'Funktion nach G-Funktion "
                              "nicht erlaubt')")),
    pytest.param("%  1\nN1 G74 X10\nN2 M02\n", 5, 1,
                 marks=manual("§2.6.10", "the X function is forbidden with G74")),
    pytest.param("%  1\nN1 G24 F65001\nN2 X1 F1\nN3 G20\nN4 M02\n", 11, 1,
                 marks=manual("§2.6.8", "as a loop count F lies in 0 … 65000")),
    pytest.param("%  1\nN1 L5 X10\nN2 M02\n", 9, 1,
                 marks=manual("§2.6.5", "no function may follow the L function; the block ends there")),
    pytest.param("%  1\nN1 G90 G91\nN2 M02\n", 9, 1,
                 marks=manual("§2.6.6", "a block holds one G function only")),
    pytest.param("%  1\nN1 X1 F1 M10 M11\nN2 M02\n", 9, 1,
                 marks=manual("§2.6.3", "each function appears at most once in a block")),
]


@pytest.mark.parametrize(("text", "errno", "block"), SYNTAX)
def test_syntax_errors_at_input_name_the_error_and_block(ready: Module, text: str, errno: int, block: int) -> None:
    """§4.3.18: BA22 stores a faulty program marked faulty (module error 48) with its error and block."""
    assert stored(ready, 1, text) == (48, errno, block)
    ready.operate(1, 8, START, b=1)
    assert ready.device.read("axis.1.error") == 48  # a faulty program does not run


@manual("§2.6.2", "the header holds % (main) or L (sub), the number and up to 58 characters of free text")
@manual("§2.6.2", "main and subprograms differ only in documentation: any program can be used as either")
@manual("§2.6.4", "the block markers /N (skippable) and :N (main block) are allowed but mean nothing")
@manual("§2.6.4", "block numbers may come in any order and repeat; blocks run in their order in the program")
@manual("§2.6.3", "spaces around the line feed are allowed")
def test_headers_block_numbers_and_markers(ready: Module) -> None:
    assert stored(ready, 12, "L 12  das ist ein Unterprogramm im DB12\n/N30 X10 F1000 \n:N30 X20 F1000 M11\n"
                  "N5 M02\n") == (0, 0, 0)
    run(ready, "L 12\nN1 M02\n".replace("L 12", "%  3 " + "x" * 58), number=3, seconds=1)
    ready.operate(1, 8, START, b=12)  # an L program started as a main program
    ready.clock.advance(30)
    assert state(ready) == (0, 20_000, 2)  # both N30 ran, in their order
    run(ready, "%  4\nN9 X5 F1000 M12\nN9 L12\nN1 M02\n", number=4)  # the L program as a subprogram
    assert state(ready) == (0, 20_000, 2)


# -- §2.6.6 G functions ----------------------------------------------------------------------------------------
@manual("§2.6.6.1", "G00 goes to the target at the maximum velocity of the machine data")
def test_g00_runs_at_the_maximum_velocity(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(a=1_000_000))[8] == 0  # tau 95 ms: f_max after 0.3 s, 23 mm
    mod.operate(1, 5, START, b=1)
    run(mod, "%  1\nN1 G00 X200 M23\nN2 M02\n", seconds=1.0)
    md = mod.m.units[0].md
    assert md is not None
    assert mod.device.read("axis.1.velocity") == pytest.approx(md.f_max * md.resolution, rel=1e-6)
    assert mod.device.read("axis.1.m_function") == 23  # output at the start of the block


@manual("§2.6.6.2", "G04 waits F × 100 ms; its M function is output at the start of the block")
def test_g04_waits_in_steps_of_100_ms(ready: Module) -> None:
    run(ready, "%  1\nN38 G04 F10 M34\nN40 X2 F1000\nN50 M02\n", seconds=0.99)
    assert ready.device.read("axis.1.m_function") == 34 and ready.device.read("axis.1.position") == 1_000
    ready.clock.advance(0.02)
    assert ready.device.read("axis.1.running") is True
    ready.clock.advance(5)
    assert state(ready) == (0, 2_000, 2)


@manual("§2.6.6.3", "blocks joined by G10 count as one block in BA9: no halt between them")
@manual("§2.6.6.3", "position reached is not set at the end of a G10 block")
def test_a_g10_chain_is_one_step_in_single_block(ready: Module) -> None:
    assert stored(ready, 1, "%  1\nN30 G10 X50 F1000 M30\nN32 X100 F1000 M31\nN36 X120 F1000\nN40 M02\n")[0] == 0
    ready.operate(1, 9, START, b=1)
    ready.operate(1, 9, TAKE_OVER, b=1)
    ready.clock.advance(2.9)  # the holder passes 50 mm (about 49 mm in 2.9 s of a 3 s leg)
    ready.clock.advance(0.3)
    assert ready.device.read("axis.1.running") is True and ready.device.read("output.PE1") is False
    ready.clock.advance(10)
    assert state(ready) == (0, 100_000, 31) and ready.device.read("output.PE1") is True


@manual("§2.6.6.4", "G24 F0 is an endless loop; it is allowed only on the top level (38 in a called program)")
def test_endless_loop_only_on_the_top_level(ready: Module) -> None:
    assert stored(ready, 2, "L  2\nN1 G24 F0\nN2 X2 F1000\nN3 G20\nN4 M02\n")[0] == 0
    run(ready, "%  1\nN1 L2\nN2 M02\n")
    assert state(ready)[0] == 38


@manual("§2.6.6.4", "G24 F n repeats the blocks up to its G20 n times")
def test_a_loop_runs_n_times(ready: Module) -> None:
    run(ready, "%  1\nN1 G91\nN2 G24 F3\nN3 X2 F1000\nN4 G20\nN5 M02\n")
    assert state(ready)[:2] == (0, 1_000 + 3 * 2_000)


@manual("§2.6.6.5", "G25, G26 and G27 are ignored on a linear axis; they do not abort the program")
def test_rotary_direction_functions_on_a_linear_axis(ready: Module) -> None:
    run(ready, "%  1\nN1 G27\nN2 X5 F1000\nN3 G26\nN4 X2 F1000\nN5 M02\n")
    assert state(ready) == (0, 2_000, 2)


@manual("§2.6.6.5", "the manual's example on a 0 … 360° axis: G27 X180 backward, G25 X0 forward on a tie, G26 X0 "
        "standing at 0° one revolution forward, G25 X360 no motion")
@pytest.mark.parametrize(("g", "turn"), [("G26", 360_000), ("G27", -360_000)], ids=["G26", "G27"])
def test_the_rotary_direction_example(make: Make, g: str, turn: int) -> None:
    mod = rotary(make)
    run(mod, f"%  1\nN10 G74 M10\nN20 G27\nN30 X180 F1000 M30\nN40 G25 X0 F500\nN50 {g}\nN60 X0 F1000 M60\n"
        "N70 G25 X360 F500\nN80 M02\n", seconds=40)  # (G27 in N50: the turn backward, by symmetry)
    read = mod.device.read
    assert read("axis.1.m_function") == 60 and read("axis.1.velocity") * turn > 0  # N60 turns
    mod.clock.advance(60)
    assert state(mod) == (0, 0, 2) and read("axis.1.machine_position") == pytest.approx(turn)


@manual("§2.6.6.6", "each G43/G44 adds/subtracts the MD tool offset to the existing one; G40 removes the program's "
        "part only")
@manual("§2.6.6.6", "tool offsets of a program stay after its end until BA16")
def test_program_tool_offsets_add_up_and_stay(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(tool_length=10_000, backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    assert mod.operate(1, 15, 3, dd=100_000)[4] == 0  # BA15: 100 mm forward
    assert mod.device.read("axis.1.position") == 1_000 + 100_000
    run(mod, "%  1\nN1 G44\nN2 G44\nN3 M02\n", seconds=1)
    assert mod.device.read("axis.1.position") == 1_000 + 80_000  # Bild 2/19: 100 − 10 − 10
    run(mod, "%  2\nN1 G43\nN2 G40\nN3 M02\n", number=2, seconds=1)
    assert mod.device.read("axis.1.position") == 1_000 + 100_000  # G40: the program's part is gone
    assert mod.operate(1, 16, START)[4] == 0
    assert mod.device.read("axis.1.position") == 1_000


@manual("§2.6.6.7", "G54 … G57 switch one MD zero offset on; a second replaces the first")
@manual("§2.6.6.7", "the program's zero offsets are switched off at its end, not when it is aborted by Stopp")
def test_program_zero_offsets(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(zero_offsets=(40_000, 80_000, 0, 0), backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    run(mod, "%  1\nN1 G54\nN2 G55\nN3 G04 F100\nN4 M02\n", seconds=1)
    assert mod.device.read("axis.1.position") == 1_000 - 80_000  # G55 replaced G54
    mod.operate(1, 8, 2)  # Stopp: interrupted (65)
    mod.operate(1, 8, 2)  # Stopp again: aborted
    assert mod.device.read("axis.1.position") == 1_000 - 80_000  # still shifted
    assert mod.operate(1, 14, START)[4] == 0
    run(mod, "%  2\nN1 G54\nN2 M02\n", number=2, seconds=1)
    assert mod.device.read("axis.1.position") == 1_000  # the end switched it off


@manual("§2.6.6.8", "after G70 paths are in 0.1 inch on a metric axis; after G71 in mm again")
def test_g70_and_g71_on_a_metric_axis(ready: Module) -> None:
    run(ready, "%  1\nN1 G70\nN2 X10 F1000\nN3 M02\n")
    assert state(ready)[1] == 25_400  # 10 × 0.1 inch = 25.4 mm
    run(ready, "%  2\nN1 G70\nN2 G71\nN3 X10 F1000\nN4 M02\n", number=2)
    assert state(ready)[1] == 10_000


@manual("§2.6.6.9", "G74 takes the holder to the physical reference point at the step velocity, whatever zero "
        "offset is active; the actual value then shows the offsets")
def test_g74_goes_to_the_physical_reference_point(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(zero_offsets=(50_000, 0, 0, 0), backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    motor = mod.device.read("axis.1.machine_position")
    run(mod, "%  1\nN1 X30 F1000\nN2 G54\nN3 G74\nN4 G04 F100\nN5 M02\n", seconds=10)
    assert mod.device.read("axis.1.machine_position") == pytest.approx(motor)
    assert mod.device.read("axis.1.position") == 1_000 - 50_000


@manual("§2.6.6.10", "G90 (default) interprets X as absolute, G91 as relative, until the other is given")
def test_g90_and_g91(ready: Module) -> None:
    run(ready, "%  1\nN1 X5 F1000\nN2 G91\nN3 X5 F1000\nN4 X5 F1000\nN5 G90\nN6 X2 F1000\nN7 M02\n")
    assert state(ready)[:2] == (0, 2_000)
    run(ready, "%  2\nN1 G91\nN2 X5 F1000\nN3 X5 F1000\nN4 M02\n", number=2)
    assert state(ready)[:2] == (0, 12_000)


@manual("§2.6.7", "X50, X50. and X+12345.678 are valid; without a point it is taken at the end")
def test_x_notations(ready: Module) -> None:
    run(ready, "%  1\nN1 X50. F6000\nN2 M02\n")
    assert state(ready)[1] == 50_000
    run(ready, "%  2\nN1 X+123.456 F6000\nN2 M02\n", number=2)
    assert state(ready)[1] == 123_456


@manual("§2.6.9", "M functions are output only with a traverse or dwell; M alone or with switches is read over")
@manual("§2.6.9", "M255 is output until a traverse or dwell with an M function runs")
@manual("§2.6.9", "an M function stays output until the next traverse or dwell with an M function")
def test_m_functions(ready: Module) -> None:
    assert stored(ready, 1, "%  1\nN05 G91\nN10 X1 F1000\nN20 X1 F1000 M10\nN30 G57 M11\nN35 X1 F1000\n"
                  "N40 G04 F10 M20\nN75 M02\n") == (0, 0, 0)
    ready.operate(1, 9, START, b=1)
    shown = [ready.device.read("axis.1.m_function")]
    for _ in range(4):
        ready.operate(1, 9, TAKE_OVER, b=1)
        ready.clock.advance(5)
        shown.append(ready.device.read("axis.1.m_function"))
    assert shown[1:] == [255, 10, 10, 20]


@manual("§2.6.9", "a block with M00 runs; the next traverse or dwell waits for Übernahme, shifts before it are "
        "done before the halt")
@manual("§2.6.9", "an M00 alone in a block acts as a traverse of length 0: it needs an Übernahme of its own")
@manual("§2.6.9", "an M00 followed only by switches or by M02 no longer halts")
@manual("§4.3.1", "N10 X100 F1000 M00 / N15 M00 / N20 G56 M00 / N25 G43 X200: three Übernahme before the move "
        "to 200")
def test_m00_halts(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(zero_offsets=(0, 0, 3_250, 0), tool_length=2_300, backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    run(mod, "%  3\nN10 X100 F1000 M00\nN15 M00\nN20 G56 M00\nN25 G43 X200 F1000\nN30 X250 F1000 M00\n"
        "N35 G40\nN40 M02\n", number=3, seconds=20)
    assert state(mod)[:2] == (0, 100_000) and mod.device.read("axis.1.running") is False  # N10 ran; halt
    takes = []
    for _ in range(3):
        mod.operate(1, 8, TAKE_OVER, b=3)
        mod.clock.advance(20)
        takes.append(mod.device.read("axis.1.position"))
    # G56; G43; then N25 and N30 ran, N35 G40 dropped the tool offset and the end the shift:
    assert takes == [100_000 - 3_250, 100_000 - 3_250 + 2_300, 250_000 - 2_300 + 3_250]
    assert state(mod)[0] == 0 and mod.device.read("axis.1.running") is False
    assert mod.m.units[0].automatic is None  # the M00 of N30 before G40 and M02 did not halt


@manual("§2.6.6.9", "after G74 the actual value counts both the zero offset and the tool offset (the example's "
        "values, with the sign §2.6.6.7 gives a positive zero offset: see the deviation row)")
def test_g74_example_values(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(reference=0, zero_offsets=(500_000, 0, 0, 0), tool_length=20_000,
                                     backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    run(mod, "%  1\nN1 G54\nN2 G43\nN3 G74\nN4 G04 F100\nN5 M02\n", seconds=5)
    assert mod.device.read("axis.1.running") is True  # in the dwell
    assert state(mod)[1] == -480_000


@manual("§2.5.5.1", "each G43/G44 checks the resulting tool offset against the limits; beyond them the program is "
        "aborted with an error (63)")
def test_g43_beyond_the_limits_aborts(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(tool_length=40_000_000, limit_end=10_000_000, backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    run(mod, "%  1\nN1 G43\nN2 G43\nN3 G43\nN4 X2 F1000\nN5 M02\n", seconds=10)
    assert state(mod)[0] == 63 and mod.m.units[0].automatic is None
    assert mod.device.read("axis.1.position") == 1_000 + 80_000_000  # the two G43 that fitted stay


@manual("§2.6.9", "in BA9 an M00 with a traverse adds no halt of its own: one Übernahme starts the next traverse "
        "or dwell")
@manual("§2.6.9", "in BA9 an M00 alone still is a traverse of length 0 that needs its own Übernahme")
def test_m00_in_single_block(ready: Module) -> None:
    assert stored(ready, 1, "%  1\nN10 X10 F1000 M00\nN20 G04 F10\nN30 M00\nN40 X20 F1000\nN50 M02\n")[0] == 0
    ready.operate(1, 9, START, b=1)
    ready.operate(1, 9, TAKE_OVER, b=1)
    ready.clock.advance(10)
    assert state(ready)[1] == 10_000
    ready.operate(1, 9, TAKE_OVER, b=1)  # one Übernahme: the dwell runs
    ready.clock.advance(0.5)
    assert ready.device.read("axis.1.running") is True
    ready.clock.advance(5)
    ready.operate(1, 9, TAKE_OVER, b=1)  # N30 (length 0)
    ready.clock.advance(5)
    assert state(ready)[1] == 10_000 and ready.device.read("axis.1.running") is False
    ready.operate(1, 9, TAKE_OVER, b=1)  # N40
    ready.clock.advance(10)
    assert state(ready)[1] == 20_000
