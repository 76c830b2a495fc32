"""The web page's server through a real ``devsim run sers --web`` (a subprocess): its JSON API,
its WebSocket and its guards, driven by aiohttp's client; the device driven through its pty."""

from __future__ import annotations

import asyncio
import socket
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import aiohttp
import pytest
import serial

from devsim.cli import exits
from devsim.runtime.client import ControlClient
from tests.support.process import ROOT, DevsimProcess, devsim_env, free_port
from tests.web.conftest import WebSim, answer, start_sers

JSON = {"Content-Type": "application/json"}


async def wait_for(get: Any, accept: Any, timeout: float, what: str) -> Any:
    """Ask ``get()`` until ``accept`` takes its answer (bounded by ``timeout``)."""
    deadline = asyncio.get_running_loop().time() + timeout
    while True:
        got = await get()
        if accept(got):
            return got
        if asyncio.get_running_loop().time() > deadline:
            raise AssertionError(f"no {what} within {timeout} s: last {got!r}")
        await asyncio.sleep(0.05)


async def test_the_plant_and_the_device_as_the_pages_show_them(sim: WebSim) -> None:
    async with aiohttp.ClientSession(sim.url) as http:
        plant = await (await http.get("/api/plant")).json()
        assert plant["name"] == "sers" and plant["attached"]
        (device,) = plant["devices"]
        assert (device["name"], device["kind"]) == ("sers", "sers")
        main = device["ports"]["main"]
        assert main["address"] == sim.pty  # what a host opens
        assert main["line"]["device"]["text"] == "9600 8N1" and main["line"]["host"] is None
        assert device["declared_faults"] == ["blocked_axis", "emergency_stop", "power"] and device["faults"] == []
        with serial.Serial(sim.pty, 9600, timeout=5) as port:
            answer(port, b"#1P11?\r")
            shown = await wait_for(lambda: _json(http.get("/api/plant")),
                                   lambda p: p["devices"][0]["ports"]["main"]["connected"], 5, "a host connected")
            assert shown["devices"][0]["ports"]["main"]["line"]["host"]["baudrate"] == 9600
        assert len(device["display"]) == 1  # the 7-segment digit, as the monitor shows it
        page = await (await http.get("/api/devices/sers")).json()
        assert {"axis.position", "axis.velocity"} <= set(page["charts"])
        assert any(p["name"] == "param.P91" and "w" in p["access"] for p in page["points"])  # V
        missing = await http.get("/api/devices/nope")
        assert missing.status == 404 and (await missing.json())["type"] == "UnknownDevice"
        with ControlClient(sim.control) as client:  # as the device is now, read anew (the device page's watch is over)
            assert (device["ready"], device["booting"]) == (client.read("sers", "ready"), client.read("sers", "booting"))
            client.set("sers", "quantity.supply_voltage", 40.0)  # below U_L: a drive error, not ready
            assert await wait_for(lambda: _json(http.get("/api/plant")), lambda p: p["devices"][0]["ready"] is False,
                                  5, "ready false on the plant page")
            client.set("sers", "quantity.supply_voltage", 68.0)
            client.power_cycle("sers")
            assert await wait_for(lambda: _json(http.get("/api/plant")), lambda p: p["devices"][0]["booting"] is True,
                                  5, "booting on the plant page")


async def _json(request: Any) -> Any:
    async with request as response:
        return await response.json()


async def test_a_set_is_checked_as_ctl_set_checks_it_and_reaches_the_device(sim: WebSim) -> None:
    async with aiohttp.ClientSession(sim.url) as http:
        refused = await http.post("/api/devices/sers/set", json={"name": "param.V", "value": "99999999"})
        assert refused.status == 422
        assert await refused.json() == {"error": "P91: errno 122: V zu gro\u00df", "type": "BadValue"}
        unknown = await http.post("/api/devices/sers/set", json={"name": "param.nope", "value": "1"})
        assert unknown.status == 422 and (await unknown.json())["type"] == "UnknownName"
        done = await http.post("/api/devices/sers/set", json={"name": "param.V", "value": "500"})
        assert done.status == 200
    with serial.Serial(sim.pty, 9600, timeout=5) as port:
        assert answer(port, b"#1V?\r") == b"#1V?\rV=500U/min\n\r\nok1\n\r"


