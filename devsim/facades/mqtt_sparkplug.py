"""Sparkplug B payloads of the MQTT facade (``--mqtt-convention sparkplug``), through the Eclipse
Tahu Python binding as packaged on PyPI (``tahutils``: Tahu's ``sparkplug_b`` helper and protobuf
schema).  Pure: topics and payload bytes in, topics and payload bytes out; the connection is in
:mod:`devsim.facades.mqtt`.

Sparkplug B 3.0 mapping: the group is ``devsim``, the edge node is the plant (one MQTT session
per plant process, so its NDEATH last will covers every device), each device a Sparkplug
device.  NBIRTH carries ``bdSeq`` and ``Node Control/Rebirth``; a DBIRTH per device carries every
declared point as a metric with its datatype (bool → Boolean, int → Int64, float → Double, str
and json → String) and, as writable command metrics, ``Device Control/Power Cycle`` and
``Device Control/Fault/<kind>``; DDATA carries what changed.  Every payload but NDEATH carries
``seq`` (0 … 255, wrapping); NDEATH's ``bdSeq`` matches the NBIRTH of the same session.  DCMD
metrics are set through the device's own validation (a command that is not a Sparkplug B
payload is refused like a metric the device refuses); NCMD ``Node Control/Rebirth`` sends the
births again.  A command metric without a datatype (§6.4.6: "The datatype SHOULD NOT be included
with metric definitions in NDATA, NCMD, DDATA, and DCMD messages") is read as its birth's; one
whose datatype is not its birth's, or whose value is not in its datatype's field, is refused
(§5, tck-id-operational-behavior-data-commands-dcmd-metric-value: "A DCMD message MUST include a
compatible metric value for the metric name that it is writing to").  Tahu's helper keeps
sequence numbers in module globals; here they live in :class:`SparkplugNode`, one per session,
and only its stateless ``addMetric`` is used.
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping
from typing import Any

from tahutils.tahu import sparkplug_b as tahu

from devsim.core.device import Device
from devsim.core.points import Point
from devsim.facades.mqtt_sparkplug_host import NAMESPACE
from devsim.runtime import requests as rq

__all__ = ["DATATYPES", "GROUP", "NAMESPACE", "SparkplugNode", "birth_datatype", "command_request", "command_value",
           "decode_command", "decode_metrics", "metric_value"]

GROUP = "devsim"
T = tahu.MetricDataType
#: A point's declared type → its Sparkplug metric datatype.
DATATYPES: dict[str, int] = {"bool": T.Boolean, "int": T.Int64, "float": T.Double, "str": T.String,
                             "json": T.String}
REBIRTH = "Node Control/Rebirth"
POWER_CYCLE = "Device Control/Power Cycle"
FAULT = "Device Control/Fault/"

_SIGNED = {T.Int8: 8, T.Int16: 16, T.Int32: 32, T.Int64: 64}
_FIELD = {T.Int8: "int_value", T.Int16: "int_value", T.Int32: "int_value", T.UInt8: "int_value",
          T.UInt16: "int_value", T.UInt32: "int_value", T.Int64: "long_value", T.UInt64: "long_value",
          T.DateTime: "long_value", T.Float: "float_value", T.Double: "double_value",
          T.Boolean: "boolean_value", T.String: "string_value", T.Text: "string_value", T.UUID: "string_value"}
_NAMES = {getattr(T, name): name for name in dir(T) if not name.startswith("_")}
#: A birth's datatype → the datatypes a command's value for it may have (the same kind of value).
_COMPATIBLE = {T.Boolean: {T.Boolean}, T.Int64: {*_SIGNED, T.UInt8, T.UInt16, T.UInt32, T.UInt64},
               T.Double: {T.Float, T.Double}, T.String: {T.String, T.Text}}


def metric_value(metric: Any, datatype: int | None = None) -> Any:
    """A received metric's value (signed integers from their two's complement), None when null;
    read as ``datatype`` when given (a command metric without one), else as its own.  ValueError
    when the value is not in the field its datatype names."""
    if datatype is None:
        datatype = metric.datatype
    if metric.is_null:
        return None
    name = _FIELD.get(datatype)
    if name is None:
        raise ValueError(f"metric {metric.name!r}: datatype {datatype} is not supported")
    held = metric.WhichOneof("value")
    if held != name:
        raise ValueError(f"metric {metric.name!r}: datatype {_NAMES[datatype]}, but its value is "
                         f"{'a ' + held if held else 'missing'}")
    value = getattr(metric, name)
    bits = _SIGNED.get(datatype)
    if bits is not None and value >= 1 << (bits - 1):
        value -= 1 << bits
    return value


def _now_ms() -> int:
    return int(time.time() * 1000)  # Sparkplug timestamps are UTC wall time (metadata, no wait)


def _add(payload: Any, point: Point, value: Any) -> None:
    datatype = DATATYPES[point.type]
    if value is None:
        tahu.addNullMetric(payload, point.name, None, datatype)
        return
    if point.type == "json" or (point.type == "str" and not isinstance(value, str)):
        value = json.dumps(value)
    tahu.addMetric(payload, point.name, None, datatype, value, _now_ms())


class SparkplugNode:
    """One Sparkplug edge node session (the plant) and its devices' births, data and commands."""

    def __init__(self, plant: str) -> None:
        self.plant = plant
        self.bd_seq = -1
        self._seq = 0

    def topic(self, kind: str, device: str | None = None) -> str:
        tail = f"/{device}" if device is not None else ""
        return f"{NAMESPACE}/{GROUP}/{kind}/{self.plant}{tail}"

    def filters(self) -> list[str]:
        return [self.topic("NCMD"), self.topic("DCMD", "+")]

    def _payload(self) -> Any:
        payload = tahu.Payload()
        payload.timestamp = _now_ms()
        payload.seq = self._seq
        self._seq = (self._seq + 1) % 256
        return payload

    def new_session(self) -> tuple[str, bytes]:
        """Start a session: the next bdSeq, and the NDEATH that is its last will."""
        self.bd_seq = (self.bd_seq + 1) % 256
        self._seq = 0
        return self.death()

    def death(self) -> tuple[str, bytes]:
        """The NDEATH of this session (its bdSeq)."""
        payload = tahu.Payload()
        payload.timestamp = _now_ms()
        tahu.addMetric(payload, "bdSeq", None, T.Int64, self.bd_seq)
        return self.topic("NDEATH"), payload.SerializeToString()

    def node_birth(self) -> tuple[str, bytes]:
        self._seq = 0
        payload = self._payload()
        tahu.addMetric(payload, "bdSeq", None, T.Int64, self.bd_seq)
        tahu.addMetric(payload, REBIRTH, None, T.Boolean, False)
        return self.topic("NBIRTH"), payload.SerializeToString()

    def device_birth(self, device: Device, values: Mapping[str, Any]) -> tuple[str, bytes]:
        """Every declared point (write-only ones as null), and the command metrics."""
        payload = self._payload()
        for point in device.points:
            _add(payload, point, values.get(point.name))
        tahu.addMetric(payload, POWER_CYCLE, None, T.Boolean, False)
        for kind in device.faults.names():
            tahu.addMetric(payload, FAULT + kind, None, T.Boolean, False)
        return self.topic("DBIRTH", device.name), payload.SerializeToString()

    def device_data(self, device: Device, changes: Mapping[str, Any]) -> tuple[str, bytes]:
        payload = self._payload()
        for name, value in changes.items():
            _add(payload, device.points.lookup(name), value)
        return self.topic("DDATA", device.name), payload.SerializeToString()

    def device_death(self, device: Device) -> tuple[str, bytes]:
        return self.topic("DDEATH", device.name), self._payload().SerializeToString()

    def command_target(self, topic: str) -> str | None:
        """The device a DCMD topic names, None for the node's NCMD; ValueError for another topic."""
        parts = topic.split("/")
        if parts[:2] == [NAMESPACE, GROUP] and len(parts) == 5 and parts[2] == "DCMD" and parts[3] == self.plant:
            return parts[4]
        if parts[:2] == [NAMESPACE, GROUP] and len(parts) == 4 and parts[2] == "NCMD" and parts[3] == self.plant:
            return None
        raise ValueError(f"not a command topic of node {self.plant!r}: {topic!r}")


