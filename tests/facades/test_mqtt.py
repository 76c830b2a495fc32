"""The MQTT facade in the devsim convention (issue 14), on a real mosquitto and on the embedded
amqtt broker, checked with mosquitto_sub / mosquitto_pub: birth, status, retained state, state
after a set and after the device changed by itself (sampled at the rate, in virtual time; at once
after a moment of the model: test_mqtt_events.py), fault and power-cycle commands, refusals on
…/error, and the last will when ``devsim run`` is killed."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from pathlib import Path

import pytest

from devsim.facades.mqtt import start_broker, start_mqtt
from devsim.runtime import Runtime
from tests.support.broker import Broker
from tests.support.mqtt import Sub, pub
from tests.support.process import free_port
from tests.test_cli import Sim

_plants = itertools.count()
RATE = 0.5


@pytest.fixture(scope="module")
def mosquitto() -> Iterator[Broker]:
    broker = Broker().start()
    yield broker
    broker.stop()


class Served:
    """A sers named ``x`` in a virtual-time runtime, published over MQTT as plant ``plant``."""

    def __init__(self, runtime: Runtime, port: int, plant: str) -> None:
        self.runtime, self.port, self.plant = runtime, port, plant
        self.base = f"devsim/{plant}/x"
        self.device = runtime.devices["x"]

    def sub(self) -> Sub:
        return Sub(self.port, f"{self.base}/#")


def broker_port(lines: list[str]) -> int:
    """The port of ``mqtt: broker mqtt://127.0.0.1:PORT ...``."""
    first = lines[0].split()[2]
    assert first.startswith("mqtt://127.0.0.1:"), lines
    return int(first.rpartition(":")[2])


@pytest.fixture(params=["mosquitto", "embedded"])
def served(request: pytest.FixtureRequest, mosquitto: Broker) -> Iterator[Served]:
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        plant = f"p{next(_plants)}"
        url = mosquitto.url if request.param == "mosquitto" else None
        lines = runtime.run(start_mqtt(runtime, [device], url, plant=plant, rate=RATE), timeout=20)
        assert lines[0].endswith("(embedded)") == (url is None)
        yield Served(runtime, broker_port(lines), plant)
    finally:
        runtime.stop()


def test_birth_status_and_retained_state(served: Served) -> None:
    with served.sub() as sub:
        birth = sub.wait(f"{served.base}/birth")
        assert birth.retain
        body = birth.json()
        assert body["device"] == "x" and body["kind"] == "sers" and body["rate"] == RATE
        assert [p["name"] for p in body["points"]] == served.device.points.names()
        position = next(p for p in body["points"] if p["name"] == "axis.position")
        assert (position["type"], position["unit"], position["access"]) == ("float", "inc", "r")
        assert next(p for p in body["points"] if p["name"] == "input.I1")["access"] == "rw"
        assert "emergency_stop" in body["faults"]
        assert sub.wait(f"{served.base}/status").text == "online"
        state = sub.wait(f"{served.base}/state/axis.position")
        assert state.retain and state.json() == 0.0
        display = sub.wait(f"{served.base}/state/display").json()
        assert display == served.runtime.read("x", "display")


def test_a_set_and_a_change_by_the_device_are_published(served: Served) -> None:
    state = f"{served.base}/state"
    with served.sub() as sub:
        assert sub.wait(f"{state}/input.I1").json() is False
        pub(served.port, f"{served.base}/set/input.I1", "true")
        assert sub.wait(f"{state}/input.I1", lambda m: m.json() is True)
        assert served.runtime.read("x", "input.I1") is True
        pub(served.port, f"{served.base}/set/input.I1", "false")  # plain text as well as JSON
        assert sub.wait(f"{state}/input.I1", lambda m: m.json() is False)

        # an analog quantity set through the control API is no moment of the model (an input
        # would be: tests/facades/test_mqtt_events.py): it is seen at the next sample
        temperature = f"{state}/quantity.heatsink_temperature"
        before = sub.wait(temperature).json()
        served.runtime.set("x", "quantity.heatsink_temperature", before + 11.5)
        with Sub(served.port, temperature) as late:
            assert late.wait(temperature).json() == before  # not sampled yet
        served.runtime.advance(RATE)
        assert sub.wait(temperature, lambda m: m.json() == before + 11.5)
    with Sub(served.port, temperature) as late:  # and it is what a newcomer gets
        retained = late.wait(temperature)
        assert retained.retain and retained.json() == before + 11.5


