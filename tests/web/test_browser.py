"""The web page in a real browser: Debian's chromium, headless, driven by Playwright, on the page
of a ``devsim run sers --web`` subprocess whose pty the test talks to as a host would."""

from __future__ import annotations

import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import serial
from playwright.sync_api import expect

from tests.support.process import DevsimProcess, free_port
from tests.support.programs import needs_program
from tests.web.conftest import WebSim, answer, chromium, start_sers
from tests.web.test_api import SCENARIO, non_loopback_address


@pytest.fixture
def browser() -> Iterator[Any]:
    with chromium(needs_program("chromium")) as context:
        yield context


POSITION = "document.querySelector(\"canvas[data-series='axis.position']\")"


def test_a_move_appears_on_the_chart_and_the_page_steers_the_device(sim: WebSim, browser: Any) -> None:
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(sim.url)
    card = page.locator("[data-device=sers]")
    expect(card).to_contain_text(sim.pty, timeout=10_000)  # where a host connects
    expect(card).to_contain_text("9600 8N1")
    card.get_by_role("link", name="sers").click()
    expect(page.locator("#status")).to_have_text("live", timeout=10_000)
    expect(page.locator("tr[data-point='axis.position'] td.value")).to_have_text("0")
    # every value the chart draws, recorded as it is drawn (no timing: a MutationObserver sees each)
    page.evaluate(f"""() => {{
        window.drawn = [];
        new MutationObserver(records => records.forEach(r => window.drawn.push(Number(r.target.dataset.last))))
            .observe({POSITION}, {{attributes: true, attributeFilter: ["data-last"]}});
    }}""")
    with serial.Serial(sim.pty, 9600, timeout=5) as port:
        assert answer(port, b"#1ON W=360 E\r").endswith(b"\nok0\n\r")  # one turn: 12800 increments, about 1 s
        page.wait_for_function(f"Number({POSITION}.dataset.marks) > 0", timeout=5_000)  # move_start marked
        expect(page.locator("#events")).to_contain_text("move_start")
        expect(page.locator("#events")).to_contain_text("move_end", timeout=5_000)
        expect(page.locator("tr[data-point='axis.position'] td.value")).to_have_text("12800")
        # the chart followed the move while it ran (positions between start and end), not only its end
        assert any(0 < value < 12800 for value in page.evaluate("window.drawn"))

        # a value set through the page, checked as `ctl set` checks it, reaches the device
        row = page.locator("tr[data-point='param.P91']")
        row.locator("input").fill("99999999")
        row.locator("button").click()
        expect(row.locator("td.error")).to_have_text("BadValue: P91: errno 122: V zu gro\u00df")
        row.locator("input").fill("500")
        row.locator("input").press("Enter")
        expect(row.locator("td.ok")).to_have_text("set")
        assert answer(port, b"#1V?\r") == b"#1V?\rV=500U/min\n\r\nok1\n\r"

        # a fault switched on the page: the device's answer changes
        page.locator("button[data-fault='emergency_stop']").click()
        expect(page.locator("button[data-fault='emergency_stop']")).to_have_text("emergency_stop on")
        assert answer(port, b"#1ON W=100 E\r").endswith(b"\n*Stop Schalter ist offen\n\r")
        page.locator("button[data-fault='emergency_stop']").click()
        expect(page.locator("button[data-fault='emergency_stop']")).to_have_text("emergency_stop off")

        # the traffic, decoded and newest first; paused, then resumed
        traffic = page.locator("tbody[data-traffic=main]")
        expect(traffic.locator("tr").first).to_contain_text("Stop Schalter")
        page.locator("#pause").click()
        expect(page.locator("#pause")).to_have_text("resume")
        assert answer(port, b"#1P11?\r").startswith(b"#1P11?\rP11=0")
        page.locator("#pause").click()
        expect(traffic.locator("tr").first).to_contain_text("P11=")

        # a line fault and a power cycle
        page.locator("select[data-line-kind=main]").select_option("noise")
        page.locator("button[data-line-on=main]").click()
        expect(page.locator("[data-line-result=main]")).to_have_text("noise on")
        page.locator("button[data-line-off=main]").click()
        expect(page.locator("[data-line-result=main]")).to_have_text("noise off")
    page.locator("#power-cycle").click()
    expect(page.locator("#status")).to_have_text("power cycled")
    assert errors == []


