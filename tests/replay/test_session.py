"""The session file and its cutting into exchanges, without processes (pure)."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from devsim.cli import cli, exits
from devsim.core.device import SerialSettings
from devsim.core.registry import port_framing
from devsim.devices.gms96 import codec as ft12
from devsim.observe.replay.session import SessionError, SessionWriter, load_session


def _write(path: Path, kind: str | None, chunks: list[tuple[float, str, bytes]]) -> Path:
    writer = SessionWriter(path, kind=kind, port="main", device="/dev/null", settings=SerialSettings())
    for t, direction, data in chunks:
        writer.chunk(t, direction, data)
    writer.close()
    return path


def test_an_echo_goes_with_the_request_it_echoes(tmp_path: Path) -> None:
    # the host types a line slowly; the SERS echoes each character, answers at the CR
    session = load_session(_write(tmp_path / "s", "sers", [
        (0.0, "host", b"#V"), (0.001, "device", b"#V"), (0.01, "host", b"?\r"), (0.011, "device", b"?\r"),
        (0.02, "device", b"V=2000U/min\n\r\nok1\n\r"),
        (0.5, "host", b"#1"), (0.501, "device", b"#1"), (0.6, "host", b"\r"), (0.65, "device", b"\r\nok1\n\r"),
    ]))
    first, second = session.exchanges
    assert first.request == b"#V?\r" and first.answer == b"#V?\rV=2000U/min\n\r\nok1\n\r"
    assert [(round(r.delay, 3), r.data) for r in first.replies] == [
        (0.0, b"#V"), (0.001, b"?\r"), (0.01, b"V=2000U/min\n\r\nok1\n\r")]
    assert second.request == b"#1\r" and second.answer == b"#1\r\nok1\n\r"
    assert [round(r.delay, 3) for r in second.replies] == [0.0, 0.05]  # the echo before the CR: at once


def test_an_unframed_kind_ends_a_request_where_the_device_answers(tmp_path: Path) -> None:
    session = load_session(_write(tmp_path / "s", "ip247", [
        (0.0, "host", b"\x10"), (0.1, "host", b"\x02"), (0.2, "device", b"\x10\x06"), (0.3, "host", b"AB"),
    ]))
    assert [(e.request, e.answer) for e in session.exchanges] == [(b"\x10\x02", b"\x10\x06"), (b"AB", b"")]
    lines = [json.loads(text) for text in (tmp_path / "s").read_text().splitlines()]
    assert all("decoded" not in entry for entry in lines[1:])  # no codec: bytes only


def test_gms96_tolerances_ignore_the_checksum_and_the_frame_count_bit() -> None:
    frame = ft12.encode(ft12.LongFrame(ft12.control_host(0), 3, ft12.letter("A", 10000)))
    flipped = ft12.encode(ft12.LongFrame(ft12.control_host(1), 3, ft12.letter("A", 10000)))
    other = ft12.encode(ft12.LongFrame(ft12.control_host(0), 3, ft12.letter("A", 10001)))
    broken = frame[:-2] + bytes([frame[-2] ^ 0xFF]) + frame[-1:]
    tolerances = {t.name: t.key for t in port_framing("gms96").tolerances}
    assert tolerances["checksum"](broken) == tolerances["checksum"](frame) != tolerances["checksum"](flipped)
    assert tolerances["fcb"](flipped) == tolerances["fcb"](frame) != tolerances["fcb"](other)
    split = port_framing("gms96").split
    assert split is not None and split(frame + flipped[:5]) == ([frame], flipped[:5])


@pytest.mark.parametrize("content, message", [
    ("", "empty file"),
    ('{"hello": 1}\n', ":1: not a devsim session"),
    ('{"format": "devsim-session", "kind": "sers"}\n{"t": 1, "dir": "host", "hex": "zz"}\n', ":2: "),
    # cut short, but not the last line: a damaged file, not a recording that ended
    ('{"format": "devsim-session", "kind": "sers"}\n{"t": 1, "dir": "ho\n{"t": 2, "dir": "host", "hex": "00"}',
     ":2: "),
    # nested deeper than the decoder goes (a RecursionError's traceback before)
    ("[" * 100_000 + "\n", ":1: not a devsim session"),
    ('{"format": "devsim-session", "kind": "sers"}\n' + "[" * 100_000 + "\n" + '{"t": 2, "dir": "host", "hex": "00"}\n',
     ":2: maximum recursion depth"),
    # line settings no UART takes (edited by hand): a traceback at every byte of the host before
    ('{"format": "devsim-session", "kind": "sers", "settings": {"parity": "EE"}}\n', ":1: settings: parity 'EE'"),
    ('{"format": "devsim-session", "kind": "sers", "settings": {"bytesize": 9}}\n', ":1: settings: bytesize 9"),
    ('{"format": "devsim-session", "kind": "sers", "settings": {"baudrate": 0}}\n', ":1: settings: baudrate 0"),
    ('{"format": "devsim-session", "kind": "sers", "settings": {"stopbits": 3}}\n', ":1: settings: stopbits 3"),
    # a time no clock reaches (fuzzed): the answer was due at infinity and the replay went silent
    ('{"format": "devsim-session", "kind": "sers"}\n{"t": 0, "dir": "host", "hex": "00"}\n'
     '{"t": "1e999", "dir": "device", "hex": "00"}\n', ":3: t: '1e999' is no finite time"),
    ('{"format": "devsim-session", "kind": "sers"}\n{"t": 1e999, "dir": "host", "hex": "00"}\n', ":2: t: inf is no"),
    ('{"format": "devsim-session", "kind": "sers"}\n{"t": "nan", "dir": "host", "hex": "00"}\n', ":2: t: 'nan' is no"),
])
def test_a_bad_session_is_one_line_exit_bad_file(tmp_path: Path, content: str, message: str) -> None:
    path = tmp_path / "bad.devsim"
    path.write_text(content)
    with pytest.raises(SessionError, match=message):
        load_session(path)
    result = CliRunner().invoke(cli, ["replay", str(path), "--pty"])
    assert result.exit_code == exits.BAD_FILE and message in result.output


async def test_the_handover_clock_is_virtual_then_real() -> None:
    from devsim.observe.replay.live import HandoverClock

    clock = HandoverClock()
    fired: list[float] = []
    clock.call_later(100.0, lambda: fired.append(clock.now()))
    assert clock.virtual and clock.advance(100.0) == 1 and fired == [100.0]  # seeding: no wall time
    loop = asyncio.get_running_loop()
    clock.go_live()
    assert not clock.virtual
    done = asyncio.Event()
    start = loop.time()
    clock.call_later(0.05, done.set)
    await asyncio.wait_for(done.wait(), 5)
    assert loop.time() - start >= 0.05 - 1e-3 and clock.now() >= 100.05 - 1e-3  # then real time, from there
    await clock.close()


def test_a_last_line_cut_short_ends_the_recording_there(tmp_path: Path) -> None:
    """The recorder's disk stopped taking the file in the middle of a line (tests/test_full_disk.py):
    the lines before it are the recording."""
    path = _write(tmp_path / "cut.devsim", "sers", [(0.0, "host", b"#1 P11?\r"), (0.01, "device", b"#1 P11?\rP11=0\n\r\nok1\n\r"),
                                                    (0.5, "host", b"#1 P12?\r")])
    whole = path.read_text()
    path.write_text(whole[: whole.rindex('"hex"')])  # the third chunk's line cut short
    session = load_session(path)
    assert session.cut == 4
    assert [(e.request, e.answer) for e in session.exchanges] == [(b"#1 P11?\r", b"#1 P11?\rP11=0\n\r\nok1\n\r")]
    assert load_session(_write(tmp_path / "whole.devsim", "sers", [(0.0, "host", b"#1 P11?\r")])).cut == 0


def test_unframed_requests_follow_the_recording_at_the_cursor(tmp_path: Path) -> None:
    """An IP247 PG transaction (spec ip247.md §3.5.2): the PG's DLE ACK and its parameter block
    reach the recorder as one request (the device answers neither alone).  Replayed, the DLE ACK
    may come on its own: it waits for the block instead of matching a later DLE ACK, and the
    transaction gets its answers in order."""
    from devsim.observe.replay.player import Replayer, ReplayPlan

    steps = [("02", "10 06"), ("64", "02"), ("10 06", "16 10 03"), ("10 06 04 46 00 00 10 04", "10 06 02"),
             ("10 06", "00 04 46 00 00 00 00 00 10 03"), ("10 06", "02"), ("10 06", "12 10 03")]
    writer = SessionWriter(tmp_path / "pg.devsim", kind="ip247", port="pg", device="-", settings=SerialSettings())
    for n, (host, device) in enumerate(steps):
        writer.chunk(n + 0.0, "host", bytes.fromhex(host))
        writer.chunk(n + 0.01, "device", bytes.fromhex(device))
    writer.close()

    class Outbox:
        write = None

        def __init__(self) -> None:
            self.sent: list[bytes] = []

        def put(self, due: float, data: bytes) -> None:
            self.sent.append(data)

    async def replay() -> list[bytes]:
        outbox = Outbox()
        replayer = Replayer(ReplayPlan(load_session(tmp_path / "pg.devsim"), as_fast=True), outbox)  # type: ignore[arg-type]
        answers = []
        for host in ("02", "64", "10 06", "10 06", "04 46 00 00 10 04", "10 06", "10 06", "10 06"):
            replayer.feed(bytes.fromhex(host))  # each step on its own, the DLE ACK apart from its block
            answers.append(b"".join(outbox.sent).hex(" "))
            outbox.sent.clear()
        return answers

    assert asyncio.run(replay()) == ["10 06", "02", "16 10 03", "", "10 06 02", "00 04 46 00 00 00 00 00 10 03", "02",
                                     "12 10 03"]
