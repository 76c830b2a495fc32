"""The web page's server: an aiohttp application over a :class:`~devsim.web.plant.PlantView`.

Routes (JSON unless said otherwise):

* ``GET /`` the page, ``GET /static/…`` its script and style (shipped in the package, no CDN);
* ``GET /api/plant`` every device as the plant page shows it;
* ``GET /api/devices/{device}`` its declared points, charts, values, faults and recent events;
* ``GET /api/devices/{device}/telegrams?port=P&count=N`` the port's traffic, decoded by the kind's
  framing (control op ``telegrams``), newest last;
* ``POST /api/devices/{device}/{action}`` one of :data:`ACTIONS` (``set``, ``fault``,
  ``line_fault``, ``power_cycle``): the control op of the same name, with its checks; a refusal
  is ``422 {"error", "type"}``;
* ``GET /api/scenario`` a running scenario's steps and progress (control op ``scenario``);
* ``GET /api/ws[?device=NAME]`` a WebSocket: first ``{"snapshot": …}``, then batches of
  :meth:`~devsim.web.feed.Subscriber.take` at most every :data:`BATCH` seconds;
* ``POST /api/login {"token"}`` sets the token cookie.

With a token (a bind that is not loopback) every ``/api/`` request but the login needs it, as the
cookie ``devsim_token`` or the header ``X-Devsim-Token``; without one, ``/api/`` answers only
requests addressed to a loopback name (no DNS rebinding).  A ``POST`` must be JSON (no form
posted from another site), a WebSocket must come from the page's own origin.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any
from urllib.parse import SplitResult, urlsplit

from aiohttp import WSMsgType, web

from devsim.core.points import BadValue, parse_bool
from devsim.observe.monitor_text import LINE_FAULTS
from devsim.runtime.client import ControlError
from devsim.web.feed import Subscriber
from devsim.web.plant import PlantView

__all__ = ["ACTIONS", "BATCH", "COOKIE", "HEADER", "STATIC", "make_app"]

STATIC = Path(__file__).parent / "static"
COOKIE = "devsim_token"
HEADER = "X-Devsim-Token"
BATCH = 0.05  # seconds between two messages to one browser
SEND_TIMEOUT = 10.0  # seconds a browser may take to take one batch before it is disconnected
VIEW: web.AppKey[PlantView] = web.AppKey("view", PlantView)
TOKEN: web.AppKey[str | None] = web.AppKey("token", str)
SOCKETS: web.AppKey[set[web.WebSocketResponse]] = web.AppKey("sockets", set)
LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1"})

Action = Callable[[PlantView, str, dict[str, Any]], Awaitable[Any]]


def _flag(body: dict[str, Any], name: str, default: bool = True) -> Any:
    """The flag as the page sent it: the control API checks it as it checks ``ctl``'s (a word
    that is no boolean is refused there; read here as off, it switched a fault off)."""
    return body.get(name, default)


async def _set(view: PlantView, device: str, body: dict[str, Any]) -> Any:
    return await view.link.request("set", device=device, name=body.get("name"), value=body.get("value"))


async def _fault(view: PlantView, device: str, body: dict[str, Any]) -> Any:
    return await view.link.request("fault", device=device, kind=body.get("kind"), active=_flag(body, "active"))


async def _line_fault(view: PlantView, device: str, body: dict[str, Any]) -> Any:
    active = _flag(body, "active")
    kind = body.get("kind")
    params = body.get("params")
    if not isinstance(params, dict):
        try:
            on = parse_bool(active)
        except BadValue:
            on = True  # (the control API refuses the word itself, with its message)
        params = dict(LINE_FAULTS.get(str(kind), {})) if on else {}
    return await view.link.request("line_fault", device=device, kind=kind, active=active,
                                   port=body.get("port") or "main", params=params)


async def _power_cycle(view: PlantView, device: str, body: dict[str, Any]) -> Any:
    return await view.link.request("power_cycle", device=device, wipe=_flag(body, "wipe", False))


#: What the device page may do: action → the control request it makes.
ACTIONS: dict[str, Action] = {"set": _set, "fault": _fault, "line_fault": _line_fault, "power_cycle": _power_cycle}


def _refused(exc: ControlError) -> web.Response:
    return web.json_response({"error": str(exc.args[0]), "type": exc.type}, status=422)


def _unreachable(exc: Exception) -> web.Response:
    return web.json_response({"error": f"the simulator does not answer: {exc}", "type": "Unreachable"}, status=503)


async def _index(_request: web.Request) -> web.StreamResponse:
    return web.FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-cache"})


async def _plant(request: web.Request) -> web.Response:
    try:
        return web.json_response(await request.app[VIEW].plant())
    except ControlError as exc:
        return _refused(exc)
    except (OSError, ConnectionError) as exc:
        return _unreachable(exc)


async def _device(request: web.Request) -> web.Response:
    if not await request.app[VIEW].known():
        return _unreachable(ConnectionError("its devices are not known yet"))
    try:
        return web.json_response(request.app[VIEW].device(request.match_info["device"]))
    except KeyError:
        return web.json_response({"error": f"no device {request.match_info['device'][:60]!r}",
                                  "type": "UnknownDevice"}, status=404)


async def _telegrams(request: web.Request) -> web.Response:
    try:
        count = int(request.query.get("count", "50"))
    except ValueError:
        return web.json_response({"error": "count: a number", "type": "BadRequest"}, status=400)
    try:
        found = await request.app[VIEW].link.request("telegrams", device=request.match_info["device"],
                                                     port=request.query.get("port", "main"), count=count)
    except ControlError as exc:
        return _refused(exc)
    except (OSError, ConnectionError) as exc:
        return _unreachable(exc)
    return web.json_response(found)


async def _json_body(request: web.Request) -> Any:
    """The request's JSON body, ``None`` when it is not JSON, nested too deep to decode (a
    ``RecursionError``), in a charset Python does not know (``charset=nope``: a ``LookupError``)
    or cut off by a client that left mid-body (``ConnectionResetError``); each answered 500 with
    a traceback in the log."""
    try:
        return await request.json()
    except (ValueError, RecursionError, LookupError, ConnectionResetError):
        return None


async def _action(request: web.Request) -> web.Response:
    action = ACTIONS.get(request.match_info["action"])
    if action is None:
        return web.json_response({"error": f"no action {request.match_info['action'][:40]!r} (actions: "
                                  f"{', '.join(ACTIONS)})", "type": "BadRequest"}, status=404)
    body = await _json_body(request)
    if not isinstance(body, dict):
        return web.json_response({"error": "the body: a JSON object", "type": "BadRequest"}, status=400)
    view = request.app[VIEW]
    try:
        result = await action(view, request.match_info["device"], body)
    except ControlError as exc:
        return _refused(exc)
    except (OSError, ConnectionError) as exc:
        return _unreachable(exc)
    finally:
        view.changed()
    return web.json_response({"ok": True, "result": result})


async def _scenario(request: web.Request) -> web.Response:
    try:
        return web.json_response(await request.app[VIEW].link.request("scenario"))
    except ControlError as exc:
        return _refused(exc)
    except (OSError, ConnectionError) as exc:
        return _unreachable(exc)


async def _login(request: web.Request) -> web.Response:
    token = request.app[TOKEN]
    body = await _json_body(request)
    given = str(body.get("token", "")) if isinstance(body, dict) else ""
    if token is not None and not _is_token(given, token):
        return web.json_response({"error": "wrong token", "type": "Unauthorized"}, status=401)
    response = web.json_response({"ok": True})
    if token is not None:
        response.set_cookie(COOKIE, token, httponly=True, samesite="Strict", path="/")
    return response


async def _ws(request: web.Request) -> web.StreamResponse:
    view = request.app[VIEW]
    device = request.query.get("device")
    if device is not None and not await view.known():
        return _unreachable(ConnectionError("its devices are not known yet"))
    if device is not None and device not in view.feeds:
        return web.json_response({"error": f"no device {device[:60]!r}", "type": "UnknownDevice"}, status=404)
    origin = request.headers.get("Origin")
    site = _split(origin) if origin is not None else None
    if origin is not None and (site is None or site.netloc != request.host):
        return web.json_response({"error": "another site's page", "type": "Forbidden"}, status=403)
    ws = web.WebSocketResponse(heartbeat=20.0)
    await ws.prepare(request)
    request.app[SOCKETS].add(ws)
    subscriber = Subscriber({device} if device else None)
    feeds = [view.feeds[device]] if device else list(view.feeds.values())
    for feed in feeds:
        feed.subscribers.add(subscriber)

    async def listen() -> None:  # the browser says nothing; this notices it leave
        async for message in ws:
            if message.type == WSMsgType.ERROR:
                break

    listener = asyncio.get_running_loop().create_task(listen())
    looking = view.looking_at(device) if device is not None else contextlib.nullcontext()
    try:
        async with looking:
            await ws.send_json({"snapshot": {feed.device: feed.snapshot() for feed in feeds}})
            await _send(ws, subscriber, listener)
    except (ConnectionError, RuntimeError):
        pass  # the browser has gone
    finally:
        request.app[SOCKETS].discard(ws)
        for feed in list(view.feeds.values()) + feeds:
            feed.subscribers.discard(subscriber)
        listener.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await listener
    return ws


async def _send(ws: web.WebSocketResponse, subscriber: Subscriber, listener: asyncio.Task[None]) -> None:
    """What the subscriber gathers, in batches, until the browser leaves (``listener`` ends)."""
    while not listener.done():
        waiter = asyncio.ensure_future(subscriber.ready.wait())
        await asyncio.wait({waiter, listener}, return_when=asyncio.FIRST_COMPLETED)
        waiter.cancel()
        if listener.done():
            return
        if subscriber.overflow:  # events it has not taken pile up: it reloads rather than miss one
            await ws.close(code=4000, message=b"too slow: reload")
            return
        try:
            await asyncio.wait_for(ws.send_json(subscriber.take()), SEND_TIMEOUT)
        except TimeoutError:
            subscriber.overflow = True
            await ws.close(code=4000, message=b"too slow: reload")
            return
        await asyncio.sleep(BATCH)  # batches: what comes meanwhile goes in the next one


async def _close_sockets(app: web.Application) -> None:
    for ws in list(app[SOCKETS]):
        await ws.close(code=1001, message=b"the server stops")


def _is_token(given: str, token: str) -> bool:
    """``given`` is the token (compared in constant time).  A header's bytes that are no UTF-8
    (``\\xff``: aiohttp's surrogate escapes) or a JSON string's lone surrogate are compared as they
    are; encoded strictly they raised UnicodeEncodeError, a 500 with a traceback."""
    return hmac.compare_digest(given.encode("utf-8", "surrogatepass"), token.encode())


def _split(url: str) -> SplitResult | None:
    """``url`` in its parts, None where it is no URL (``http://[``: urlsplit raised ValueError,
    a 500 with a traceback, for an Origin or Host header a client sent)."""
    try:
        return urlsplit(url)
    except ValueError:
        return None


@web.middleware
async def _guard(request: web.Request, handler: Callable[[web.Request], Awaitable[web.StreamResponse]]
                 ) -> web.StreamResponse:
    """The token (or, without one, a loopback name as host) for every ``/api/`` request but the
    login; JSON bodies only."""
    if request.path.startswith("/api/") and request.path != "/api/login":
        token = request.app[TOKEN]
        if token is None:
            addressed = _split(f"//{request.host}")
            if addressed is None or (addressed.hostname or "") not in LOOPBACK_NAMES:
                return web.json_response({"error": "served on loopback: address it as localhost or 127.0.0.1",
                                          "type": "Forbidden"}, status=403)
        else:
            given = request.cookies.get(COOKIE) or request.headers.get(HEADER) or ""
            if not _is_token(given, token):
                return web.json_response({"error": "the page needs the token devsim printed at start",
                                          "type": "Unauthorized"}, status=401)
    if request.method == "POST" and request.content_type != "application/json":
        return web.json_response({"error": "the body: JSON (Content-Type: application/json)",
                                  "type": "BadRequest"}, status=415)
    return await handler(request)


def make_app(view: PlantView, token: str | None) -> web.Application:
    """The application for ``view``; ``token``: what every API request must carry (None: none,
    on a loopback bind only)."""
    app = web.Application(middlewares=[_guard], client_max_size=1 << 20)
    app[VIEW] = view
    app[TOKEN] = token
    app[SOCKETS] = set()
    app.on_shutdown.append(_close_sockets)
    app.router.add_get("/", _index)
    app.router.add_static("/static/", STATIC)
    app.router.add_get("/api/plant", _plant)
    app.router.add_get("/api/scenario", _scenario)
    app.router.add_get("/api/ws", _ws)
    app.router.add_post("/api/login", _login)
    app.router.add_get("/api/devices/{device}", _device)
    app.router.add_get("/api/devices/{device}/telegrams", _telegrams)
    app.router.add_post("/api/devices/{device}/{action}", _action)
    return app
