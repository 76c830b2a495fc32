"""``devsim replay``: play the device side of a recorded session to a host on a new pty (or a
raw TCP port, for a session recorded on a network port such as Ether-S-Bus on TCP).

The host's bytes are cut into requests by the framing the kind declares on the port
(:attr:`devsim.core.kit.PortDef.framing`; unframed ports: a request is complete when it equals a
recorded one and the recorded one at the cursor does not go on beyond it).  Each request is matched
against the recording's requests (:mod:`devsim.observe.replay.session`), starting at the exchange after
the last one matched and wrapping around: the first that matches byte-exact or by one of the
kind's port's tolerances (GMS96: checksum, FCB; Ether-S-Bus: sequence number).  A match is answered with the recorded answer, each
chunk after its recorded delay divided by ``speed`` (``as_fast``: no delay); answers leave in
order through one queue.

A request the recording does not know:

* ``fallback="error"`` – one line on stderr (``replay: request not in the recording: ...``) and
  silence on the line, as from a dead device; later known requests are answered again.
* ``fallback="live"`` – the live model of the recorded kind takes over for good: a devsim device
  (:mod:`devsim.observe.replay.live`), booted before the pty is offered.  At the handover it is
  sent every request the host wrote that the recording answered, as the host wrote it, at the
  recorded time of the exchange it matched (in virtual time, so at once), its answers discarded,
  so it holds what the host wrote (parameters, modes, positions, a frame count bit); then its
  clock runs in real time (times ``speed``) and the unknown request and all after it go to it.
"""

from __future__ import annotations

import asyncio
from collections import deque
from collections.abc import Callable
from typing import Any

import msgspec

from devsim.core.console import say, stop_on_signals, warn
from devsim.core.device import SerialSettings
from devsim.core.registry import port_framing
from devsim.observe.replay.live import HandoverClock, seed, start_live
from devsim.observe.replay.session import Exchange, Reply, Session

__all__ = ["ReplayPlan", "Replayer", "replay_session"]


class ReplayPlan(msgspec.Struct):
    session: Session
    link: str | None = None
    tcp: tuple[str, int] | None = None  # a raw TCP port instead of the pty
    speed: float = 1.0
    as_fast: bool = False
    fallback: str = "error"  # "error" | "live"
    config: dict[str, Any] = msgspec.field(default_factory=dict)  # the live model's configuration


def _show(message: bytes) -> str:
    return f"{message.decode('latin-1')!r} ({message.hex(' ')})"


class _Outbox:
    """Bytes for the host, each not before its due time, strictly in order."""

    def __init__(self) -> None:
        self.write: Callable[[bytes], None] | None = None
        self._queue: deque[tuple[float, bytes]] = deque()
        self._wake = asyncio.Event()
        self._task = asyncio.get_running_loop().create_task(self._run())

    def put(self, due: float, data: bytes) -> None:
        self._queue.append((due, data))
        self._wake.set()

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        while True:
            while not self._queue:
                self._wake.clear()
                await self._wake.wait()
            due, data = self._queue.popleft()
            wait = due - loop.time()
            if wait > 0:
                await asyncio.sleep(wait)
            if self.write is not None:
                self.write(data)

    async def close(self) -> None:
        self._task.cancel()
        await asyncio.gather(self._task, return_exceptions=True)


