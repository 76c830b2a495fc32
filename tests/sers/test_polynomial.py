"""Polynomial moves (manual §4.6.7, spec §4.10.12 G-POLY, test vector T-14) through the pty."""

from __future__ import annotations

import math

import pytest

from tests.sers.conftest import Plant

T14 = [
    "ON",
    "WP=100 A=1000 V=200 E",
    "WP=120 A=300 V=400 E",
    "O1=1",
    "WP=100 A=1000 V=50 E",
    "WP=100 A=1500 V=700 E",
    "WP=200 A=500 V=100 E",
    "O2=1",
    "WPT=130 A=1000 B=500 V=50 E",
]


def download(plant: Plant, lines: list[str]) -> None:
    assert plant.host.ask("#NEW\r") == b"#NEW\r\npgm\n\r"
    for line in lines:
        assert plant.host.ask(f"#{line}\r").endswith(b"\npgm\n\r")
    assert plant.host.ask("#QUIT\r").endswith(b"ok1\n\r")


@pytest.mark.manual("§4.6.7", "the 6-segment example: O1 is set at the end of the first segment, O2 at the end of the fourth")
def test_t14_six_segments_outputs_at_segment_ends(sers: Plant) -> None:
    download(sers, T14)
    dev = sers.runtime.device("sers")
    velocities: list[float] = []
    sers.host.ask("#RUN\r")
    # O1 follows the end of segment 1 (P51 = 100) within one control cycle
    assert sers.runtime.run_until(lambda: dev.read("output.O1") is True, 5)
    assert 100 <= sers.read("param.P51") < 101.5
    assert sers.read("output.O2") is False
    # O2 follows the end of segment 4 (P51 = 420)
    assert sers.runtime.run_until(lambda: velocities.append(dev.model.axis.velocity()) or dev.read("output.O2"), 5)
    assert 420 <= sers.read("param.P51") < 422.2  # one 0.5 ms cycle at up to 700 rpm
    sers.settle()
    assert sers.read("param.P51") == pytest.approx(750, abs=0.01)
    sers.advance(0.001)  # the program ends one control cycle later
    assert sers.read("param.P0") == 0
    # the speed never drops to zero between the segments
    assert min(abs(v) for v in velocities) > 0


@pytest.mark.manual("§4.6.7", "P1123=1 when the next segment may be sent; without it before the current segment ends an error message follows and the drive stops")
def test_serial_polynomial_mode_p1123_and_missing_segment(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON\r")
    assert host.ask("#P1123?\r") == b"#P1123?\rP1123=0\n\r\nok1\n\r"
    host.ask("#WP=360 V=100 E\r")  # segment 1 runs
    assert host.ask("#P1123?\r") == b"#P1123?\rP1123=1\n\r\nok0\n\r"
    host.ask("#WP=360 E\r")  # segment 2 pending
    assert host.ask("#P1123?\r") == b"#P1123?\rP1123=0\n\r\nok0\n\r"
    reply = host.ask("#WP=360 E\r")  # the slot is occupied
    assert reply.endswith("\n*Polynomdaten Nachladen nicht möglich\n\r".encode("latin-1"))
    # nothing more comes: after segment 2 the drive brakes with B and reports errno 108
    sers.settle(timeout=30)
    assert sers.read("errno") == 108
    assert sers.read("param.P51") > 720


@pytest.mark.manual("§4.8.3.1", "errno 107 'Polynom mit Getriebespiel nicht erlaubt'")
def test_polynomial_not_with_backlash(plant_factory) -> None:
    plant = plant_factory({"params": {"P1037": 0.5}})
    reply = plant.host.ask("#ON WP=90 E\r")
    assert reply.endswith("\n*Polynom mit Getriebespiel nicht erlaubt\n\r".encode("latin-1"))


@pytest.mark.manual("§4.8.3.1", "errno 118 'Polynom Ende zu kurz zum Anhalten'")
def test_last_segment_too_short_to_brake(sers: Plant) -> None:
    sers.host.ask("#ON\r")
    sers.host.ask("#WP=3600 V=1000 A=1000 E\r")
    sers.host.ask("#WPT=1 B=2 E\r")  # 1° left at 1000 rpm with B = 2 rad/s²
    sers.settle(timeout=60)
    assert sers.read("errno") == 118


@pytest.mark.manual("§4.6.7", "in the last segment the drive changes to v6 with a6 and only then brakes with B "
                    "(\"Der letzte Abschnitt X6 wird durch die Beschleunigung a6, die Geschwindigkeit v6 und die "
                    "Bremsrampe B gebildet\")")
def test_last_segment_slows_to_its_speed_with_a_and_brakes_with_b(sers: Plant) -> None:
    host = sers.host
    rad = 12800 / (2 * math.pi)  # increments per radian
    host.ask("#ON WP=3600 V=600 A=100 E\r")  # 0 -> 20π rad/s with 100 rad/s², then 20π rad/s
    host.ask("#WPT=3600 A=50 B=100 V=300 E\r")  # 20π -> 10π rad/s with 50 rad/s², brake with 100
    dev = sers.runtime.device("sers")
    assert sers.runtime.run_until(lambda: dev.read("param.P51") >= 3600, 10)
    sers.advance(0.01)  # inside the change of speed of the last segment
    assert dev.model.axis.acceleration() == pytest.approx(-50 * rad)
    sers.settle()
    assert sers.read("param.P51") == pytest.approx(7200)
    v1, v2, x = 20 * math.pi, 10 * math.pi, 20 * math.pi  # rad/s, rad/s, rad per segment
    first = v1 / 100 + (x - v1**2 / 200) / v1
    last = (v1 - v2) / 50 + (x - (v1**2 - v2**2) / 100 - v2**2 / 200) / v2 + v2 / 100
    assert sers.runtime.now() - 2.0 == pytest.approx(first + last, abs=2e-3)
