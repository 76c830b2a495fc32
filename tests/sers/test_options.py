"""The spec's configurable readings (⚙ in the gap table, sers.md G-rows) through a real pty:
with the option set, the drive answers as the other reading has it; without, as before."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize("star", [False, True], ids=["no_star", "error_trailing_star"])
@pytest.mark.parametrize("ok", [False, True], ids=["no_ok", "ok_after_error"])
def test_error_message_framing_follows_the_g_errfmt_options(plant_factory, star: bool, ok: bool) -> None:
    """G-ERRFMT: ``*text`` (⚙ ``error_trailing_star``: ``*text*``) and no ``ok`` for a line with
    an error (⚙ ``ok_after_error``: its acknowledgement after the message); the rest of the
    line is not executed either way.  Lines failing at their first character in one chunk (what
    the noise path takes in one step) get the same."""
    plant = plant_factory({"error_trailing_star": star, "ok_after_error": ok})
    host = plant.host
    end = b"*\n\r" if star else b"\n\r"
    ack = b"\nok3\n\r" if ok else b""  # (the refusal leaves P12 value 16, a warning: ok3)
    expected = b"#V=99999 \n*V zu gro\xdf" + end + b"W=5\r" + ack
    host.send("#V=99999 W=5\r")
    assert host.read_exact(len(expected)) == expected
    assert plant.read("param.W") == 0
    failed = b"#%\n*Anweisung erwartet" + end + b"\r" + ack
    expected = failed * 3 + b"#V?\rV=100U/min\n\r\nok3\n\r"
    host.send(b"#%\r#%\r#%\r#V?\r")
    assert host.read_exact(len(expected)) == expected


@pytest.mark.parametrize(("config", "taken", "left"), [({}, True, 1), ({"counter_decrement_first": True}, False, 1)],
                         ids=["compare_old", "counter_decrement_first"])
def test_a_counter_in_if_is_compared_as_g_counter_says(plant_factory, config, taken: bool, left: int) -> None:
    """G-COUNTER: ``IF C1>1`` compares the old value, then decrements (the manual's examples:
    C1=10 gives 10 passes); ⚙ ``counter_decrement_first`` decrements first (its rule)."""
    plant = plant_factory(config)
    host = plant.host
    assert host.ask("#C1=2 X=0\r").endswith(b"ok1\n\r")
    assert host.ask("#IF C1>1 X=7\r").endswith(b"ok1\n\r")
    assert plant.read("param.X") == (7 if taken else 0)
    assert plant.read("param.C1") == left


@pytest.mark.parametrize(("mode", "after_release"), [("toggle", True), ("level", False)])
def test_input_i6_switches_the_motor_as_i6_mode_says(plant_factory, mode: str, after_release: bool) -> None:
    """G-INFUNC: I6 (P1021 bit 32) toggles ON/OFF at each rising edge; ⚙ ``i6_mode: level``
    keeps the motor ON while it is active and switches it OFF at release.  Both clear P11 and
    P12 as they switch ON (§4.8.1.1)."""
    plant = plant_factory({"params": {"P1021": 32}, "i6_mode": mode})
    assert plant.host.ask("#P1017=7\r").startswith(b"#P1017=7\r\n*")  # P12 value 16 (a refusal)
    assert plant.read("P12") != 0
    plant.set("input.I6", True)
    assert (plant.read("energized"), plant.read("P12")) == (True, 0)
    plant.set("input.I6", False)
    assert plant.read("energized") is after_release
    plant.set("input.I6", True)
    assert plant.read("energized") is not after_release


@pytest.mark.parametrize(("config", "rows"), [
    ({}, b"1: V=500.0000\n\r2: W=90.5000\n\r3: A=100.000\n\r"),
    ({"list_decimals": 3}, b"1: V=500.000\n\r2: W=90.500\n\r3: A=100.000\n\r"),
], ids=["weighting", "list_decimals"])
def test_list_shows_weighted_constants_with_the_list_decimals(plant_factory, config, rows: bytes) -> None:
    """G-LIST: a weighted constant in LIST with all the decimals of its weighting; ⚙
    ``list_decimals: 3`` as the manual's example ``V=500.000`` (§4.3)."""
    host = plant_factory({"params": {"P1028": 1}, **config}).host
    for line in ("#NEW\r", "#V=500\r", "#W=90.5\r", "#A=100\r", "#QUIT\r"):
        assert host.ask(line).endswith((b"pgm\n\r", b"ok1\n\r"))
    assert host.ask("#LIST\r") == b"#LIST\r" + rows + b"\nok1\n\r"


