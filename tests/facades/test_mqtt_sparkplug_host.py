"""The Sparkplug edge node with a Primary Host Application (``--mqtt-primary-host``, a plant file's
``mqtt.primary_host``), on mosquitto (and the embedded amqtt broker), the host played by
``mosquitto_pub`` publishing its retained ``spBv1.0/STATE/<id>`` JSON, the node watched with
``mosquitto_sub``: no births while the host is not online, NBIRTH/DBIRTH once it is, NDEATH and a
new session (next bdSeq) that waits again when it goes offline, and the STATE timestamps'
rules (Sparkplug 3.0 §5, Edge Node Session Establishment / Termination).

"Nothing yet" is shown without waiting a while: the node refuses a command while it waits
(on ``devsim/<plant>/error``), and its messages come in order on one connection, so what it sent
before that refusal has been seen once the refusal is."""

from __future__ import annotations

import contextlib
import itertools
import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from tahutils.parse import parse_payload_to_metric_dict, payload_from_string
from tahutils.tahu import sparkplug_b as tahu

from devsim.facades.mqtt import start_mqtt
from devsim.facades.mqtt_sparkplug_host import PrimaryHost, parse_state
from devsim.runtime import Runtime
from tests.facades.test_mqtt import mosquitto  # noqa: F401 - the module's broker fixture
from tests.facades.test_mqtt_sparkplug import broker_port  # noqa: F401 - mosquitto or an amqtt broker
from tests.support.broker import Broker
from tests.support.mqtt import Sub, pub
from tests.test_cli import Sim

_names = itertools.count()
T = tahu.MetricDataType
SPB = "spBv1.0/devsim"
T0 = 1_700_000_000_000  # a host's connect time, UTC milliseconds


def state(online: bool, timestamp: int) -> str:
    """A Primary Host Application's STATE payload (§6, tck-id-payloads-state-birth-payload)."""
    return json.dumps({"online": online, "timestamp": timestamp})


def rebirth() -> bytes:
    payload = tahu.Payload()
    tahu.addMetric(payload, "Node Control/Rebirth", None, T.Boolean, True)
    return bytes(payload.SerializeToString())


def set_input(name: str) -> bytes:
    payload = tahu.Payload()
    tahu.addMetric(payload, name, None, T.Boolean, True)
    return bytes(payload.SerializeToString())


def bd_seq(message_payload: bytes) -> int:
    return int(parse_payload_to_metric_dict(payload_from_string(message_payload))["bdSeq"].value)


def unborn(port: int, sub: Sub, plant: str, *, retained: bool = False) -> None:
    """Show that the node waits, unborn: an NCMD rebirth is refused on the plant's error topic
    (``retained``: as a retained message, so that a session that is still being made takes it
    when it subscribes; cleared after), and no NBIRTH came before that refusal."""
    pub(port, f"{SPB}/NCMD/{plant}", rebirth(), retain=retained)
    error = sub.wait(f"devsim/{plant}/error").json()
    if retained:
        pub(port, f"{SPB}/NCMD/{plant}", b"", retain=True)  # (an empty retained message clears it)
    assert error["topic"] == f"{SPB}/NCMD/{plant}" and "waits for primary host" in error["error"], error
    assert not [m for m in sub.seen if m.topic in (f"{SPB}/NBIRTH/{plant}", f"{SPB}/DBIRTH/{plant}/x")]


@contextlib.contextmanager
def edge_node(broker: Broker, plant: str, host: str, *, errors: bool = False) -> Iterator[Sub]:
    """A SERS ``x`` behind a Sparkplug edge node of ``plant`` on ``broker`` that waits for the
    primary host ``host``, and a subscriber to the node's topics (and to the plant's error topic
    with ``errors``), ready before the node starts."""
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        topics = [f"{SPB}/+/{plant}", f"{SPB}/+/{plant}/#", *([f"devsim/{plant}/#"] if errors else [])]
        with Sub(broker.port, *topics).sync() as sub:
            runtime.run(start_mqtt(runtime, [device], broker.url, plant=plant, convention="sparkplug",
                                   rate=0.5, primary_host=host), timeout=20)
            yield sub
    finally:
        runtime.stop()


