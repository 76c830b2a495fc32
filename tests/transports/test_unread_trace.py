"""A trace written to a fifo, a pipe or a terminal whose reader does not read (``less`` scrolled
back, a program that stopped reading, a terminal stopped with Ctrl-S): the simulator goes on
answering, and what the reader gets is whole lines, with a note where some were dropped.

Before, the trace's write blocked once the pipe was full, and the whole simulator with it: a
fifo's reader that did not read stopped ``devsim run sers`` after about 460 polls, and SIGTERM
could not stop the process."""

from __future__ import annotations

import asyncio
import os
import re
import select
import struct
import subprocess
import sys
import threading
from pathlib import Path

import pytest
import serial

from devsim.core.backlog import Backlog
from devsim.observe.plot_data import read_pcap_trace
from devsim.runtime.client import ControlClient
from tests.support.process import ROOT, collect_lines, devsim_env, next_match, stop

POLL, ANSWER = b"#P11?\r", b"#P11?\rP11=0\n\r\nok1\n\r"
JUNK = b"x" * 1000 + b"\r"  # a line the drive takes and ignores (no '#'): 5 kB of text trace, 1 kB of pcap
CHUNKS = {"line.trace": 400, "line.pcap": 1300}  # 2 MB, 1.3 MB: more than the pipe and the backlog hold together
DATA_LINE = re.compile(r'^\d+\.\d{6} (H>D|D>H) [0-9a-f]{2}( [0-9a-f]{2})* ".*"$')


def read_all(fd: int, timeout: float) -> bytes:
    """What the fifo holds now and brings within ``timeout`` of its last byte, until its end."""
    got = bytearray()
    poller = select.poll()
    poller.register(fd, select.POLLIN)
    while poller.poll(timeout * 1000):
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            break
        got += chunk
    return bytes(got)


@pytest.mark.parametrize("name", ["line.trace", "line.pcap"])
def test_a_trace_whose_reader_does_not_read_does_not_stop_the_drive(tmp_path: Path, name: str) -> None:
    fifo = tmp_path / name
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # there, and reading nothing
    address = f"unix:{tmp_path}/c.sock"
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "run", "sers", "--pty", "--virtual", "--control", address,
         "--trace", str(fifo)],
        cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    out, err = collect_lines(proc.stdout), collect_lines(proc.stderr)
    try:
        pty = next_match(out, lambda line: line.startswith("sers: pty "), 30, "the port line").split()[-1]
        next_match(out, lambda line: line.startswith("control: "), 30, "the control line")
        with ControlClient(address) as client, serial.Serial(pty, 9600, timeout=10, write_timeout=10) as port:
            client.request("advance", seconds=3.0)  # the power-on
            for n in range(CHUNKS[name]):
                port.write(JUNK)
                if n % 50 == 0:  # (the drive keeps up: what it took, it traced)
                    port.write(POLL)
                    assert port.read_until(ANSWER) == ANSWER, f"poll after {n} lines"
            told = next_match(err, lambda line: "does not keep up" in line, 30, "the line on stderr")
            port.write(POLL)
            assert port.read_until(ANSWER) == ANSWER
            traced = read_all(reader, 2.0)  # the reader reads again: it gets what waited, then the rest
            port.write(POLL)
            assert port.read_until(ANSWER) == ANSWER
            traced += read_all(reader, 2.0)
    finally:
        status = stop(proc, timeout=15)
    traced += read_all(reader, 2.0)
    os.close(reader)
    assert status == 0
    lines = [told]
    while (line := err.get(timeout=15)) is not None:
        lines.append(line)
    assert lines.count(f"devsim: trace {fifo}: its reader does not keep up; what it has no room for is dropped") == 1
    assert not any("Traceback" in line for line in lines), lines
    if name.endswith(".pcap"):
        offset, records = 24, 0
        while offset < len(traced):  # whole records only: the last one ends where the stream does
            offset += 16 + struct.unpack_from("<I", traced, offset + 8)[0]
            records += 1
        assert offset == len(traced) and records < CHUNKS[name]  # (some were dropped)
        (tmp_path / "got.pcap").write_bytes(traced)
        chunks = read_pcap_trace(tmp_path / "got.pcap").chunks
        assert len(chunks) == records  # (every record decodes)
        assert [(way, data) for _, way, data in chunks[-2:]] == [("H>D", POLL), ("D>H", ANSWER)]
        return
    text = traced.decode("ascii")
    assert text.endswith("\n")
    trace = text.splitlines()
    assert trace[0] == "0.000000 -- source sers port main kind sers"
    notes = [i for i, line in enumerate(trace) if re.fullmatch(
        r"\d+\.\d{6} -- \d+ lines dropped here: the trace's reader did not take them", line)]
    assert notes  # (a poll's short lines still fit where a flood's long one did not: a note before each)
    assert all(DATA_LINE.match(line) or " -- " in line for line in trace), "a line cut short"
    assert [line.split(" ", 1)[1] for line in trace[-2:]] == [  # the poll after the reader read again
        'H>D 23 50 31 31 3f 0d "#P11?\\r"', 'D>H 23 50 31 31 3f 0d 50 31 31 3d 30 0a 0d 0a 6f 6b 31 0a 0d "#P11?\\rP11=0\\n\\r\\nok1\\n\\r"']


