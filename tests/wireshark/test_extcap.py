"""Live capture: the control op ``capture`` (every chunk as it crosses, with the line settings of
the moment; a bounded queue per subscriber that drops and counts instead of holding the device
back), ``devsim extcap`` (Wireshark's extcap interface) and ``devsim wireshark --install``, and
tshark capturing a running simulator's pty through the installed launcher."""

from __future__ import annotations

import io
import os
import struct
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import serial

from devsim.observe.plot_data import read_pcap_trace
from devsim.runtime import Runtime
from devsim.runtime.capture_stream import MAX_BYTES, CaptureStream
from devsim.runtime.client import CaptureSubscription, ControlClient, ControlError
from devsim.runtime.control import ControlServer
from devsim.runtime.discovery import Simulator
from devsim.transports.pcap import parse_serial_header
from devsim.transports.pty import PtyTransport
from devsim.wireshark.extcap import dlt_line, interface_lines, interfaces, main, parse_interface
from devsim.wireshark.installer import LAUNCHER, extcap_dir, launcher_text, parse_folders
from tests.support.process import ROOT, devsim_env, wait_until
from tests.support.programs import needs_program
from tests.test_cli import Sim
from tests.wireshark.test_capture import end_session, tshark_env, tshark_records


# -- the pure parts of the extcap ----------------------------------------------------------------
def _simulator(**info: Any) -> Simulator:
    return Simulator(**{"address": "unix:/x.sock", "name": "plant", "pid": 4242, **info})


def test_every_captured_port_of_every_answering_simulator_is_an_interface() -> None:
    plant = _simulator(devices=["cnc", "a.b"], captures={
        "cnc.v7": {"link": 147, "protocol": 3, "port_byte": 7}, "a.b": {"link": 147, "protocol": 1, "port_byte": 0},
        "pcd.ether_udp": {"link": 228, "protocol": 0, "port_byte": 0}})
    silent = _simulator(pid=7, answering=False, captures={"x": {"link": 147}})
    found = interfaces([plant, silent])
    assert [i.name for i in found] == ["devsim-4242-a.b", "devsim-4242-cnc.v7", "devsim-4242-pcd.ether_udp"]
    assert [i.device_port() for i in found] == [("a.b", "main"), ("cnc", "v7"), ("pcd", "ether_udp")]
    lines = interface_lines(found)
    assert lines[0].startswith("extcap {version=")
    assert lines[2] == "interface {value=devsim-4242-cnc.v7}{display=devsim cnc.v7 (serial line of plant, pid 4242)}"
    assert dlt_line(147) == "dlt {number=147}{name=USER0}{display=devsim serial line (USER0)}"
    assert dlt_line(228) == "dlt {number=228}{name=IPV4}{display=Raw IPv4}"
    assert parse_interface("devsim-4242-cnc.v7") == (4242, "cnc.v7")
    assert parse_interface("devsim-1-a-b") == (1, "a-b")
    for wrong in ("eth0", "devsim-x-sers", "devsim-12", "other-12-sers"):
        with pytest.raises(ValueError, match="not a devsim capture interface"):
            parse_interface(wrong)


def test_the_installer_reads_wiresharks_folders_and_writes_a_launcher() -> None:
    folders = parse_folders("Temp:                \t/tmp\nPersonal configuration:\t/h/.config/wireshark\n"
                            "Personal Lua Plugins:\t/h/.local/lib/wireshark/plugins\n"
                            "MaxMind database path:\t/a\nMaxMind database path:\t/b\n")
    assert folders["Personal Lua Plugins"] == "/h/.local/lib/wireshark/plugins" and folders["MaxMind database path"] == "/a"
    assert extcap_dir(folders) == Path("/h/.config/wireshark/extcap")  # Wireshark 4.0: the configuration's
    assert extcap_dir({**folders, "Personal Extcap path": "/h/.local/lib/wireshark/extcap"}) == Path(
        "/h/.local/lib/wireshark/extcap")  # 4.2 and later name it
    text = launcher_text("/opt/py 3/bin/python", "/src/devsim")
    assert text.startswith("#!/bin/sh\n") and "exec '/opt/py 3/bin/python' -m devsim extcap \"$@\"" in text
    assert "PYTHONPATH=/src/devsim${PYTHONPATH:+:$PYTHONPATH}" in text
    assert "PYTHONPATH" not in launcher_text("/usr/bin/python3", None)


def test_an_unsafe_runtime_directory_lists_no_interfaces(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "devsim").mkdir(mode=0o777)
    (tmp_path / "devsim").chmod(0o777)  # open to others: no control socket there is trusted
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    out = io.StringIO()
    assert main(["--extcap-interfaces"], out) == 0
    assert out.getvalue().splitlines() == interface_lines([])
    assert "is open to others" in capsys.readouterr().err


