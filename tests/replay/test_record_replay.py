"""devsim record / devsim replay end to end: real processes, real ptys, pyserial hosts.

The SERS host is the README's worked example (``tests/test_readme_example.py``: ``ask`` and
``home_and_move``), run against ``devsim run sers --pty`` through ``devsim record``; its session
is then replayed to the same host code.  Every wait is bounded.
"""

from __future__ import annotations

import contextlib
import json
import queue
import socket
import struct
import subprocess
import sys
import termios
import time
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

import pytest
import serial

from devsim.devices.gms96.client import Gms96Client
from devsim.devices.gms96.codec import LongFrame
from tests import test_readme_example as readme
from tests.support.process import DevsimProcess
from tests.test_readme_example import ask, home_and_move

ROOT = Path(__file__).resolve().parents[2]

# A SERS that boots at once and homes and moves fast, so the example takes well under a second.
FAST_SERS = """\
boot_time: 0
axis:
  reference_low: 1280
params:
  P41: 600
  P1003: 300
  P42: 5000
  P91: 3000
  P138: 5000
"""


class Proc(DevsimProcess):
    """A ``devsim`` subprocess; its stdout and stderr lines are collected by threads."""

    def __init__(self, *args: str) -> None:
        super().__init__(*args)
        self.err_lines: list[str] = []
        self.result: tuple[int, str] | None = None

    def _wait(self, lines: queue.Queue[str | None], prefix: str, timeout: float, keep: list[str] | None) -> str:
        return self.next_match(lines, lambda line: line.startswith(prefix), timeout,
                               f"line starting {prefix!r}", keep)

    def line(self, prefix: str, timeout: float = 20.0) -> str:
        """The next stdout line starting with ``prefix``."""
        return self._wait(self.out, prefix, timeout, None)

    def value(self, prefix: str, timeout: float = 20.0) -> str:
        """The last word of the next stdout line starting with ``prefix``: a path or URL."""
        return self.line(prefix, timeout).split()[-1]

    def err_line(self, prefix: str, timeout: float = 10.0) -> str:
        return self._wait(self.err, prefix, timeout, self.err_lines)

    def stop(self) -> tuple[int, str]:
        """SIGINT, bounded wait; the exit status and the rest of stderr (idempotent)."""
        if self.result is not None:
            return self.result
        self.interrupt()
        rest: list[str] = []
        while True:
            try:
                line = self.err.get(timeout=5)
            except queue.Empty:
                break
            if line is None:
                break
            rest.append(line)
        self.err_lines += rest
        self.result = self.proc.returncode, "\n".join(self.err_lines)
        return self.result


@pytest.fixture
def procs() -> Iterator[list[Proc]]:
    started: list[Proc] = []
    yield started
    for proc in started:
        proc.stop()


def _start(procs: list[Proc], *args: str) -> Proc:
    proc = Proc(*args)
    procs.append(proc)
    return proc


def run_host(monkeypatch: pytest.MonkeyPatch, url: str) -> tuple[str, list[tuple[bytes, bytes]]]:
    """The README's host example against ``url``: its result, and each line it wrote with the
    bytes it read back (the port's own read/write, seen from the host's side)."""
    transcript: list[tuple[bytes, bytes]] = []
    real_open = serial.serial_for_url

    def open_port(*args, **kwargs):
        port = real_open(*args, **kwargs)
        read, write = port.read, port.write

        def spy_write(data: bytes) -> int | None:
            transcript.append((bytes(data), b""))
            return write(data)

        def spy_read(size: int = 1) -> bytes:
            data = read(size)
            request, answer = transcript[-1]
            transcript[-1] = (request, answer + data)
            return data

        port.write, port.read = spy_write, spy_read
        return port

    with monkeypatch.context() as patch:
        patch.setattr(readme.serial, "serial_for_url", open_port)
        position = home_and_move(url, 3600, wait=lambda: time.sleep(0.02))  # the host's poll interval
    return position, transcript