async def test_a_body_that_is_no_json_object_is_a_bad_request(sim: WebSim) -> None:
    """Not JSON, not an object, or nested deeper than the decoder goes (that one answered 500 and
    logged a RecursionError's traceback): 400, and the page goes on."""
    async with aiohttp.ClientSession(sim.url) as http:
        for body in (b"{not json", b"[1]", b"[" * 100_000):
            refused = await http.post("/api/devices/sers/set", data=body, headers={"Content-Type": "application/json"})
            assert refused.status == 400, body[:10]
            assert await refused.json() == {"error": "the body: a JSON object", "type": "BadRequest"}
        assert (await http.post("/api/login", data=b"[" * 100_000, headers={"Content-Type": "application/json"})).status == 200
        assert (await http.post("/api/devices/sers/set", json={"name": "param.V", "value": "500"})).status == 200


def test_a_request_that_is_not_http_is_refused_in_one_line(sim: WebSim) -> None:
    """aiohttp answers a header it cannot parse with 400 and logged it with a traceback (a port
    scanner's or a broken client's request filled the simulator's stderr): now one line says it."""
    host, port = sim.url.split("//")[1].rstrip("/").rsplit(":", 1)
    for _ in range(2):
        with socket.create_connection((host, int(port)), timeout=10) as client:
            client.sendall(b"GET / HTTP/1.1\r\nHost: x\r\nContent-Length: abc\r\n\r\n")
            assert client.recv(4096).startswith(b"HTTP/1.0 400 Bad Request\r\n")
    before: list[str] = []
    told = sim.process.next_match(sim.process.err, lambda line: line.startswith("devsim web: "), 10, "the line",
                                  keep=before)
    assert told == ("devsim web: a request from 127.0.0.1 that is not HTTP as it should be (Invalid character in "
                    "Content-Length): answered 400 Bad Request")
    assert sim.process.next_match(sim.process.err, lambda line: line.startswith("devsim web: "), 10, "the line",
                                  keep=before) == told
    assert not any("Traceback" in line for line in before), before


def exchange(sim: WebSim | str, request: bytes, *, leave: bool = False) -> bytes:
    """``request`` sent raw to the page's server (of ``sim``, or at an ``http://HOST:PORT/``); its
    answer's status line (``b""`` if the client ``leave``s at once, closing the connection mid-request)."""
    url = sim if isinstance(sim, str) else sim.url
    host, port = url.split("//")[1].split("#")[0].rstrip("/").rsplit(":", 1)
    with socket.create_connection(("127.0.0.1" if host == "0.0.0.0" else host, int(port)), timeout=10) as client:
        client.sendall(request)
        if leave:
            return b""
        return client.recv(4096).split(b"\r\n", 1)[0]


def no_traceback_until_the_next_line(sim: WebSim) -> None:
    """A request aiohttp cannot parse makes one ``devsim web:`` line: nothing before it is a traceback."""
    assert exchange(sim, b"GET / HTTP/1.1\r\nHost: x\r\nContent-Length: abc\r\n\r\n").startswith(b"HTTP/1.0 400")
    before: list[str] = []
    sim.process.next_match(sim.process.err, lambda line: line.startswith("devsim web: a request"), 10, "the line",
                           keep=before)
    assert not any("Traceback" in line or "Error" in line for line in before), before


def test_a_host_or_origin_that_is_no_address_is_refused(sim: WebSim) -> None:
    """Found fuzzing a real devsim web: a Host header ``[`` (or ``[::1``), or a WebSocket's Origin
    ``http://[``, made urlsplit raise ValueError in the guards: 500 and a traceback on stderr.
    They are not the page's loopback name, nor its site: 403, and the page goes on."""
    for host in (b"[", b"[::1", b"[x]]"):
        assert exchange(sim, b"GET /api/plant HTTP/1.1\r\nHost: " + host + b"\r\n\r\n") == b"HTTP/1.1 403 Forbidden"
    port = sim.url.rstrip("/").rsplit(":", 1)[1].encode()
    upgrade = (b"GET /api/ws HTTP/1.1\r\nHost: 127.0.0.1:" + port + b"\r\nOrigin: http://[\r\nUpgrade: websocket\r\n"
               b"Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")
    assert exchange(sim, upgrade) == b"HTTP/1.1 403 Forbidden"
    no_traceback_until_the_next_line(sim)
    assert exchange(sim, b"GET /api/plant HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n") == b"HTTP/1.1 200 OK"


