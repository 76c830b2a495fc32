"""The OPC UA address space a device's declared points give (issue 14), pure: no server, no I/O.

Under ``Objects`` one object per device, named after it (NodeId ``ns=<urn:devsim>;s=DEVICE``),
holding one variable per declared point that can be read or set:

* **browse name = the point's name**, dots and all (``axis.position``, ``param.V``): the names a
  host already uses with the control API, flat under the device object.  Folders per dotted
  prefix were the alternative, but kinds have a point that is also a prefix (SERS ``motion`` and
  ``motion.x``), and a flat list keeps one name for one thing.  NodeId ``s=DEVICE.POINT``, so a
  host can address a point without browsing (``ns=2;s=x.axis.position``);
* **data type** from the point type (:data:`DATA_TYPES`): Boolean, Int32 (an int point whose
  declared range fits) or Int64, Double, String; a ``json`` point is String holding JSON text.
  A client writes a variable with its own data type only (:func:`from_opcua`);
* **AccessLevel** CurrentRead and/or CurrentWrite as declared (``r``, ``rw``, ``w``);
* **Description** the point's doc (and manual section); an **EngineeringUnits** property
  (EUInformation, UNECE code where :data:`UNECE` knows the unit, else UnitId -1) where the point
  has a unit.

Beside the variables each device object has the properties ``Kind`` and ``FaultKinds`` (the
declared faults) and the methods ``Fault(kind, active)`` and ``PowerCycle(wipe)``
(:mod:`devsim.facades.opcua` serves it all).  Conversions between a point's values and OPC UA
values (:func:`to_opcua`, :func:`from_opcua`) live here too.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from typing import Any

import msgspec

from devsim.core.points import BadValue, Point, ascii_digits

__all__ = [
    "DATA_TYPES",
    "DEFAULT_ENDPOINT",
    "NAMESPACE",
    "RESERVED",
    "TypeMismatch",
    "UNECE",
    "Variable",
    "data_type",
    "endpoint_url",
    "eu_information",
    "from_opcua",
    "to_opcua",
    "variables",
]

NAMESPACE = "urn:devsim"
DEFAULT_ENDPOINT = "opc.tcp://127.0.0.1:4840/devsim/"
#: Browse names on a device object that are not points.
RESERVED = frozenset({"Kind", "FaultKinds", "Fault", "PowerCycle"})

#: Point type → OPC UA built-in data type (``int`` is Int32 where its declared range fits).
DATA_TYPES = {"bool": "Boolean", "int": "Int64", "float": "Double", "str": "String", "json": "String"}

_INT32 = (-(2**31), 2**31 - 1)

#: Units the points use → UN/CEFACT common code (OPC UA Part 8, 5.6.3).  A unit not listed
#: (``inc``, ``counts``, ``P123 unit`` ...) gets UnitId -1 and its text as DisplayName.
UNECE = {
    "s": "SEC",
    "ms": "C26",
    "m": "MTR",
    "mm": "MMT",
    "V": "VLT",
    "mA": "4K",
    "A": "AMP",
    "Hz": "HTZ",
    "%": "P1",
    "°C": "CEL",
    "°": "DD",
    "1/s": "C97",
    "1/min": "C94",
}
UNECE_NAMESPACE = "http://www.opcfoundation.org/UA/units/un/cefact"


class TypeMismatch(ValueError):
    """A value written by a client that does not have the variable's data type."""


class Variable(msgspec.Struct, frozen=True):
    """One point as an OPC UA variable of a device object."""

    point: str  # the point's name = the browse name
    node_id: str  # the string NodeId identifier: DEVICE.POINT
    data_type: str  # Boolean, Int32, Int64, Double, String
    readable: bool
    writable: bool
    type: str  # the point's own type (bool, int, float, str, json)
    unit: str
    description: str


