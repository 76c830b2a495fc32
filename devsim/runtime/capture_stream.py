"""One port captured live: every chunk that crosses its line, as a stream of JSON-able dicts.

The control op ``capture`` (:mod:`devsim.runtime.control`), ``devsim ctl capture`` and ``devsim
extcap`` (Wireshark's live capture, :mod:`devsim.wireshark.extcap`) are built on
:class:`CaptureStream`.  It listens on the line's chunk tap (:func:`devsim.transports.tap.chunk_tap`)
in the runtime's loop thread and queues each chunk as it crosses:

* ``{"type": "chunk", "device": D, "port": P, "t": T, "dir": "H>D" | "D>H", "data": HEX,
  "settings": {"baud", "bits", "parity", "stop", "mismatch"}}`` -- ``t`` the device time,
  ``settings`` the host's line settings of the moment (:func:`devsim.transports.line.wire_settings`:
  0 / ``""`` where not known) and whether they differ from the device's;
* ``{"type": "dropped", "device": D, "port": P, "t": T, "count": N}`` -- the subscriber read too
  slowly: its queue (:data:`MAX_QUEUE` chunks, :data:`MAX_BYTES` bytes of them) was full and N
  chunks were left out after the ones before this item.

The queue is bounded per subscriber and filled without waiting, so a slow or stalled reader
never holds the device back; the reader takes whole batches (:meth:`CaptureStream.batches`).
What a port is captured as (:func:`capture_info`): link type USER0 with the port's protocol and
port bytes (a serial line, :class:`devsim.core.kit.CaptureTag`), else raw IPv4.
"""

from __future__ import annotations

import asyncio
from collections import deque
from collections.abc import AsyncIterator
from typing import Any

from devsim.runtime.process import Runtime, port_key
from devsim.transports.line import wire_settings
from devsim.transports.pcap import LINKTYPE_IPV4, LINKTYPE_USER0
from devsim.transports.tap import chunk_tap, untap_chunks

__all__ = ["MAX_BYTES", "MAX_QUEUE", "CaptureStream", "capture_info", "captures"]

#: Chunks a subscriber may have waiting; more are dropped (and counted) until it catches up.
MAX_QUEUE = 4096
#: Bytes of chunks a subscriber may have waiting (as many again go out in one batch): a flooded TCP
#: port's chunks are 16 KiB each, and MAX_QUEUE of them held 130 MB for one reader that stalled.
#: [SIM-CHOICE] the control API's own bound (a watch's ``MAX_BACKLOG``, 4 MiB); no manual has one.
MAX_BYTES = 4 << 20


def capture_info(runtime: Runtime, key: str) -> dict[str, Any]:
    """How the port ``key`` (``port_key``) is captured: ``link`` (147 USER0 for a serial line,
    228 raw IPv4), ``protocol`` and ``port_byte`` (the devsim header's bytes; 0 for IPv4)."""
    tag = runtime.capture_tags.get(key)
    if tag is None:
        return {"link": LINKTYPE_IPV4, "protocol": 0, "port_byte": 0}
    return {"link": LINKTYPE_USER0, "protocol": tag.protocol, "port_byte": tag.port}


def captures(runtime: Runtime) -> dict[str, dict[str, Any]]:
    """Every port on a line (by its key, ``cnc.v7``, ``drive.modbus``) and how it is captured."""
    return {key: capture_info(runtime, key) for key in runtime.lines}


class CaptureStream:
    """Captures the line of ``device``'s ``port`` in ``runtime`` (made, started and stopped in
    the loop thread); :meth:`batches` hands the queued items to one reader."""

    def __init__(self, runtime: Runtime, device: str, port: str = "main", *, limit: int = MAX_QUEUE,
                 max_bytes: int = MAX_BYTES) -> None:
        key = port_key(device, port)
        line = runtime.lines.get(key)
        if line is None:
            runtime.line_status(device, port)  # raises the reason: no such device, port or line
        self.runtime = runtime
        self.device = device
        self.port = port
        self.line: Any = line
        self.limit = limit
        self.max_bytes = max_bytes
        self._bytes = 0  # of the chunks queued
        self.info = {"device": device, "port": port, **capture_info(runtime, key)}
        #: an IPv4 capture's real addresses, where the transport knows them (as a --trace pcap has)
        self._peers = runtime.trace_peers.get(key) if self.info["link"] == LINKTYPE_IPV4 else None
        self.items: deque[dict[str, Any]] = deque()
        #: Chunks dropped since the last batch (the queue was full).
        self.dropped = 0
        #: Chunks dropped in all.
        self.dropped_total = 0
        self._ready = asyncio.Event()
        self._closed = False

    def start(self) -> None:
        chunk_tap(self.line).listeners.append(self._chunk)

    def stop(self) -> None:
        if not self._closed:
            self._closed = True
            untap_chunks(self.line, self._chunk)
            self._ready.set()

    def _chunk(self, direction: str, data: bytes, when: float) -> None:
        if len(self.items) >= self.limit or self._bytes + len(data) > self.max_bytes:
            self.dropped += 1
            self.dropped_total += 1
            self._ready.set()
            return
        item = {"type": "chunk", "device": self.device, "port": self.port, "t": round(when, 6),
                "dir": direction, "data": data.hex(), "settings": wire_settings(self.line)}
        if self._peers is not None and (peers := self._peers()) is not None:
            item["peers"] = peers
        self.items.append(item)
        self._bytes += len(data)
        self._ready.set()

    def take(self) -> list[dict[str, Any]]:
        """What is queued now (a ``dropped`` item after the chunks that came before the drops)."""
        batch = list(self.items)
        self.items.clear()
        self._bytes = 0
        if self.dropped:
            batch.append({"type": "dropped", "device": self.device, "port": self.port,
                          "t": round(self.runtime.clock.now(), 6), "count": self.dropped})
            self.dropped = 0
        return batch

    async def batches(self) -> AsyncIterator[list[dict[str, Any]]]:
        """Batches of items as they come, until :meth:`stop`."""
        while not self._closed:
            await self._ready.wait()
            self._ready.clear()
            batch = self.take()
            if batch:
                yield batch
