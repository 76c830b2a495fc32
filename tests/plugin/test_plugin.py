"""The pytest plugin: device and plant fixtures, scenarios as tests, async use, no leaks."""

from __future__ import annotations

import asyncio
import gc
import os
import re
import textwrap
import threading
from pathlib import Path

import pytest
import serial

import devsim.pytest_plugin as plugin
from devsim.pytest_plugin import DeviceFactory, PlantFactory, SimDevice

pytest_plugins = ["pytester"]  # (a non-root conftest may not define pytest_plugins)

ACK = re.compile(rb"\n(ok\d|pgm)\n\r|\n\*[^\n]*\n\r")
HERE = Path(__file__).parent


def ask(port: serial.SerialBase, line: bytes) -> bytes:
    """Send a line, read up to its acknowledgement or error message."""
    port.write(line)
    reply = b""
    while not ACK.search(reply):
        byte = port.read(1)
        assert byte, f"no answer to {line!r}; got {reply!r}"
        reply += byte
    return reply


def fd_count() -> int:
    gc.collect()  # ports that earlier tests dropped without closing
    return len(os.listdir("/proc/self/fd"))


def run_inner(pytester: pytest.Pytester, *args: str) -> pytest.RunResult:
    """An inner session in this process (hypothesis' plugin is left out: pytester restores
    sys.modules after each run, so it would be imported again every time)."""
    return pytester.runpytest_inprocess(
        "-p", "no:cacheprovider", "-p", "no:hypothesispytest", "-o", "asyncio_default_fixture_loop_scope=function", *args
    )


def runtime_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "devsim-runtime" and t.is_alive()]


# -- registration --------------------------------------------------------------------------------
def test_registered_through_the_pytest11_entry_point(pytestconfig: pytest.Config) -> None:
    from importlib.metadata import entry_points

    assert any(ep.value == "devsim.pytest_plugin" for ep in entry_points(group="pytest11"))
    assert pytestconfig.pluginmanager.get_plugin("devsim") is plugin
    assert any(line.startswith("devsim_scenario(") for line in pytestconfig.getini("markers"))


# -- devsim_device -----------------------------------------------------------------------------------
def test_device_on_a_pty_is_booted_and_answers(devsim_device) -> None:
    drive = devsim_device("sers")
    assert isinstance(drive, SimDevice)
    assert drive.name == "sers" and drive.kind == "sers"
    assert drive.port == drive.url == drive.address and drive.port.startswith("/dev/")
    assert os.path.exists(drive.port)
    assert drive.virtual and drive.now() == pytest.approx(2.0)  # '-' for 2 s after power-on
    assert drive.read("booting") is False
    with serial.Serial(drive.port, 9600, timeout=2) as port:
        assert ask(port, b"#ON\r") == b"#ON\r\nok1\n\r"
    assert drive.read("energized") is True
    assert drive.state()["energized"] is True
    assert drive.runtime.ports["sers"] == drive.port


def test_boot_false_leaves_the_device_booting(devsim_device) -> None:
    drive = devsim_device("sers", boot=False)
    assert drive.now() == 0.0
    assert drive.read("display")["char"] == "-"
    drive.wait_booted()
    assert drive.now() == pytest.approx(2.0)
    assert drive.read("display")["char"] != "-"


def test_config_set_advance_run_until(devsim_device) -> None:
    drive = devsim_device("sers", {"address": 3, "axis": {"limit_right": 64000}})
    port = drive.open_serial()
    assert port.baudrate == 9600
    assert ask(port, b"#3 ON W=3600 E\r") == b"#3 ON W=3600 E\r\nok0\n\r"
    start = drive.now()
    assert drive.advance(0.25) == pytest.approx(start + 0.25)
    assert drive.run_until(lambda device: device.read("P11") == 8192, 30)
    assert drive.read("axis.position") == pytest.approx(64000)
    assert drive.run_until(lambda device: device.read("motion.kind") is None, 10)
    assert ask(port, b"#E\r") == b"#E\r\n*Endschalter offen\n\r"
    assert drive.run_until(lambda device: False, 0.5) is False
    drive.set("input.limit_right", False)
    assert drive.read("input.limit_right") is False


