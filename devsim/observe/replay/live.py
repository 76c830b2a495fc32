"""The live model behind ``devsim replay --fallback live``: a devsim device of the recorded kind,
seeded with the recording, that answers the host once the recording runs out.

The device runs in a :class:`~devsim.runtime.Runtime` on the replay's event loop, behind a
:class:`~devsim.transports.line.Line` served on a :class:`Bridge` (a transport with no port:
the replay feeds it the host's bytes and takes the device's).  Its clock is a
:class:`HandoverClock`: virtual while the model boots and, at the handover, while it is seeded
with what the host wrote (:func:`seed`: each request the recording answered, as the host sent
it, at the instant of the recorded exchange it matched; moves, timeouts and program steps in
between take their simulated time, not wall time), its answers discarded; then real time, from
where the seeding left off.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from devsim.core.clock import Timer, VirtualClock
from devsim.observe.replay.session import Exchange
from devsim.transports.base import Transport

__all__ = ["Bridge", "HandoverClock", "seed", "start_live"]

#: How long (simulated seconds) the live model may take to boot.
BOOT_WAIT = 60.0
#: Simulated time after the last seeded request, for its answer to finish.
SETTLE = 0.5


class HandoverClock(VirtualClock):
    """Virtual time (moved by :meth:`advance`) until :meth:`go_live`; from then on it runs with
    the loop's wall time times ``rate``, firing each timer when that time reaches it."""

    def __init__(self) -> None:
        super().__init__()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._live_at = 0.0
        self._base = 0.0
        self._rate = 1.0
        self._wake: asyncio.Event | None = None
        self._task: asyncio.Task[None] | None = None

    @property
    def virtual(self) -> bool:
        return self._loop is None  # real time once handed over

    def now(self) -> float:
        if self._loop is None:
            return super().now()
        return self._base + (self._loop.time() - self._live_at) * self._rate

    def call_at(self, when: float, callback: Callable[[], Any]) -> Timer:
        timer = super().call_at(when, callback)
        if self._wake is not None:
            self._wake.set()
        return timer

    def go_live(self, rate: float = 1.0) -> None:
        """From now on, real time (``rate`` times as fast), starting at the virtual time reached."""
        if self._loop is not None:
            return
        self._base = super().now()
        self._rate = rate
        self._wake = asyncio.Event()
        self._loop = asyncio.get_running_loop()
        self._live_at = self._loop.time()
        self._task = self._loop.create_task(self._pace())

    async def _pace(self) -> None:
        assert self._wake is not None
        while True:
            self.advance_to(self.now())  # runs the timers due by now
            when = self.next_event()
            self._wake.clear()
            delay = None if when is None else max(0.0, (when - self.now()) / self._rate)
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._wake.wait(), delay)

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            await asyncio.gather(self._task, return_exceptions=True)
            self._task = None


class Bridge(Transport):
    """The live model's transport: what the device sends goes to ``sink`` (``None``: nowhere)."""

    def __init__(self) -> None:
        self.endpoint: Any = None
        self.sink: Callable[[bytes], None] | None = None

    async def start(self, endpoint: Any) -> None:
        self.endpoint = endpoint
        endpoint.attach(self._from_device)

    async def close(self) -> None:
        if self.endpoint is not None:
            self.endpoint.attach(None)

    def _from_device(self, data: bytes) -> None:
        if self.sink is not None:
            self.sink(data)


async def start_live(runtime: Any, clock: HandoverClock, kind: str, port: str,
                     config: Mapping[str, Any]) -> tuple[Any, Bridge]:
    """Create the device in ``runtime`` (whose clock is ``clock``) and boot it; returns its Line
    and Bridge (sink still ``None``).  At the handover the caller seeds it (:func:`seed`), goes
    live (``clock.go_live()``) and sets the sink."""
    device = runtime.add_device(kind, kind, dict(config))
    bridge = Bridge()
    line = await runtime.serve(device, bridge, port=port)
    ready = [False]
    device.on_ready(lambda: ready.__setitem__(0, True))
    if not clock.run_until(lambda: ready[0], BOOT_WAIT):
        raise RuntimeError(f"the live {kind} model did not boot within {BOOT_WAIT:g} simulated seconds")
    return line, bridge


def seed(clock: HandoverClock, line: Any, heard: Sequence[tuple[Exchange, bytes]]) -> None:
    """Send the model what the host wrote before the handover: each ``(exchange, request)`` the
    recording answered, the host's own bytes (its frame count bit, its sequence number), at the
    recorded instant of the exchange (in virtual time), and let the last answer finish."""
    previous = heard[0][0].t if heard else 0.0
    for exchange, request in heard:
        clock.advance(max(0.0, exchange.t - previous))
        previous = max(previous, exchange.t)
        line.feed(request)
    if heard:
        last = heard[-1][0].replies
        clock.advance((last[-1].delay if last else 0.0) + SETTLE)