def test_a_backlog_drops_whole_writes_and_the_loop_sends_it_once_the_reader_reads() -> None:
    read_end, write_end = os.pipe()
    failures: list[OSError] = []

    async def write_then_read() -> bytes:
        backlog = Backlog(write_end, failures.append, cap=100_000)
        taken = [backlog.write(bytes([n]) * 10_000) for n in range(30)]  # 300 kB; the pipe holds 64 kB
        kept = taken.count(True)  # up to 64 kB in the pipe and 100 kB waiting; then each one dropped
        assert 10 <= kept < 30 and taken == [True] * kept + [False] * (30 - kept)
        assert backlog.dropped == taken.count(False) and backlog.waiting > 90_000
        got = bytearray()
        loop = asyncio.get_running_loop()
        while len(got) < (taken.count(True)) * 10_000:  # no write after: the loop sends what waited
            ready = asyncio.Event()
            loop.add_reader(read_end, ready.set)
            await asyncio.wait_for(ready.wait(), 5)
            loop.remove_reader(read_end)
            got += os.read(read_end, 1 << 16)
        assert backlog.waiting == 0
        assert backlog.write(b"end") and backlog.dropped == 0
        backlog.close()
        return bytes(got)

    got = asyncio.run(write_then_read())
    got += os.read(read_end, 1 << 16)
    os.close(read_end)
    writes = [got[i:i + 10_000] for i in range(0, len(got) - 3, 10_000)]
    assert all(len(set(w)) == 1 and len(w) == 10_000 for w in writes)  # whole writes, in order
    assert [w[0] for w in writes] == sorted(w[0] for w in writes)
    assert got.endswith(b"end") and not failures


def test_a_backlog_whose_reader_goes_tells_its_owner() -> None:
    read_end, write_end = os.pipe()
    failures: list[OSError] = []

    async def write_then_close_the_reader() -> None:
        backlog = Backlog(write_end, failures.append)
        for _ in range(20):
            backlog.write(b"y" * 10_000)
        assert backlog.waiting
        os.close(read_end)
        for _ in range(100):
            if failures:
                break
            await asyncio.sleep(0)
        backlog.close(patience=0)

    asyncio.run(write_then_close_the_reader())
    assert [type(f) for f in failures] == [BrokenPipeError]


def test_threads_sharing_a_backlog_each_get_every_line_out_once_and_whole() -> None:
    """A log line may come from the web page's thread while the loop's thread writes: with a
    reader slower than the writers, bytes wait, and each thread's write sends what waits first.
    Every line reaches the reader once, whole, and each thread's lines in their order."""
    read_end, write_end = os.pipe()
    failures: list[OSError] = []
    backlog = Backlog(write_end, failures.append, cap=1 << 30)  # (nothing dropped: every line must arrive)
    writers, lines = 4, 5_000
    got = bytearray()

    def reader() -> None:
        while chunk := os.read(read_end, 1000):  # (small reads: the pipe stays nearly full)
            got.extend(chunk)

    def writer(number: int) -> None:
        for line in range(lines):
            assert backlog.write(f"{number} {line:05d} {'.' * 40}\n".encode())

    reading = threading.Thread(target=reader)
    reading.start()
    threads = [threading.Thread(target=writer, args=(n,)) for n in range(writers)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    backlog.close(patience=30)
    reading.join(30)
    os.close(read_end)
    received = got.decode().splitlines()
    assert not failures and len(received) == writers * lines
    for number in range(writers):
        mine = [line for line in received if line.startswith(f"{number} ")]
        assert mine == [f"{number} {line:05d} {'.' * 40}" for line in range(lines)]