def test_power_cycle_boots_again_and_keeps_the_eeprom(devsim_device, tmp_path) -> None:
    drive = devsim_device("sers", state_dir=tmp_path)
    port = drive.open_serial()
    assert ask(port, b"#ON V=500 PSAVE\r").endswith(b"ok1\n\r")
    assert (tmp_path / "sers.nvram.json").exists()
    before = drive.now()
    drive.power_cycle()
    assert drive.now() == pytest.approx(before + 2.0)
    assert drive.read("energized") is False
    assert ask(port, b"#V?\r") == b"#V?\rV=500U/min\n\r\nok1\n\r"
    drive.power_cycle(wipe=True, boot=False)
    assert drive.read("display")["char"] == "-"
    drive.wait_booted()
    assert ask(port, b"#V?\r") == b"#V?\rV=100U/min\n\r\nok1\n\r"


def test_several_devices_each_with_its_own_port(devsim_device) -> None:
    a = devsim_device("sers")
    b = devsim_device("sers", {"address": 2})
    c = devsim_device("sers", name="z")
    assert [a.name, b.name, c.name] == ["sers", "sers2", "z"]
    assert len({a.port, b.port, c.port}) == 3
    with a.open_serial() as pa, b.open_serial() as pb:
        assert ask(pa, b"#1 ON\r").endswith(b"ok1\n\r")
        assert ask(pb, b"#2 P11?\r") == b"#2 P11?\rP11=0\n\r\nok1\n\r"
    assert a.read("energized") is True and b.read("energized") is False


def test_ports_that_declare_a_network_transport_keep_it(devsim_device) -> None:  # noqa: ANN001
    """The PCD4.H3's Ether-S-Bus ports are UDP and TCP, as in a plant (they were ptys), whatever
    serves its serial S-Bus port."""
    for transport in ("pty", "tcp"):
        pcd = devsim_device("pcd4h3", transport=transport, name=f"pcd-{transport}")
        assert pcd.port_url("ether_udp").startswith("udp://127.0.0.1:"), transport
        assert pcd.port_url("ether_tcp").startswith("socket://127.0.0.1:"), transport
        assert pcd.port_url("sbus").startswith("/dev/pts/" if transport == "pty" else "socket://"), transport


def test_tcp_and_rfc2217_urls(devsim_device) -> None:
    tcp = devsim_device("sers", transport="tcp")
    rfc = devsim_device("sers", transport={"rfc2217": {"port": 0}}, name="rfc")
    assert tcp.url.startswith("socket://127.0.0.1:") and tcp.port == tcp.url
    assert rfc.url.startswith("rfc2217://127.0.0.1:")
    assert tcp.address == tcp.url.removeprefix("socket://")
    for device in (tcp, rfc):
        port = serial.serial_for_url(device.url, baudrate=9600, timeout=2)
        try:
            assert ask(port, b"#ON\r") == b"#ON\r\nok1\n\r"
        finally:
            port.close()
        assert device.read("energized") is True


def test_pty_with_a_stable_link(devsim_device, tmp_path) -> None:
    link = tmp_path / "ttySERS"
    drive = devsim_device("sers", transport={"pty": {"link": str(link)}})
    assert drive.port == str(link) and os.path.realpath(link) == drive.address
    drive.stop()
    assert not os.path.lexists(link)


def test_bad_arguments_fail_without_leaking(devsim_device) -> None:
    threads = len(runtime_threads())
    with pytest.raises(ValueError):
        devsim_device("sers", {"baud": 1234})
    with pytest.raises(ValueError):
        devsim_device("sers", transport="usb")
    with pytest.raises(ValueError):
        devsim_device("sers", transport={"bus": "x"})
    assert len(runtime_threads()) == threads


def test_real_time_device(devsim_device) -> None:
    drive = devsim_device("sers", {"boot_time": 0.05}, virtual=False)
    assert not drive.virtual and drive.read("booting") is False
    with pytest.raises(RuntimeError):
        drive.advance(1.0)
    with drive.open_serial() as port:
        assert ask(port, b"#ON\r") == b"#ON\r\nok1\n\r"