@pytest.mark.parametrize("messages", [False, True], ids=["silent", "spontaneous_fault_messages"])
def test_faults_are_announced_on_the_line_as_g_faultmsg_says(plant_factory, messages: bool) -> None:
    """G-FAULTMSG: no unsolicited text for a fault (the host polls P11/P12 and reads the ok
    digit); ⚙ ``spontaneous_fault_messages`` sends ``*<text>`` between lines once as the bit gets
    set (§2.1.4 „Vorwarnung Unterspannung“, „Fehler Unterspannung“; the P11 texts of §4.8.3.1)."""
    plant = plant_factory({"spontaneous_fault_messages": messages})
    host = plant.host
    plant.set("quantity.supply_voltage", 45.0)  # below U_W, above U_B: P12 value 4
    plant.set("quantity.supply_voltage", 44.0)  # (still: no second message)
    expected = (b"\n*Vorwarnung Unterspannung\n\r" if messages else b"") + b"#P12?\rP12=4\n\r\nok3\n\r"
    host.send("#P12?\r")
    assert host.read_exact(len(expected)) == expected
    plant.set("input.limit_right", True)  # P11 value 8192
    expected = (b"\n*Fehler Lagegrenzwert\n\r" if messages else b"") + b"#P11?\rP11=8192\n\r\nok4\n\r"
    host.send("#P11?\r")
    assert host.read_exact(len(expected)) == expected


@pytest.mark.parametrize(("config", "v", "w", "c1"), [
    ({}, b"V=100U/min", b"W=2.5\xb0", b"C1=3"),
    ({"query_units": False}, b"V=100", b"W=2.5", b"C1=3"),
    ({"query_fixed_decimals": True}, b"V=100.0000U/min", b"W=2.5000\xb0", b"C1=3"),
    ({"query_name_style": "number"}, b"P91=100U/min", b"P47=2.5\xb0", b"P100=3"),
], ids=["default", "query_units_false", "query_fixed_decimals", "query_name_style_number"])
def test_query_answers_follow_the_g_queryfmt_options(plant_factory, config, v: bytes, w: bytes, c1: bytes) -> None:
    """G-QUERYFMT: the name as asked, trailing zeros dropped, the unit appended (``V=100U/min``);
    ⚙ ``query_units``, ``query_fixed_decimals``, ``query_name_style``.  Asked twice: a host's
    repeated poll is answered from what the face kept (the same answer)."""
    host = plant_factory(config).host
    assert host.ask("#W=2.5 C1=3\r").endswith(b"ok1\n\r")
    for _ in range(2):
        for line, answer in (("#V?\r", v), ("#W?\r", w), ("#C1?\r", c1)):
            assert host.ask(line) == line.encode() + answer + b"\n\r\nok1\n\r"


@pytest.mark.parametrize("each", [False, True], ids=["one_ack", "ack_each_terminator"])
def test_a_cr_lf_pair_is_acknowledged_as_g_crlf_says(plant_factory, each: bool) -> None:
    """G-CRLF: CR LF (or LF CR) after a line gives one acknowledgement, its second half only
    echoed; ⚙ ``ack_each_terminator`` acknowledges that too.  Lines failing at once in one chunk
    (the noise path), and a pair split over two writes, the same way."""
    host = plant_factory({"ack_each_terminator": each}).host
    again = b"\nok1\n\r" if each else b""
    expected = b"#V?\rV=100U/min\n\r\nok1\n\r\n" + again
    host.send("#V?\r\n")
    assert host.read_exact(len(expected)) == expected
    again = b"\nok3\n\r" if each else b""  # (after a refusal: P12 value 16, a warning)
    failed = b"#%\n*Anweisung erwartet\n\r\r\n" + again
    expected = failed * 2 + b"#W=1\n\nok3\n\r\r" + again
    host.send("#%\r\n#%\r\n#W=1\n\r")
    assert host.read_exact(len(expected)) == expected
    expected = b"#V?\rV=100U/min\n\r\nok3\n\r\n" + again
    host.send("#V?\r")
    host.send("\n")
    assert host.read_exact(len(expected)) == expected