def data_type(point: Point) -> str:
    """The OPC UA data type a point is shown as."""
    if point.type == "int" and point.minimum is not None and point.maximum is not None \
            and _INT32[0] <= point.minimum and point.maximum <= _INT32[1]:
        return "Int32"
    return DATA_TYPES[point.type]


def variables(device: str, points: Iterable[Point]) -> list[Variable]:
    """The variables of a device named ``device`` with ``points``, in declaration order."""
    rows = []
    for point in points:
        if not (point.readable or point.settable):
            continue
        if point.name in RESERVED:
            raise ValueError(f"point {point.name!r} has a name the OPC UA device object uses itself")
        doc = f"{point.doc} ({point.section})" if point.section else point.doc
        rows.append(Variable(point.name, f"{device}.{point.name}", data_type(point), point.readable,
                             point.settable, point.type, point.unit, doc))
    return rows


def endpoint_url(spec: str | None) -> str:
    """The endpoint for ``--opcua [[HOST:]PORT]`` (or a whole ``opc.tcp://`` URL); empty or None:
    :data:`DEFAULT_ENDPOINT`.  Loopback unless a host is named."""
    if not spec:
        return DEFAULT_ENDPOINT
    if spec.startswith("opc.tcp://"):
        return spec
    host, sep, port_text = spec.rpartition(":")
    if not sep:
        host = ""
    host = host.strip("[]") or "127.0.0.1"
    if not ascii_digits(port_text) or len(port_text) > 5 or not 0 <= int(port_text) <= 65535:
        raise ValueError(f"--opcua: expected [HOST:]PORT, not {spec!r}")
    shown = f"[{host}]" if ":" in host else host
    return f"opc.tcp://{shown}:{int(port_text)}/devsim/"


def eu_information(unit: str) -> tuple[str, int, str, str]:
    """EUInformation of a unit: (NamespaceUri, UnitId, DisplayName, Description)."""
    code = UNECE.get(unit)
    if code is None:
        return UNECE_NAMESPACE, -1, unit, unit
    unit_id = 0
    for char in code:
        unit_id = (unit_id << 8) | ord(char)
    return UNECE_NAMESPACE, unit_id, unit, unit


def to_opcua(variable: Variable, value: Any) -> Any:
    """A point's value as the variable's OPC UA value.  A point with no value now (None: a
    ``motion.kind`` at rest) is JSON ``null`` for a JSON point, a null String for a text point
    (Part 6, 5.2.2.4) and None, no value, for the others."""
    if variable.type == "json":
        return json.dumps(value, separators=(",", ":"))
    if value is None:
        return None
    if variable.type == "bool":
        return bool(value)
    if variable.type == "int":
        return int(value)
    if variable.type == "float":
        return float(value)
    return str(value)


def from_opcua(variable: Variable, variant_type: str, value: Any) -> Any:
    """A value a client wrote (its variant type's name and value) as the point's value, for
    :meth:`devsim.core.device.Device.check`; :class:`TypeMismatch` unless it is a scalar of the
    variable's own data type.

    One type policy for every point (OPC UA Part 4, 5.10.4.1: Bad_TypeMismatch when the written
    value's data type is not the variable's DataType or a subtype; the built-in types Boolean,
    Int32, Int64, Double and String have none a client can send): a Double variable takes only
    Double, Int32 only Int32, Int64 only Int64, Boolean only Boolean, String only String.  No
    number is converted to another type, so a value is never rounded or widened on its way in.
    A String that is not JSON text, for a JSON point, has the right type and a value the point
    refuses: :class:`devsim.core.points.BadValue` (Bad_OutOfRange), as for any other point."""
    if variant_type != variable.data_type or isinstance(value, list | tuple):
        raise TypeMismatch(f"{variable.point} takes {variable.data_type}, not {variant_type}")
    if variable.type == "json":
        try:
            return json.loads(value)
        except (ValueError, RecursionError):
            raise BadValue(f"{variable.point} takes JSON text") from None  # a String, not one it takes
    return value