@pytest.fixture(scope="module")
def sers_session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict]:
    """Record the README example against ``devsim run sers`` through ``devsim record``; then ask
    the device itself (the recorder gone) what a live SERS says to requests never recorded."""
    tmp = tmp_path_factory.mktemp("sers-session")
    config = tmp / "sers.yaml"
    config.write_text(FAST_SERS)
    session = tmp / "session.devsim"
    started: list[Proc] = []
    monkeypatch = pytest.MonkeyPatch()
    try:
        device = _start(started, "run", "sers", "--pty", "--config", str(config))
        device_pty = device.value("sers: pty")
        device.line("sers: ready")
        recorder = _start(started, "record", "--port", device_pty, "--out", str(session), "--kind", "sers")
        host_pty = recorder.value("record: pty")
        recorder.line("record: out")
        position, transcript = run_host(monkeypatch, host_pty)
        status, err = recorder.stop()
        assert status == 0, err
        with serial.Serial(device_pty, 9600, timeout=2) as port:  # the device as it is now
            live_answer = ask(port, "#W?\r")
        yield {"config": config, "path": session, "position": position, "transcript": transcript,
               "live_answer": live_answer, "device_pty": device_pty}
    finally:
        monkeypatch.undo()
        for proc in started:
            proc.stop()


def test_the_session_file_holds_both_directions_decoded(sers_session: dict) -> None:
    lines = [json.loads(text) for text in sers_session["path"].read_text().splitlines()]
    header, chunks = lines[0], [entry for entry in lines[1:] if "dir" in entry]
    assert header["format"] == "devsim-session" and header["kind"] == "sers"
    assert header["settings"] == {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}
    host_lines = [text for entry in chunks if entry["dir"] == "host" for text in entry["decoded"]]
    device_lines = [text for entry in chunks if entry["dir"] == "device" for text in entry["decoded"]]
    sent = [request.decode("latin-1") for request, _ in sers_session["transcript"]]
    assert host_lines == sent  # every line the host wrote, in order, as lines
    assert "\nok1\n\r" in device_lines and "P51=3600°\n\r" in device_lines
    assert b"".join(bytes.fromhex(e["hex"]) for e in chunks if e["dir"] == "device") == b"".join(
        answer for _, answer in sers_session["transcript"])  # what the host read, byte for byte
    times = [entry["t"] for entry in chunks]
    assert times == sorted(times) and times[-1] > times[0]


@pytest.mark.parametrize("timing", [[], ["--as-fast"]], ids=["recorded-timing", "as-fast"])
def test_replay_gives_the_host_the_same_answers(sers_session: dict, procs: list[Proc],
                                                monkeypatch: pytest.MonkeyPatch, timing: list[str]) -> None:
    replay = _start(procs, "replay", str(sers_session["path"]), "--pty", *timing)
    position, transcript = run_host(monkeypatch, replay.value("replay: pty"))
    assert position == sers_session["position"] == "P51=3600°"
    assert transcript == sers_session["transcript"]
    status, err = replay.stop()
    assert status == 0, err
    assert f"requests answered: exact {len(transcript)}" in err and "unknown" not in err


def test_fallback_live_answers_what_was_never_recorded_as_a_live_sers(
        sers_session: dict, procs: list[Proc], monkeypatch: pytest.MonkeyPatch) -> None:
    replay = _start(procs, "replay", str(sers_session["path"]), "--pty", "--fallback", "live",
                    "--config", str(sers_session["config"]))
    url = replay.value("replay: pty")
    position, transcript = run_host(monkeypatch, url)  # all of it from the recording
    assert transcript == sers_session["transcript"]
    with serial.Serial(url, 9600, timeout=2) as port:
        answer = ask(port, "#W?\r")  # never recorded: the live model, seeded with the recording
        assert answer == sers_session["live_answer"] == "#W?\rW=3600°\n\r\nok1\n\r"
        ask(port, "#W=1800 E\r")  # a relative move from where the recorded drive stood
        deadline = time.monotonic() + 10
        while "POS=1" not in ask(port, "#POS?\r"):
            assert time.monotonic() < deadline, "the live model's move did not end"
            time.sleep(0.02)
        assert ask(port, "#P51?\r").split("\r")[1].strip() == "P51=5400°"  # W is relative (P1014 0)
    replay.err_line("replay: request not in the recording: '#W?\\r'")
    status, err = replay.stop()
    assert status == 0, err
    assert "the live sers model answers from now on" in err


