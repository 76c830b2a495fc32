"""What a positioning E reads from the parameters, read anew whenever one of them changes: the
ramp shape and its sections (P1032, P1005–P1008, §4.8.4.4), the software limits (P1040/P1041,
§4.8.6.12), the compare outputs (P1024–P1027, §4.8.1.2) and the range of W after a new
weighting (P76, §4.8.4.6).  The drive keeps what it made of them between moves (issue 31); a
write between two moves must reach the next one."""

from __future__ import annotations

import math

import pytest

from tests.sers.conftest import Plant

A_INC = 100 * 12800 / (2 * math.pi)  # A = 100 rad/s² in increments per s²


def _acceleration_mid_ramp(sers: Plant, move: str) -> float:
    """Start ``move`` (V = 600 rpm, A = 100 rad/s²) and read the acceleration half-way through
    the ramp up, then let the drive stand again."""
    sers.host.ask(f"#V=600 A=100 {move}\r")
    sers.advance(20 * math.pi / 100 / 2)  # the ramp to 20π rad/s at 100 rad/s² takes 0.2π s
    acceleration = float(sers.read("axis.acceleration"))
    sers.settle()
    return acceleration


def test_the_ramp_shape_written_between_two_moves_shapes_the_next(sers: Plant) -> None:
    sers.host.ask("#ON\r")
    assert _acceleration_mid_ramp(sers, "W=3600 E") == pytest.approx(A_INC, rel=1e-9)
    sers.host.ask("#P1032=1\r")
    assert _acceleration_mid_ramp(sers, "W=-3600 E") == pytest.approx(-math.pi / 2 * A_INC, rel=1e-9)
    sers.host.ask("#P1032=0 P1007=50 P1005=50\r")  # section 1: up to 50 % V at 50 % A
    assert _acceleration_mid_ramp(sers, "W=3600 E") == pytest.approx(A_INC / 2, rel=1e-9)
    sers.host.ask("#P1007=100 P1005=100\r")
    assert _acceleration_mid_ramp(sers, "W=-3600 E") == pytest.approx(-A_INC, rel=1e-9)


def test_limits_and_compare_outputs_set_after_a_move_watch_the_next(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON V=60 A=1000 W=30 E\r")
    sers.settle()
    assert sers.read("param.P51") == pytest.approx(30, abs=0.03)  # (W in whole increments)
    host.ask("#P1024=60 P1025=2\r")  # compare position 60°: O2 on
    host.ask("#W=60 E\r")
    sers.settle()
    assert sers.read("output.O2") is True
    host.ask("#P1025=0 P1040=-100 P1041=100 W=360 E\r")
    sers.settle()
    assert 100 < sers.read("param.P51") < 110  # stopped past the positive software limit
    assert sers.read("P12") & 1
    host.ask("#P1040=0 P1041=0\r")  # limits off again: a move past them goes all the way
    before = sers.read("param.P51")
    host.ask("#W=300 E\r")
    sers.settle()
    assert sers.read("param.P51") == pytest.approx(before + 300, abs=0.03)


def test_the_range_of_w_follows_the_weighting(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#W=200000\r") == b"#W=200000\r\nok1\n\r"  # ±214748.3647° (§4.8.4.2)
    host.ask("#P76=0\r")  # increments: ±2147483639
    assert host.ask("#W=2000000000\r") == b"#W=2000000000\r\nok1\n\r"
    host.ask("#P76=2\r")
    assert host.ask("#W=2000000000\r").startswith(b"#W=2000000000\r\n*")


@pytest.mark.manual("§4.8.3.1", "P12 8 'Interner Lagegrenzwert - der intern berechnete Positionswert kann nicht auf den "
                    "skalierten Wert abgebildet werden': a jog beyond the position range of the weighting (§4.8.4.2)")
@pytest.mark.parametrize(("weighting", "start", "limit"), [(2, "214740", 214748.3647), (0, "2147480000", 2147483639)])
def test_a_jog_beyond_the_position_range_warns_with_p12_8(sers: Plant, weighting: int, start: str,
                                                             limit: float) -> None:
    host = sers.host
    host.ask(f"#P76={weighting} ON P1035=0 P1019=60 P1018=100000 P51={start}\r")
    host.ask("#RS\r")  # 60 rpm: 360° or 12800 increments per second
    sers.advance(0.01)
    assert sers.read("param.P51") < limit
    assert sers.read("P12") == 0
    sers.advance(1.0)
    assert sers.read("param.P51") > limit
    assert sers.read("P12") & 8
    host.ask("#S\r")
    sers.settle()
    assert host.ask("#P12=0\r").endswith(b"ok1\n\r")
    host.ask(f"#P51={start} LS\r")  # inside the range the warning does not come again
    sers.advance(0.5)
    assert sers.read("P12") == 0
