"""The control API over asyncio streams: what the web page's server asks a simulator.

The same newline-delimited JSON as :class:`devsim.runtime.client.ControlClient` (the protocol:
:mod:`devsim.runtime.control`), on the web server's own event loop: one connection for the
requests (answered in order), one more per watched device.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
from collections.abc import AsyncIterator
from typing import Any

from devsim.runtime.client import ControlError
from devsim.runtime.control import ControlAddress, parse_address

__all__ = ["ControlLink"]

LIMIT = 1 << 22  # bytes in one answer line (200 telegrams with their decoded fields)
TIMEOUT = 10.0  # seconds a request may wait for its answer before the simulator counts as gone

Streams = tuple[asyncio.StreamReader, asyncio.StreamWriter]


class ControlLink:
    """An asyncio client of the control API at ``address`` (``unix:/path.sock`` or ``[HOST:]PORT``)."""

    def __init__(self, address: str | ControlAddress) -> None:
        self.address = parse_address(address) if isinstance(address, str) else address
        self._streams: Streams | None = None
        self._lock = asyncio.Lock()
        self._next_id = 0

    async def _open(self) -> Streams:
        if self.address.path is not None:
            return await asyncio.open_unix_connection(self.address.path, limit=LIMIT)
        return await asyncio.open_connection(self.address.host, self.address.port, limit=LIMIT)

    async def request(self, op: str, **fields: Any) -> Any:
        """One request's ``result``; :class:`ControlError` with the simulator's error type,
        :class:`ConnectionError` when the simulator has gone (or has not answered within
        :data:`TIMEOUT`)."""
        async with self._lock:
            if self._streams is None:
                self._streams = await self._open()
            reader, writer = self._streams
            self._next_id += 1
            message = {"id": self._next_id, "op": op, **{k: v for k, v in fields.items() if v is not None}}
            try:
                writer.write((json.dumps(message) + "\n").encode("utf-8"))
                line = await asyncio.wait_for(self._answer(writer, reader), TIMEOUT)
            except (OSError, asyncio.IncompleteReadError, ValueError, TimeoutError) as exc:
                await self._drop()
                raise ConnectionError(f"control connection broke: {exc}") from None
            if not line:
                await self._drop()
                raise ConnectionError("control connection closed by the simulator")
        reply = json.loads(line)
        if not reply.get("ok"):
            raise ControlError(str(reply.get("error")), str(reply.get("type", "Error")))
        return reply.get("result")

    @staticmethod
    async def _answer(writer: asyncio.StreamWriter, reader: asyncio.StreamReader) -> bytes:
        await writer.drain()
        return await reader.readline()

    async def _drop(self) -> None:
        if self._streams is not None:
            writer = self._streams[1]
            self._streams = None
            writer.close()
            with contextlib.suppress(OSError, ConnectionError):
                await writer.wait_closed()

    async def watch(self, device: str, names: list[str] | None = None, period: float | None = None
                    ) -> AsyncIterator[dict[str, Any]]:
        """The items of a ``watch`` of ``device`` on a connection of its own, until the simulator
        stops (the first ones are the present values)."""
        reader, writer = await self._open()
        try:
            request = {"id": 1, "op": "watch", "device": device, "names": names or None, "period": period}
            writer.write((json.dumps({k: v for k, v in request.items() if v is not None}) + "\n").encode("utf-8"))
            await writer.drain()
            first = json.loads(await reader.readline() or b"{}")
            if not first.get("ok"):
                raise ControlError(str(first.get("error", "the watch ended")), str(first.get("type", "Error")))
            while line := await reader.readline():
                item = json.loads(line)
                if item.pop("watch", None) is not None:
                    yield item
        except (OSError, ValueError):
            return
        finally:
            writer.close()
            with contextlib.suppress(OSError, ConnectionError):
                await writer.wait_closed()

    async def close(self) -> None:
        async with self._lock:
            await self._drop()