def decode_metrics(data: bytes) -> list[Any]:
    """The metrics of a DCMD/NCMD payload (Sparkplug B 3.0 ch. 6, Payloads: a protobuf
    ``Payload``); ValueError when the bytes are not one (not protobuf, fields the Sparkplug B
    schema does not have) or carry no metric."""
    payload = tahu.Payload()
    try:
        payload.ParseFromString(data)
    except Exception as exc:  # protobuf's DecodeError
        raise ValueError(f"not a Sparkplug B payload: {exc}") from None
    size = payload.ByteSize()
    payload.DiscardUnknownFields()
    if payload.ByteSize() != size:
        raise ValueError("not a Sparkplug B payload: fields its schema does not have")
    if not payload.metrics:
        raise ValueError("a Sparkplug B command without metrics")
    return list(payload.metrics)


def decode_command(data: bytes) -> list[tuple[str, Any]]:
    """The (metric, value) pairs of a DCMD/NCMD payload whose metrics carry their datatypes."""
    return [(m.name, metric_value(m)) for m in decode_metrics(data)]


def birth_datatype(device: Device, name: str) -> int | None:
    """The datatype the device's DBIRTH gives metric ``name``; None for a name it does not have."""
    if name == POWER_CYCLE or (name.startswith(FAULT) and name[len(FAULT):] in device.faults.names()):
        return T.Boolean
    point = device.points.find(name)
    return DATATYPES[point.type] if point is not None else None


def command_value(metric: Any, birth: int | None) -> Any:
    """A command metric's value, as its birth's datatype ``birth`` (None: a name no birth has)
    when it carries none (§6.4.6); ValueError when it has neither, when its datatype is not of the
    birth's kind (an integer for Int64, Float or Double for Double, String or Text for String),
    or when its value is not in its datatype's field (§5,
    tck-id-operational-behavior-data-commands-dcmd-metric-value)."""
    datatype = metric.datatype if metric.HasField("datatype") else birth
    if datatype is None:
        raise ValueError(f"metric {metric.name!r}: no datatype, and no birth names one")
    if birth is not None and datatype not in _COMPATIBLE[birth]:
        raise ValueError(f"metric {metric.name!r}: datatype {_NAMES.get(datatype, datatype)}, "
                         f"but its DBIRTH's is {_NAMES[birth]}")
    return metric_value(metric, datatype)


def command_request(device: Device, name: str, value: Any) -> rq.ControlRequest | None:
    """The control request of one DCMD metric: a point set, a power cycle (None when the metric
    is false), or a fault switched."""
    if name == POWER_CYCLE:
        return rq.PowerCycle(device.name) if value else None
    if name.startswith(FAULT):
        return rq.SwitchFault(device.name, name[len(FAULT):], value)
    return rq.Set(device.name, name, value)
