"""The MQTT links' keep-alive clock (devsim.facades.mqtt_keepalive): calls come in their loop's
thread, in the order of their moments, never before them; a call sooner than the one the thread
waits for wakes it; a closed loop's call is dropped and the clock goes on; a forked child
starts a thread of its own."""

from __future__ import annotations

import asyncio
import os
import threading
import time

from devsim.facades.mqtt_keepalive import KeepAliveClock, keepalive_clock


def test_calls_come_in_their_loop_in_order_and_a_closed_loop_is_skipped() -> None:
    clock = KeepAliveClock()
    closed = asyncio.new_event_loop()
    closed.close()

    async def run() -> None:
        loop = asyncio.get_running_loop()
        got: list[tuple[str, int, float]] = []
        done = asyncio.Event()

        def call(name: str) -> None:
            got.append((name, threading.get_ident(), time.monotonic()))
            if name == "last":
                done.set()

        start = time.monotonic()
        clock.call_at(start + 3600, loop, lambda: call("far"))  # the thread waits for this one ...
        clock.call_at(start + 0.3, loop, lambda: call("last"))  # ... and is woken for these
        clock.call_at(start + 0.1, closed, lambda: call("closed"))
        clock.call_at(start + 0.2, loop, lambda: call("second"))
        clock.call_at(start + 0.1, loop, lambda: call("first"))
        await asyncio.wait_for(done.wait(), 10)
        assert [(name, thread) for name, thread, _at in got] == [
            ("first", threading.get_ident()), ("second", threading.get_ident()), ("last", threading.get_ident())]
        assert [at - start >= due for (_name, _thread, at), due in zip(got, (0.1, 0.2, 0.3), strict=True)] == [True] * 3

    asyncio.run(run())


def test_a_forked_child_keeps_its_own_clock() -> None:
    clock = keepalive_clock()

    async def wait_for_a_call() -> None:
        called = asyncio.Event()
        clock.call_at(time.monotonic() + 0.01, asyncio.get_running_loop(), called.set)
        await asyncio.wait_for(called.wait(), 5)

    asyncio.run(wait_for_a_call())  # the process's clock thread runs
    child = os.fork()
    if child == 0:  # (the child: no thread but this one)
        try:
            asyncio.run(wait_for_a_call())
        except BaseException:
            os._exit(1)
        os._exit(0)
    _pid, status = os.waitpid(child, 0)
    assert os.waitstatus_to_exitcode(status) == 0