def test_fallback_error_reports_the_unknown_request_and_stays_silent(
        sers_session: dict, procs: list[Proc], monkeypatch: pytest.MonkeyPatch) -> None:
    replay = _start(procs, "replay", str(sers_session["path"]), "--pty", "--as-fast", "--fallback", "error")
    url = replay.value("replay: pty")
    with serial.Serial(url, 9600, timeout=0.5) as port:
        port.write(b"#W?\r")
        line = replay.err_line("replay: request not in the recording")
        assert "'#W?\\r' (23 57 3f 0d)" in line and "no answer" in line
        assert port.read(64) == b""  # silence, as from a dead device
        port.timeout = 2
        assert ask(port, "#1\r") == "#1\r\nok1\n\r"  # a recorded request is answered again
    status, err = replay.stop()
    assert status == 0, err
    assert "exact 1, unknown 1" in err


# -- GMS96: FT1.2 frames, and the FCB tolerance ---------------------------------------------------
class _Gms96Recording(NamedTuple):
    config: Path
    session: Path
    device_pty: str
    host_pty: str
    recorder: Proc


def _gms96_recording(tmp_path: Path, procs: list[Proc], config_text: str) -> _Gms96Recording:
    """A GMS96 (``config_text``) on a pty, and ``devsim record`` between it and a host pty."""
    config = tmp_path / "gms96.yaml"
    config.write_text(config_text)
    session = tmp_path / "gms96.devsim"
    device = _start(procs, "run", "gms96", "--pty", "--config", str(config))
    device_pty = device.value("gms96: pty")
    device.line("gms96: ready")
    recorder = _start(procs, "record", "--port", device_pty, "--out", str(session), "--kind", "gms96")
    host_pty = recorder.value("record: pty")
    recorder.line("record: out")
    return _Gms96Recording(config, session, device_pty, host_pty, recorder)


@contextlib.contextmanager
def _card(url: str, first_fcb: int) -> Iterator[Gms96Client]:
    """A host of the card at ``url`` whose next letter command goes out with ``first_fcb``."""
    deadline = time.monotonic() + 10
    while True:  # (a pty another host has just let go takes a moment to take one at 8E1 again)
        try:
            port = serial.Serial(url, 9600, parity="E", timeout=0.5)
            break
        except (serial.SerialException, termios.error):
            assert time.monotonic() < deadline, f"{url} did not open"
            time.sleep(0.02)  # (the next try; the condition is the open itself)
    with port:
        card = Gms96Client(port, address=3, timeout=2)
        card.fcb = first_fcb ^ 1
        yield card


def test_gms96_replay_matches_frames_with_another_frame_count_bit(tmp_path: Path, procs: list[Proc]) -> None:
    recording = _gms96_recording(tmp_path, procs, "boot_time: 0\n")

    def host(url: str, first_fcb: int) -> list[object]:
        with _card(url, first_fcb) as card:
            return [card.send_letter("Q", 3), card.read(0), card.status()]

    recorded = host(recording.host_pty, 0)
    status, err = recording.recorder.stop()
    assert status == 0, err
    frames = [entry["decoded"] for entry in map(json.loads, recording.session.read_text().splitlines()[1:])
              if entry.get("dir") == "host"]
    assert {"frame": "long", "C": "53", "A": 3, "data": "51 03 00 00", "letter": "Q", "params": [3],
            "fcb": 0} in [frame for chunk in frames for frame in chunk]

    replay = _start(procs, "replay", str(recording.session), "--pty", "--as-fast")
    url = replay.value("replay: pty")
    assert host(url, 0) == recorded  # the same frames: exact
    assert host(url, 1) == recorded  # every FCB flipped (and so every checksum): tolerated
    status, err = replay.stop()
    assert status == 0, err
    assert "requests answered: exact 4, fcb 2" in err


