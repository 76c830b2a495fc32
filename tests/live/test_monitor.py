"""devsim monitor: the textual app against a real control server (headless pilot), and the
`devsim monitor` command in a real terminal (tmux), with a `devsim run` subprocess behind it."""

from __future__ import annotations

import asyncio
import socket
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from devsim.core.registry import kinds
from devsim.observe.monitor import DevicePanel, MonitorApp
from devsim.runtime import Runtime
from devsim.runtime.control import ControlServer
from devsim.transports.tcp import TcpTransport
from tests.support.programs import needs_library

ROOT = Path(__file__).resolve().parents[2]
SCREENSHOT = ROOT / "docs" / "monitor.png"


@pytest.fixture
def plant() -> Iterator[tuple[Runtime, str, tuple[str, int]]]:
    """A virtual-time SERS on a TCP port, with a control server."""
    runtime = Runtime(virtual=True).start()
    device = runtime.add_device("sers")
    transport = TcpTransport(port=0)
    runtime.serve_sync(device, transport)
    server = ControlServer(runtime, "127.0.0.1:0")
    address = server.start_sync()
    runtime.advance(3)  # booted
    host, _, port = transport.url.removeprefix("socket://").rpartition(":")
    try:
        yield runtime, str(address), (host, int(port))
    finally:
        server.close_sync()
        runtime.stop()


