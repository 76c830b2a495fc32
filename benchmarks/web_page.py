"""What an open web page costs the device: SERS round trips on its pty with and without a
device page watching, in interleaved runs.

Starts ``devsim run sers --web`` (a subprocess, the page's server on its own thread there), sets
the axis on a long move (so that the charts have samples to send), then in each of ``--runs``
rounds times ``--n`` queries ``#1P11?\\r`` on the pty up to their acknowledgement, first with no
browser, then with one page open: a WebSocket client of the device page (the 0.05 s chart
samples, every point every 0.25 s) taking every batch, and the page's traffic poll every 0.5 s.
Prints p50/p99 of both and the p50 ratio page/none per round.

Target: p50 ratio ≤ 1.1 in each round (the page must not slow the device).

    python benchmarks/web_page.py [--n 500] [--runs 5]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import serial  # noqa: E402

from tests.web.conftest import answer, start_sers  # noqa: E402

RATIO_TARGET = 1.1


def round_trips(pty: str, n: int) -> tuple[float, float]:
    """p50 and p99 of ``n`` queries, in milliseconds."""
    times = []
    with serial.Serial(pty, 9600, timeout=5) as port:
        answer(port, b"#1P11?\r")
        for _ in range(n):
            start = time.perf_counter()
            answer(port, b"#1P11?\r")
            times.append(time.perf_counter() - start)
    times.sort()
    return statistics.median(times) * 1e3, times[int(len(times) * 0.99)] * 1e3


class Page(threading.Thread):
    """A device page's traffic: its WebSocket, read as fast as it comes, and the telegram poll."""

    def __init__(self, url: str) -> None:
        super().__init__(daemon=True)
        self.url = url
        self.stop = threading.Event()
        self.open = threading.Event()
        self.messages = 0

    def run(self) -> None:
        import aiohttp

        async def main() -> None:
            async with aiohttp.ClientSession(self.url) as http:
                ws = await http.ws_connect("/api/ws?device=sers")
                self.open.set()
                polled = 0.0
                while not self.stop.is_set():
                    if time.monotonic() - polled > 0.5:
                        polled = time.monotonic()
                        await (await http.get("/api/devices/sers/telegrams?port=main&count=50")).read()
                    try:
                        await ws.receive_json(timeout=0.2)
                        self.messages += 1
                    except TimeoutError:
                        pass
                await ws.close()

        asyncio.run(main())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=500)
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="dsb") as directory:
        process, seen, _ = start_sers("--control", f"unix:{directory}/c.sock")
        pty = seen["sers"].split(" ", 1)[1]
        try:
            with serial.Serial(pty, 9600, timeout=5) as port:
                answer(port, b"#1ON V=20 W=36000 E\r")  # 100 turns at 20 rpm: five minutes of motion
            print(f"{'round':>5}  {'none p50':>9}  {'none p99':>9}  {'page p50':>9}  {'page p99':>9}  ratio  batches")
            met = 0
            for index in range(1, args.runs + 1):
                bare = round_trips(pty, args.n)
                page = Page(seen["web"])
                page.start()
                page.open.wait(10)
                watched = round_trips(pty, args.n)
                page.stop.set()
                page.join(10)
                ratio = watched[0] / bare[0]
                met += ratio <= RATIO_TARGET
                print(f"{index:>5}  {bare[0]:>7.3f}ms  {bare[1]:>7.3f}ms  {watched[0]:>7.3f}ms  {watched[1]:>7.3f}ms"
                      f"  {ratio:5.2f}  {page.messages}")
            print(f"p50 ratio page/none <= {RATIO_TARGET} in {met} of {args.runs} rounds")
        finally:
            process.interrupt()


if __name__ == "__main__":
    main()
