"""Where the web page is served and with which token; :class:`WebServer` on a loop of its own.

``--listen``/``--web`` take ``[HOST:]PORT`` (IPv6 hosts in brackets); the host is ``127.0.0.1``
unless named.  A bind that is not loopback gets a random token (:func:`new_token`) that the page
asks for and every API request must carry; a loopback bind needs none.

:class:`WebServer` runs the aiohttp application (:func:`devsim.web.app.make_app`) in a thread with
its own event loop, so that ``devsim run|up|scenario run --web`` serve the page from the
simulator's process without its browsers ever holding up the simulator's loop.
"""

from __future__ import annotations

import asyncio
import logging
import secrets
import threading
from typing import Any

from devsim.core.console import warn
from devsim.runtime.control import ControlAddress, ControlAddressError, parse_address

__all__ = ["ListenAddress", "WebServer", "new_token", "parse_listen", "serve"]

ListenAddress = ControlAddress


def parse_listen(text: str) -> ListenAddress:
    """``[HOST:]PORT`` (``[V6]:PORT``) as a TCP address; :class:`ControlAddressError` otherwise."""
    if text.strip().startswith("unix:"):
        raise ControlAddressError(f"{text!r}: the page is served on [HOST:]PORT, not on a Unix socket")
    return parse_address(text)


def new_token() -> str:
    """A random token of 128 bits, URL-safe."""
    return secrets.token_urlsafe(16)


def urls(address: ListenAddress, port: int, token: str | None) -> list[str]:
    """The lines that say where the page is: ``web: http://HOST:PORT/`` and, with a token, the
    token and the address that carries it (``#token=``: the page logs in by itself)."""
    host = f"[{address.host}]" if ":" in address.host else address.host
    base = f"http://{host}:{port}/"
    if token is None:
        return [f"web: {base}"]
    return [f"web: {base}#token={token}", f"web token: {token}"]


def _malformed_request(record: logging.LogRecord) -> bool:
    """A request aiohttp cannot parse (a header it refuses, a port scanner's bytes) is answered 400
    Bad Request, and aiohttp logs it with a traceback: one line says it instead."""
    from aiohttp.http_exceptions import HttpProcessingError

    exc = record.exc_info[1] if record.exc_info else None
    if not isinstance(exc, HttpProcessingError) or exc.code != 400:
        return True
    what = (exc.message or "").strip().splitlines()[0].rstrip(":") if exc.message else "not HTTP"
    remote = record.args[0] if isinstance(record.args, tuple) and record.args else "?"
    warn(f"devsim web: a request from {remote} that is not HTTP as it should be ({what}): answered 400 Bad Request")
    return False


async def serve(control: str, listen: ListenAddress, token: str | None) -> tuple[Any, Any, int]:
    """Start the page's server in the running loop: its runner, the plant view and the bound port."""
    from aiohttp import web

    logging.getLogger("aiohttp.server").addFilter(_malformed_request)

    from devsim.web.app import make_app
    from devsim.web.plant import PlantView

    view = PlantView(control)
    view.start()
    runner = web.AppRunner(make_app(view, token), access_log=None, handle_signals=False, shutdown_timeout=2.0)
    await runner.setup()
    site = web.TCPSite(runner, listen.host, listen.port, reuse_address=True)
    try:
        await site.start()
    except BaseException:
        await runner.cleanup()
        await view.close()
        raise
    sockets = getattr(site._server, "sockets", None) or []  # the port the system chose for port 0
    port = int(sockets[0].getsockname()[1]) if sockets else listen.port
    return runner, view, port


class WebServer:
    """The page for the control API at ``control``, served on ``listen`` from a thread."""

    def __init__(self, control: str, listen: ListenAddress, token: str | None) -> None:
        self.control = control
        self.listen = listen
        self.token = token
        self.port = 0
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._done: asyncio.Event | None = None

    def start(self, timeout: float = 10.0) -> list[str]:
        """Listen (an :class:`OSError` when it cannot); the lines saying where (:func:`urls`)."""
        started: dict[str, Any] = {}
        ready = threading.Event()

        async def main() -> None:
            self._done = asyncio.Event()
            try:
                runner, view, self.port = await serve(self.control, self.listen, self.token)
            except BaseException as exc:
                started["error"] = exc
                ready.set()
                return
            ready.set()
            try:
                await self._done.wait()
            finally:
                await runner.cleanup()
                await view.close()

        def run() -> None:
            loop = asyncio.new_event_loop()
            self._loop = loop
            try:
                loop.run_until_complete(main())
            finally:
                loop.close()

        self._thread = threading.Thread(target=run, name="devsim-web", daemon=True)
        self._thread.start()
        if not ready.wait(timeout):
            raise OSError(f"the web server did not start within {timeout} s")
        if "error" in started:
            error = started["error"]
            raise error if isinstance(error, OSError) else OSError(str(error))
        return urls(self.listen, self.port, self.token)

    def stop(self, timeout: float = 10.0) -> None:
        loop, done = self._loop, self._done
        if loop is not None and done is not None and self._thread is not None and self._thread.is_alive():
            loop.call_soon_threadsafe(done.set)
            self._thread.join(timeout)
        self._thread = None