def test_the_births_wait_for_the_primary_host_online(broker_port: int) -> None:  # noqa: F811
    """tck-id-message-flow-edge-node-birth-publish-phid-wait ("MUST verify the Primary Host
    Application is online via the STATE topic before publishing NBIRTH and DBIRTH"), -phid-wait-id
    (another host's STATE does not count), -phid-wait-online (an offline STATE does not),
    tck-id-operational-behavior-edge-node-birth-sequence-wait.  A DCMD while it waits changes
    nothing."""
    n = next(_names)
    plant, host = f"h{n}", f"scada{n}"
    pub(broker_port, f"spBv1.0/STATE/{host}", state(False, T0), retain=True)  # the host's last will
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        with Sub(broker_port, f"{SPB}/+/{plant}", f"{SPB}/+/{plant}/#", f"devsim/{plant}/#").sync() as sub:
            lines = runtime.run(start_mqtt(runtime, [device], f"mqtt://127.0.0.1:{broker_port}", plant=plant,
                                           convention="sparkplug", rate=0.5, primary_host=host), timeout=20)
            assert f"mqtt: primary host spBv1.0/STATE/{host} (the births wait for it online)" in lines
            unborn(broker_port, sub, plant)
            pub(broker_port, f"{SPB}/DCMD/{plant}/x", set_input("input.I1"))
            assert "waits for primary host" in sub.wait(f"devsim/{plant}/x/error").json()["error"]
            assert runtime.read("x", "input.I1") is False
            pub(broker_port, f"spBv1.0/STATE/other{n}", state(True, T0 + 1), retain=True)  # not its host
            unborn(broker_port, sub, plant)

            pub(broker_port, f"spBv1.0/STATE/{host}", state(True, T0 + 1), retain=True)
            nbirth = payload_from_string(sub.wait(f"{SPB}/NBIRTH/{plant}").payload)
            assert nbirth.seq == 0 and parse_payload_to_metric_dict(nbirth)["bdSeq"].value == 0
            dbirth = payload_from_string(sub.wait(f"{SPB}/DBIRTH/{plant}/x").payload)
            assert parse_payload_to_metric_dict(dbirth)["input.I1"].value is False
            pub(broker_port, f"{SPB}/DCMD/{plant}/x", set_input("input.I1"))
            ddata = payload_from_string(sub.wait(f"{SPB}/DDATA/{plant}/x").payload)
            assert parse_payload_to_metric_dict(ddata)["input.I1"].value is True
    finally:
        runtime.stop()


def test_a_host_already_online_gets_the_births_at_once(mosquitto: Broker) -> None:  # noqa: F811
    """The retained online STATE the node finds when it subscribes is enough (§5, Figure 7 step 1:
    "examine the current STATE value")."""
    n = next(_names)
    plant, host = f"o{n}", f"scada{n}"
    pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(True, T0), retain=True)
    with edge_node(mosquitto, plant, host) as sub:
        assert payload_from_string(sub.wait(f"{SPB}/NBIRTH/{plant}").payload).seq == 0
        sub.wait(f"{SPB}/DBIRTH/{plant}/x")


def test_an_offline_host_ends_the_session_and_the_next_one_waits(mosquitto: Broker) -> None:  # noqa: F811
    """tck-id-message-flow-edge-node-birth-publish-phid-offline: an offline STATE whose timestamp
    is not older than the online one's → "it MUST immediately publish an NDEATH message and
    disconnect from the MQTT Server and start the connection establishment process over"
    (tck-id-operational-behavior-edge-node-termination-host-offline, -reconnect); the NDEATH is
    the session's bdSeq, the new session takes the next and waits for the host again."""
    n = next(_names)
    plant, host = f"f{n}", f"scada{n}"
    pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(True, T0), retain=True)
    with edge_node(mosquitto, plant, host, errors=True) as sub:
        first = bd_seq(sub.wait(f"{SPB}/NBIRTH/{plant}").payload)
        sub.wait(f"{SPB}/DBIRTH/{plant}/x")

        pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(False, T0), retain=True)  # the host's will
        death = sub.wait(f"{SPB}/NDEATH/{plant}")
        assert not death.retain and bd_seq(death.payload) == first
        unborn(mosquitto.port, sub, plant, retained=True)  # the next session: connected, unborn
        assert not [m for m in sub.seen if m.topic == f"{SPB}/NDEATH/{plant}"]  # one NDEATH (no will too)

        pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(True, T0 + 5000), retain=True)  # back again
        nbirth = sub.wait(f"{SPB}/NBIRTH/{plant}")
        assert bd_seq(nbirth.payload) == first + 1 and payload_from_string(nbirth.payload).seq == 0
        sub.wait(f"{SPB}/DBIRTH/{plant}/x")