def test_a_body_in_an_unknown_charset_or_cut_off_is_a_bad_request(sim: WebSim) -> None:
    """Found fuzzing a real devsim web: ``Content-Type: application/json; charset=nope`` made the
    body's decoding raise LookupError (500, a traceback), and a client that left before its body
    was all sent made ConnectionResetError's traceback ('Error handling request').  The first is
    400 as any body that is no JSON object; the second answers nobody and logs nothing."""
    post = b"POST /api/devices/sers/set HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json; charset="
    assert exchange(sim, post + b"nope\r\nContent-Length: 2\r\n\r\n{}") == b"HTTP/1.1 400 Bad Request"
    for _ in range(3):
        exchange(sim, post + b"utf-8\r\nContent-Length: 100\r\n\r\n{\"name\"", leave=True)
    no_traceback_until_the_next_line(sim)
    body = b'{"name": "param.V", "value": "500"}'
    assert exchange(sim, post + b"utf-8\r\nContent-Length: %d\r\n\r\n%s" % (len(body), body)) == b"HTTP/1.1 200 OK"


async def test_faults_line_faults_and_power_cycle_go_to_the_device(sim: WebSim) -> None:
    async with aiohttp.ClientSession(sim.url) as http:
        assert (await http.post("/api/devices/sers/fault", json={"kind": "emergency_stop", "active": True})).status == 200
        with serial.Serial(sim.pty, 9600, timeout=5) as port:
            assert answer(port, b"#1ON W=100 E\r").endswith(b"\n*Stop Schalter ist offen\n\r")
        await wait_for(lambda: _json(http.get("/api/plant")), lambda p: p["devices"][0]["faults"] == ["emergency_stop"],
                       5, "the fault on the plant page")
        wrong = await http.post("/api/devices/sers/fault", json={"kind": "flood"})
        assert wrong.status == 422 and "declared: blocked_axis" in (await wrong.json())["error"]
        for typo in ("ture", 2):  # refused as by ctl (read as off, it switched the fault off)
            refused = await http.post("/api/devices/sers/fault", json={"kind": "emergency_stop", "active": typo})
            assert refused.status == 422, typo
        with ControlClient(sim.control) as client:
            assert client.read("sers", "input.stop") is True
        refused = await http.post("/api/devices/sers/power_cycle", json={"wipe": "yes please"})
        assert refused.status == 422  # (it wiped the memory)
        assert (await http.post("/api/devices/sers/line_fault", json={"kind": "noise", "port": "main"})).status == 200
        plant = await (await http.get("/api/plant")).json()
        assert plant["devices"][0]["ports"]["main"]["line"]["faults"] == ["noise"]
        assert (await http.post("/api/devices/sers/line_fault", json={"kind": "noise", "active": False})).status == 200
        plant = await (await http.get("/api/plant")).json()
        assert plant["devices"][0]["ports"]["main"]["line"]["faults"] == []
        assert (await http.post("/api/devices/sers/power_cycle", json={})).status == 200
        with ControlClient(sim.control) as client:
            assert client.read("sers", "booting") in (True, False)
        stream = await http.ws_connect("/api/ws?device=sers")
        snapshot = (await stream.receive_json(timeout=5))["snapshot"]["sers"]
        assert any(e["type"] == "event" and e["name"] == "power_on" for e in snapshot["events"]) or any(
            e["type"] == "fault" for e in snapshot["events"])
        await stream.close()


