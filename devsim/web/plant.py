"""The simulator a web server shows: what it asks over the control API and what it watches.

:class:`PlantView` attaches to the control address (and attaches again when the simulator behind
it stops and another starts there, as between the files of ``devsim scenario run``), reads the
devices and their declared points once, keeps each port's telegrams from then on (op ``telegrams``)
and watches each device as the monitor does (the ``watch`` op's default points, every
:data:`SUMMARY_PERIOD` of device time, and every event), into the device's
:class:`~devsim.web.feed.Feed`.  While a browser looks at a device (:meth:`PlantView.looking_at`)
two more streams sample its axes for the charts every :data:`CHART_PERIOD` and every readable point
for the table every :data:`TABLE_PERIOD`: a plant of many devices is sampled in detail only where
someone looks.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from typing import Any

from devsim.observe.monitor_text import display_line, is_display, message_line
from devsim.runtime.client import ControlError
from devsim.web.feed import Feed, is_chart
from devsim.web.link import ControlLink

__all__ = ["CHART_PERIOD", "TABLE_PERIOD", "PlantView"]

CHART_PERIOD = 0.05  # device seconds between two chart samples
TABLE_PERIOD = 0.25  # device seconds between two samples of every point
SUMMARY_PERIOD = 0.25  # device seconds between two samples of what the plant page shows
RETRY = 0.5  # wall seconds between two attempts to attach
FRESH = 0.4  # wall seconds the plant page's answer serves every browser that asks
FIRST_ATTACH = 10.0  # wall seconds a device's page waits for the first attachment to the simulator


class PlantView:
    """The devices behind ``address`` as the page shows them."""

    def __init__(self, address: str) -> None:
        self.address = address
        self.link = ControlLink(address)
        self.attached = asyncio.Event()
        self.info: dict[str, Any] = {}
        self.infos: list[dict[str, Any]] = []
        self.names: dict[str, list[dict[str, Any]]] = {}
        self.feeds: dict[str, Feed] = {}
        self._task: asyncio.Task[None] | None = None
        self._looking: dict[str, int] = {}  # device → browsers looking at it
        self._details: dict[str, asyncio.Task[None]] = {}
        self._plant: tuple[float, dict[str, Any]] | None = None  # (when, the plant page's answer)

    def start(self) -> None:
        self._task = asyncio.get_running_loop().create_task(self._run())

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        await self.link.close()

    async def _run(self) -> None:
        while True:
            try:
                await self._attach()
            except (OSError, ControlError, ValueError):
                await self.link.close()
                await asyncio.sleep(RETRY)
                continue
            self.attached.set()
            for device, count in self._looking.items():
                if count and device in self.feeds:
                    self._start_detail(device)
            await asyncio.gather(*(self._summary(name) for name in self.feeds))  # until the simulator stops
            self.attached.clear()
            for task in self._details.values():
                task.cancel()
            self._details.clear()
            await self.link.close()
            await asyncio.sleep(RETRY)

    async def _attach(self) -> None:
        self.info = await self.link.request("info")
        infos = await self.link.request("devices")
        names = {info["name"]: await self.link.request("names", device=info["name"]) for info in infos}
        for info in infos:  # the lines keep their telegrams from now on
            for port in info.get("ports") or {}:
                with contextlib.suppress(ControlError):
                    await self.link.request("telegrams", device=info["name"], port=port, count=0)
        self.infos, self.names = infos, names
        old = self.feeds
        self.feeds = {info["name"]: Feed(info["name"]) for info in infos}
        for name, feed in self.feeds.items():  # the browsers watching stay with the new process
            if name in old:
                feed.subscribers = old[name].subscribers

    async def _summary(self, device: str) -> None:
        """What the plant page shows of ``device``, and all its events, until the simulator stops."""
        feed = self.feeds[device]
        with contextlib.suppress(ControlError):
            async for item in self.link.watch(device, None, SUMMARY_PERIOD):
                feed.apply(item)
        feed.ended = True
        feed.apply({"type": "ended", "device": device, "t": feed.t})

    @contextlib.asynccontextmanager
    async def looking_at(self, device: str) -> AsyncIterator[None]:
        """While a browser shows ``device``: its charts and every point are sampled."""
        self._looking[device] = self._looking.get(device, 0) + 1
        if self._looking[device] == 1 and self.attached.is_set() and device in self.feeds:
            self._start_detail(device)
        try:
            yield
        finally:
            self._looking[device] -= 1
            if not self._looking[device]:
                task = self._details.pop(device, None)
                if task is not None:
                    task.cancel()

    def _start_detail(self, device: str) -> None:
        self._details[device] = asyncio.get_running_loop().create_task(self._detail(device))

    async def _detail(self, device: str) -> None:
        """The chart and table streams of ``device`` (their changes: the events come with the summary)."""
        feed = self.feeds[device]
        readable = [p["name"] for p in self.names[device] if "r" in p.get("access", "")]
        charted = [name for name in readable if is_chart(name)]

        async def table() -> None:
            async for item in self.link.watch(device, readable, TABLE_PERIOD):
                if item.get("type") == "change" and not is_chart(str(item.get("name"))):
                    feed.apply(item)

        async def chart() -> None:
            async for item in self.link.watch(device, charted, CHART_PERIOD):
                if item.get("type") == "change":
                    feed.apply(item, chart=True)

        await asyncio.gather(table(), *([chart()] if charted else []), return_exceptions=True)

    # -- what the pages show ----------------------------------------------------------------------
    async def known(self, timeout: float = FIRST_ATTACH) -> bool:
        """Whether the simulator's devices are known: once attached they stay known (across its
        restarts); before the first attachment this waits for it, at most ``timeout`` seconds (a
        page opened the moment the server started asks before the devices have been read)."""
        if not self.infos:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.attached.wait(), timeout)
        return bool(self.infos)

    async def plant(self) -> dict[str, Any]:
        """Every device: kind, ports (where a host connects, the line's settings and its host),
        ready, display, state words, faults; asked at most every :data:`FRESH` seconds, however
        many browsers show the plant page."""
        now = asyncio.get_running_loop().time()
        if self._plant is not None and now - self._plant[0] < FRESH:
            return self._plant[1]
        answer = await self._ask_plant()
        self._plant = (asyncio.get_running_loop().time(), answer)
        return answer

    def changed(self) -> None:
        """A request has changed the plant: the next plant page is asked anew."""
        self._plant = None

    async def _ask_plant(self) -> dict[str, Any]:
        devices = []
        for info in self.infos:
            name = info["name"]
            feed = self.feeds[name]
            ports = {}
            for port, where in (info.get("ports") or {}).items():
                try:
                    line: dict[str, Any] | None = await self.link.request("line", device=name, port=port)
                except ControlError:
                    line = None  # a port not on a line
                connected = feed.hosts.get(port)  # its connect or disconnect, else its settings seen
                if connected is None and line is not None:
                    connected = line.get("host") is not None
                ports[port] = {"address": where, "line": line, "connected": connected}
            values = feed.values
            now = {}  # read as the page is made: the feed watches them only while the device's page is open
            for point in ("ready", "booting"):
                try:
                    now[point] = await self.link.request("read", device=name, name=point)
                except ControlError:
                    now[point] = None  # (a kind without it)
            devices.append({
                "name": name, "kind": info.get("kind"), "ports": ports,
                "ready": now["ready"], "booting": now["booting"],
                "display": display_line(values), "message": message_line(values), "state": status_words(values),
                "faults": sorted(feed.faults), "declared_faults": info.get("faults", []), "ended": feed.ended,
            })
        return {"name": self.info.get("name"), "clock": self.info.get("clock"), "attached": self.attached.is_set(),
                "devices": devices}

    def device(self, name: str) -> dict[str, Any]:
        """One device: its declared points, chart names and what its stream said so far."""
        info = next((i for i in self.infos if i["name"] == name), None)
        if info is None:
            raise KeyError(name)
        points = self.names[name]
        return {"info": info, "points": points, "charts": [p["name"] for p in points if is_chart(p["name"])
                                                           and "r" in p.get("access", "")],
                **self.feeds[name].snapshot()}


#: Points the state words leave out: shown elsewhere (axes, lamps, displays) or not words.
_ELSEWHERE = ("input.", "output.", "axis.", "param.", "line.")


def status_words(values: dict[str, Any], limit: int = 12) -> dict[str, Any]:
    """The device's state as the monitor's state line shows it: scalar points, not axes, inputs,
    outputs or displays, at most ``limit``."""
    words: dict[str, Any] = {}
    for name, value in values.items():
        if name.startswith(_ELSEWHERE) or is_display(name) or isinstance(value, dict | list) or "." in name:
            continue
        words[name] = value
        if len(words) == limit:
            break
    return words
