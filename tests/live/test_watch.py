"""The control API's watch stream, `devsim ctl watch` and the stderr log of `devsim run`, with
real processes: a `devsim run` simulator, a host on its TCP port, pyserial's RFC 2217 client."""

from __future__ import annotations

import json
import socket
from pathlib import Path

import serial

from devsim.runtime.client import ControlClient

from .run import Proc, ctl


def _start(tmp_path: Path, *extra: str) -> tuple[Proc, str, tuple[str, int]]:
    sim = Proc("run", "sers", "--tcp", "0", "--virtual", "--control", f"unix:{tmp_path}/ctl.sock", *extra)
    url = sim.expect(lambda line: line.startswith("sers: tcp ")).split()[-1]
    addr = sim.expect(lambda line: line.startswith("control: ")).split()[-1]
    host, _, port = url.removeprefix("socket://").rpartition(":")
    with ControlClient(addr) as client:
        client.advance(3)  # booted
    return sim, addr, (host, int(port))


def _move(host_port: tuple[str, int]) -> socket.socket:
    host = socket.create_connection(host_port, timeout=10)
    host.sendall(b"#ON W=2000 E\r")
    answer = b""
    while b"ok" not in answer:
        answer += host.recv(100)
    return host


def test_ctl_watch_streams_changes_and_events(tmp_path: Path) -> None:
    sim, addr, host_port = _start(tmp_path)
    watch = Proc("ctl", "--control", addr, "watch", "sers", "axis.position", "input.I1", "--json")
    text = Proc("ctl", "--control", addr, "watch", "sers", "axis.position")
    try:
        first = json.loads(watch.expect(lambda line: '"axis.position"' in line))
        assert first == {"t": 3.0, "device": "sers", "type": "change", "name": "axis.position", "value": 0.0}
        assert text.expect(lambda line: "axis.position" in line) == "3.000 sers axis.position 0.0"
        host = _move(host_port)
        assert json.loads(watch.expect(lambda line: '"connect"' in line))["port"] == "main"
        assert json.loads(watch.expect(lambda line: '"move_start"' in line))["t"] == 3.0
        client = ControlClient(addr)
        client.set("sers", "input.I1", True)
        client.advance(1)
        seen = json.loads(watch.expect(lambda line: '"axis.position"' in line))
        assert seen["t"] == 3.1 and seen["value"] > 0
        assert json.loads(watch.expect(lambda line: '"input.I1"' in line))["value"] is True
        client.advance(30)
        assert json.loads(watch.expect(lambda line: '"move_end"' in line))["type"] == "event"
        assert ctl(addr, "fault", "sers", "blocked_axis", "on").returncode == 0  # (ctl's own fault command)
        fault = json.loads(watch.expect(lambda line: '"fault"' in line))
        assert (fault["name"], fault["active"]) == ("blocked_axis", True)
        assert text.expect(lambda line: " fault " in line).endswith("sers fault blocked_axis on")
        host.close()
        assert json.loads(watch.expect(lambda line: '"disconnect"' in line))["text"] == "host disconnected"
        client.close()
        assert text.stop() == 0  # Ctrl-C ends a watch quietly
        assert text.err.get(timeout=10) is None  # (nothing on stderr)
        # the simulator stops: the other watcher ends by itself, status 0
        assert sim.stop() == 0
        assert watch.proc.wait(timeout=15) == 0
    finally:
        for proc in (watch, text, sim):
            proc.stop()


def test_client_watch_and_telegrams(tmp_path: Path) -> None:
    sim, addr, host_port = _start(tmp_path)
    try:
        with ControlClient(addr) as client:
            assert client.telegrams("sers") == []  # kept from now on
            stream = client.watch("sers", ["axis.position"], timeout=10)
            assert next(stream)["value"] == 0.0
            with _move(host_port):
                got = client.telegrams("sers")
            assert [t["dir"] for t in got] == ["H>D", "D>H"]
            assert got[0]["text"] == '"#ON W=2000 E\\r"' and "ok0" in got[1]["text"]
            assert got[0]["decoded"] == ["#ON W=2000 E\r"]  # SERS lines, as record and replay cut them
            assert got[1]["decoded"] == ["#ON W=2000 E\r", "\nok0\n\r"]
            assert next(item for item in stream if item["type"] == "event")["name"] == "move_start"
            stream.close()
            assert client.now() == 3.0  # the client still answers
    finally:
        sim.stop()