async def test_the_stream_carries_the_move_and_its_events(sim: WebSim) -> None:
    async with aiohttp.ClientSession(sim.url) as http:
        stream = await http.ws_connect("/api/ws?device=sers")
        first = await stream.receive_json(timeout=5)
        assert first["snapshot"]["sers"]["values"]["axis.position"] == 0
        assert "param.P91" not in first["snapshot"]["sers"]["values"]  # every point: only while a page looks
        with serial.Serial(sim.pty, 9600, timeout=5) as port:
            assert answer(port, b"#1ON W=36000 E\r").endswith(b"\nok0\n\r")
            positions: list[float] = []
            events: list[str] = []
            values: set[str] = set()
            while "move_start" not in events or not any(p > 0 for p in positions) or "param.P91" not in values:
                batch = await stream.receive_json(timeout=5)
                positions += [p["value"] for p in batch["points"] if p["name"] == "axis.position"]
                events += [e.get("name") for e in batch["events"]]
                values |= {v["name"] for v in batch["values"]}
                assert batch["dropped"] == 0  # a browser that keeps up loses nothing
        await stream.close()
        telegrams = await (await http.get("/api/devices/sers/telegrams?port=main&count=10")).json()
        assert [t["dir"] for t in telegrams[-2:]] == ["H>D", "D>H"]
        assert telegrams[-2]["text"] == '"#1ON W=36000 E\\r"' and telegrams[-2]["decoded"]
        for count in ("-1", "201", "99999999999999999999"):  # as ctl telegrams --count refuses them
            refused = await http.get(f"/api/devices/sers/telegrams?port=main&count={count}")
            assert refused.status == 422 and (await refused.json())["type"] == "BadRequest", count


async def test_requests_from_elsewhere_are_refused(sim: WebSim) -> None:
    async with aiohttp.ClientSession(sim.url) as http:
        form = await http.post("/api/devices/sers/set", data={"name": "param.V", "value": "5"})
        assert form.status == 415  # no form posted from another site
        rebound = await http.get("/api/plant", headers={"Host": "attacker.example:80"})
        assert rebound.status == 403  # DNS rebinding onto a loopback page
        with pytest.raises(aiohttp.WSServerHandshakeError) as info:
            await http.ws_connect("/api/ws", headers={"Origin": "http://attacker.example"})
        assert info.value.status == 403
        assert (await http.get("/")).status == 200
        script = await http.get("/static/app.js")
        assert script.status == 200 and "class Chart" in await script.text()


