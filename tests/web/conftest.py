"""A SERS served by ``devsim run --web`` in a subprocess: its page's address, its pty and its
control socket."""

from __future__ import annotations

import contextlib
import re
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest

from tests.support.process import DevsimProcess, free_port


@dataclass
class WebSim:
    process: DevsimProcess
    url: str  # http://127.0.0.1:PORT/
    pty: str
    control: str
    lines: list[str]


def start_sers(*extra: str, web: str | None = None) -> tuple[DevsimProcess, dict[str, str], list[str]]:
    """``devsim run sers --web WEB …``; its first lines by their keys (``web``, ``sers``, ``control``)."""
    process = DevsimProcess("run", "sers", "--web", web or f"127.0.0.1:{free_port()}", *extra)
    lines: list[str] = []
    process.next_match(process.out, lambda line: line == "sers: ready", 30, "sers: ready", keep=lines)
    seen: dict[str, str] = {}
    for line in lines:
        key, _, value = line.partition(": ")
        seen.setdefault(key, value)
    return process, seen, lines


@pytest.fixture
def sim() -> Iterator[WebSim]:
    with tempfile.TemporaryDirectory(prefix="dsw") as directory:
        control = f"unix:{directory}/c.sock"
        process, seen, lines = start_sers("--control", control)
        try:
            assert seen["sers"].startswith("pty /dev/"), lines
            yield WebSim(process, seen["web"], seen["sers"].split(" ", 1)[1], control, lines)
        finally:
            assert process.interrupt() == 0


def answer(port: Any, command: bytes) -> bytes:
    """Send a SERS line and read its whole answer: up to ``ok<d>`` or an error line ``*…``
    (the port's timeout bounds each read)."""
    port.write(command)
    got = b""
    while not re.search(rb"(\nok\d|\n\*[^\n]*)\n\r$", got):
        chunk = port.read_until(b"\n\r")
        if not chunk:
            raise AssertionError(f"no whole answer to {command!r}: {got!r}")
        got += chunk
    return got


#: Chromium's switches for the browser tests and the docs picture: headless, no sandbox (CI
#: containers run as root), nothing fetched from the network on its own.
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@contextlib.contextmanager
def chromium(executable: str, width: int = 1280, height: int = 900) -> Iterator[Any]:
    """A Playwright browser context of Debian's chromium at ``executable`` in a fresh user-data dir."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright, tempfile.TemporaryDirectory(prefix="dsc") as profile:
        context = playwright.chromium.launch_persistent_context(
            profile, executable_path=executable, args=CHROMIUM_ARGS, viewport={"width": width, "height": height})
        try:
            yield context
        finally:
            context.close()
