"""The out-of-process control API: JSON lines over Unix sockets and loopback TCP."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator

import pytest

from devsim.cli import exits
from devsim.runtime import Runtime
from devsim.runtime.client import ControlClient, ControlError
from devsim.runtime.control import ControlAddress, ControlAddressError, ControlServer, parse_address
from tests.support.process import ROOT, devsim_env

ECHO = "echo=tests.support.echo:EchoDevice"


@pytest.fixture(autouse=True)
def _echo_kind(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", ECHO)


@pytest.fixture
def sockdir() -> Iterator[str]:
    # A short directory: Unix socket paths are limited to ~100 bytes.
    with tempfile.TemporaryDirectory(prefix="dsc") as path:
        yield path


@pytest.fixture
def runtime() -> Iterator[Runtime]:
    rt = Runtime(virtual=True).start()
    rt.add_device("echo", "echo1", {"address": 4})
    rt.add_device("echo", "echo2")
    try:
        yield rt
    finally:
        rt.stop()


@pytest.fixture(params=["unix", "tcp"])
def served(request: pytest.FixtureRequest, runtime: Runtime, sockdir: str) -> Iterator[tuple[Runtime, str]]:
    addr = f"unix:{sockdir}/ctl.sock" if request.param == "unix" else "127.0.0.1:0"
    server = ControlServer(runtime, addr)
    bound = server.start_sync()
    try:
        yield runtime, str(bound)
    finally:
        server.close_sync()


def test_read_set_state_over_one_connection(served: tuple[Runtime, str]) -> None:
    runtime, addr = served
    with ControlClient(addr) as client:
        assert client.read("echo1", "address") == 4
        assert client.read("echo1", "input.mute") is False
        client.set("echo1", "input.mute", True)
        assert client.read("echo1", "input.mute") is True
        assert runtime.read("echo1", "input.mute") is True  # the same state as in process
        state = client.state("echo1")
        assert state["address"] == 4
        assert state["input"]["mute"] is True
        names = [d["name"] for d in client.devices()]
        assert names == ["echo1", "echo2"]
        assert {d["kind"] for d in client.devices()} == {"echo"}


def test_advance_moves_virtual_time_and_fires_timers(served: tuple[Runtime, str]) -> None:
    _, addr = served
    with ControlClient(addr) as client:
        assert client.now() == 0.0
        client.set("echo2", "timer", 1.5)
        assert client.advance(1.0) == pytest.approx(1.0)
        assert client.read("echo2", "fired") is False
        assert client.advance(0.5) == pytest.approx(1.5)
        assert client.read("echo2", "fired") is True
        assert client.now() == pytest.approx(1.5)


def test_power_cycle_with_and_without_wipe(served: tuple[Runtime, str]) -> None:
    _, addr = served
    with ControlClient(addr) as client:
        client.set("echo1", "nvram.note", "kept")
        client.power_cycle("echo1")
        assert client.read("echo1", "boots") == 2
        assert client.read("echo1", "nvram.note") == "kept"
        client.power_cycle("echo1", wipe=True)
        assert client.read("echo1", "nvram.note") is None


def test_errors_are_typed_and_the_connection_survives(served: tuple[Runtime, str]) -> None:
    _, addr = served
    with ControlClient(addr) as client:
        with pytest.raises(ControlError) as info:
            client.read("echo1", "no.such.name")
        assert info.value.type == "UnknownName"
        assert "no.such.name" in info.value.args[0]
        with pytest.raises(ControlError) as info:
            client.read("nobody", "address")
        assert info.value.type == "UnknownDevice"
        assert info.value.args[0].startswith("no device named 'nobody'")
        with pytest.raises(ControlError) as info:
            client.request("read", device="echo1")
        assert info.value.type == "BadRequest"
        with pytest.raises(ControlError) as info:
            client.request("explode")
        assert info.value.type == "BadRequest"
        with pytest.raises(ControlError) as info:
            client.line("echo1")  # not served on any line
        assert info.value.type == "UnknownName"
        assert client.read("echo1", "address") == 4


def test_advance_refused_on_a_real_clock(sockdir: str) -> None:
    rt = Runtime().start()
    try:
        server = ControlServer(rt, f"unix:{sockdir}/real.sock")
        server.start_sync()
        with ControlClient(str(server.address)) as client:
            with pytest.raises(ControlError) as info:
                client.advance(1)
            assert info.value.type == "RuntimeError"
            assert client.now() >= 0.0
        server.close_sync()
    finally:
        rt.stop()


def test_raw_protocol(served: tuple[Runtime, str]) -> None:
    _, addr = served
    parsed = parse_address(addr)
    if parsed.path is not None:
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.connect(parsed.path)
    else:
        sock = socket.create_connection((parsed.host, parsed.port))
    with sock, sock.makefile("rwb") as stream:

        def ask(payload: bytes) -> dict[str, object]:
            stream.write(payload + b"\n")
            stream.flush()
            return json.loads(stream.readline())

        assert ask(b'{"id": 1, "op": "read", "device": "echo1", "name": "address"}') == {
            "id": 1,
            "ok": True,
            "result": 4,
        }
        assert ask(b'{"id": "x", "op": "set", "device": "echo1", "name": "value", "value": 2.5}') == {
            "id": "x",
            "ok": True,
            "result": None,
        }
        reply = ask(b'{"id": 3, "op": "read", "device": "echo1", "name": "bogus"}')
        assert reply["ok"] is False and reply["type"] == "UnknownName" and reply["id"] == 3
        reply = ask(b"this is not json")
        assert reply == {"id": None, "ok": False, "error": reply["error"], "type": "BadRequest"}
        reply = ask(b'{"id": 5, "op": "now", "colour": "red"}')
        assert reply["type"] == "BadRequest" and reply["id"] == 5 and "colour" in str(reply["error"])
        reply = ask(b'{"id": 6, "op": "advance", "seconds": -1}')
        assert reply["type"] == "BadRequest"
        reply = ask(b'{"id": 8, "op": "read", "device": "echo1", "name": "value", "seconds": "abc"}')
        assert reply["type"] == "BadRequest" and "seconds" in str(reply["error"])  # another op's field, checked too
        assert ask(b'{"id": 7, "op": "read", "device": "echo1", "name": "value"}')["result"] == 2.5


def test_non_loopback_host_is_refused(runtime: Runtime) -> None:
    with pytest.raises(ControlAddressError, match="non-loopback"):
        ControlServer(runtime, "0.0.0.0:0")
    with pytest.raises(ControlAddressError, match="non-loopback"):
        ControlServer(runtime, "192.0.2.1:7000")
    ControlServer(runtime, "0.0.0.0:0", allow_remote=True)  # allowed when asked for (not started)
    ControlServer(runtime, "localhost:0")
    ControlServer(runtime, "[::1]:0")


def test_parse_address() -> None:
    assert parse_address("unix:/tmp/x.sock") == ControlAddress(path="/tmp/x.sock")
    assert parse_address("7000") == ControlAddress(host="127.0.0.1", port=7000)
    assert parse_address("tcp:localhost:7000") == ControlAddress(host="localhost", port=7000)
    assert parse_address("[::1]:7000") == ControlAddress(host="::1", port=7000)
    assert str(parse_address("[::1]:7000")) == "[::1]:7000"
    assert str(parse_address("unix:/a.sock")) == "unix:/a.sock"
    for bad in ("unix:", "x", "host:port", "99999", "[::1]7"):
        with pytest.raises(ControlAddressError):
            parse_address(bad)


@pytest.mark.parametrize("host", ["x" * 64, "a..b", "."])
def test_a_host_that_is_no_host_name_is_refused_in_one_line(host: str) -> None:
    """Found fuzzing devsim web --listen: a label over 63 characters (or empty) made getaddrinfo's
    IDNA encoding raise UnicodeError (not an OSError) in is_loopback or the connect:
    `devsim web --listen`, `devsim ctl --control` and `devsim run --control` ended with a traceback."""
    with pytest.raises(ControlAddressError, match="is no host name"):
        parse_address(f"{host}:1")
    for args in (["web", "--control", f"{host}:1"], ["ctl", "--control", f"{host}:1", "now"],
                 ["run", "sers", "--control", f"{host}:1"], ["web", "--control", "1", "--listen", f"{host}:1"]):
        done = subprocess.run([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=devsim_env(), capture_output=True,
                              text=True, timeout=30, stdin=subprocess.DEVNULL)
        assert done.stderr.startswith("Error: ") and done.stderr.count("\n") == 1, done.stderr  # (not a simulator's name either)
        assert done.returncode == (2 if "is no host name" in done.stderr else exits.UNREACHABLE), done.stderr


def test_stale_socket_is_replaced_but_a_live_one_is_not(runtime: Runtime, sockdir: str) -> None:
    path = os.path.join(sockdir, "s.sock")
    stale = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    stale.bind(path)
    stale.close()  # leaves the socket file behind, nobody listening
    first = ControlServer(runtime, f"unix:{path}")
    first.start_sync()
    try:
        with pytest.raises(ControlAddressError, match="another process"):
            ControlServer(runtime, f"unix:{path}").start_sync()
    finally:
        first.close_sync()
    assert not os.path.exists(path)


def test_clients_in_parallel(served: tuple[Runtime, str]) -> None:
    _, addr = served
    with ControlClient(addr) as a, ControlClient(addr) as b:
        a.set("echo1", "value", 1)
        b.set("echo2", "value", 2)
        assert a.read("echo2", "value") == 2
        assert b.read("echo1", "value") == 1


def _raw(addr: str, line: bytes) -> dict:
    path = addr.removeprefix("unix:")
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
        sock.settimeout(10)
        sock.connect(path)
        sock.sendall(line + b"\n")
        data = b""
        while not data.endswith(b"\n"):
            chunk = sock.recv(65536)
            assert chunk, "connection closed without an answer"
            data += chunk
        # the connection still serves the next request
        sock.sendall(b'{"id": 9, "op": "now"}\n')
        follow = b""
        while not follow.endswith(b"\n"):
            follow += sock.recv(65536)
        assert json.loads(follow)["ok"] is True
        return json.loads(data)


def test_hostile_requests_get_an_error_and_the_connection_lives(runtime: Runtime, sockdir: str) -> None:
    server = ControlServer(runtime, f"unix:{sockdir}/ctl.sock")
    addr = str(server.start_sync())
    try:
        deep = _raw(addr, b"[" * 100_000 + b"]" * 100_000)
        assert deep["type"] == "BadRequest" and "nested deeper than 64" in deep["error"]
        nested = {"id": 1, "op": "set", "device": "echo1", "name": "nvram.note", "value": {}}
        node = nested["value"]
        for _ in range(80):
            node["x"] = {}
            node = node["x"]
        assert "nested deeper" in _raw(addr, json.dumps(nested).encode())["error"]
        long_name = "n" * 900_000
        answer = _raw(addr, json.dumps({"id": 2, "op": "read", "device": "echo1", "name": long_name}).encode())
        assert answer["type"] == "UnknownName" and len(answer["error"]) < 400
        answer = _raw(addr, json.dumps({"id": 3, "op": "read", "device": long_name, "name": "x"}).encode())
        assert answer["type"] == "UnknownDevice" and len(answer["error"]) < 400
        nan = _raw(addr, b'{"id": 4, "op": "set", "device": "echo1", "name": "value", "value": NaN}')
        assert nan["type"] == "BadValue" and "finite" in nan["error"]
    finally:
        server.close_sync()


def test_advance_is_bounded(sockdir: str) -> None:
    rt = Runtime(virtual=True).start()
    try:
        with pytest.raises(ValueError, match="advance takes 0 … 1e\\+07 seconds"):
            rt.advance(1e308)
        assert rt.now() == 0.0  # the clock did not move (nor freeze)
        server = ControlServer(rt, f"unix:{sockdir}/v.sock")
        addr = str(server.start_sync())
        try:
            answer = _raw(addr, b'{"id": 1, "op": "advance", "seconds": NaN}')
            assert answer["type"] == "BadRequest" and "finite" in answer["error"]
            with ControlClient(addr) as client:
                assert client.advance(2.5) == 2.5
        finally:
            server.close_sync()
    finally:
        rt.stop()


def test_every_control_op_is_one_row_offered_by_ctl_the_clients_and_the_facades() -> None:
    """The op table is the one list of ops: ``devsim ctl`` has a command for each, each typed
    request belongs to one row, and the MQTT verbs are ops of the table."""
    from devsim.cli.ctl import command_name, ctl
    from devsim.facades.mqtt_topics import COMMANDS
    from devsim.runtime import requests as rq
    from devsim.runtime.ops import CONTROL, op_of

    ops = [row.token for row in CONTROL]
    assert sorted(ctl.commands) == sorted(command_name(op) for op in ops)
    kinds = [row.request for row in CONTROL]
    assert len(set(kinds)) == len(kinds) and all(issubclass(k, rq.ControlRequest) for k in kinds)
    assert all(callable(row.handler) and row.doc for row in CONTROL)
    assert op_of(rq.Read("d", "n")) == "read" and op_of(rq.SwitchFault("d", "k")) == "fault"
    assert set(COMMANDS) <= set(ops)


def test_typed_requests_run_in_process(runtime: Runtime) -> None:
    from devsim.runtime import requests as rq
    from devsim.runtime.ops import BadRequest, run

    run(runtime, rq.Set("echo1", "input.mute", True))
    assert run(runtime, rq.Read("echo1", "input.mute")) is True
    assert run(runtime, rq.Advance(1.0)) == 1.0
    with pytest.raises(BadRequest, match="finite"):
        run(runtime, rq.Advance(float("nan")))


def test_a_line_fault_refused_is_typed_as_the_control_api_types_refusals(runtime: Runtime, sockdir: str) -> None:
    """(They came as Python's ValueError and TypeError; an infinite count was taken.)"""
    from devsim.transports.pty import PtyTransport

    runtime.serve_sync(runtime.device("echo1"), PtyTransport())
    server = ControlServer(runtime, f"unix:{sockdir}/ctl.sock")
    address = str(server.start_sync())
    try:
        with ControlClient(address) as client:
            for kind, params, kind_of_error, words in [
                ("noise", {"rate": -5}, "BadValue", "rate must be positive"),
                ("noise", {"rate": 1e308}, "BadValue", "rate must be at most"),  # (the simulator hung)
                ("corrupt", {"count": float("inf")}, "BadValue", "count must be a whole number"),
                ("delay", {"delay": float("inf")}, "BadValue", "delay must be a finite number"),
                ("noise", {"rate": 5, "bogus": 1}, "BadRequest", "bogus"),
            ]:
                with pytest.raises(ControlError) as info:
                    client.request("line_fault", device="echo1", kind=kind, active=True, params=params)
                assert info.value.type == kind_of_error and words in info.value.args[0], (kind, params, info.value)
            assert client.line("echo1")["faults"] == []
    finally:
        server.close_sync()
