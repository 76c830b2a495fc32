"""The plant in a browser: ``devsim web`` and ``devsim run|up|scenario run --web [HOST:]PORT``.

An aiohttp application (extra ``[web]``) that is a client of the control API, like ``devsim ctl``
and ``devsim monitor``: the same ops, the same watch stream (:mod:`devsim.runtime.watch_stream`).
It runs on a loop of its own (a thread in the simulator's process, or ``devsim web``'s own process),
so a browser never holds up a device's clock or ports; each browser has a bounded queue that drops
chart points, never device events (:mod:`devsim.web.feed`).

* :mod:`devsim.web.link` -- the control API over asyncio streams;
* :mod:`devsim.web.feed` -- one watched device, fanned out to the browsers;
* :mod:`devsim.web.app` -- the routes (JSON, the WebSocket, the page's static files) and the token;
* :mod:`devsim.web.server` -- where it listens, the token, the thread of ``--web``.
"""
