"""The MQTT facade in the Sparkplug B convention (issue 14), on mosquitto and on an amqtt broker,
seen through mosquitto_sub / mosquitto_pub and decoded with the Tahu binding's own parser
(``tahutils.parse``): NBIRTH (bdSeq, seq 0), DBIRTH (every point with its datatype), DCMD → DDATA
with increasing seq, a refused DCMD on …/error, NCMD rebirth, and NDEATH (same bdSeq) as the last
will when ``devsim run`` is killed."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

import pytest
from tahutils.parse import parse_payload_to_metric_dict, payload_from_string
from tahutils.tahu import sparkplug_b as tahu

from devsim.facades.mqtt import start_broker, start_mqtt
from devsim.runtime import Runtime
from tests.facades.test_mqtt import mosquitto  # noqa: F401 - the module's broker fixture
from tests.support.broker import Broker
from tests.support.mqtt import Sub, pub
from tests.support.process import free_port
from tests.test_cli import Sim

_plants = itertools.count()
T = tahu.MetricDataType
SPB = "spBv1.0/devsim"


def dcmd(*metrics: tuple[str, int, Any]) -> bytes:
    """A DCMD payload made with Tahu's helper, as a SCADA host would send it."""
    payload = tahu.Payload()
    for name, datatype, value in metrics:
        tahu.addMetric(payload, name, None, datatype, value)
    return bytes(payload.SerializeToString())


@pytest.fixture(params=["mosquitto", "amqtt"])
def broker_port(request: pytest.FixtureRequest, mosquitto: Broker) -> Iterator[int]:  # noqa: F811
    if request.param == "mosquitto":
        yield mosquitto.port
        return
    runtime = Runtime().start()
    try:
        broker, port = runtime.run(start_broker(port=free_port()), timeout=20)
        runtime.add_closer(broker.shutdown)
        yield port
    finally:
        runtime.stop()


def test_births_commands_data_and_rebirth(broker_port: int) -> None:
    plant = f"s{next(_plants)}"
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        with Sub(broker_port, f"{SPB}/#", f"devsim/{plant}/#").sync() as sub:
            runtime.run(start_mqtt(runtime, [device], f"mqtt://127.0.0.1:{broker_port}", plant=plant,
                                   convention="sparkplug", rate=0.5), timeout=20)
            nbirth = payload_from_string(sub.wait(f"{SPB}/NBIRTH/{plant}").payload)
            assert nbirth.seq == 0
            node_metrics = parse_payload_to_metric_dict(nbirth)
            assert node_metrics["bdSeq"].datatype == T.Int64
            assert node_metrics["Node Control/Rebirth"].datatype == T.Boolean
            bd_seq = node_metrics["bdSeq"].value

            dbirth = payload_from_string(sub.wait(f"{SPB}/DBIRTH/{plant}/x").payload)
            assert dbirth.seq == 1
            metrics = parse_payload_to_metric_dict(dbirth)
            assert set(device.points.names()) <= set(metrics)
            assert (metrics["axis.position"].datatype, metrics["axis.position"].value) == (T.Double, 0.0)
            assert (metrics["input.I1"].datatype, metrics["input.I1"].value) == (T.Boolean, False)
            assert metrics["program"].datatype == T.String
            assert metrics["encoder.pulses"].is_null  # write-only: declared, no value
            assert metrics["Device Control/Power Cycle"].datatype == T.Boolean
            assert "Device Control/Fault/emergency_stop" in metrics

            pub(broker_port, f"{SPB}/DCMD/{plant}/x", dcmd(("input.I1", T.Boolean, True)))
            ddata = payload_from_string(sub.wait(f"{SPB}/DDATA/{plant}/x").payload)
            assert ddata.seq == 2
            assert parse_payload_to_metric_dict(ddata)["input.I1"].value is True
            assert runtime.read("x", "input.I1") is True

            pub(broker_port, f"{SPB}/DCMD/{plant}/x", dcmd(("Device Control/Fault/emergency_stop", T.Boolean, True)))
            stopped = payload_from_string(sub.wait(f"{SPB}/DDATA/{plant}/x").payload)
            assert stopped.seq == 3 and parse_payload_to_metric_dict(stopped)["input.stop"].value is True

            pub(broker_port, f"{SPB}/DCMD/{plant}/x", dcmd(("axis.position", T.Double, 5.0)))
            error = sub.wait(f"devsim/{plant}/x/error").json()
            assert error["type"] == "ReadOnlyName" and error["topic"].endswith("#axis.position")

            pub(broker_port, f"{SPB}/NCMD/{plant}", dcmd(("Node Control/Rebirth", T.Boolean, True)))
            again = payload_from_string(sub.wait(f"{SPB}/NBIRTH/{plant}").payload)
            assert again.seq == 0 and parse_payload_to_metric_dict(again)["bdSeq"].value == bd_seq
            reborn = parse_payload_to_metric_dict(payload_from_string(sub.wait(f"{SPB}/DBIRTH/{plant}/x").payload))
            assert reborn["input.I1"].value is True
    finally:
        runtime.stop()