def test_a_set_at_qos_0_works_while_someone_watches_every_topic(served: Served) -> None:
    """What the docs suggest, ``mosquitto_sub -t 'devsim/#'`` to watch and ``mosquitto_pub`` (QoS 0)
    to command: amqtt 0.12.1 sent every connecting client the retained messages of every other
    client's subscriptions, so a watcher of the retained state made each mosquitto_pub take the
    whole state first, and its QoS 0 set was lost."""
    state = f"{served.base}/state"
    with Sub(served.port, "devsim/#") as watcher:
        assert watcher.wait(f"{state}/input.I1").json() is False
        with Sub(served.port, "elsewhere/#") as other:  # no retained message of ours is its business
            pub(served.port, f"{served.base}/set/input.I1", "true", qos=0)
            assert watcher.wait(f"{state}/input.I1", lambda m: m.json() is True)
            assert served.runtime.read("x", "input.I1") is True
            pub(served.port, "elsewhere/ping", "1", qos=0)
            assert other.wait("elsewhere/ping").text == "1"
            assert [m.topic for m in other.seen if m.topic.startswith("devsim/")] == []


def test_fault_and_power_cycle_commands(served: Served) -> None:
    state = f"{served.base}/state"
    with served.sub() as sub:
        assert sub.wait(f"{state}/input.stop").json() is False
        pub(served.port, f"{served.base}/fault/emergency_stop", "true")
        assert sub.wait(f"{state}/input.stop", lambda m: m.json() is True)

        assert sub.wait(f"{state}/booting").json() is True  # from power-on
        served.runtime.advance(2 + RATE)  # the SERS boots in 2 s; the next sample shows it
        assert sub.wait(f"{state}/booting", lambda m: m.json() is False)
        pub(served.port, f"{served.base}/power_cycle", "")
        assert sub.wait(f"{state}/booting", lambda m: m.json() is True)
        served.runtime.advance(2 + RATE)
        assert sub.wait(f"{state}/booting", lambda m: m.json() is False)


REFUSED = [
    ("set/axis.position", "5", "ReadOnlyName", "read-only"),
    ("set/input.I1", "maybe", "BadValue", "boolean"),
    ("set/nope", "1", "UnknownName", "nope"),
    ("fault/nope", "true", "UnknownName", "no fault 'nope'"),
    ("fault/emergency_stop", "perhaps", "BadValue", "boolean"),
    ("power_cycle", '{"now": 1}', "BadRequest", "wipe"),
    # a level too many or too few: answered, not lost at the broker's filter
    ("set/input/I1", "true", "BadRequest", "topic ends in set/<point>"),
    ("set", "true", "BadRequest", "topic ends in set/<point>"),
    ("fault/emergency_stop/now", "true", "BadRequest", "topic ends in fault/<kind>"),
    ("power_cycle/now", "", "BadRequest", "topic ends in power_cycle"),
]


def test_a_refused_command_is_answered_on_error(served: Served) -> None:
    with served.sub() as sub:
        sub.wait(f"{served.base}/birth")  # subscribed (a retained message came back)
        for topic, payload, kind, words in REFUSED:
            pub(served.port, f"{served.base}/{topic}", payload)
            error = sub.wait(f"{served.base}/error")
            assert not error.retain
            body = error.json()
            assert (body["topic"], body["type"]) == (f"{served.base}/{topic}", kind)
            assert words in body["error"]
    assert served.runtime.read("x", "input.I1") is False
    assert served.runtime.read("x", "input.stop") is False


@pytest.fixture(params=["mosquitto", "amqtt"])
def broker_url(request: pytest.FixtureRequest, mosquitto: Broker) -> Iterator[tuple[str, int]]:
    """A broker for a `devsim run` subprocess: the mosquitto, or an amqtt one in this process."""
    if request.param == "mosquitto":
        yield mosquitto.url, mosquitto.port
        return
    runtime = Runtime().start()
    try:
        broker, port = runtime.run(start_broker(port=free_port()), timeout=20)
        runtime.add_closer(broker.shutdown)
        yield f"mqtt://127.0.0.1:{port}", port
    finally:
        runtime.stop()


