"""``devsim web [--control ADDR|NAME] [--listen [HOST:]PORT]``: the plant in a browser
(:mod:`devsim.web`) for a running ``devsim run``, ``devsim up`` or real-time scenario, found as
``devsim ctl`` finds it; and :func:`web_option` / :func:`start_web`, the ``--web [HOST:]PORT`` of
``devsim run``, ``devsim up`` and ``devsim scenario run``.  aiohttp (extra ``[web]``) is imported
only here, when a page is served."""

from __future__ import annotations

import asyncio
import contextlib
import sys
from collections.abc import Iterator
from typing import Any

import click

from devsim.cli import exits
from devsim.core.console import say, stop_on_signals, warn

__all__ = ["DEFAULT_PORT", "page_beside", "start_web", "web", "web_option"]

DEFAULT_PORT = 8580


def require_aiohttp(what: str) -> None:
    """A one-line error (a missing extra) unless aiohttp imports."""
    try:
        import aiohttp  # noqa: F401
    except ImportError as exc:
        from devsim.core.extras import install_command

        raise exits.MissingExtra(f"{what} needs aiohttp: {install_command('web')} ({exc})") from None


def web_option(text: str | None, option: str = "--web") -> Any:
    """``--web [HOST:]PORT`` checked (and the extra): its :class:`~devsim.web.server.ListenAddress`, or None."""
    if text is None:
        return None
    from devsim.runtime.control import ControlAddressError
    from devsim.web.server import parse_listen

    try:
        address = parse_listen(text)
    except ControlAddressError as exc:
        raise click.UsageError(f"{option}: {exc}") from None
    require_aiohttp(f"{option}")
    return address


def start_web(control: str, listen: Any) -> tuple[Any, list[str]]:
    """Serve the page for ``control`` on ``listen`` from a thread: the server (``stop()`` it) and
    the lines saying where; a token when the bind is not loopback.  OSError when it cannot listen."""
    from devsim.web.server import WebServer, new_token

    server = WebServer(control, listen, None if listen.is_loopback() else new_token())
    return server, server.start()


@click.command("web")
@click.option(
    "--control", "addr", envvar="DEVSIM_CONTROL", metavar="ADDR",
    help="Control address (unix:/path.sock or [HOST:]PORT) or name of the running plant; default: the only one"
    " running ('devsim ps'); env DEVSIM_CONTROL.",
)
@click.option("--name", "name", metavar="NAME", help="The running simulator or plant of this name (as --control NAME).")
@click.option("--listen", default=str(DEFAULT_PORT), show_default=True, metavar="[HOST:]PORT",
              help="Where to serve the page (host 127.0.0.1 unless named; another host gets a token).")
def web(addr: str | None, name: str | None, listen: str) -> None:
    """Serve the plant in a browser: every device's state, display, faults and lines; per device
    live charts of the axes, the points (settable), faults, power cycle and the decoded traffic;
    a running scenario's steps.  Needs the extra [web] (aiohttp)."""
    if addr is not None and name is not None:
        raise click.UsageError("--control and --name exclude each other")
    address = web_option(listen, "--listen")
    from devsim.cli.running import control_target
    from devsim.runtime.client import ControlClient, ControlError

    target = control_target(addr if addr is not None else name)
    try:
        with ControlClient(target, timeout=5.0) as client:
            client.now()
    except (OSError, ControlError) as exc:
        raise exits.Unreachable(f"cannot connect to {target}: {getattr(exc, 'strerror', None) or exc}") from None
    try:
        asyncio.run(_serve(target, address))
    except KeyboardInterrupt:
        sys.exit(exits.INTERRUPTED)


async def _serve(control: str, listen: Any) -> None:
    from devsim.web.server import new_token, serve, urls

    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    stop_on_signals(loop, stop.set)
    token = None if listen.is_loopback() else new_token()
    try:
        runner, view, port = await serve(control, listen, token)
    except OSError as exc:
        raise exits.SystemFailure(f"cannot serve the page on {listen}: {exc.strerror or exc}") from None
    try:
        for line in urls(listen, port, token):
            say(line)
        warn(f"devsim web: the plant at {control}; Ctrl-C to stop")
        await stop.wait()
    finally:
        await runner.cleanup()
        await view.close()


@contextlib.contextmanager
def page_beside(control: Any, listen: Any) -> Iterator[None]:
    """The page for the control API at ``control`` served from a thread while the block runs
    (``devsim up --web``, ``devsim scenario run --web``; it attaches once the control API answers
    there, and again after each restart); its lines printed first; a one-line error (status
    SYSTEM) when it cannot listen."""
    if listen is None:
        yield
        return
    try:
        server, lines = start_web(str(control), listen)
    except OSError as exc:
        raise exits.SystemFailure(f"cannot serve the web page on {listen}: {exc.strerror or exc}") from None
    try:
        for line in lines:
            say(line)
        yield
    finally:
        server.stop()