def test_ndeath_with_the_birth_bdseq_when_devsim_is_killed(broker_port: int) -> None:
    plant = f"d{next(_plants)}"
    with Sub(broker_port, f"{SPB}/+/{plant}").sync() as sub:
        sim = Sim("sers", "--virtual", "--mqtt", f"mqtt://127.0.0.1:{broker_port}", "--mqtt-convention", "sparkplug",
                  "--mqtt-plant", plant)
        try:
            sim.read_until(f"mqtt: sparkplug {SPB}/+/{plant}")
            birth = parse_payload_to_metric_dict(payload_from_string(sub.wait(f"{SPB}/NBIRTH/{plant}").payload))
            sim.proc.kill()
            death = payload_from_string(sub.wait(f"{SPB}/NDEATH/{plant}", timeout=20).payload)
            assert parse_payload_to_metric_dict(death)["bdSeq"].value == birth["bdSeq"].value
        finally:
            sim.stop()


def test_a_clean_stop_publishes_the_ndeath_itself(broker_port: int) -> None:
    """Sparkplug 3.0 §5 (Edge Node Session Termination), tck-id-operational-behavior-edge-node-
    intentional-disconnect-ndeath: "When an Edge Node disconnects intentionally, it MUST publish an
    NDEATH before terminating the connection" (the DISCONNECT drops the will): the session's bdSeq,
    no seq, not retained."""
    plant = f"c{next(_plants)}"
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        with Sub(broker_port, f"{SPB}/+/{plant}").sync() as sub:
            runtime.run(start_mqtt(runtime, [device], f"mqtt://127.0.0.1:{broker_port}", plant=plant,
                                   convention="sparkplug", rate=0.5), timeout=20)
            birth = parse_payload_to_metric_dict(payload_from_string(sub.wait(f"{SPB}/NBIRTH/{plant}").payload))
            runtime.stop()
            message = sub.wait(f"{SPB}/NDEATH/{plant}")
            death = payload_from_string(message.payload)
            assert not message.retain and not death.HasField("seq")
            assert [(m.name, m.long_value) for m in death.metrics] == [("bdSeq", birth["bdSeq"].value)]
    finally:
        runtime.stop()


NOT_SPARKPLUG = [
    pytest.param(b"not protobuf", "not a Sparkplug B payload", id="text"),
    pytest.param(b'{"input.I1": true}', "not a Sparkplug B payload", id="json"),
    pytest.param(b"\x78\x01", "not a Sparkplug B payload", id="protobuf-field-15"),  # the schema stops at 5
    pytest.param(b"", "without metrics", id="empty"),
]


@pytest.mark.parametrize(("payload", "words"), NOT_SPARKPLUG)
def test_a_command_that_is_not_sparkplug_is_refused_on_the_devices_error_topic(
        broker_port: int, payload: bytes, words: str) -> None:
    """A DCMD whose payload is not a Sparkplug B protobuf ``Payload`` is answered on
    ``devsim/<plant>/<device>/error`` (docs/facades/mqtt.md), an NCMD's on the plant's; the node
    goes on serving (the next DCMD is taken)."""
    plant = f"n{next(_plants)}"
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        with Sub(broker_port, f"{SPB}/+/{plant}/#", f"devsim/{plant}/#").sync() as sub:
            runtime.run(start_mqtt(runtime, [device], f"mqtt://127.0.0.1:{broker_port}", plant=plant,
                                   convention="sparkplug", rate=0.5), timeout=20)
            sub.wait(f"{SPB}/DBIRTH/{plant}/x")
            pub(broker_port, f"{SPB}/DCMD/{plant}/x", payload)
            error = sub.wait(f"devsim/{plant}/x/error")
            assert not error.retain
            body = error.json()
            assert body["topic"] == f"{SPB}/DCMD/{plant}/x" and words in body["error"]
            pub(broker_port, f"{SPB}/NCMD/{plant}", payload)
            node_error = sub.wait(f"devsim/{plant}/error").json()
            assert node_error["topic"] == f"{SPB}/NCMD/{plant}" and words in node_error["error"]
            pub(broker_port, f"{SPB}/DCMD/{plant}/x", dcmd(("input.I1", T.Boolean, True)))
            ddata = payload_from_string(sub.wait(f"{SPB}/DDATA/{plant}/x").payload)
            assert parse_payload_to_metric_dict(ddata)["input.I1"].value is True
    finally:
        runtime.stop()