def test_the_last_will_says_offline_when_devsim_is_killed(broker_url: tuple[str, int]) -> None:
    url, port = broker_url
    plant = f"k{next(_plants)}"
    sim = Sim("sers", "--virtual", "--mqtt", url, "--mqtt-plant", plant)
    try:
        seen = sim.read_until("mqtt: topics")
        assert seen["mqtt"] == f"broker {url}"
        with Sub(port, f"devsim/{plant}/sers/status") as sub:
            assert sub.wait(f"devsim/{plant}/sers/status").text == "online"
            sim.proc.kill()  # SIGKILL: no goodbye, the broker sends the will
            offline = sub.wait(f"devsim/{plant}/sers/status", lambda m: m.text == "offline", timeout=20)
            assert offline.topic.endswith("/status")
    finally:
        sim.stop()


def test_run_with_mqtt_and_no_url_starts_an_embedded_broker() -> None:
    sim = Sim("sers", "--virtual", "--mqtt", "--mqtt-plant", "cli")
    try:
        seen = sim.read_until("mqtt: topics")
        assert seen["mqtt"].endswith("(embedded)")
        port = int(seen["mqtt"].split()[1].rpartition(":")[2])
        with Sub(port, "devsim/cli/sers/#") as sub:
            assert sub.wait("devsim/cli/sers/birth").json()["kind"] == "sers"
            pub(port, "devsim/cli/sers/set/input.I3", "1")
            assert sub.wait("devsim/cli/sers/state/input.I3", lambda m: m.json() is True)
        code, _err = sim.stop()
        assert code == 0
    finally:
        sim.stop()


@pytest.mark.parametrize(("args", "message"), [
    (["--mqtt", "http://x"], "--mqtt: expected mqtt://HOST[:PORT], not 'http://x'"),
    (["--mqtt", "--mqtt-rate", "0"], "--mqtt-rate: must be a positive, finite number of seconds"),
    (["--mqtt", "--mqtt-plant", "a/b"], "one topic level"),
])
def test_bad_mqtt_options_are_one_line(args: list[str], message: str) -> None:
    from click.testing import CliRunner

    from devsim.cli import cli

    result = CliRunner().invoke(cli, ["run", "sers", *args])
    assert result.exit_code == 2 and message in result.output


def test_a_plant_file_mqtt_section(tmp_path: Path, mosquitto: Broker) -> None:
    from devsim.scenario.plant import plant_running
    from devsim.scenario.schema import load_plant

    path = tmp_path / "plant.yaml"
    path.write_text(f"name: hall\ndevices:\n  - {{name: a, kind: sers}}\n  - {{name: b, kind: gms96}}\n"
                    f"mqtt: {{url: '{mosquitto.url}', rate: 250ms}}\n")
    spec = load_plant(path)
    assert spec.mqtt is not None and spec.mqtt.rate == 0.25
    with plant_running(spec, virtual=True) as plant, Sub(mosquitto.port, "devsim/hall/+/birth") as sub:
        assert f"mqtt: broker {mosquitto.url}" in plant.describe()
        assert "mqtt: topics devsim/hall/" in plant.describe()
        assert sub.wait("devsim/hall/a/birth").json()["kind"] == "sers"
        assert sub.wait("devsim/hall/b/birth").json()["rate"] == 0.25


def test_a_bad_plant_file_mqtt_section_names_its_line(tmp_path: Path) -> None:
    from devsim.core.config import ConfigError
    from devsim.scenario.schema import load_plant

    path = tmp_path / "plant.yaml"
    path.write_text("devices:\n  - {name: a, kind: sers}\nmqtt:\n  url: http://x\n")
    with pytest.raises(ConfigError, match=r"plant.yaml:4: mqtt.url: .*expected mqtt://HOST\[:PORT\]"):
        load_plant(path)


def test_the_devices_come_back_when_the_broker_restarts() -> None:
    first = Broker().start()
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        runtime.run(start_mqtt(runtime, [device], first.url, plant="again", rate=RATE), timeout=20)
        with Sub(first.port, "devsim/again/x/status") as sub:
            assert sub.wait("devsim/again/x/status").text == "online"
        first.stop()  # a broker without persistence: everything retained is gone
        second = Broker()
        second.port = first.port
        second.start()
        try:
            with Sub(second.port, "devsim/again/x/#") as sub:
                assert sub.wait("devsim/again/x/birth", timeout=15).json()["device"] == "x"
                assert sub.wait("devsim/again/x/status").text == "online"
                pub(second.port, "devsim/again/x/set/input.I4", "true")
                assert sub.wait("devsim/again/x/state/input.I4", lambda m: m.json() is True)
        finally:
            second.stop()
    finally:
        runtime.stop()
        first.stop()