# -- async tests (pytest-asyncio, asyncio_mode=auto) ---------------------------------------------------
async def test_async_host_over_tcp(devsim_device) -> None:
    drive = devsim_device("sers", transport="tcp")
    reader, writer = await asyncio.open_connection(drive.transport.host, drive.transport.port)
    try:
        writer.write(b"#ON W=360 E\r")
        assert await asyncio.wait_for(reader.readuntil(b"ok0\n\r"), 5) == b"#ON W=360 E\r\nok0\n\r"
        drive.advance(5.0)  # sync control call inside the test's loop: the simulator has its own
        writer.write(b"#POS?\r")
        assert await asyncio.wait_for(reader.readuntil(b"ok1\n\r"), 5) == b"#POS?\rPOS=1\n\r\nok1\n\r"
    finally:
        writer.close()
        await writer.wait_closed()


async def test_async_pyserial_host_in_a_thread(devsim_device) -> None:
    drive = devsim_device("sers")

    def host() -> bytes:
        with serial.Serial(drive.port, 9600, timeout=2) as port:
            return ask(port, b"#P11?\r")

    assert await asyncio.to_thread(host) == b"#P11?\rP11=0\n\r\nok1\n\r"
    assert drive.now() == pytest.approx(2.0)


# -- devsim_plant ----------------------------------------------------------------------------------
def test_plant_from_a_file_next_to_the_test(devsim_plant) -> None:
    from devsim.scenario.plant import Plant

    plant = devsim_plant("scenarios/plant.yaml")
    assert isinstance(plant, Plant)
    assert set(plant.devices) == {"x", "y1", "y2"}
    assert set(plant.transports) == {"x", "line"}
    assert plant.now() == pytest.approx(2.0)
    with serial.Serial(plant.port("x"), 9600, timeout=2) as port:
        assert ask(port, b"#ON H\r") == b"#ON H\r\nok0\n\r"
    assert plant.run_until(lambda p: p.devices["x"].read("homed"), 20)
    assert plant.read("x", "axis.position") == pytest.approx(1280)
    plant.set("y2", "input.I1", True)
    assert plant.read("y2", "input.I1") is True
    assert plant.state("y2")["input"]["I1"] is True
    with serial.Serial(plant.port("line"), 9600, timeout=2) as port:
        assert ask(port, b"#2 ON\r") == b"\nok1\n\r"  # P1017=2: no echo, ok at the line end
    assert plant.read("y2", "energized") is True and plant.read("y1", "energized") is False
    y2 = plant.device("y2")
    assert y2.port == plant.port("line") and y2.read("energized") is True
    start = plant.now()
    assert plant.advance(1.5) == pytest.approx(start + 1.5)


def test_plant_from_a_dict(devsim_plant) -> None:
    plant = devsim_plant({"devices": [{"name": "d", "kind": "sers", "transport": {"tcp": {}}}]}, boot=False)
    assert plant.port("d").startswith("socket://127.0.0.1:")
    assert plant.read("d", "booting") is True
    plant.power_cycle("d")
    assert plant.describe() == [f"d: tcp {plant.port('d')}"]


def test_plant_errors_name_the_file(devsim_plant, tmp_path) -> None:
    from devsim.core.config import ConfigError

    bad = tmp_path / "bad.yaml"
    bad.write_text("devices:\n  - name: d\n    kind: sers\n    config: {baud: 1234}\n")
    with pytest.raises(ConfigError, match=r"bad.yaml:4: devices.1.config.baud"):
        devsim_plant(bad)


# -- scenarios -------------------------------------------------------------------------------------
@pytest.mark.devsim_scenario("scenarios/move.yaml")
def test_marker_scenario_result(devsim_scenario_result) -> None:
    assert devsim_scenario_result.passed
    assert devsim_scenario_result.mode == "virtual"
    assert devsim_scenario_result.sim_time > 0.5


@pytest.mark.devsim_scenario(
    {"devices": [{"name": "d", "kind": "sers"}],
     "steps": [{"send": "#P11?\r"}, {"expect": "#P11?\rP11=0\n\r\nok1\n\r"}]}
)
def test_marker_scenario_from_a_dict() -> None:
    pass  # the marker alone runs the scenario; a failure would fail this test