def test_an_offline_state_older_than_the_online_one_is_ignored(mosquitto: Broker) -> None:  # noqa: F811
    """tck-id-operational-behavior-edge-node-termination-host-offline-timestamp: an offline STATE
    older than the last online one (a host session that is already over) "MUST NOT" end the
    node's session: it goes on (the next DCMD's DDATA follows in the same seq), no NDEATH."""
    n = next(_names)
    plant, host = f"t{n}", f"scada{n}"
    pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(True, T0 + 2000), retain=True)
    with edge_node(mosquitto, plant, host) as sub:
        sub.wait(f"{SPB}/NBIRTH/{plant}")
        assert payload_from_string(sub.wait(f"{SPB}/DBIRTH/{plant}/x").payload).seq == 1
        pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(False, T0 + 1999), retain=True)
        pub(mosquitto.port, f"{SPB}/DCMD/{plant}/x", set_input("input.I2"))
        ddata = payload_from_string(sub.wait(f"{SPB}/DDATA/{plant}/x").payload)
        assert ddata.seq == 2 and parse_payload_to_metric_dict(ddata)["input.I2"].value is True
        assert not [m for m in sub.seen if m.topic in (f"{SPB}/NDEATH/{plant}", f"{SPB}/NBIRTH/{plant}")]
        pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(False, T0 + 2000), retain=True)  # equal: it counts
        sub.wait(f"{SPB}/NDEATH/{plant}")


def test_a_state_that_is_not_the_json_of_the_spec_is_refused(mosquitto: Broker) -> None:  # noqa: F811
    """§6 STATE: JSON with an ``online`` boolean and a numeric ``timestamp``; another payload is
    answered on the plant's error topic and changes nothing (the node still waits)."""
    n = next(_names)
    plant, host = f"j{n}", f"scada{n}"
    with edge_node(mosquitto, plant, host, errors=True) as sub:
        pub(mosquitto.port, f"spBv1.0/STATE/{host}", "ONLINE", retain=True)  # Sparkplug 2.2's plain text
        error = sub.wait(f"devsim/{plant}/error").json()
        assert error["topic"] == f"spBv1.0/STATE/{host}" and "JSON" in error["error"]
        unborn(mosquitto.port, sub, plant)


def test_run_with_mqtt_primary_host(mosquitto: Broker) -> None:  # noqa: F811
    """``devsim run … --mqtt-convention sparkplug --mqtt-primary-host ID`` (docs/facades/mqtt.md)."""
    n = next(_names)
    plant, host = f"r{n}", f"ignition{n}"
    with Sub(mosquitto.port, f"{SPB}/+/{plant}", f"devsim/{plant}/#").sync() as sub:
        sim = Sim("sers", "--virtual", "--mqtt", mosquitto.url, "--mqtt-convention", "sparkplug",
                  "--mqtt-plant", plant, "--mqtt-primary-host", host)
        try:
            seen = sim.read_until("mqtt: primary host")
            assert seen["mqtt"] == f"broker {mosquitto.url}"
            unborn(mosquitto.port, sub, plant, retained=True)
            pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(True, T0), retain=True)
            assert bd_seq(sub.wait(f"{SPB}/NBIRTH/{plant}").payload) == 0
        finally:
            sim.stop()


