"""Manual §4.6.6 and §4.8.4 (positioning, position data, speeds, accelerations, weighting, gear)
through the pty on virtual time; expected values computed from the manual's definitions."""

from __future__ import annotations

import math

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import number, query, refused

DEG = 12800 / 360  # increments per degree (§4.8.4.6: 12800 increments = 360° = one motor revolution)
INC = 1 / DEG  # one increment in degrees


@pytest.mark.manual("§4.8.4.2", "W range (rotational): -214748.3647 to +214748.3647 °")
def test_w_range_rotational(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#W=214748.3647\r").endswith(b"ok1\n\r")
    assert host.ask("#W=-214748.3647\r").endswith(b"ok1\n\r")
    refused(host, "#W=214748.3648\r", 1)
    refused(host, "#W=-214748.3648\r", 2)


@pytest.mark.manual("§4.8.4.2", "W range (incremental): -2147483639 to +2147483639 increments")
@pytest.mark.parametrize("weighting", [0, 64])
def test_w_range_incremental(sers: Plant, weighting: int) -> None:
    host = sers.host
    host.ask(f"#P76={weighting}\r")
    assert host.ask("#W=2147483639\r").endswith(b"ok1\n\r")
    assert host.ask("#W=-2147483639\r").endswith(b"ok1\n\r")
    assert query(host, "W") == "-2147483639inkr"
    refused(host, "#W=2147483640\r", 1)
    refused(host, "#W=-2147483640\r", 2)
    assert query(host, "W") == "-2147483639inkr"


@pytest.mark.manual("§4.8.3.1", "P12 64 'Lagegrenzwert Vorgabe - der vorgegebene Positionswert ist zu groß': a "
                    "relative move whose target lies beyond the position range is refused (errno 85 / 86)")
@pytest.mark.manual("§3.5", "'A' blinking: 'Warnung Positionsüberlauf' - W is too large for the position range")
@pytest.mark.parametrize(("start", "w", "errno"), [("200000", "100000", 85), ("-200000", "-100000", 86)])
def test_a_target_beyond_the_position_range_warns_with_p12_64(sers: Plant, start: str, w: str, errno: int) -> None:
    host = sers.host
    refused(host, f"#ON P51={start} W={w} E\r", errno)
    assert int(query(host, "P12")) & 64
    assert sers.read("display") == {"char": "A", "blinking": True}  # §3.5 'Warnung Positionsüberlauf'
    assert query(host, "POS") == "1"  # nothing moves
    assert host.ask("#P12=0\r").endswith(b"ok1\n\r")


@pytest.mark.manual("§4.8.6.2", "P1033 after a single stop and a new start of a positioning: 0 travels the whole W "
                    "anew (relative), 1 continues the interrupted positioning; after two stops 1 acts as 0")
@pytest.mark.parametrize(("p1033", "stops", "continued"), [(0, 1, False), (1, 1, True), (1, 2, False)])
def test_a_stopped_positioning_and_the_next_e(sers: Plant, p1033: int, stops: int, continued: bool) -> None:
    host = sers.host
    host.ask(f"#P1033={p1033} ON V=600 A=1000 WR=3600 E\r")
    sers.advance(0.4)
    for _ in range(stops):
        host.ask("#S\r")  # (the second while the drive brakes)
    sers.settle()
    stopped_at = sers.read("param.P51")
    assert 1000 < stopped_at < 3000
    assert host.ask("#E\r").endswith(b"ok0\n\r")
    sers.settle()
    assert sers.read("param.P51") == pytest.approx(3600 if continued else stopped_at + 3600, abs=INC)


@pytest.mark.manual("§4.8.4.2", "WR (P1051) is W and sets P1014=0 (relative); WA (P1052) is W and sets P1014=2 "
                    "(absolute)")
def test_wr_and_wa_set_the_positioning_mode(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON WA=90 E\r")
    sers.settle()
    assert query(host, "P1014") == "2"
    host.ask("#WA=90 E\r")  # absolute: already there
    sers.settle()
    assert number(host, "P51") == 90
    host.ask("#WR=90 E\r")
    sers.settle()
    assert query(host, "P1014") == "0"
    assert number(host, "P51") == 180


@pytest.mark.manual("§4.8.4.2", "P51 can be given any value (e.g. P51=1000)")
def test_p51_can_be_set(sers: Plant) -> None:
    host = sers.host
    host.ask("#P51=1000\r")
    assert number(host, "P51") == pytest.approx(1000, abs=1 / DEG)  # (whole increments)
    host.ask("#ON WA=1090 E\r")
    sers.settle()
    assert sers.read("axis.position") == pytest.approx(90 * DEG)


@pytest.mark.manual("§4.8.4.2", "P51 is 0 after switching on unless stored with POSSAVE")
def test_p51_is_zero_after_power_on(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON W=90 E\r")
    sers.settle()
    sers.runtime.power_cycle(sers.name)
    sers.advance(2.0)
    assert number(host, "P51") == 0


@pytest.mark.manual("§4.8.4.2", "P1058=1: below U_B (undervoltage error in P11) POSSAVE is executed")
def test_p1058_saves_the_position_on_undervoltage(plant_factory, tmp_path) -> None:
    plant = plant_factory({"params": {"P1058": 1}}, state_dir=tmp_path)
    host = plant.host
    host.ask("#ON W=90 E\r")
    plant.settle()
    plant.set("quantity.supply_voltage", 40.0)  # below U_B 43 of the .85 class (§2.1.4)
    plant.set("quantity.supply_voltage", 0.0)  # the supply goes
    plant.set("quantity.supply_voltage", 68.0)  # and comes back: a power-on
    plant.advance(2.0)
    assert number(host, "P51") == 90


@pytest.mark.manual("§4.8.4.2", "P1043=3 executes POSR also without an error P11=32 or warning P12=32")
def test_p1043_3_posr_without_a_step_loss(plant_factory) -> None:
    plant = plant_factory({"options": ["E50"], "params": {"P1053": 8, "P1029": 1}})
    host = plant.host
    host.ask("#ON W=90\r")  # setpoint P47 = 90, not started
    assert host.ask("#P1043=3\r").endswith(b"ok0\n\r")
    plant.settle()
    assert number(host, "P51") == 90


@pytest.mark.manual("§4.8.4.3", "V at most 10000 rpm (rotational weighting)")
@pytest.mark.manual("§4.8.4.4", "A at most 100000 rad/s² (rotational weighting)")
def test_v_and_a_maxima(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#V=10000 A=100000\r").endswith(b"ok1\n\r")
    refused(host, "#V=10000.1\r", 122)
    refused(host, "#A=100001\r", 120)


@pytest.mark.manual("§4.8.4.3", "P108 feedrate override 0..100 %: the homing speed P41 and the jog speeds "
                    "P1019/P1020 are multiplied by it (not V)")
def test_feedrate_override_scales_jog_not_v(sers: Plant) -> None:
    host = sers.host
    host.ask("#P108=50 P1035=0 ON RF\r")
    sers.advance(2.0)
    fast = 300 * 12800 / 60  # P1020 default 300 rpm
    assert sers.read("axis.velocity") == pytest.approx(fast * 0.5)
    host.ask("#S\r")
    sers.settle()
    host.ask("#V=60 W=3600 E\r")
    sers.advance(1.0)
    assert sers.read("axis.velocity") == pytest.approx(60 * 12800 / 60)
    refused(host, "#P108=101\r", 1)


@pytest.mark.manual("§4.6.6", "A and V written while positioning take effect only for the next positioning")
def test_v_written_during_a_move_waits_for_the_next(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON V=60 W=3600 E\r")
    sers.advance(1.0)
    host.ask("#V=120\r")
    sers.advance(0.5)
    assert sers.read("axis.velocity") == pytest.approx(60 * 12800 / 60)
    sers.settle()
    host.ask("#W=3600 E\r")
    sers.advance(2.0)
    assert sers.read("axis.velocity") == pytest.approx(120 * 12800 / 60)


@pytest.mark.manual("§4.6.6", "P1015 = 1 while the drive accelerates (or brakes); P1016 = 1 while it runs at "
                    "constant speed")
@pytest.mark.manual("§4.8.3.2", "P1015 accelerating or braking -> 1; P1016 constant speed -> 1")
def test_phase_flags(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON V=600 A=100 W=3600 E\r")
    sers.advance(0.1)
    assert (query(host, "P1015"), query(host, "P1016")) == ("1", "0")
    for _ in range(100):  # (virtual time, in steps: the constant phase starts between events)
        if sers.read("axis.velocity") == pytest.approx(600 * 12800 / 60):
            break
        sers.advance(0.05)
    assert (query(host, "P1015"), query(host, "P1016")) == ("0", "1")
    sers.settle()
    assert (query(host, "P1015"), query(host, "P1016")) == ("0", "0")


@pytest.mark.manual("§4.8.4.6", "P76=0 incremental: 12800 increments = one motor revolution")
@pytest.mark.manual("§4.8.4.6", "P76=2 rotational: 360° = one motor revolution (4 decimals)")
@pytest.mark.parametrize(("p76", "w", "revolutions", "answer"), [(0, "12800", 1, "12800inkr"),
                                                               (2, "360", 1, "360°")])
def test_position_weighting(plant_factory, p76: int, w: str, revolutions: float, answer: str) -> None:
    plant = plant_factory({"params": {"P76": p76}})
    host = plant.host
    host.ask(f"#ON W={w} E\r")
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(revolutions * 12800)
    assert query(host, "P51") == answer


@pytest.mark.manual("§4.8.4.6", "P76=66 rotational referred to the load: the gear P121/P122 is included")
@pytest.mark.manual("§4.8.4.7", "gear ratio = P121 / P122, e.g. 8:1 -> P121=8, P122=1")
def test_rotational_weighting_at_the_load(plant_factory) -> None:
    plant = plant_factory({"params": {"P76": 66, "P121": 8, "P122": 1}})
    plant.host.ask("#ON W=45 E\r")  # 45° at the load = 8 × 45° = one motor revolution
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(12800)


@pytest.mark.manual("§4.8.4.6", "P160 weighting of the acceleration data: 2 rad/s² at the motor, 66 rad/s² at the "
                    "load, 1 mm/s² and 17 in/s² translational (gear and feed constant included); 3 decimals, "
                    "in/s² 5")
@pytest.mark.parametrize(("p160", "answer", "motor_rad_s2"), [
    (2, "12.346rad/s²", 12.5), (66, "12.346rad/s²", 2 * 12.5),  # gear 2:1
    (1, "12.346mm/s²", 12.5 / 5 * 2 * 2 * math.pi),  # 5 mm per spindle revolution = 2 motor revolutions
    (17, "12.34568in/s²", 12.5 * 25.4 / 5 * 2 * 2 * math.pi),  # an inch is 25.4 mm, P123 in mm (P76 not 17)
])
def test_acceleration_weighting(plant_factory, p160: int, answer: str, motor_rad_s2: float) -> None:
    plant = plant_factory({"params": {"P160": p160, "P121": 2, "P122": 1, "P123": 5}})
    host = plant.host
    assert host.ask("#A=12.3456789\r").endswith(b"ok1\n\r")
    assert query(host, "A") == answer
    host.ask("#ON P76=0 P44=0 V=1000 A=12.5 W=1000000 E\r")  # (increments and rpm at the motor: A alone weighted)
    plant.advance(0.1)
    assert plant.read("axis.velocity") / 12800 * 2 * math.pi / 0.1 == pytest.approx(motor_rad_s2, rel=1e-6)


@pytest.mark.manual("§4.8.4.7", "feed constant P123: spindle pitch 5 mm per revolution -> P123=5 "
                    "(translational weighting P76=1)")
def test_feed_constant(plant_factory) -> None:
    plant = plant_factory({"params": {"P76": 1, "P123": 5}})
    plant.host.ask("#ON W=10 E\r")  # 10 mm = 2 spindle revolutions
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(2 * 12800)
    assert query(plant.host, "P51") == "10mm"


@pytest.mark.manual("§4.8.4.4", "P1030: the drive is braked with this deceleration on a drive error")
def test_error_deceleration(plant_factory) -> None:
    plant = plant_factory({"params": {"P1030": 500}})
    plant.host.ask("#ON V=600 W=36000 E\r")
    plant.advance(2.0)
    speed = plant.read("axis.velocity")
    plant.set("input.limit_right", True)
    took = plant.settle()
    assert took == pytest.approx((speed / 12800 * 2 * math.pi) / 500, abs=1e-3)