def bare(**values: Any) -> bytes:
    """A command payload whose metrics carry a name and a value field but no datatype, as Sparkplug
    3.0 §6.4.6 would have it ("The datatype SHOULD NOT be included with metric definitions in
    NDATA, NCMD, DDATA, and DCMD messages", tck-id-payloads-metric-datatype-not-req); values are
    ``name=(field, value)``."""
    payload = tahu.Payload()
    for name, (field, value) in values.items():
        metric = payload.metrics.add()
        metric.name = name
        setattr(metric, field, value)
    return bytes(payload.SerializeToString())


def test_commands_without_a_datatype_take_the_births(broker_port: int) -> None:
    """A DCMD metric without a datatype is read as its DBIRTH datatype, an NCMD ``Node
    Control/Rebirth`` as the NBIRTH's Boolean (§6.4.6, tck-id-payloads-metric-datatype-not-req)."""
    plant = f"b{next(_plants)}"
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        with Sub(broker_port, f"{SPB}/+/{plant}/#", f"{SPB}/+/{plant}", f"devsim/{plant}/#").sync() as sub:
            runtime.run(start_mqtt(runtime, [device], f"mqtt://127.0.0.1:{broker_port}", plant=plant,
                                   convention="sparkplug", rate=0.5), timeout=20)
            sub.wait(f"{SPB}/DBIRTH/{plant}/x")
            pub(broker_port, f"{SPB}/DCMD/{plant}/x", bare(**{"input.I1": ("boolean_value", True)}))
            ddata = payload_from_string(sub.wait(f"{SPB}/DDATA/{plant}/x").payload)
            assert parse_payload_to_metric_dict(ddata)["input.I1"].value is True
            assert runtime.read("x", "input.I1") is True
            pub(broker_port, f"{SPB}/NCMD/{plant}", bare(**{"Node Control/Rebirth": ("boolean_value", True)}))
            again = payload_from_string(sub.wait(f"{SPB}/NBIRTH/{plant}").payload)
            assert again.seq == 0
            assert not [m for m in sub.seen if m.topic.endswith("/error")]
    finally:
        runtime.stop()


INCOMPATIBLE = [
    pytest.param(dcmd(("input.I1", T.Double, 1.0)), "datatype Double, but its DBIRTH's is Boolean", id="double-for-boolean"),
    pytest.param(dcmd(("input.I1", T.String, "true")), "datatype String, but its DBIRTH's is Boolean",
                 id="string-for-boolean"),
    pytest.param(dcmd(("input.I1", T.Int64, 1)), "datatype Int64, but its DBIRTH's is Boolean", id="int64-for-boolean"),
    pytest.param(bare(**{"input.I1": ("double_value", 1.0)}), "datatype Boolean, but its value is a double_value",
                 id="bare-double-for-boolean"),
    pytest.param(dcmd(("param.P0", T.String, "0")), "datatype String, but its DBIRTH's is Double", id="string-for-double"),
    pytest.param(dcmd(("Device Control/Fault/emergency_stop", T.Int32, 1)), "datatype Int32, but its DBIRTH's is Boolean",
                 id="int-for-fault"),
]


@pytest.mark.parametrize(("payload", "words"), INCOMPATIBLE)
def test_a_dcmd_value_of_another_datatype_than_the_births_is_refused(
        broker_port: int, payload: bytes, words: str) -> None:
    """§5 tck-id-operational-behavior-data-commands-dcmd-metric-value: "A DCMD message MUST include a
    compatible metric value for the metric name that it is writing to. In other words, if the metric
    has a datatype of a boolean the value must be true or false."  An incompatible one changes
    nothing and is answered on the device's error topic; the next DCMD is taken."""
    plant = f"w{next(_plants)}"
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        before = {name: runtime.read("x", name) for name in ("input.I1", "param.P0", "input.stop")}
        with Sub(broker_port, f"{SPB}/+/{plant}/#", f"devsim/{plant}/#").sync() as sub:
            runtime.run(start_mqtt(runtime, [device], f"mqtt://127.0.0.1:{broker_port}", plant=plant,
                                   convention="sparkplug", rate=0.5), timeout=20)
            sub.wait(f"{SPB}/DBIRTH/{plant}/x")
            pub(broker_port, f"{SPB}/DCMD/{plant}/x", payload)
            error = sub.wait(f"devsim/{plant}/x/error").json()
            assert error["topic"].startswith(f"{SPB}/DCMD/{plant}/x") and words in error["error"], error
            assert {name: runtime.read("x", name) for name in before} == before
            pub(broker_port, f"{SPB}/DCMD/{plant}/x", dcmd(("input.I2", T.Boolean, True)))
            changed = parse_payload_to_metric_dict(payload_from_string(sub.wait(f"{SPB}/DDATA/{plant}/x").payload))
            assert changed["input.I2"].value is True and "input.I1" not in changed
    finally:
        runtime.stop()