def non_loopback_address() -> str:
    """The machine's own non-loopback IPv4 address, else 0.0.0.0 (reached through 127.0.0.1)."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))  # no packet is sent: the route names the address
            address = str(probe.getsockname()[0])
        except OSError:
            return "0.0.0.0"
    return "0.0.0.0" if address.startswith("127.") else address


@pytest.fixture
def remote_sim() -> Any:
    host = non_loopback_address()
    with tempfile.TemporaryDirectory(prefix="dsw") as directory:
        process, seen, lines = start_sers("--control", f"unix:{directory}/c.sock", web=f"{host}:{free_port()}")
        try:
            yield host, seen, lines
        finally:
            assert process.interrupt() == 0


async def test_a_non_loopback_bind_needs_the_token_it_printed(remote_sim: Any) -> None:
    host, seen, lines = remote_sim
    token = seen["web token"]
    assert len(token) >= 20 and seen["web"].endswith(f"/#token={token}"), lines
    port = int(seen["web"].split("#")[0].rstrip("/").rsplit(":", 1)[1])
    connect = "127.0.0.1" if host == "0.0.0.0" else host
    jar = aiohttp.CookieJar(unsafe=True)  # keeps a cookie of an IP address, as a browser does
    async with aiohttp.ClientSession(f"http://{connect}:{port}", headers={"Host": f"{host}:{port}"},
                                     cookie_jar=jar) as http:
        assert (await http.get("/")).status == 200  # the page itself asks for the token
        for path in ("/api/plant", "/api/devices/sers", "/api/scenario", "/api/devices/sers/telegrams"):
            assert (await http.get(path)).status == 401, path
        assert (await http.post("/api/devices/sers/set", json={"name": "param.V", "value": "5"})).status == 401
        with pytest.raises(aiohttp.WSServerHandshakeError) as info:
            await http.ws_connect("/api/ws")
        assert info.value.status == 401
        assert (await http.get("/api/plant", headers={"X-Devsim-Token": token + "x"})).status == 401
        assert (await http.get("/api/plant", headers={"X-Devsim-Token": token})).status == 200
        assert (await http.post("/api/login", json={"token": "guess"})).status == 401
        assert (await http.post("/api/login", json={"token": token})).status == 200  # sets the cookie
        assert (await http.get("/api/plant")).status == 200
        stream = await http.ws_connect("/api/ws?device=sers")
        assert "snapshot" in await stream.receive_json(timeout=5)
        await stream.close()


def test_a_token_that_is_no_utf_8_is_a_wrong_token(remote_sim: Any) -> None:
    """Found fuzzing a real devsim run --web on a non-loopback bind: a token header or cookie of
    bytes that are no UTF-8 (aiohttp reads them as surrogate escapes), or a login's JSON token
    with a lone surrogate, made the comparison's encode() raise UnicodeEncodeError: 500 and a
    traceback.  It is a wrong token: 401."""
    host, seen, _lines = remote_sim
    url = seen["web"]
    for header in (b"X-Devsim-Token: \xff\xfe", b"Cookie: devsim_token=\xff"):
        assert exchange(url, b"GET /api/plant HTTP/1.1\r\nHost: " + host.encode() + b"\r\n" + header + b"\r\n\r\n") == \
            b"HTTP/1.1 401 Unauthorized"
    body = b'{"token": "\\udc80"}'
    login = b"POST /api/login HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: %d\r\n\r\n" % len(body)
    assert exchange(url, login + body) == b"HTTP/1.1 401 Unauthorized"
    token = seen["web token"].encode()
    assert exchange(url, b"GET /api/plant HTTP/1.1\r\nHost: " + host.encode() + b"\r\nX-Devsim-Token: " + token +
                    b"\r\n\r\n") == b"HTTP/1.1 200 OK"


def test_devsim_web_attaches_to_a_running_simulator_and_to_the_next_one(tmp_path: Path) -> None:
    control = f"unix:{tmp_path}/c.sock"
    sims = [DevsimProcess("run", "sers", "--control", control)]
    page = None
    try:
        sims[0].next_match(sims[0].out, lambda line: line == "sers: ready", 30, "sers: ready")
        page = DevsimProcess("web", "--control", control, "--listen", f"127.0.0.1:{free_port()}")
        url = page.next_match(page.out, lambda line: line.startswith("web: "), 30, "the page's address")[5:]

        async def kinds() -> list[str]:
            async with aiohttp.ClientSession(url) as http:
                plant = await wait_for(lambda: _json(http.get("/api/plant")),
                                       lambda p: p.get("attached") and not p["devices"][0]["ended"], 20, "a plant")
                return [device["kind"] for device in plant["devices"]]

        assert asyncio.run(kinds()) == ["sers"]
        assert sims[0].interrupt() == 0
        sims.append(DevsimProcess("run", "gms96", "--control", control))  # the same address, another simulator
        sims[1].next_match(sims[1].out, lambda line: line == "gms96: ready", 30, "gms96: ready")

        async def next_kinds() -> list[str]:
            async with aiohttp.ClientSession(url) as http:
                plant = await wait_for(lambda: _json(http.get("/api/plant")),
                                       lambda p: p.get("devices") and p["devices"][0]["kind"] == "gms96", 20,
                                       "the next simulator")
                return [device["kind"] for device in plant["devices"]]

        assert asyncio.run(next_kinds()) == ["gms96"]
    finally:
        if page is not None:
            assert page.interrupt() == 0
        for sim in sims:
            sim.interrupt()


@pytest.mark.parametrize(("args", "status", "words"), [
    (["--control", "unix:/nonexistent/devsim.sock"], exits.UNREACHABLE, "cannot connect"),
    (["--listen", "unix:/tmp/x.sock", "--control", "unix:/nonexistent/devsim.sock"], exits.USAGE, "not on a Unix"),
    (["--control", "unix:/a.sock", "--name", "x"], exits.USAGE, "exclude each other"),
])
def test_devsim_web_says_what_is_wrong(args: list[str], status: int, words: str) -> None:
    done = subprocess.run([sys.executable, "-m", "devsim", "web", *args], cwd=ROOT, env=devsim_env(),
                          capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == status and words in done.stderr, done.stderr


def test_run_refuses_a_web_page_without_control() -> None:
    done = subprocess.run([sys.executable, "-m", "devsim", "run", "sers", "--no-control", "--web", "0"], cwd=ROOT,
                          env=devsim_env(), capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == exits.USAGE and "--no-control" in done.stderr


def test_a_plain_run_does_not_import_the_web_server() -> None:
    code = ("import sys, devsim.cli.main, devsim.runtime.control, devsim.runtime.ops; "
            "print(sorted(m for m in sys.modules if m.startswith(('aiohttp', 'devsim.web'))))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=devsim_env(), capture_output=True, text=True,
                          timeout=60)
    assert done.stdout.strip() == "[]", done.stderr


SCENARIO = """\
name: web progress
devices:
  - name: x
    kind: sers
    config: {address: 1}