def test_gms96_e_version_live_model_takes_the_hosts_frame_count_bit(tmp_path: Path, procs: list[Proc]) -> None:
    """E-version: a frame with the frame count bit of the one before is a repetition, answered but
    not carried out (spec gms96.md §3.9).  The host's N300;10 matched the recording's with the
    other FCB; the live model, seeded with the host's own frame, takes its next one (N400;10, the
    first not recorded) as new."""
    recording = _gms96_recording(tmp_path, procs, "boot_time: 0\ndil: {protocol: E}\n")

    def host(url: str, first_fcb: int, *letters: tuple[int, ...]) -> list[object]:
        with _card(url, first_fcb) as card:
            return [card.send_letter(letter, *params) for letter, *params in letters]

    recorded = host(recording.host_pty, 0, ("N", 300, 10))  # the recording ends with a frame of FCB 0
    assert recording.recorder.stop()[0] == 0
    (n10,) = host(recording.device_pty, 1, ("T", 5, 10))  # N10 on the card: 300
    replay = _start(procs, "replay", str(recording.session), "--pty", "--as-fast", "--fallback", "live",
                    "--config", str(recording.config))
    answers = host(replay.value("replay: pty"), 1, ("N", 300, 10), ("N", 400, 10), ("T", 5, 10))
    assert answers[0] == recorded[0]  # (the recording's answer, by the FCB tolerance)
    assert isinstance(n10, LongFrame) and (300).to_bytes(2, "little") in n10.data
    assert answers[2] == LongFrame(n10.control, n10.address,
                                   n10.data.replace((300).to_bytes(2, "little"), (400).to_bytes(2, "little")))
    status, err = replay.stop()
    assert status == 0, err


# -- the example of docs/replay.md, as printed there ---------------------------------------------------------
def _readme_host(tmp_path: Path) -> Path:
    text = (ROOT / "docs" / "replay.md").read_text(encoding="utf-8")
    section = text[text.index("# Record and replay") :]
    code = section[section.index("```python\n") + len("```python\n") :]
    host = tmp_path / "host.py"
    host.write_text(code[: code.index("```")])
    return host


def _run(host: Path, *args: str) -> list[str]:
    done = subprocess.run([sys.executable, str(host), *args], capture_output=True, text=True, timeout=20)
    assert done.returncode == 0, done.stderr
    return done.stdout.splitlines()


def _readme_recording(tmp_path: Path, procs: list[Proc], *extra: str) -> tuple[Path, list[str], Path]:
    """docs/replay.md's host (with ``extra`` lines) recorded against a SERS: the host, what it
    printed, the session."""
    host = _readme_host(tmp_path)
    config = tmp_path / "sers.yaml"
    config.write_text("boot_time: 0\n")
    device = _start(procs, "run", "sers", "--pty", "--config", str(config))
    device_pty = device.value("sers: pty")
    device.line("sers: ready")
    session = tmp_path / "drive.devsim"
    recorder = _start(procs, "record", "--port", device_pty, "--out", str(session), "--kind", "sers")
    recorded = _run(host, recorder.value("record: pty"), *extra)
    assert recorder.stop()[0] == 0
    return host, recorded, session


def test_the_readme_example(tmp_path: Path, procs: list[Proc]) -> None:
    host, recorded, session = _readme_recording(tmp_path, procs)
    assert recorded[2] == r"b'#V?\rV=2000U/min\n\r\nok1\n\r'"
    replay = _start(procs, "replay", str(session), "--pty", "--as-fast")
    assert _run(host, replay.value("replay: pty")) == recorded
    live = _start(procs, "replay", str(session), "--pty", "--fallback", "live")
    assert _run(host, live.value("replay: pty"), "#P91?") == [*recorded, r"b'#P91?\rP91=2000U/min\n\r\nok1\n\r'"]


