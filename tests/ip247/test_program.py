"""The IP247's traverse-program record and language check (spec ip247.md §3.4.2, §4.5, §4.11;
vectors §6.4, §6.5)."""

from __future__ import annotations

import pytest

from devsim.devices.ip247.program import SyntaxFault, parse, record_text, record_words

DB155 = ("%155 BEISPIEL EINES VERFAHRPROGRAMMS\nN10 G74 M10\nN11 G04 F50 M11\nN20 G00 X110.500 M20\nN25 G24 F7\n"
         "N30 X-200.000 F4500 M30\nN35 G10 X-50.000 F400 M35\nN40 X150.000 F2000 M40\nN45 G20\nN99 M02\n")
DB155_WORDS = """
0062 0044 429B 0000 0000 2531 3535 2042 4549 5350
4945 4C20 4549 4E45 5320 5645 5246 4148 5250 524F
4752 414D 4D53 0A4E 3130 2047 3734 204D 3130 0A4E
3131 2047 3034 2046 3530 204D 3131 0A4E 3230 2047
3030 2058 3131 302E 3530 3020 4D32 300A 4E32 3520
4732 3420 4637 0A4E 3330 2058 2D32 3030 2E30 3030
2046 3435 3030 204D 3330 0A4E 3335 2047 3130 2058
2D35 302E 3030 3020 4634 3030 204D 3335 0A4E 3430
2058 3135 302E 3030 3020 4632 3030 3020 4D34 300A
4E34 3520 4732 300A 4E39 3920 4D30 320A
"""
BEISPIEL = "%  1 BEISPIEL\nN1 X100 F1000 M10\nN2 M02\n"


def test_the_com247_example_record_of_section_6_4() -> None:
    words = [int(w, 16) for w in DB155_WORDS.split()]
    assert len(DB155) == 186 and record_words(155, DB155) == words
    assert record_text(words) == (155, 0, 0, DB155)
    program = parse(DB155)
    assert (program.number, program.main, len(program.blocks)) == (155, True, 9)
    assert program.blocks[2].x == 110_500 and program.blocks[3].f == 7 and program.blocks[4].x == -200_000
    assert [b.m for b in program.blocks] == [10, 11, 20, None, 30, 35, 40, None, 2]


def test_the_manuals_example_record_of_section_3_4_2() -> None:
    """25 words, the odd text padded with 00H in the last word."""
    words = record_words(1, BEISPIEL)
    assert words[:5] == [25, 0x0044, 0x4201, 0, 0] and words[5:7] == [0x2520, 0x2031] and words[-1] == 0x0A00
    assert parse(BEISPIEL).blocks[0].x == 100_000


def test_the_manuals_loop_and_halt_examples_are_valid() -> None:
    """Spec §4.11: functions in the order N, L, G, X, F, M; G24 F0 an endless loop, F5 five
    repetitions; X in mm to 3 decimals (µm); /N and :N blocks taken as N; blocks in text order;
    the end block may carry a traverse (``N25 G43 X200 F100 M02``)."""
    loops = parse("%  2 LOOPS\nN10 G24 F0\nN20 G74\nN30 G24 F5\nN40 L30\nN50 G04 F10\nN60 L30\nN70 G20\nN80 G20\n"
                  "N90 M02\n")
    assert (loops.number, loops.main, loops.comment) == (2, True, "LOOPS")
    assert [(b.number, b.call, b.g, b.f, b.m) for b in loops.blocks] == [
        (10, None, 24, 0, None), (20, None, 74, None, None), (30, None, 24, 5, None), (40, 30, None, None, None),
        (50, None, 4, 10, None), (60, 30, None, None, None), (70, None, 20, None, None), (80, None, 20, None, None),
        (90, None, None, None, 2)]
    halts = parse("%  3\nN10 G10 X100 F500 M00\nN20 M00\nN30 G56 M00\nN40 X500 F1000\nN50 M02\n")
    assert [(b.g, b.x, b.f, b.m) for b in halts.blocks] == [
        (10, 100_000, 500, 0), (None, None, None, 0), (56, None, None, 0), (None, 500_000, 1000, None),
        (None, None, None, 2)]
    sub = parse("L12   das ist ein Unterprogramm im DB12\n/N1 G91\n:N2 X+12345.678 F1\nN25 G43 X200 F100 M02\n")
    assert (sub.number, sub.main, sub.comment) == (12, False, "das ist ein Unterprogramm im DB12")
    assert [(b.ordinal, b.number, b.kind) for b in sub.blocks] == [(1, 1, "/N"), (2, 2, ":N"), (3, 25, "N")]
    assert [(b.g, b.x, b.f, b.m) for b in sub.blocks] == [
        (91, None, None, None), (None, 12_345_678, 1, None), (43, 200_000, 100, 2)]


@pytest.mark.parametrize(
    ("text", "errno", "block"),
    [
        ("N1 M02\n", 2, 0),  # no header
        ("%  1\nX100 F10\nN2 M02\n", 2, 1),  # a block without N
        ("%  1\nN1000 M02\n", 3, 1),
        ("%  1\nN1 L256\nN2 M02\n", 4, 1),
        ("%  1\nN1 G00 F100\nN2 M02\n", 5, 1),  # G00 not followed by X
        ("%  1\nN1 G04 X10 F5\nN2 M02\n", 5, 1),
        ("%  1\nN1 X10\nN2 M02\n", 6, 1),  # X without F
        ("%  1\nN1 M02", 8, 1),  # end block without LF
        ("%  1\nN1 F100 X10\nN2 M02\n", 9, 1),  # out of order
        ("%  1\nN1 X123456 F10\nN2 M02\n", 10, 1),
        ("%  1\nN1 X1 F65001\nN2 M02\n", 11, 1),
        ("%  1\nN1 X1 F0\nN2 M02\n", 11, 1),
        ("%  1\nN1 X1.2345 F10\nN2 M02\n", 12, 1),
        ("%  1\nN1 G24 F2\nN2 M02\n", 13, 2),
        ("%  1\nN1 G20\nN2 M02\n", 14, 1),
        ("%  1\nN1 X1 F10\n", 15, 1),
        ("%  1\nN1 Q5\nN2 M02\n", 16, 1),
        ("%  1\nN1 X1 F10 M123\nN2 M02\n", 17, 1),
        ("%  1\nN1 M02\nN2 X1 F10\n", 18, 2),
        ("%  1\nN1 X1 F10" + " " * 41 + "\nN2 M02\n", 19, 1),  # 51 characters with its LF
        ("%  1\nN1 G33\nN2 M02\n", 37, 1),
        ("%  1\nN1 G24 F3 M10\nN2 G20\nN3 M02\n", 9, 1),  # no M in a G24 block
        # functions are separated by blanks (20H): any other character is one the module does not know
        *((f"%  1\nN1 X1{c}F10\nN2 M02\n", 16, 1) for c in "\t\r\x1c\x1f\x85\xa0"),
        ("%  1\nN1 X1 F10 M10\xa0\nN2 M02\n", 16, 1),
        ("%  1 " + "x" * 58 + "\x1c\nN1 M02\n", 1, 0),  # a comment of 59 characters, the last FS
        ("%  1 " + "x" * 58 + "\xa0\nN1 M02\n", 1, 0),
    ],
)
def test_syntax_errors_name_their_number_and_block(text: str, errno: int, block: int) -> None:
    with pytest.raises(SyntaxFault) as info:
        parse(text)
    assert (info.value.errno, info.value.block) == (errno, block)