def test_extcap_config_and_a_foreign_interface() -> None:
    out = io.StringIO()
    assert main(["--extcap-interface", "devsim-1-x", "--extcap-config"], out) == 0 and out.getvalue() == ""
    assert main(["--extcap-interface", "eth0", "--extcap-dlts"], out) == 1


# -- the capture op ------------------------------------------------------------------------------
@pytest.fixture
def served() -> Any:
    runtime = Runtime(virtual=True).start()
    device = runtime.add_device("sers", "sers")
    transport = PtyTransport()
    line = runtime.serve_sync(device, transport)
    server = ControlServer(runtime, "127.0.0.1:0")
    address = str(server.start_sync())
    runtime.advance(2.5)  # booted
    yield runtime, line, transport, address
    server.close_sync()
    runtime.stop()


def test_the_capture_op_streams_each_chunk_with_the_host_settings(served: Any) -> None:
    runtime, line, transport, address = served
    with pytest.raises(ControlError, match="no port 'nope'"):
        CaptureSubscription(address, "sers", "nope")
    with CaptureSubscription(address, "sers", timeout=10) as stream, ControlClient(address) as control:
        assert stream.info == {"device": "sers", "port": "main", "link": 147, "protocol": 1, "port_byte": 0, "t": 2.5}
        assert control.line("sers")["capturing"] == 1
        host = serial.Serial(transport.address, 4800, timeout=0.2)  # the drive runs at 9600: a mismatch
        try:
            host.write(b"#RF\r")
            items = iter(stream)
            item = next(items)
        finally:
            host.close()
        assert item == {"type": "chunk", "device": "sers", "port": "main", "t": 2.5, "dir": "H>D", "data": "2352460d",
                        "settings": {**item["settings"], "baud": 4800, "stop": 1.0, "mismatch": True}}
    with ControlClient(address) as control:  # the server notices the closed connection
        wait_until(lambda: not control.line("sers")["capturing"], "end of the capture with its connection", 10.0)
    assert runtime.call(lambda: line.tracer) is None  # the line has its fast path back


def test_a_subscriber_that_does_not_read_loses_chunks_counted_and_the_device_goes_on(served: Any) -> None:
    runtime, line, _transport, _address = served

    def start() -> CaptureStream:
        stream = CaptureStream(runtime, "sers", limit=3)
        stream.start()
        return stream

    stream = runtime.call(start)
    for n in range(10):  # what the host sends, as the pty hands it over: the device answers each
        runtime.call(lambda n=n: line.feed(f"#P{n}?\r".encode()))
    assert runtime.call(lambda: line.bytes_out) > 0  # it answered meanwhile
    batch = runtime.call(stream.take)
    assert [(i["dir"], bytes.fromhex(i["data"])) for i in batch[:3]] == [
        ("H>D", b"#P0?\r"), ("D>H", bytes.fromhex(batch[1]["data"])), ("H>D", b"#P1?\r")]
    assert batch[3]["type"] == "dropped" and batch[3]["count"] == stream.dropped_total > 0 and len(batch) == 4
    runtime.call(lambda: line.feed(b"#P1?\r"))
    assert [i["dir"] for i in runtime.call(stream.take)] == ["H>D", "D>H"]  # caught up: the chunks again
    runtime.call(stream.stop)
    assert runtime.call(lambda: line.tracer) is None