# -- leaks -------------------------------------------------------------------------------------------
def test_explicit_factories_leave_nothing_behind(tmp_path) -> None:
    before_fds, before_threads = fd_count(), len(runtime_threads())
    devices, plants = DeviceFactory(), PlantFactory(HERE)
    drive = devices("sers")
    devices("sers", transport="tcp").open_serial()
    devices("sers", transport="rfc2217").open_serial()
    plant = plants("scenarios/plant.yaml")
    port = drive.open_serial()
    assert ask(port, b"#ON\r").endswith(b"ok1\n\r")
    paths = [drive.address, plant.path("x"), plant.path("line")]
    assert all(os.path.exists(p) for p in paths)
    assert len(runtime_threads()) == before_threads + 4
    devices.close()
    plants.close()
    assert not port.is_open
    assert len(runtime_threads()) == before_threads
    assert not any(os.path.exists(p) for p in paths)
    assert fd_count() == before_fds
    assert drive.runtime._loop is None and drive.runtime._stopped.is_set()


def test_no_leaks_after_a_test_session(pytester: pytest.Pytester) -> None:
    """An inner session uses every fixture; afterwards ptys, threads and fds are gone."""
    record = pytester.path / "paths.txt"
    pytester.makeini("[pytest]\nasyncio_mode = auto\nasyncio_default_fixture_loop_scope = function\n")
    pytester.makefile(".yaml", plant="devices:\n  - {name: p, kind: sers}\n")
    pytester.makepyfile(
        test_inner=f"""
        import asyncio
        import pytest
        import threading

        RECORD = {str(record)!r}

        def note(*paths):
            with open(RECORD, "a") as f:
                for p in paths:
                    f.write(p + "\\n")

        def test_devices(devsim_device):
            a = devsim_device("sers")
            b = devsim_device("sers", transport="tcp")
            a.open_serial().write(b"#ON\\r")   # left open: the plugin closes it
            b.open_serial()
            note(a.address)

        def test_plant(devsim_plant):
            plant = devsim_plant("plant.yaml")
            note(plant.path("p"))

        async def test_async(devsim_device):
            d = devsim_device("sers", transport="rfc2217")
            await asyncio.sleep(0)
            note(d.device.name)

        def test_failing_test_still_cleans_up(devsim_device):
            note(devsim_device("sers").address)
            assert False, "on purpose"

        def test_threads_of_earlier_tests_are_gone():
            assert [t for t in threading.enumerate() if t.name == "devsim-runtime"] == []
        """
    )
    before_fds, before_threads = fd_count(), len(runtime_threads())
    result = run_inner(pytester, "-q")
    result.assert_outcomes(passed=4, failed=1)
    paths = [p for p in record.read_text().split() if p.startswith("/")]
    assert len(paths) == 3
    assert not any(os.path.exists(p) for p in paths)
    assert len(runtime_threads()) == before_threads
    assert fd_count() == before_fds


# -- scenarios as tests (inner sessions) --------------------------------------------------------------
PASSING = """\
devices:
  - {name: d, kind: sers}
steps:
  - send: "#ON\\r"
  - expect: "#ON\\r\\nok1\\n\\r"
"""

FAILING = """\
devices:
  - {name: d, kind: sers}
steps:
  - send: "#ON\\r"
  - expect: "#ON\\r\\nok9\\n\\r"
  - expect_state: {device: d, name: energized, equals: false}
"""


def test_collected_scenario_files(pytester: pytest.Pytester) -> None:
    pytester.makefile(".yaml", scenario_good=PASSING, scenario_bad=FAILING, other=FAILING)
    pytester.makefile(".yml", scenario_short=PASSING)
    pytester.makefile(".yaml", scenario_invalid="devices:\n  - {name: d, kind: sers}\nsteps:\n  - bogus: 1\n")
    result = run_inner(pytester, "-v")
    result.assert_outcomes(passed=2, failed=2)
    result.stdout.fnmatch_lines(
        [
            "*scenario_bad.yaml::scenario_bad FAILED*",
            "*scenario_good.yaml::scenario_good PASSED*",
            "*scenario_invalid.yaml::scenario_invalid FAILED*",
            "*scenario_short.yml::scenario_short PASSED*",
        ]
    )
    text = result.stdout.str()
    # the failure is the scenario report, not a traceback
    assert "scenario scenario_bad" in text and "FAILED: 0 of 2 checks passed" in text
    assert "expected b'#ON\\r\\nok9\\n\\r'" in text
    assert "scenario_invalid.yaml:4: steps.1" in text
    assert "Traceback" not in text and "devsim/pytest_plugin.py" not in text