@pytest.mark.parametrize(("args", "message"), [
    (["--mqtt", "--mqtt-primary-host", "scada"], "--mqtt-primary-host: a Sparkplug host application, only with"
                                                 " --mqtt-convention sparkplug"),
    (["--mqtt", "--mqtt-convention", "sparkplug", "--mqtt-primary-host", "a/b"], "one topic level"),
])
def test_bad_primary_host_options_are_one_line(args: list[str], message: str) -> None:
    from click.testing import CliRunner

    from devsim.cli import cli

    result = CliRunner().invoke(cli, ["run", "sers", *args])
    assert result.exit_code == 2 and message in result.output, result.output


def test_a_plant_file_names_the_primary_host(tmp_path: Path, mosquitto: Broker) -> None:  # noqa: F811
    from devsim.scenario.plant import plant_running
    from devsim.scenario.schema import load_plant

    n = next(_names)
    plant, host = f"y{n}", f"scada{n}"
    path = tmp_path / "plant.yaml"
    path.write_text(f"name: {plant}\ndevices:\n  - {{name: x, kind: sers}}\n"
                    f"mqtt: {{url: '{mosquitto.url}', convention: sparkplug, primary_host: {host}}}\n")
    spec = load_plant(path)
    assert spec.mqtt is not None and spec.mqtt.primary_host == host
    with Sub(mosquitto.port, f"{SPB}/+/{plant}", f"devsim/{plant}/#").sync() as sub, \
            plant_running(spec, virtual=True) as running:
        assert f"mqtt: primary host spBv1.0/STATE/{host} (the births wait for it online)" in running.describe()
        unborn(mosquitto.port, sub, plant, retained=True)
        pub(mosquitto.port, f"spBv1.0/STATE/{host}", state(True, T0), retain=True)
        sub.wait(f"{SPB}/NBIRTH/{plant}")


def test_a_primary_host_without_sparkplug_names_its_line(tmp_path: Path) -> None:
    from devsim.core.config import ConfigError
    from devsim.scenario.schema import load_plant

    path = tmp_path / "plant.yaml"
    path.write_text("devices:\n  - {name: a, kind: sers}\nmqtt:\n  primary_host: scada\n")
    with pytest.raises(ConfigError, match=r"plant.yaml:3: mqtt: primary_host is a Sparkplug host application"):
        load_plant(path)


# -- the STATE rules, pure ---------------------------------------------------------------------
def test_state_timestamps() -> None:
    """tck-id-message-flow-edge-node-birth-publish-phid-wait-timestamp: an online STATE counts when
    none came before or its timestamp is ≥ the previous STATE's; an offline one when none was
    online before or it is ≥ the last online one's (-phid-offline, -termination-host-offline-timestamp);
    whether the host is online is per MQTT session, the timestamps are not."""
    host = PrimaryHost("h")
    assert host.topic == "spBv1.0/STATE/h"
    assert host.take(state(False, 50).encode()) is False  # no STATE before: honoured
    assert host.take(state(True, 100).encode()) is True
    assert host.take(state(True, 99).encode()) is None and host.online  # older than the previous: ignored
    assert host.take(state(False, 99).encode()) is None and host.online  # an earlier host session's death
    assert host.take(state(False, 100).encode()) is False and not host.online  # equal: counts
    assert host.take(state(True, 99).encode()) is None
    assert host.take(state(True, 100).encode()) is True
    host.new_session()
    assert not host.online and host.take(state(True, 99).encode()) is None  # the memory outlives the session
    assert host.take(state(True, 101.5).encode()) is True


@pytest.mark.parametrize("payload", [b"ONLINE", b"OFFLINE", b"", b"\xff", b"[]", b'{"online": true}',
                                     b'{"online": "true", "timestamp": 1}', b'{"online": 1, "timestamp": 1}',
                                     b'{"online": true, "timestamp": "1"}', b'{"online": true, "timestamp": true}',
                                     b'{"online": true, "timestamp": NaN}'])
def test_a_state_payload_is_json_with_online_and_timestamp(payload: bytes) -> None:
    with pytest.raises(ValueError, match="STATE payload"):
        parse_state(payload)
    host = PrimaryHost("h")
    with pytest.raises(ValueError):
        host.take(payload)
    assert (host.online, host.last) == (False, None)