def test_a_subscriber_that_does_not_read_holds_at_most_max_bytes_of_chunks(served: Any) -> None:
    """A flooded port's chunks are big (a TCP read's 16 KiB slices): the queue holds at most
    MAX_BYTES of them, however few chunks that is (before: MAX_QUEUE chunks of any size, 130 MB
    resident for one stalled reader of a flooded TCP port)."""
    runtime, line, _transport, _address = served
    stream = runtime.call(lambda: CaptureStream(runtime, "sers"))
    runtime.call(stream.start)
    for _ in range(2 * MAX_BYTES // (64 * 1024)):
        runtime.call(lambda: line.feed(b"\x00" * 64 * 1024))
    batch = runtime.call(stream.take)
    assert sum(len(i["data"]) // 2 for i in batch if i["type"] == "chunk") <= MAX_BYTES
    assert batch[-1]["type"] == "dropped" and batch[-1]["count"] > 0
    runtime.call(lambda: line.feed(b"#P1?\r"))
    assert [i["dir"] for i in runtime.call(stream.take)][:1] == ["H>D"]  # caught up: the chunks again
    runtime.call(stream.stop)


# -- Wireshark's live capture through the installed extcap ----------------------------------------
def test_tshark_captures_a_running_simulators_pty_live(tmp_path: Path) -> None:
    tshark = needs_program("tshark")
    home = tmp_path / "home"
    env = {**tshark_env(home), "PYTHONPATH": devsim_env()["PYTHONPATH"]}
    installed = subprocess.run([sys.executable, "-m", "devsim", "wireshark", "--install"], capture_output=True,
                               text=True, timeout=120, env=env, cwd=ROOT, check=False)
    assert installed.returncode == 0, installed.stderr
    launcher = home / ".config" / "wireshark" / "extcap" / LAUNCHER
    assert f"extcap: {launcher}" in installed.stdout and os.access(launcher, os.X_OK)
    assert (home / ".local" / "lib" / "wireshark" / "plugins").is_dir()

    sim = Sim("sers")  # its control socket where devsim ps and the extcap find it
    try:
        seen = sim.read_until("control:")
        sim.read_until("sers: ready")  # booted: a command before that gets no answer
        control_address = seen["control"]
        pty = seen["sers"].split()[-1]
        pid = sim.proc.pid
        listed = subprocess.run([str(launcher), "--extcap-interfaces"], capture_output=True, text=True, timeout=60,
                                env=env, check=False)
        assert f"interface {{value=devsim-{pid}-sers}}" in listed.stdout, listed.stderr
        dlts = subprocess.run([str(launcher), "--extcap-interface", f"devsim-{pid}-sers", "--extcap-dlts"],
                              capture_output=True, text=True, timeout=60, env=env, check=False)
        assert dlts.stdout.startswith("dlt {number=147}{name=USER0}"), dlts.stderr

        out = tmp_path / "live.pcap"
        capture = subprocess.Popen([tshark, "-i", f"devsim-{pid}-sers", "-c", "2", "-w", str(out)], env=env,
                                   stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                   start_new_session=True)  # dumpcap and the extcap end with it
        try:
            with ControlClient(control_address) as control:
                wait_until(lambda: control.line("sers")["capturing"] or capture.poll() is not None, "capture running", 30.0)
            assert capture.poll() is None, capture.communicate()
            with serial.Serial(pty, 9600, timeout=5) as host:
                host.write(b"#RF\r")
                answer = host.read_until(b"\n\r")
            assert answer.startswith(b"#RF\r")
            _stdout, stderr = capture.communicate(timeout=60)
        finally:
            end_session(capture)
        assert capture.returncode == 0, stderr
    finally:
        code, err = sim.stop()
    assert code == 0, err
    records = tshark_records(out, tmp_path / "plain")  # read without the dissectors: the records as they are
    headers = [parse_serial_header(data) for _, data in records]
    assert [(h["direction"], h["protocol"], h["baud"]) for h in headers] == [("H>D", 1, 9600), ("D>H", 1, 9600)]
    assert [data[16:] for _, data in records] == [b"#RF\r", answer]
    assert records[1][0] >= records[0][0] > 0  # the device clock's time (real, since the start)


def test_devsim_ctl_capture_prints_the_chunks_as_trace_lines(tmp_path: Path) -> None:
    from tests.support.process import collect_lines, next_match, stop

    sim = Sim("sers", "--virtual")
    try:
        seen = sim.read_until("control:")
        printer = subprocess.Popen([sys.executable, "-m", "devsim", "ctl", "--control", seen["control"], "capture",
                                    "sers"], env=devsim_env(), cwd=ROOT, stdin=subprocess.DEVNULL,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            lines = collect_lines(printer.stdout)
            with ControlClient(seen["control"]) as control:
                wait_until(lambda: control.line("sers")["capturing"] or printer.poll() is not None, "capture running", 30.0)
            with serial.Serial(seen["sers"].split()[-1], 9600, timeout=1) as host:
                host.write(b"#RF\r")
            assert next_match(lines, lambda line: "H>D" in line, 30, "the chunk") == '0.000000 H>D 23 52 46 0d "#RF\\r"'
        finally:
            stop(printer)
            assert printer.stderr is not None
            printer.stderr.close()
    finally:
        code, err = sim.stop()
    assert code == 0, err


def _whole_packets(path: Path) -> int:
    """The whole packets in a pcap file still being written: 0 before its 24-byte header is there,
    and a record cut short does not count (the writer flushes when it likes)."""
    data = path.read_bytes() if path.exists() else b""
    count, offset = 0, 24
    while len(data) >= offset + 16:
        caplen = struct.unpack_from("<I", data, offset + 8)[0]
        if len(data) < offset + 16 + caplen:
            break
        count, offset = count + 1, offset + 16 + caplen
    return count


def test_the_extcap_writes_a_network_port_as_ipv4(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The PCD's Ether-S-Bus kind of port: raw IPv4 packets with the real addresses and ports of
    the UDP conversation, as a --trace FILE.pcap of the port has them (Wireshark's own Ether-S-Bus
    dissector knows the packets by their port; invented ones it did not decode)."""
    import socket
    import threading

    from devsim.transports.udp import UdpTransport
    from devsim.wireshark.extcap import Interface, capture
    from tests.transports.test_pcap import ETHERBUS, REPLY, REQUEST, read_pcap

    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", ETHERBUS)
    runtime = Runtime(virtual=True).start()
    server = ControlServer(runtime, "127.0.0.1:0")
    address = str(server.start_sync())
    try:
        runtime.serve_sync(runtime.add_device("etherbus", "pcd"), transport := UdpTransport(), port="ether")
        simulator = _simulator(address=address, devices=["pcd"])
        interface = Interface(simulator, "pcd.ether", {"link": 228})
        out = tmp_path / "live.pcap"
        done: list[int] = []
        writer = threading.Thread(target=lambda: done.append(capture(interface, str(out))), daemon=True)
        writer.start()
        with ControlClient(address) as control:
            wait_until(lambda: control.line("pcd", "ether")["capturing"], "capture running", 30.0)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.settimeout(5)
            sock.sendto(REQUEST, ("127.0.0.1", transport.port))
            assert sock.recv(100) == REPLY
            host = ("127.0.0.1", sock.getsockname()[1])
        wait_until(lambda: _whole_packets(out) == 2, "both packets in the file", 30.0)
    finally:
        server.close_sync()  # the stream ends: the extcap closes its file
        runtime.stop()
    writer.join(10)
    assert done == [0]
    packets = read_pcap(out)
    device = ("127.0.0.1", transport.port)
    assert [(p[1], p[2], p[3]) for p in packets] == [(host, device, REQUEST), (device, host, REPLY)]


def test_the_extcap_ends_when_wireshark_closes_the_fifo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    """Wireshark ends a capture by closing the fifo: the extcap's next write fails (EPIPE), and it
    ends at once, quietly, while the simulator goes on."""
    import socket
    import threading

    from devsim.transports.udp import UdpTransport
    from devsim.wireshark.extcap import Interface, capture
    from tests.transports.test_pcap import ETHERBUS, REPLY, REQUEST

    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", ETHERBUS)
    fifo = tmp_path / "wireshark.fifo"
    os.mkfifo(fifo)
    runtime = Runtime(virtual=True).start()
    server = ControlServer(runtime, "127.0.0.1:0")
    address = str(server.start_sync())
    try:
        runtime.serve_sync(runtime.add_device("etherbus", "pcd"), transport := UdpTransport(), port="ether")
        interface = Interface(_simulator(address=address, devices=["pcd"]), "pcd.ether", {"link": 228})
        done: list[int] = []
        writer = threading.Thread(target=lambda: done.append(capture(interface, str(fifo))), daemon=True)
        writer.start()
        with open(fifo, "rb") as wireshark:  # (opens once the extcap has opened its end)
            assert len(wireshark.read(24)) == 24  # the pcap header; then Wireshark stops the capture
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.settimeout(5)
            sock.sendto(REQUEST, ("127.0.0.1", transport.port))  # a chunk the extcap cannot write
            assert sock.recv(100) == REPLY
            writer.join(10)
            assert done == [0]
            sock.sendto(REQUEST, ("127.0.0.1", transport.port))
            assert sock.recv(100) == REPLY  # the simulator goes on
    finally:
        server.close_sync()
        runtime.stop()
    assert "devsim:" not in capsys.readouterr().err


def test_taps_chain_in_front_of_the_trace_and_leave_it_intact(tmp_path: Path) -> None:
    """The monitor's telegram tap and a live capture on a traced line: every chunk reaches the
    trace file and both taps, in whichever order they came; the capture leaves, the rest stays."""
    from devsim.transports.tap import capturing, chunk_tap, tap, untap_chunks

    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "sers")
        line = runtime.serve_sync(device, PtyTransport(), trace=tmp_path / "t.pcap")
        trace = line.tracer
        seen: list[tuple[str, bytes, float]] = []

        def build() -> Any:
            telegrams = tap(line)
            chunk_tap(line).listeners.append(lambda *chunk: seen.append(chunk))
            assert tap(line) is telegrams and chunk_tap(line) is line.tracer  # found behind, not made twice
            line.feed(b"#RF\r")
            return telegrams

        telegrams = runtime.call(build)
        assert [t["hex"] for t in telegrams.last(5)][:1] == ["23 52 46 0d"] and seen[0] == ("H>D", b"#RF\r", 0.0)
        runtime.call(lambda: untap_chunks(line, line.tracer.listeners[0]))
        assert runtime.call(lambda: (line.tracer, capturing(line))) == (telegrams, 0)
        assert telegrams.inner is trace  # the pcap trace is still at the end of the chain
    finally:
        runtime.stop()
    assert read_pcap_trace(tmp_path / "t.pcap").chunks[0] == (0.0, "H>D", b"#RF\r")
