"""A request in flight to a fleet member that dies fails at once with the offline error, not
after the client's timeout (issue 32, item 6): a real mosquitto, two ``devsim up --part``
members, one frozen (SIGSTOP, so it cannot answer) while a request to it is in flight, then
``kill -9``; the broker's last will marks it offline and the request fails with ``Offline``."""

from __future__ import annotations

import asyncio
import os
import signal
from pathlib import Path

import pytest

from devsim.fleet.client import AsyncFleetClient
from devsim.runtime.client import ControlError
from tests.fleet.conftest import Member
from tests.support.broker import Broker

LONG = 60.0  # the client's timeout: a failure that waited for it would come far too late
BOUND = 20.0  # how long the test waits for the failure


async def test_a_request_in_flight_to_a_killed_member_fails_at_once(plant_file: Path, tmp_path: Path) -> None:
    broker = Broker().start()  # its own: the offline mark stays out of the other tests' listings
    members: list[Member] = []
    try:
        for part in ("cell-a", "cell-c"):
            members.append(Member(["up", str(plant_file), "--part", part], broker.url, tmp_path / f"{part}.log"))
        doomed, other = members
        async with AsyncFleetClient(broker.url, timeout=LONG) as fleet:
            await fleet.wait_for_devices(["feeder", "robot"], timeout=30)
            os.kill(doomed.proc.pid, signal.SIGSTOP)  # it can no longer answer
            asked = asyncio.ensure_future(fleet.request("read", device="feeder", name="input.I1"))
            for _ in range(1000):  # until the request is registered and on its way (no clock involved)
                if fleet.in_flight(doomed.process) or asked.done():
                    break
                await asyncio.sleep(0)
            assert fleet.in_flight(doomed.process) == 1
            os.kill(doomed.proc.pid, signal.SIGKILL)
            await asyncio.to_thread(doomed.proc.wait, 15)
            with pytest.raises(ControlError) as caught:
                await asyncio.wait_for(asked, BOUND)  # a TimeoutError here: it waited for the client timeout
            assert caught.value.type == "Offline"
            assert f"{doomed.process} went offline before answering 'read'" in str(caught.value)
            assert fleet.in_flight() == 0
            # the next request to it is refused at once, the other member still answers
            with pytest.raises(ControlError) as again:
                await fleet.request("read", device="feeder", name="input.I1")
            assert again.value.type == "Offline"
            assert await fleet.request("read", device="robot", name="input.I1") in (False, True, 0, 1)
    finally:
        for member in members:
            member.stop()
        broker.stop()
