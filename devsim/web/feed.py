"""One watched device fanned out to the browsers, each through a bounded :class:`Subscriber`.

A :class:`Feed` reads the device's ``watch`` stream (:mod:`devsim.runtime.watch_stream`) as fast as
it comes, keeps what the plant page needs (the latest values, the active faults and line faults,
the hosts on the lines) and hands every item to each browser's :class:`Subscriber` without waiting
for any browser.  A subscriber keeps, until its browser takes them:

* the device's events (motion, faults, errors, refusals, connects, line faults) -- never dropped;
  a browser that lets :data:`MAX_EVENTS` pile up, or does not take a batch within
  :data:`devsim.web.app.SEND_TIMEOUT`, is disconnected (``overflow``) and loads the page anew;
* the latest value of every watched point -- coalesced, the newest always kept;
* chart points (``axis[.N].position``, ``velocity``, ``following_error``) -- at most
  :data:`MAX_POINTS`; the oldest is dropped when a slow browser lets them pile up, and counted.
"""

from __future__ import annotations

import asyncio
import re
from collections import deque
from typing import Any

__all__ = ["CHART", "MAX_EVENTS", "MAX_POINTS", "Feed", "Subscriber", "is_chart"]

MAX_POINTS = 2000  # chart points a browser may leave untaken
MAX_EVENTS = 10000  # device events a browser may leave untaken before it is disconnected
RECENT = 200  # events a feed keeps for a page that opens later
#: The points a device page draws as charts.
CHART = re.compile(r"^axis(?:\.[^.]+)?\.(position|velocity|following_error)$")


def is_chart(name: str) -> bool:
    return CHART.match(name) is not None


class Subscriber:
    """What one browser has not taken yet (see the module's docstring)."""

    def __init__(self, devices: set[str] | None = None, *, max_points: int = MAX_POINTS) -> None:
        self.devices = devices  # None: every device
        self.events: list[dict[str, Any]] = []
        self.values: dict[tuple[str, str], dict[str, Any]] = {}
        self.points: deque[dict[str, Any]] = deque(maxlen=max_points)
        self.dropped = 0  # chart points dropped, in all
        self.overflow = False
        self.ready = asyncio.Event()

    def wants(self, device: str) -> bool:
        return self.devices is None or device in self.devices

    def put(self, item: dict[str, Any], chart: bool = False) -> None:
        """Take one item of the stream (never waits); ``chart``: a sample of a chart's stream."""
        if self.overflow:
            return  # it is being disconnected: the page reloads what is now
        if item.get("type") == "change":
            name = str(item.get("name"))
            self.values[(str(item.get("device")), name)] = item
            if chart and is_chart(name) and isinstance(item.get("value"), int | float):
                if len(self.points) == self.points.maxlen:
                    self.dropped += 1
                self.points.append(item)
        else:
            self.events.append(item)
            if len(self.events) > MAX_EVENTS:
                self.overflow = True
        self.ready.set()

    def take(self) -> dict[str, Any]:
        """Everything waiting, as one message to the browser: ``events``, ``values`` (latest
        change per point), ``points`` (chart samples, oldest first) and ``dropped`` (so far)."""
        batch = {"events": self.events, "values": list(self.values.values()), "points": list(self.points),
                 "dropped": self.dropped}
        self.events = []
        self.values = {}
        self.points.clear()
        self.ready.clear()
        return batch


class Feed:
    """The watch stream of one device, what it says about the device now, and its subscribers."""

    def __init__(self, device: str) -> None:
        self.device = device
        self.values: dict[str, Any] = {}
        self.faults: set[str] = set()
        self.hosts: dict[str, bool] = {}  # port → a host is connected (as the stream last said)
        self.recent: deque[dict[str, Any]] = deque(maxlen=RECENT)
        self.subscribers: set[Subscriber] = set()
        self.ended = False
        self.t = 0.0  # the device time last heard of

    def apply(self, item: dict[str, Any], chart: bool = False) -> None:
        """One item of the streams: remember it, hand it to every subscriber (``chart``: a
        sample of the chart stream, a point for the charts)."""
        kind = item.get("type")
        if isinstance(item.get("t"), int | float):
            self.t = float(item["t"])
        if kind == "change":
            self.values[str(item.get("name"))] = item.get("value")
        else:
            self.recent.append(item)
            if kind == "fault":
                (self.faults.add if item.get("active") else self.faults.discard)(str(item.get("name")))
            elif kind in ("connect", "disconnect"):
                self.hosts[str(item.get("port", "main"))] = kind == "connect"
        for subscriber in list(self.subscribers):
            if subscriber.wants(self.device):
                subscriber.put(item, chart)

    def snapshot(self) -> dict[str, Any]:
        """What the stream has said so far: values, active faults, hosts, the recent events."""
        return {"values": dict(self.values), "faults": sorted(self.faults), "hosts": dict(self.hosts),
                "events": list(self.recent), "ended": self.ended, "t": self.t}
