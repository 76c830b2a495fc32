"""Repeated log lines are rate-limited (issue 32, item 3): the limiter on an injected clock, and
``devsim run poselesta`` with a host writing 100,000 bad bytes on V8 (a line each, before) through
the real CLI and a real pty."""

from __future__ import annotations

import os
import re
import termios
import tty

from devsim.observe.repeats import RepeatLimiter
from tests.support.process import DevsimProcess

BAD_BYTES = 100_000


def test_a_repeated_line_is_written_once_then_counted_every_window() -> None:
    now = [0.0]
    limiter = RepeatLimiter(window=5.0, clock=lambda: now[0])
    assert not limiter.pending
    assert limiter.offer("k", "bad byte") == ["bad byte"]
    assert limiter.offer("other", "other") == ["other"]
    assert not limiter.pending  # (lines that do not repeat need no timer in the log: a host's connect)
    for _ in range(12345):
        now[0] += 0.0001
        assert limiter.offer("k", "bad byte") == []
    assert limiter.pending  # (the log's timer is armed while a count waits to be written)
    assert limiter.due() == []
    now[0] = 5.0
    assert limiter.due() == ["bad byte ... repeated 12345 times in the last 5 s"]
    assert not limiter.pending  # (and then the log has no timer: an idle simulator does not wake up)
    now[0] = 10.0
    assert limiter.due() == []  # nothing counted: the key is forgotten, the next one is written
    assert not limiter.pending
    assert limiter.offer("k", "bad byte") == ["bad byte"]
    limiter.offer("k", "bad byte")
    now[0] = 11.0
    assert limiter.offer("k", "bad byte") == []
    assert limiter.flush() == ["bad byte ... repeated 2 times in the last 1 s"]


def test_a_window_ends_by_itself_when_nothing_was_counted() -> None:
    """No call of due() between (the log arms no timer for a line that did not repeat): the next
    line of the key after its window is written; pruning ended windows forgets none that runs."""
    now = [0.0]
    limiter = RepeatLimiter(window=5.0, clock=lambda: now[0])
    assert limiter.offer("k", "connect") == ["connect"]
    now[0] = 4.9
    assert limiter.offer("k", "connect") == []  # in its window: counted
    assert limiter.pending
    assert limiter.due() == []
    now[0] = 5.0
    assert limiter.due() == ["connect ... repeated 1 times in the last 5 s"]
    now[0] = 10.0  # the window that began with the count ended with nothing counted: no due() needed
    assert limiter.offer("k", "connect") == ["connect"]
    for i in range(1000):  # (the table is pruned of ended windows on the way)
        now[0] += 0.001
        assert limiter.offer(i, "line") == ["line"]
    assert limiter.offer(999, "line") == []  # still in its window after the prunes
    assert limiter.offer("k", "connect") == []


def test_a_repeat_is_counted_before_its_text_is_made() -> None:
    now = [0.0]
    limiter = RepeatLimiter(window=5.0, clock=lambda: now[0])
    assert not limiter.counted("k")  # nothing written yet: the caller makes the text and offers it
    assert limiter.offer("k", "bad byte") == ["bad byte"]
    now[0] = 1.0
    assert limiter.counted("k") and limiter.counted("k") and not limiter.counted("other")
    now[0] = 6.0
    assert not limiter.counted("k")  # the window is over: offered, written after its count
    assert limiter.offer("k", "bad byte") == ["bad byte ... repeated 2 times in the last 6 s", "bad byte"]


def test_bad_bytes_on_poselesta_v8_write_a_line_then_a_count() -> None:
    sim = DevsimProcess("run", "poselesta", "--pty", "--speed", "100")  # V8 takes 1200 baud
    try:
        line = sim.next_match(sim.out, lambda text: ".v8: pty " in text, 30, "the V8 pty")
        path = line.split(" pty ", 1)[1].strip()
        sim.next_match(sim.out, lambda text: text.endswith(": ready"), 30, "ready")
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        try:
            tty.setraw(fd)
            attrs = termios.tcgetattr(fd)
            attrs[4] = attrs[5] = termios.B1200
            termios.tcsetattr(fd, termios.TCSANOW, attrs)
            data = b"\x01" * BAD_BYTES  # odd parity: an ISO parity error, each byte (manual §2.6.4)
            written = 0
            while written < len(data):
                written += os.write(fd, data[written : written + 4096])
            err: list[str] = []
            count = sim.next_match(sim.err, lambda text: "repeated" in text, 60, "the count line", keep=err)
            total = int(re.search(r"repeated (\d+) times", count).group(1))  # type: ignore[union-attr]
            while total < BAD_BYTES - 1 and len(err) < 60:  # the count of the next windows, until every byte is told
                count = sim.next_match(sim.err, lambda text: "repeated" in text, 60, "the next count", keep=err)
                total += int(re.search(r"repeated (\d+) times", count).group(1))  # type: ignore[union-attr]
        finally:
            os.close(fd)
    finally:
        sim.interrupt()
    parity = [text for text in err if "v8_parity_error" in text]
    assert len(parity) <= 1 + BAD_BYTES // 1000, parity[:5]  # (before: one line per byte)
    assert len(err) < 60 and total == BAD_BYTES - 1, err