def test_a_late_watch_starts_with_the_faults_already_on(tmp_path: Path) -> None:
    """A monitor or web page that attaches after a fault was switched on still shows it: the
    stream begins with every device fault and line fault active at that moment."""
    sim, addr, _ = _start(tmp_path)
    try:
        with ControlClient(addr) as client:
            client.fault("sers", "blocked_axis", True)
            client.fault("sers", "emergency_stop", True)
            client.fault("sers", "emergency_stop", False)
            client.line_fault("sers", "noise", rate=5)
            stream = client.watch("sers", ["axis.position"], timeout=10)
            first = [next(stream) for _ in range(3)]
            stream.close()
        assert [(item["type"], item.get("name")) for item in first[:2]] == \
            [("fault", "blocked_axis"), ("line_fault", None)]
        assert first[0]["active"] is True
        assert first[1]["port"] == "main" and first[1]["text"].startswith("fault start: noise")
        assert first[2]["name"] == "axis.position"
    finally:
        sim.stop()


def test_run_logs_connects_mismatch_and_levels(tmp_path: Path) -> None:
    sim = Proc("run", "sers", "--rfc2217", "0", "--virtual", "--control", f"unix:{tmp_path}/ctl.sock")
    quiet = Proc("run", "sers", "--rfc2217", "0", "--virtual", "-q")
    try:
        url = sim.expect(lambda line: line.startswith("sers: rfc2217 ")).split()[-1]
        sim.expect(lambda line: line.startswith("control: "))
        # pyserial's RFC 2217 client opens the port at 4800 baud: the drive runs at 9600
        with serial.serial_for_url(url, baudrate=4800, timeout=5):
            assert sim.expect(lambda line: "connect" in line, err=True) == "devsim: 0.000 sers connect host connected"
            line = sim.expect(lambda line: "host_settings" in line, err=True)
            assert "4800 8N1 (mismatch, device 9600 8N1)" in line
        assert sim.expect(lambda line: "disconnect" in line, err=True).endswith("sers disconnect host disconnected")
        quiet_url = quiet.expect(lambda line: line.startswith("sers: rfc2217 ")).split()[-1]
        with serial.serial_for_url(quiet_url, baudrate=4800, timeout=5):
            line = quiet.expect(lambda line: line.startswith("devsim: 0.000"), err=True)
            assert "mismatch" in line  # -q: the mismatch, not the connect before it
        quiet.stop()
        rest = []
        while (item := quiet.err.get(timeout=10)) is not None:
            rest.append(item)
        assert not any("connect" in item for item in rest), rest
    finally:
        sim.stop()
        quiet.stop()


def test_watch_through_up_workers(tmp_path: Path) -> None:
    """`devsim up --workers 2`: the proxy hands a watch to the worker holding the device; the
    workers log their connects on stderr."""
    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n"
                     "  - {name: a, kind: sers, transport: {tcp: {port: 0}}, config: {boot_time: 0.05}}\n"
                     "  - {name: b, kind: sers, transport: {tcp: {port: 0}}, config: {boot_time: 0.05}}\n")
    up = Proc("up", str(plant), "--workers", "2", "--control", f"unix:{tmp_path}/up.sock")
    try:
        ports = {}
        for _ in range(2):
            line = up.expect(lambda line: " tcp " in line)
            ports[line.split(":")[0]] = line.split()[-1]
        addr = up.expect(lambda line: line.startswith("control: ")).split()[-1]
        with ControlClient(addr) as client:
            streams = {name: client.watch(name, ["input.I1"], timeout=10) for name in ("a", "b")}
            assert [next(streams[name])["value"] for name in ("a", "b")] == [False, False]
            client.set("b", "input.I1", True)
            item = next(item for item in streams["b"] if item["type"] == "change")
            assert (item["device"], item["name"], item["value"]) == ("b", "input.I1", True)
            host, _, port = ports["a"].removeprefix("socket://").rpartition(":")
            with socket.create_connection((host, int(port)), timeout=10):
                assert next(item for item in streams["a"] if item["type"] == "connect")["port"] == "main"
                assert up.expect(lambda line: "connect" in line, err=True).endswith("a connect host connected")
            for stream in streams.values():
                stream.close()
            assert client.read("a", "input.I1") is False  # the proxy still answers
    finally:
        up.stop()