class Replayer:
    """The pty's endpoint: matches the host's requests and answers them (see the module docstring)."""

    def __init__(self, plan: ReplayPlan, outbox: _Outbox, live: Any = None,
                 hand_over: Callable[[list[tuple[Exchange, bytes]]], None] | None = None) -> None:
        self.session = plan.session
        self.serial_settings: SerialSettings = plan.session.settings  # the pty is preset with them
        self.framing = port_framing(plan.session.kind, plan.session.port)
        self._adapt = {t.name: t.adapt for t in self.framing.tolerances}
        self.speed = plan.speed
        self.as_fast = plan.as_fast
        self.fallback = plan.fallback
        self.outbox = outbox
        self.live = live  # the live model's Line (fallback "live")
        self.live_now = False
        self._hand_over = hand_over  # seeds the live model with what the host wrote, and starts it
        #: the host's requests the recording answered, with the exchange each matched
        self.heard: list[tuple[Exchange, bytes]] = []
        self._buffer = b""
        self._cursor = 0
        #: how requests were answered: "exact", a tolerance's name, or "unknown"
        self.counts: dict[str, int] = {}

    # -- Endpoint ---------------------------------------------------------------------------
    def attach(self, write: Callable[[bytes], None] | None) -> None:
        self.outbox.write = write

    def feed(self, data: bytes) -> None:
        if self.live_now:
            self.live.feed(data)
            return
        self._buffer += data
        split = self.framing.split
        if split is not None:
            messages, self._buffer = split(self._buffer)
            for index, message in enumerate(messages):
                if self.live_now:  # handed over: the rest goes to the live model
                    self.live.feed(b"".join(messages[index:]) + self._buffer)
                    self._buffer = b""
                    return
                self._request(message)
            return
        self._unframed()

    def host_settings(self, settings: SerialSettings) -> None:
        if self.live is not None:  # a host at the wrong baud rate garbles the live model's line
            self.live.host_settings(settings)

    def host_disconnected(self) -> None:
        self._buffer = b""
        if self.live_now:
            self.live.host_disconnected()

    # -- matching ---------------------------------------------------------------------------
    def _order(self) -> list[Exchange]:
        exchanges = self.session.exchanges
        return exchanges[self._cursor :] + exchanges[: self._cursor]

    def match(self, message: bytes) -> tuple[Exchange, str] | None:
        """The recorded exchange answering ``message`` and how it matched, or ``None``: the first
        from the cursor on that matches byte-exact or by a tolerance (an exact match further on
        does not beat a tolerated one here: a host whose sequence numbers or FCBs differ would
        get a later answer out of order)."""
        keys = [(tolerance.name, tolerance.key, tolerance.key(message)) for tolerance in self.framing.tolerances]
        for exchange in self._order():
            if exchange.request == message:
                return exchange, "exact"
            for name, key, mine in keys:
                if key(exchange.request) == mine:
                    return exchange, name
        return None

    def _unframed(self) -> None:
        """No framing: a request is complete when it equals a recorded one, but not while the
        recorded request at the cursor goes on beyond it (the AS511 PG's DLE ACK before its
        parameter block, which the recording holds as one request with the block: the same
        DLE ACK on its own, further on, answers something else)."""
        if not self._buffer:
            return
        exchanges = self.session.exchanges
        expected = exchanges[self._cursor].request if exchanges else b""
        if len(expected) > len(self._buffer) and expected.startswith(self._buffer):
            return
        found = self.match(self._buffer)
        if found is not None:
            message, self._buffer = self._buffer, b""
            self._answer(message, *found)
            return
        if not any(exchange.request.startswith(self._buffer) for exchange in self.session.exchanges):
            message, self._buffer = self._buffer, b""
            self._unknown(message)

    def _request(self, message: bytes) -> None:
        found = self.match(message)
        if found is None:
            self._unknown(message)
        else:
            self._answer(message, *found)

    def _answer(self, message: bytes, exchange: Exchange, how: str) -> None:
        self.counts[how] = self.counts.get(how, 0) + 1
        self._cursor = (exchange.index + 1) % max(1, len(self.session.exchanges))
        if self.live is not None:
            self.heard.append((exchange, message))
        now = asyncio.get_running_loop().time()
        replies = exchange.replies
        adapt = self._adapt.get(how)
        if adapt is not None and replies:  # the answer made to fit the host's request, as one chunk
            replies = [Reply(replies[0].delay, adapt(message, exchange.answer))]
        for reply in replies:
            delay = 0.0 if self.as_fast else reply.delay / self.speed
            self.outbox.put(now + delay, reply.data)

    def _unknown(self, message: bytes) -> None:
        self.counts["unknown"] = self.counts.get("unknown", 0) + 1
        if self.fallback == "live" and self.live is not None:
            warn(f"replay: request not in the recording: {_show(message)}; "
                 f"the live {self.session.kind} model answers from now on")
            self.live_now = True
            if self._hand_over is not None:
                self._hand_over(self.heard)
            self.heard = []
            self.live.feed(message)
            return
        warn(f"replay: request not in the recording: {_show(message)}; no answer (--fallback error)")


async def replay_session(plan: ReplayPlan) -> int:
    """Serve the replay on a new pty until SIGINT/SIGTERM/SIGHUP; returns the exit status."""
    from devsim.runtime import Runtime
    from devsim.transports.pty import PtyTransport
    from devsim.transports.tcp import TcpTransport

    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    unsignal = stop_on_signals(loop, stop.set)
    outbox = _Outbox()
    clock = HandoverClock()
    runtime = Runtime(clock=clock)
    runtime.add_closer(clock.close)
    try:
        async with runtime:
            live = None
            hand_over: Callable[[list[tuple[Exchange, bytes]]], None] | None = None
            if plan.fallback == "live":
                session = plan.session
                assert session.kind is not None
                try:
                    live, bridge = await start_live(runtime, clock, session.kind, session.port, plan.config)
                except Exception as exc:
                    warn(f"Error: cannot start the live {session.kind} model: {type(exc).__name__}: {exc}")
                    return 1

                def go_live(heard: list[tuple[Exchange, bytes]]) -> None:
                    seed(clock, live, heard)
                    clock.go_live(1.0 if plan.as_fast else plan.speed)
                    bridge.sink = lambda data: outbox.put(loop.time(), data)

                hand_over = go_live
            replayer = Replayer(plan, outbox, live, hand_over)
            transport: Any = PtyTransport(link=plan.link) if plan.tcp is None else TcpTransport(*plan.tcp)
            try:
                await transport.start(replayer)
            except OSError as exc:
                warn(f"Error: cannot open the {'pty' if plan.tcp is None else 'TCP port'}: {exc}")
                return 1
            try:
                if plan.tcp is None:
                    say(f"replay: pty {transport.address}")
                else:
                    say(f"replay: tcp {transport.url}")
                if plan.link:
                    say(f"replay: link {plan.link}")
                warn(f"replay: {len(plan.session.exchanges)} recorded requests of kind "
                     f"{plan.session.kind or '(none)'}; --fallback {plan.fallback}")
                await stop.wait()
            finally:
                await transport.close()
            counts = ", ".join(f"{how} {n}" for how, n in sorted(replayer.counts.items())) or "none"
            warn(f"replay: requests answered: {counts}")
    finally:
        await outbox.close()
        unsignal()
    return 0
