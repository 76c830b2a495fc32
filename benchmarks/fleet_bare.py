"""The bare reference of ``benchmarks/fleet.py --measure requests``: one aiomqtt responder
process that answers the fleet's ``read`` requests for its devices through the same broker,
with no device behind them.

It joins as a fleet member does, as far as a client can tell: a retained announcement on
``ROOT/process/PROCESS`` listing its devices (its last will the same with ``"online": false``),
its request topic subscribed; each request is parsed with :mod:`json` and answered on its
``reply_to`` with ``{"id": ID, "ok": true, "result": false}`` by ``await client.publish``, as
one would write it with aiomqtt.  Prints ``fleet: … as PROCESS`` once it serves.

    python benchmarks/fleet_bare.py URL PROCESS DEVICE [DEVICE ...]
"""

from __future__ import annotations

import asyncio
import json
import sys

import aiomqtt


async def serve(url: str, process: str, devices: list[str]) -> None:
    from devsim.fleet.topics import Topics, parse_fleet_url

    fleet = parse_fleet_url(url)
    topics = Topics(fleet.root)
    request = topics.request(process)

    def announcement(online: bool) -> str:
        return json.dumps({"process": process, "online": online, "request": request, "clock": "real",
                           "devices": [{"name": name, "kind": "bare"} for name in devices]})

    will = aiomqtt.Will(topics.announcement(process), announcement(False), qos=1, retain=True)
    async with aiomqtt.Client(fleet.host, fleet.port, identifier=f"bare-{process}", will=will,
                              protocol=aiomqtt.ProtocolVersion.V5) as client:
        await client.subscribe(request, qos=0)
        await client.publish(topics.announcement(process), announcement(True), qos=1, retain=True)
        print(f"fleet: {url} as {process}", flush=True)
        async for message in client.messages:
            data = json.loads(message.payload)  # type: ignore[arg-type]
            await client.publish(data["reply_to"], json.dumps({"id": data["id"], "ok": True, "result": False}))


if __name__ == "__main__":
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1]))
    try:
        asyncio.run(serve(sys.argv[1], sys.argv[2], sys.argv[3:]))
    except KeyboardInterrupt:
        pass
