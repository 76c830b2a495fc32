"""The bare references of ``benchmarks/fleet.py``: one aiomqtt process per part, with no device
behind it, doing through the same broker what the devsim processes do.

``requests``: it answers the fleet's ``read`` requests for its devices.

It joins as a fleet member does, as far as a client can tell: a retained announcement on
``ROOT/process/PROCESS`` listing its devices (its last will the same with ``"online": false``),
its request topic subscribed; each request is parsed with :mod:`json` and answered on its
``reply_to`` with ``{"id": ID, "ok": true, "result": false}`` by ``await client.publish``, as
one would write it with aiomqtt.  Prints ``fleet: … as PROCESS`` once it serves.

``states``: it stands for the MQTT facade's devices of plant ``bench``: a retained ``online`` on
each ``devsim/bench/DEVICE/status`` (one connection, its last will ``offline`` on the first), and
each ``…/set/quantity.adc_volts`` answered at once by the same value, retained, on
``…/state/quantity.adc_volts``.  Prints ``mqtt: topics …`` once it serves.

    python benchmarks/fleet_bare.py requests URL PROCESS DEVICE [DEVICE ...]
    python benchmarks/fleet_bare.py states HOST PORT DEVICE [DEVICE ...]
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


async def states(host: str, port: int, devices: list[str]) -> None:
    will = aiomqtt.Will(f"devsim/bench/{devices[0]}/status", b"offline", qos=1, retain=True)
    async with aiomqtt.Client(host, port, identifier=f"bare-states-{devices[0]}", will=will) as client:
        for name in devices:
            await client.subscribe(f"devsim/bench/{name}/set/quantity.adc_volts", qos=1)
        for name in devices:
            await client.publish(f"devsim/bench/{name}/status", b"online", qos=1, retain=True)
        print("mqtt: topics devsim/bench/", flush=True)
        async for message in client.messages:
            device = message.topic.value.split("/")[2]
            value = json.dumps(float(message.payload))  # type: ignore[arg-type]
            await client.publish(f"devsim/bench/{device}/state/quantity.adc_volts", value, retain=True)


if __name__ == "__main__":
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1]))
    what, *args = sys.argv[1:]
    try:
        if what == "states":
            asyncio.run(states(args[0], int(args[1]), args[2:]))
        else:
            asyncio.run(serve(args[0], args[1], args[2:]))
    except KeyboardInterrupt:
        pass