steps:
  - send: "#1 ON V=60 A=100 WA=90 E\\r"
  - expect: {regex: "\\nok0\\n\\r$"}
  - when: {device: x, name: param.P336, equals: 1}
    timeout: 2s
  - expect_state: {device: x, name: axis.position, approx: 3200, tolerance: 0.5}
  - wait: 60s
  - log: never reached while the test looks
"""


def test_scenario_run_publishes_its_steps_as_they_pass(tmp_path: Path) -> None:
    path = tmp_path / "progress.yaml"
    path.write_text(SCENARIO, encoding="utf-8")
    run = DevsimProcess("scenario", "run", "--realtime", str(path), "--control", f"unix:{tmp_path}/c.sock",
                        "--web", f"127.0.0.1:{free_port()}")
    try:
        url = run.next_match(run.out, lambda line: line.startswith("web: "), 30, "the page's address")[5:]

        async def check() -> dict[str, Any]:
            async with aiohttp.ClientSession(url) as http:
                return await wait_for(lambda: _json(http.get("/api/scenario")),
                                      lambda s: isinstance(s, dict) and s.get("done", 0) >= 4, 20, "four steps done")

        progress = asyncio.run(check())
        assert progress["name"] == "web progress" and progress["running"] and progress["total"] == 6
        assert [s["status"] for s in progress["steps"]][:4] == ["done", "pass", "pass", "pass"]
        assert progress["steps"][5]["status"] == "pending" and progress["end"] == 60.0
        with ControlClient(f"unix:{tmp_path}/c.sock") as client:
            assert client.request("scenario")["steps"][3]["label"] == "expect x.axis.position \u2248 3200.0 \u00b1 0.5"
    finally:
        run.proc.terminate()
        run.proc.wait(timeout=15)


def test_without_aiohttp_the_web_page_names_its_extra(tmp_path: Path) -> None:
    shadow = tmp_path / "shadow" / "aiohttp"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text("raise ImportError('aiohttp hidden by the test')\n")
    environ = devsim_env()
    environ["PYTHONPATH"] = f"{shadow.parent}:{ROOT}"
    for args in (["run", "sers", "--web", "0"], ["web", "--control", "unix:/nonexistent/x.sock"]):
        done = subprocess.run([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=environ, capture_output=True,
                              text=True, timeout=60, stdin=subprocess.DEVNULL)
        assert done.returncode == exits.SYSTEM, done.stderr
        assert "needs aiohttp: pip install '.[web]'" in done.stderr


@pytest.mark.parametrize("command", [["run", "sers"], ["up", "PLANT"]])
def test_a_web_port_in_use_is_a_system_failure(command: list[str], tmp_path: Path) -> None:
    import socket

    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n  - {name: x, kind: sers}\n", encoding="utf-8")
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        holder.listen()
        port = holder.getsockname()[1]
        args = [str(plant) if arg == "PLANT" else arg for arg in command]
        done = subprocess.run([sys.executable, "-m", "devsim", *args, "--control", f"unix:{tmp_path}/c.sock",
                               "--web", f"127.0.0.1:{port}"], cwd=ROOT, env=devsim_env(), capture_output=True,
                              text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == exits.SYSTEM, done.stderr
    assert "web page" in done.stderr and "in use" in done.stderr


async def test_a_device_page_asked_before_the_simulator_is_attached_waits_for_it(tmp_path: Path) -> None:
    """A browser may ask for a device the moment the server is up, before it has read the
    simulator's devices: the answer waits for them (bounded), it does not say the device is unknown."""
    from devsim.web.server import parse_listen, serve

    control = f"unix:{tmp_path}/c.sock"
    runner, view, port = await serve(control, parse_listen(f"127.0.0.1:{free_port()}"), None)
    sim = None
    try:
        async with aiohttp.ClientSession(f"http://127.0.0.1:{port}") as http:
            asked = asyncio.ensure_future(http.get("/api/devices/sers"))
            assert not view.attached.is_set()  # no simulator at the address yet
            sim = await asyncio.to_thread(DevsimProcess, "run", "sers", "--control", control)
            response = await asked
            assert response.status == 200, await response.text()
            assert (await response.json())["info"]["name"] == "sers"
    finally:
        await runner.cleanup()
        await view.close()
        if sim is not None:
            assert sim.interrupt() == 0
