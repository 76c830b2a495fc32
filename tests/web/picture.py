"""The picture of the device page in the docs, ``docs/web.png``: ``python -m tests.web.picture``
(run from the checkout, with chromium installed).  A SERS served by ``devsim run --web``, moved
there and back through its pty, shot by the same Playwright set-up as the browser tests."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import serial

from tests.support.process import ROOT
from tests.web.conftest import answer, chromium, start_sers

PICTURE = ROOT / "docs" / "web.png"


def take(path: Path = PICTURE, executable: str = "/usr/bin/chromium") -> None:
    from playwright.sync_api import expect

    with tempfile.TemporaryDirectory(prefix="dsw") as directory:
        process, seen, _ = start_sers("--control", f"unix:{directory}/c.sock")
        try:
            with chromium(executable, 1280, 1000) as browser, serial.Serial(seen["sers"].split(" ", 1)[1], 9600,
                                                                             timeout=5) as port:
                page = browser.new_page()
                page.goto(seen["web"] + "#/device/sers")
                expect(page.locator("#status")).to_have_text("live", timeout=10_000)
                answer(port, b"#1ON V=300 A=200 W=1080 E\r")
                expect(page.locator("#events")).to_contain_text("move_end", timeout=10_000)
                answer(port, b"#1W=-720 E\r")
                expect(page.locator("#events li", has_text="move_end")).to_have_count(2, timeout=10_000)
                answer(port, b"#1P51?\r")
                page.locator("button[data-fault='blocked_axis']").click()
                expect(page.locator("button[data-fault='blocked_axis']")).to_have_text("blocked_axis on")
                page.locator("#filter").fill("axis")
                expect(page.locator("tbody[data-traffic=main] tr").first).to_contain_text("P51")
                page.screenshot(path=str(path), full_page=True)
        finally:
            process.interrupt()


if __name__ == "__main__":
    take(Path(sys.argv[1]) if len(sys.argv) > 1 else PICTURE)
    print(f"wrote {PICTURE if len(sys.argv) < 2 else sys.argv[1]}")