def test_the_scenario_view_shows_the_steps_as_they_pass(browser: Any, tmp_path: Path) -> None:
    path = tmp_path / "progress.yaml"
    path.write_text(SCENARIO, encoding="utf-8")
    run = DevsimProcess("scenario", "run", "--realtime", str(path), "--control", f"unix:{tmp_path}/c.sock",
                        "--web", f"127.0.0.1:{free_port()}")
    try:
        url = run.next_match(run.out, lambda line: line.startswith("web: "), 30, "the page's address")[5:]
        page = browser.new_page()
        page.goto(url)
        view = page.locator("#scenario")
        expect(view).to_have_attribute("data-state", "running", timeout=20_000)
        expect(view.locator("li[data-status=pass]")).to_have_count(3, timeout=20_000)
        expect(view.locator("li[data-status=pending]")).to_have_count(2)  # the wait, the log
        expect(view).to_contain_text("web progress")
        expect(page.locator("[data-device=x]")).to_contain_text("sers")  # the scenario's plant
    finally:
        run.proc.terminate()
        run.proc.wait(timeout=15)


def test_a_non_loopback_page_asks_for_the_token(browser: Any) -> None:
    host = non_loopback_address()
    with tempfile.TemporaryDirectory(prefix="dsw") as directory:
        process, seen, lines = start_sers("--control", f"unix:{directory}/c.sock", web=f"{host}:{free_port()}")
        try:
            token = seen["web token"]
            base = seen["web"].split("#")[0]
            if host == "0.0.0.0":  # no address of its own: the bind is still not loopback
                base = base.replace("0.0.0.0", "127.0.0.1")
            page = browser.new_page()
            page.goto(base)
            expect(page.locator("#login")).to_be_visible(timeout=10_000)
            expect(page.locator("[data-device=sers]")).to_have_count(0)
            page.locator("#token").fill("guess")
            page.locator("#login button").click()
            expect(page.locator("#login-error")).to_have_text("wrong token")
            page.locator("#token").fill(token)
            page.locator("#login button").click()
            expect(page.locator("[data-device=sers]")).to_be_visible(timeout=10_000)
            # the printed address carries the token: a fresh page logs in by itself
            other = browser.browser.new_context() if browser.browser is not None else None
            if other is not None:
                fresh = other.new_page()
                fresh.goto(f"{base}#token={token}")
                expect(fresh.locator("[data-device=sers]")).to_be_visible(timeout=10_000)
                other.close()
        finally:
            assert process.interrupt() == 0


def test_the_device_page_follows_the_simulator_to_its_next_run(browser: Any, tmp_path: Path) -> None:
    control = f"unix:{tmp_path}/c.sock"
    first = DevsimProcess("run", "sers", "--control", control)
    page_server = second = None
    try:
        first.next_match(first.out, lambda line: line == "sers: ready", 30, "sers: ready")
        page_server = DevsimProcess("web", "--control", control, "--listen", f"127.0.0.1:{free_port()}")
        url = page_server.next_match(page_server.out, lambda line: line.startswith("web: "), 30, "the address")[5:]
        page = browser.new_page()
        page.goto(url + "#/device/sers")
        expect(page.locator("#status")).to_have_text("live", timeout=10_000)
        assert first.interrupt() == 0
        expect(page.locator("#status")).to_contain_text("waiting for it", timeout=10_000)
        second = DevsimProcess("run", "sers", "--control", control)
        second.next_match(second.out, lambda line: line == "sers: ready", 30, "sers: ready")
        expect(page.locator("#status")).to_have_text("live", timeout=10_000)
        expect(page.locator("tr[data-point='axis.position'] td.value")).to_have_text("0")
    finally:
        for process in (page_server, second, first):
            if process is not None:
                process.interrupt()