async def until(pilot: object, predicate: Callable[[], bool], timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError("the monitor did not show it in time")
        await pilot.pause(0.05)  # type: ignore[attr-defined]


async def test_monitor_headless(plant: tuple[Runtime, str, tuple[str, int]]) -> None:
    runtime, address, host_port = plant
    noon = time.mktime((2026, 1, 1, 12, 0, 0, 0, 1, -1))  # the picture's wall time: 12:00:00
    app = MonitorApp(address, refresh=0.05, wall_clock=lambda: noon)
    async with app.run_test(size=(120, 28)) as pilot:
        panel = app.query_one("#dev-sers", DevicePanel)
        await until(pilot, lambda: "axis.position" in panel.values)
        assert panel.values["axis.position"] == 0.0
        # a host moves the drive over its line: telegrams both ways, a sparkline, move events
        with socket.create_connection(host_port, timeout=5) as host:
            host.sendall(b"#ON W=2000 E\r")
            answer = b""
            while b"ok" not in answer:
                answer += host.recv(100)
            await pilot.press("a")  # 0.1 s of virtual time from the key
            await until(pilot, lambda: runtime.now() >= 3.1)
            await asyncio.to_thread(runtime.advance, 2.0)
            await until(pilot, lambda: panel.values.get("axis.position", 0) > 1000)
            await until(pilot, lambda: len(panel.history["axis"]) >= 3)
            assert list(panel.history["axis"]) == sorted(panel.history["axis"])  # moving forward
            await until(pilot, lambda: any(t["dir"] == "D>H" and "ok" in t["text"] for t in panel.telegrams.get("main", [])))
            texts = [t["text"] for t in panel.telegrams["main"]]
            assert '"#ON W=2000 E\\r"' in texts
        # an input lamp flipped with a press
        assert runtime.read("sers", "input.I1") is False
        assert await pilot.click("#in-input_I1")
        assert runtime.read("sers", "input.I1") is True
        await asyncio.to_thread(runtime.advance, 0.2)
        await until(pilot, lambda: panel.values.get("input.I1") is True)
        # and one flipped from the keyboard: focus moves with Tab, Enter flips
        app.query_one("#in-input_I1").focus()
        await pilot.press("tab", "enter")
        assert runtime.read("sers", "input.I2") is True
        # a fault from the menu: f, pick "sers: blocked_axis on"
        await pilot.press("f")
        await pilot.pause()
        menu = app.screen.query_one("#faults")
        labels = [str(menu.get_option_at_index(i).prompt) for i in range(menu.option_count)]  # type: ignore[attr-defined]
        index = labels.index("sers: blocked_axis on")
        assert "sers.main: line unplug on" in labels
        menu.highlighted = index  # type: ignore[attr-defined]
        await pilot.press("enter")
        await until(pilot, lambda: "blocked_axis" in panel.faults)
        state = str(panel.query_one("#state").render())
        assert "blocked_axis" in state
        app.save_screenshot(filename="monitor.svg", path=str(SCREENSHOT.parent))
    svg = SCREENSHOT.with_suffix(".svg")
    needs_library("cairo")  # cairosvg's C library
    import cairosvg

    cairosvg.svg2png(url=str(svg), write_to=str(SCREENSHOT))
    svg.unlink()
    assert SCREENSHOT.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


async def test_monitor_on_a_realtime_scenario(tmp_path: Path) -> None:
    """A real-time scenario with --control waits for input I2; the monitor's lamp sets it."""
    from .run import Proc

    path = tmp_path / "wait.yaml"
    path.write_text("devices:\n  - {name: x, kind: sers, config: {address: 1, boot_time: 0.05}}\nsteps:\n"
                    "  - when: {device: x, name: input.I2, equals: true}\n    timeout: 60s\n")
    run = Proc("scenario", "run", "--realtime", "--control", f"unix:{tmp_path}/s.sock", str(path))
    try:
        addr = run.expect(lambda line: line.startswith("control: ")).split()[-1]
        app = MonitorApp(addr, refresh=0.05)
        async with app.run_test(size=(120, 50)) as pilot:
            panel = app.query_one("#dev-x", DevicePanel)
            await until(pilot, lambda: panel.values.get("input.I2") is False)
            await pilot.wait_for_scheduled_animations()
            await pilot.pause()  # laid out: the lamp has its place on the screen
            assert await pilot.click("#in-input_I2")
            await until(pilot, lambda: app.sub_title.startswith("the simulator stopped"), timeout=30)
        assert await asyncio.to_thread(run.proc.wait, 30) == 0
        assert run.expect(lambda line: line.startswith("PASSED")).startswith("PASSED: 1 of 1 checks passed")
    finally:
        run.stop()


async def test_monitor_shows_every_kind() -> None:
    """One plant of every kind: a panel each, with its axes, lamps and faults in the menu."""
    runtime = Runtime(virtual=True).start()
    shipped = sorted(kinds())
    for kind in shipped:
        runtime.add_device(kind)
    server = ControlServer(runtime, "127.0.0.1:0")
    address = server.start_sync()
    try:
        app = MonitorApp(str(address), refresh=0.05)
        async with app.run_test(size=(160, 120)) as pilot:
            panels = {kind: app.query_one(f"#dev-{kind}", DevicePanel) for kind in shipped}
            assert panels["poselesta"].axes == ["axis.x", "axis.y", "axis.z", "axis.d"]
            assert panels["pcd4h3"].axes == ["axis.1", "axis.2"]
            for panel in panels.values():
                await until(pilot, lambda panel=panel: all(f"{axis}.position" in panel.values for axis in panel.axes))
                assert panel.inputs, panel.device
            await pilot.press("f")
            await pilot.pause()
            menu = app.screen.query_one("#faults")
            labels = [str(menu.get_option_at_index(i).prompt) for i in range(menu.option_count)]  # type: ignore[attr-defined]
            assert "pcd4h3: blocked_1 on" in labels and "poselesta: following_error on" in labels
    finally:
        server.close_sync()
        runtime.stop()


def test_monitor_without_a_simulator(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from devsim.cli import cli, exits

    result = CliRunner().invoke(cli, ["monitor", "--control", f"unix:{tmp_path}/none.sock"])
    assert result.exit_code == exits.UNREACHABLE
    assert f"cannot connect to unix:{tmp_path}/none.sock" in result.output
    # (inf and 0.0001 passed 'period > 0': the simulator refused the monitor's watches, unsaid, and
    # each device's view just ended)
    for period, said in (("inf", "inf is not a finite number"), ("0.0001", "0.0001 is not in the range x>=0.001"),
                         ("nan", "nan is not a finite number"), ("0", "0.0 is not in the range x>=0.001")):
        result = CliRunner().invoke(cli, ["monitor", "--control", "unix:/x.sock", "--period", period])
        assert result.exit_code == exits.USAGE and f"Invalid value for '--period': {said}" in result.output, period