def test_log_levels_on_a_drive_error() -> None:
    """What each level logs when a SERS sees a short circuit (a drive error: P11, EMCY code)."""
    from devsim.observe.live_log import attach_log, level_of
    from devsim.runtime import Runtime

    assert [level_of(0, 0), level_of(1, 0), level_of(0, 1), level_of(0, 5), level_of(9, 0)] == [2, 3, 1, 0, 3]
    runtime = Runtime(virtual=True).start()
    try:
        runtime.add_device("sers")
        runtime.advance(3)
        logs: dict[int, list[str]] = {level: [] for level in range(4)}
        for level, lines in logs.items():
            runtime.call(attach_log, runtime, level, lines.append)
        runtime.set("sers", "quantity.short_circuit", True)
        runtime.advance(0.2)
        runtime.fault("sers", "emergency_stop", True)  # a declared fault switched: -v only
        errors = ["devsim: 3.000 sers error P11 128: drive error: short circuit",
                  "devsim: 3.000 sers drive_fault axis 1 code 0x2320"]
        assert logs[0] == []
        assert logs[1] == logs[2] == errors
        assert logs[3] == [*errors, "devsim: 3.200 sers fault emergency_stop on"]
    finally:
        runtime.stop()


def test_a_log_below_v_makes_no_item_for_a_refused_command() -> None:
    """A host's command the drive refuses (``P11=5``: error 3) is logged at -v only, and the lower
    levels' streams make no item for it at all (raw noise has the drive refuse thousands a second);
    the bare ``error`` event that follows the coded one stays unsaid either way."""
    from devsim.observe.live_log import attach_log
    from devsim.runtime import Runtime
    from devsim.runtime.watch_stream import WatchStream

    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers")
        runtime.advance(3)
        logs: dict[int, list[str]] = {level: [] for level in (1, 2, 3)}
        for level, lines in logs.items():
            runtime.call(attach_log, runtime, level, lines.append)
        items: dict[bool, list[dict]] = {True: [], False: []}
        for refused, sent in items.items():
            stream = WatchStream(runtime, device, sent.append, values=False, refused=refused)
            runtime.call(stream.start)
        runtime.call(device.feed, b"#P11=5\r")
        runtime.advance(0.1)
        assert logs[1] == logs[2] == []
        assert logs[3] == ["devsim: 3.000 sers refused 3: ungültig — invalid"]
        assert [(item["type"], item["code"]) for item in items[True]] == [("refused", "3")]
        assert items[False] == []
    finally:
        runtime.stop()


def test_watch_protocol_by_hand() -> None:
    """The documented wire form with a bare socket: the answer, then stream lines tagged with the
    request's id; errors are ordinary error answers; other requests still get answered."""
    from devsim.runtime import Runtime
    from devsim.runtime.control import ControlServer

    runtime = Runtime(virtual=True).start()
    runtime.add_device("sers")
    server = ControlServer(runtime, "127.0.0.1:0")
    address = server.start_sync()
    try:
        with socket.create_connection((address.host, address.port), timeout=10) as sock:
            lines = sock.makefile("rwb")

            def ask(request: dict[str, object]) -> dict[str, object]:
                lines.write(json.dumps(request).encode() + b"\n")
                lines.flush()
                return json.loads(lines.readline())

            assert ask({"id": 1, "op": "watch", "device": "nope"})["type"] == "UnknownDevice"
            assert ask({"id": 2, "op": "watch", "device": "sers", "names": ["nope"]})["type"] == "UnknownName"
            assert ask({"id": 3, "op": "watch", "device": "sers", "period": 0})["type"] == "BadRequest"
            tiny = ask({"id": 4, "op": "watch", "device": "sers", "period": 1e-9})  # (it sampled 1e9 times a second)
            assert tiny["type"] == "BadRequest" and "from 0.001 on" in str(tiny["error"]), tiny
            answer = ask({"id": "w", "op": "watch", "device": "sers", "names": ["input.I2"], "period": 0.5})
            assert answer == {"id": "w", "ok": True,
                              "result": {"device": "sers", "names": ["input.I2"], "period": 0.5, "t": 0.0}}
            assert json.loads(lines.readline()) == {"watch": "w", "t": 0.0, "device": "sers", "type": "change",
                                                    "name": "input.I2", "value": False}
            assert ask({"id": 5, "op": "set", "device": "sers", "name": "input.I2", "value": True}) == {
                "id": 5, "ok": True, "result": None}
            # the change is sampled while time advances: its line comes before the answer
            assert ask({"id": 6, "op": "advance", "seconds": 1}) == {"watch": "w", "t": 0.5, "device": "sers",
                                                                      "type": "change", "name": "input.I2",
                                                                      "value": True}
            assert json.loads(lines.readline()) == {"id": 6, "ok": True, "result": 1.0}
    finally:
        server.close_sync()
        runtime.stop()