def test_fallback_live_holds_what_this_host_wrote_not_the_whole_recording(tmp_path: Path, procs: list[Proc]) -> None:
    """The recording went on (V=3000) after where this host leaves it (V=2000, then a request
    never recorded): the live model holds what this host wrote."""
    host, recorded, session = _readme_recording(tmp_path, procs, "#V=3000", "#V?")
    assert recorded[-1] == r"b'#V?\rV=3000U/min\n\r\nok1\n\r'"
    live = _start(procs, "replay", str(session), "--pty", "--fallback", "live")
    assert _run(host, live.value("replay: pty"), "#P91?") == [*recorded[:4], r"b'#P91?\rP91=2000U/min\n\r\nok1\n\r'"]


# -- PCD4.H3 Ether-S-Bus on TCP: another sequence number ---------------------------------------------
def _crc(data: bytes) -> int:  # CRC-16/XMODEM, as in the Ether-S-Bus example of docs/kinds/pcd4h3.md
    value = 0
    for byte in data:
        value ^= byte << 8
        for _ in range(8):
            value = (value << 1 ^ 0x1021) & 0xFFFF if value & 0x8000 else value << 1 & 0xFFFF
    return value


def _ether_ask(sock: socket.socket, sequence: int, payload: bytes) -> bytes:
    """One Ether-S-Bus request on a TCP stream; the whole reply frame."""
    body = struct.pack(">IBBHB", 11 + len(payload), 1, 0, sequence, 0) + payload
    sock.sendall(body + struct.pack(">H", _crc(body)))
    reply = b""
    while len(reply) < 4 or len(reply) < int.from_bytes(reply[:4], "big"):
        chunk = sock.recv(512)
        assert chunk, "connection closed"
        reply += chunk
    return reply


def _connect(url: str) -> socket.socket:
    host, _, port = url.removeprefix("socket://").rpartition(":")
    return socket.create_connection((host, int(port)), timeout=5)


def _ether_host(url: str, first_sequence: int) -> list[bytes]:
    """Write R 100 := 1234, read it back: the whole reply frames."""
    with _connect(url) as sock:
        return [_ether_ask(sock, first_sequence, bytes([1, 0x0E, 5]) + struct.pack(">Hi", 100, 1234)),
                _ether_ask(sock, first_sequence + 1, bytes([1, 0x06, 0]) + struct.pack(">H", 100))]


def test_ether_sbus_over_tcp_sequence_tolerance_and_live(tmp_path: Path, procs: list[Proc]) -> None:
    """Recorded over TCP on both sides (socket:// to the device, --tcp for the host), replayed on
    --tcp: another sequence number is answered with it; past the recording the live PCD answers
    with what the recording wrote."""
    device = _start(procs, "run", "pcd4h3", "--pty", "--port", "ether_tcp=tcp:0", "--port", "ether_udp=udp:0")
    device_url = device.value("pcd4h3.ether_tcp: tcp")
    session = tmp_path / "ether.devsim"
    recorder = _start(procs, "record", "--port", device_url, "--out", str(session), "--kind", "pcd4h3",
                      "--device-port", "ether_tcp", "--tcp", "0")
    recorded = _ether_host(recorder.value("record: tcp"), 1)
    assert recorder.stop()[0] == 0
    assert recorded[1][6:8] == b"\x00\x02" and recorded[1][9:-2] == (1234).to_bytes(4, "big")  # R 100 = 1234
    lines = session.read_text().splitlines()
    assert json.loads(lines[0])["device"] == device_url
    decoded = [d for line in lines[1:] for d in json.loads(line).get("decoded", [])]
    assert {"sequence": 2, "attribute": "request", "payload": "01 06 00 00 64", "station": 1, "command": "06",
            "crc_ok": True} in decoded

    replay = _start(procs, "replay", str(session), "--tcp", "0", "--fallback", "live")
    url = replay.value("replay: tcp")
    assert _ether_host(url, 1) == recorded
    for sequence, reply, original in zip((41, 42), _ether_host(url, 41), recorded, strict=True):
        assert reply[6:8] == sequence.to_bytes(2, "big")  # the host's sequence number
        assert reply[:6] == original[:6] and reply[8:-2] == original[8:-2]
        assert int.from_bytes(reply[-2:], "big") == _crc(reply[:-2])  # and a valid CRC
    with _connect(url) as sock:  # R 100 and R 101: never asked; the live model holds the write
        reply = _ether_ask(sock, 9, bytes([1, 0x06, 1]) + struct.pack(">H", 100))
    assert reply[6:8] == b"\x00\x09" and reply[9:-2] == struct.pack(">ii", 1234, 0)
    status, err = replay.stop()
    assert status == 0, err
    assert "requests answered: exact 2, sequence 2, unknown 1" in err