def test_collecting_scenarios_can_be_turned_off(pytester: pytest.Pytester) -> None:
    pytester.makeini("[pytest]\ndevsim_collect_scenarios = false\n")
    pytester.makefile(".yaml", scenario_bad=FAILING)
    result = run_inner(pytester)
    result.assert_outcomes()


def test_marker_runs_and_fails_with_the_report(pytester: pytest.Pytester) -> None:
    pytester.makefile(".yaml", good=PASSING, bad=FAILING, invalid="devices:\n  - {name: d, kind: sers, bogus: 1}\n")
    pytester.makepyfile(
        textwrap.dedent(
            """
            import pytest

            @pytest.mark.devsim_scenario("good.yaml")
            def test_good(devsim_scenario_result):
                assert devsim_scenario_result.passed
                assert [s.status for s in devsim_scenario_result.steps] == ["done", "pass"]

            @pytest.mark.devsim_scenario("bad.yaml")
            def test_bad():
                raise AssertionError("never reached")

            @pytest.mark.devsim_scenario("bad.yaml", check=False)
            def test_bad_unchecked(devsim_scenario_result):
                assert not devsim_scenario_result.passed
                assert len(devsim_scenario_result.failures) == 2

            @pytest.mark.devsim_scenario(
                {"devices": [{"name": "d", "kind": "sers", "config": {"boot_time": 0.01}}],
                 "steps": [{"send": "#ON\\r"}, {"expect": "#ON\\r\\nok1\\n\\r"}]},
                mode="realtime",
            )
            def test_mode(devsim_scenario_result):
                assert devsim_scenario_result.mode == "realtime"

            @pytest.mark.devsim_scenario(
                {"devices": [{"name": "d", "kind": "sers"}],
                 "steps": [{"set": {"device": "d", "values": {"input.I1": True}}}, {"wait": "100s"},
                           {"expect_state": {"device": "d", "name": "input.I1", "equals": True}}]}
            )
            def test_no_host_runs_in_virtual_time(devsim_scenario_result):
                assert devsim_scenario_result.mode == "virtual"
                assert devsim_scenario_result.sim_time == 100

            @pytest.mark.devsim_scenario("invalid.yaml")
            def test_invalid():
                pass

            @pytest.mark.devsim_scenario({"devices": []})
            def test_invalid_dict():
                pass

            def test_result_needs_the_marker(devsim_scenario_result):
                pass
            """
        )
    )
    result = run_inner(pytester, "-W", "error::pytest.PytestUnknownMarkWarning", "--strict-markers",
                                          "-rA")
    result.assert_outcomes(passed=4, failed=1, errors=3)
    assert result.parseoutcomes().get("warnings", 0) == 0
    text = result.stdout.str()
    assert "never reached" not in text
    assert "scenario bad (" in text and "FAILED: 0 of 2 checks passed" in text
    assert "needs @pytest.mark.devsim_scenario" in text
    assert "invalid.yaml:2: devices.1.bogus" in text
    assert "devsim_scenario: 1 validation error" in text
    assert "PytestUnknownMarkWarning" not in text


def test_plugin_can_be_disabled(pytester: pytest.Pytester) -> None:
    pytester.makefile(".yaml", scenario_bad=FAILING)
    pytester.makepyfile("def test_x(devsim_device): pass")
    result = run_inner(pytester, "-p", "no:devsim")
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(["*fixture 'devsim_device' not found*"])


# -- the README -------------------------------------------------------------------------------------
def test_readme_example_is_the_test_file() -> None:
    root = HERE.parent.parent
    readme = (root / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Testing host software with pytest", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    example = (root / "tests" / "test_readme_example.py").read_text(encoding="utf-8")
    assert example in blocks


def test_a_dict_scenarios_steps_are_counted_from_1(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(
        """
        import pytest

        @pytest.mark.devsim_scenario({"devices": [{"name": "d", "kind": "sers"}],
                                      "steps": [{"wait": "1s"}, {"wait": "soon"}]})
        def test_bad_step(devsim_scenario_result):
            pass
        """
    )
    result = run_inner(pytester)
    result.assert_outcomes(errors=1)
    assert "  steps.2.wait: `wait` must be a duration like 2s or 150ms" in result.stdout.str()