def test_a_clean_stop_says_offline_too(mosquitto: Broker) -> None:
    plant = f"c{next(_plants)}"
    sim = Sim("sers", "--virtual", "--mqtt", mosquitto.url, "--mqtt-plant", plant)
    try:
        sim.read_until("mqtt: topics")
        with Sub(mosquitto.port, f"devsim/{plant}/sers/status") as sub:
            assert sub.wait(f"devsim/{plant}/sers/status").text == "online"
            code, _err = sim.stop()  # SIGINT: devsim disconnects cleanly, so the broker sends no will
            assert code == 0
            assert sub.wait(f"devsim/{plant}/sers/status", lambda m: m.text == "offline").text == "offline"
        with Sub(mosquitto.port, f"devsim/{plant}/sers/status") as late:
            assert late.wait(f"devsim/{plant}/sers/status").text == "offline"  # retained
    finally:
        sim.stop()


async def test_a_subscriber_of_the_embedded_broker_that_does_not_read_is_disconnected() -> None:
    """The embedded broker, a subscriber that reads its CONNACK and SUBACK and then nothing
    (SO_RCVBUF 4096), one that reads, and 20 MB published in rounds of 100 messages of 1 KB, each
    round once the reader has the one before: the reader gets every message, and the idle one is
    disconnected once SUBSCRIBER_BACKLOG messages wait for it ([SIM-CHOICE], docs/facades/mqtt.md),
    so the broker holds no more tasks than that; it then shuts down.  (Before: amqtt kept a task per
    message for the idle subscriber, 34,442 of them after these 20,000 messages, and the idle one
    stayed connected; devsim run --mqtt with three such subscribers did not stop within 20 s of a
    SIGTERM, cancelling each task and logging its traceback.)"""
    import asyncio
    import socket

    from devsim.facades import mqtt_wire as wire
    from devsim.facades.mqtt import SUBSCRIBER_BACKLOG
    from devsim.facades.mqtt_link import open_link

    loop = asyncio.get_running_loop()
    broker, port = await start_broker(port=free_port())
    idle = socket.socket()
    links = []
    try:
        idle.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        idle.setblocking(False)
        await loop.sock_connect(idle, ("127.0.0.1", port))
        await loop.sock_sendall(idle, wire.connect("idle", 60, v5=False) + wire.subscribe(1, "flood/#", 0, v5=False))
        acks = b""
        while len(acks) < 4 + 5:  # CONNACK, SUBACK: then it reads no more
            acks += await asyncio.wait_for(loop.sock_recv(idle, 9 - len(acks)), 10)
        assert acks[0] == 0x20 and acks[4] == 0x90 and acks[8] == 0, acks
        reader = await open_link("127.0.0.1", port, "reader", v5=False)
        publisher = await open_link("127.0.0.1", port, "publisher", v5=False)
        links += [reader, publisher]
        got: list[bytes] = []
        round_done: asyncio.Future[None] = loop.create_future()
        reader.on_message = lambda message: (got.append(message.payload),
                                             len(got) % 100 == 0 and not round_done.done() and round_done.set_result(None))
        await reader.subscribe("flood/#")
        payloads = [n.to_bytes(4, "big") * 256 for n in range(20_000)]
        for start in range(0, len(payloads), 100):
            for payload in payloads[start:start + 100]:
                publisher.publish("flood/x", payload)
            await publisher.drain()
            await asyncio.wait_for(round_done, 30)
            round_done = loop.create_future()
        assert got == payloads
        # (amqtt's publishing tasks, kept behind the oldest not done: 34,442 here before)
        assert len(broker._tasks_queue) <= SUBSCRIBER_BACKLOG
        closed = False
        while not closed:  # what the kernel holds for it, then its end
            try:
                closed = not await asyncio.wait_for(loop.sock_recv(idle, 1 << 16), 10)
            except ConnectionResetError:
                closed = True
    finally:
        idle.close()
        for link in links:
            await link.disconnect()
        await asyncio.wait_for(broker.shutdown(), 30)