def test_a_tolerated_match_keeps_the_recorded_order(tmp_path: Path, procs: list[Proc]) -> None:
    """Recorded: write R 100 := 1000, read it, write 2000, read it (sequence numbers 1 … 4).  A
    host counting from 3 writes 1000 (sequence 3: the recorded first write, by the tolerance) and
    reads (sequence 4, byte for byte the recording's *second* read): it gets 1000, the answer in
    order, not 2000."""
    device = _start(procs, "run", "pcd4h3", "--pty", "--port", "ether_tcp=tcp:0", "--port", "ether_udp=udp:0")
    device_url = device.value("pcd4h3.ether_tcp: tcp")
    session = tmp_path / "ether.devsim"
    recorder = _start(procs, "record", "--port", device_url, "--out", str(session), "--kind", "pcd4h3",
                      "--device-port", "ether_tcp", "--tcp", "0")

    def host(url: str, first: int, values: tuple[int, ...]) -> list[int]:
        read = []
        with _connect(url) as sock:
            for n, value in enumerate(values):
                _ether_ask(sock, first + 2 * n, bytes([1, 0x0E, 5]) + struct.pack(">Hi", 100, value))
                reply = _ether_ask(sock, first + 2 * n + 1, bytes([1, 0x06, 0]) + struct.pack(">H", 100))
                read.append(int.from_bytes(reply[9:-2], "big", signed=True))
        return read

    assert host(recorder.value("record: tcp"), 1, (1000, 2000)) == [1000, 2000]
    assert recorder.stop()[0] == 0
    replay = _start(procs, "replay", str(session), "--tcp", "0")
    assert host(replay.value("replay: tcp"), 3, (1000,)) == [1000]
    status, err = replay.stop()
    assert status == 0, err
    assert "requests answered: sequence 2" in err


@pytest.mark.parametrize("args, earliest, latest", [([], 0.6, None), (["--speed", "4"], 0.15, 0.6)],
                         ids=["as-recorded", "speed-4"])
def test_replay_keeps_the_recorded_delay(tmp_path: Path, procs: list[Proc], args: list[str], earliest: float,
                                         latest: float | None) -> None:
    from devsim.core.device import SerialSettings
    from devsim.observe.replay.session import SessionWriter

    writer = SessionWriter(tmp_path / "slow.devsim", kind="sers", port="main", device="-", settings=SerialSettings())
    writer.chunk(1.0, "host", b"#1\r")
    writer.chunk(1.001, "device", b"#1\r")  # the echo: at once
    writer.chunk(1.6, "device", b"\nok1\n\r")  # the answer 0.6 s after the request
    writer.close()
    replay = _start(procs, "replay", str(tmp_path / "slow.devsim"), "--pty", *args)
    with serial.Serial(replay.value("replay: pty"), 9600, timeout=3) as port:
        start = time.monotonic()
        port.write(b"#1\r")
        assert port.read(3) == b"#1\r"
        assert port.read_until(b"\n\r") == b"\nok1\n\r"
        elapsed = time.monotonic() - start
    assert elapsed >= earliest - 0.01
    assert latest is None or elapsed < latest
