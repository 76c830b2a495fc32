"""The control API's operations, declared once: :data:`CONTROL`, a :class:`devsim.core.kit.Table`
of :class:`~devsim.core.kit.Command` rows (op → handler, doc, typed request record).

Everything that offers the control API runs it from here: the control server and the fleet member
(:func:`answer`, JSON in and out), the clients (:meth:`devsim.runtime.client.ControlOps.call`),
``devsim ctl`` (one command per row), the pytest plugin's :class:`~devsim.pytest_plugin.SimDevice`
and ``SimPlant``, and the MQTT and OPC UA command paths (:func:`run` with a request record).

A handler is ``handler(runtime, request) -> result``; it runs the :class:`~devsim.runtime.Runtime`'s
thread-safe methods, so it may be called from any thread.
"""

from __future__ import annotations

import copy
import enum
import json
import math
import os
import time
from collections.abc import Callable, Mapping
from typing import Any

import msgspec

from devsim.core.kit import Command, Table
from devsim.core.points import BadValue, parse_bool
from devsim.runtime import requests as rq
from devsim.runtime.process import Runtime, port_key

__all__ = [
    "answer_parsed",
    "CONTROL",
    "MAX_DEPTH",
    "BadRequest",
    "CaptureStart",
    "ErrorResponse",
    "OkResponse",
    "WatchStart",
    "answer",
    "decode",
    "encode",
    "jsonable",
    "op_of",
    "required",
    "routed_by_device",
    "run",
]

MAX_DEPTH = 64  # nesting of lists and objects in one request

Handler = Callable[[Runtime, Any], Any]


class BadRequest(ValueError):
    """A request that is well-formed JSON but misses what its op needs."""


# -- responses --------------------------------------------------------------------------------
class OkResponse(msgspec.Struct, frozen=True):
    id: int | str | None = None
    result: Any = None
    ok: bool = True


class ErrorResponse(msgspec.Struct, frozen=True):
    error: str
    type: str
    id: int | str | None = None
    ok: bool = False


class WatchStart(msgspec.Struct, frozen=True):
    """What the ``watch`` handler hands the server: the stream needs the connection."""

    device: str
    names: list[str] | None = None
    period: float | None = None


class CaptureStart(msgspec.Struct, frozen=True):
    """What the ``capture`` handler hands the server: the stream needs the connection."""

    device: str
    port: str = "main"


# -- handlers ---------------------------------------------------------------------------------
def _devices(rt: Runtime, _req: rq.Devices) -> list[dict[str, Any]]:
    return [
        {
            "name": name,
            "kind": dev.kind,
            "port": rt.ports.get(port_key(name, dev.port_names()[0])),
            "ports": {p: rt.ports.get(port_key(name, p)) for p in dev.port_names()},
            "faults": dev.faults.names(),
        }
        for name, dev in rt.devices.items()
    ]


def _info(rt: Runtime, _req: rq.Info) -> dict[str, Any]:
    """What ``devsim ps`` lists of a process: its name, pid, uptime, kinds and ports (and, for
    ``devsim extcap``, how each port on a line is captured)."""
    from devsim.runtime.capture_stream import captures

    return {
        "name": rt.name,
        "pid": os.getpid(),
        "started": rt.started,
        "uptime": time.monotonic() - rt.started_monotonic,
        "clock": "virtual" if rt.clock.virtual else "real",
        "kinds": sorted({dev.kind for dev in rt.devices.values()}),
        "devices": list(rt.devices),
        "ports": dict(rt.ports),
        "captures": captures(rt),
    }


def _advance(rt: Runtime, req: rq.Advance) -> float:
    if req.seconds is None:
        raise BadRequest("advance needs 'seconds'")
    if not math.isfinite(req.seconds) or req.seconds < 0:
        raise BadRequest("'seconds' must be a finite number, not negative")
    return rt.advance(req.seconds)


def _power_cycle(rt: Runtime, req: rq.PowerCycle) -> None:
    rt.power_cycle(req.device, wipe=req.wipe)


def _line(rt: Runtime, req: rq.Line) -> dict[str, Any]:
    from devsim.transports.tap import capturing

    rt.device(req.device)
    status = rt.line_status(req.device, req.port)
    line = rt.lines[port_key(req.device, req.port)]
    return {**status, "capturing": rt.call(lambda: capturing(line))}


def _fault(rt: Runtime, req: rq.SwitchFault) -> None:
    rt.fault(req.device, req.kind, req.active)


def _line_fault(rt: Runtime, req: rq.LineFault) -> None:
    """A value the fault refuses is a ``BadValue``, a parameter it does not take a ``BadRequest``
    (they came as Python's ValueError and TypeError)."""
    try:
        rt.line_fault(req.device, req.kind, parse_bool(req.active), port=req.port, **req.params)
    except TypeError as exc:
        raise BadRequest(f"line fault {req.kind}: {exc}") from None
    except ValueError as exc:
        if isinstance(exc, BadValue):
            raise
        raise BadValue(f"line fault {req.kind}: {exc}") from None


def _telegrams(rt: Runtime, req: rq.Telegrams) -> list[dict[str, Any]]:
    """The last ``count`` telegrams (0 … 200, as ``ctl telegrams --count`` takes), of a device's
    port or of a line a facade serves for it (the Modbus RTU line ``modbus``, which declares no
    framing: its telegrams carry no decoding)."""
    from devsim.core.registry import port_framing
    from devsim.transports.tap import tap

    if not 0 <= req.count <= 200:
        raise BadRequest(f"'count' must be 0 … 200, not {req.count}")
    line = rt.lines.get(port_key(req.device, req.port))
    if line is None:
        rt.line_status(req.device, req.port)  # the reason: no such device, port or line
    framing = port_framing(rt.device(req.device).kind, req.port)
    return tap(line, framing.decoder).last(req.count)


def _watch(rt: Runtime, req: rq.Watch) -> WatchStart:
    if req.period is not None and not (math.isfinite(req.period) and req.period >= rq.MIN_WATCH_PERIOD):
        raise BadRequest(f"'period' must be a number of seconds from {rq.MIN_WATCH_PERIOD:g} on")
    rt.device(req.device)
    return WatchStart(device=req.device, names=req.names, period=req.period)


def _capture(rt: Runtime, req: rq.Capture) -> CaptureStart:
    if rt.lines.get(port_key(req.device, req.port)) is None:
        rt.line_status(req.device, req.port)  # the reason: no such device, port or line
    return CaptureStart(device=req.device, port=req.port)


def _scenario(rt: Runtime, _req: rq.Scenario) -> dict[str, Any] | None:
    return rt.call(lambda: copy.deepcopy(rt.scenario))


def _set(rt: Runtime, req: rq.Set) -> None:
    rt.set(req.device, req.name, req.value)


#: The control API: every op, its handler and its typed request (README "Control API").
CONTROL: Table[Handler] = Table([
    Command("read", lambda rt, req: rt.read(req.device, req.name), "",
            "a declared point's value (line.* reads the status of the line serving the main port)", request=rq.Read),
    Command("set", _set, "", "set a declared point, validated against its type and range", request=rq.Set),
    Command("state", lambda rt, req: rt.state(req.device), "",
            "a snapshot of the device's state (and its line's)", request=rq.State),
    Command("power_cycle", _power_cycle, "", "switch the device off and on (wipe: erase its NVRAM first)",
            request=rq.PowerCycle),
    Command("advance", _advance, "", "advance virtual time by seconds; the new time", request=rq.Advance),
    Command("now", lambda rt, req: rt.now(), "", "the device time in seconds", request=rq.Now),
    Command("info", _info, "", "the process: name, pid, uptime, clock, kinds, devices and ports (devsim ps)",
            request=rq.Info),
    Command("devices", _devices, "", "the devices: name, kind, ports and faults", request=rq.Devices),
    Command("line", _line, "", "the status of the line serving a port (settings, mismatch, counters, live captures)",
            request=rq.Line),
    Command("names", lambda rt, req: rt.names(req.device), "",
            "the declared points: name, type, unit, access, doc, section", request=rq.Names),
    Command("fault", _fault, "", "switch a declared device fault on or off", request=rq.SwitchFault),
    Command("line_fault", _line_fault, "", "start or end a fault on the line serving a port (with its params)",
            request=rq.LineFault),
    Command("telegrams", _telegrams, "",
            "the last telegrams on a port's line, decoded by the port's framing (kept from the first request on)",
            request=rq.Telegrams),
    Command("scenario", _scenario, "", "the running scenario's steps, their outcomes so far and its progress"
            " (null without one)", request=rq.Scenario),
    Command("watch", _watch, "", "a stream of the device's changes and events (see devsim.runtime.watch_stream)",
            request=rq.Watch),
    Command("capture", _capture, "",
            "a stream of the chunks crossing a port's line with its settings (see devsim.runtime.capture_stream)",
            request=rq.Capture),
])

_OPS_BY_TYPE: dict[type, str] = {row.request: row.token for row in CONTROL}
#: Every field any request has: a request naming another is refused.
_FIELDS = frozenset(name for row in CONTROL for name in row.request.__struct_fields__) | {"id", "op"}


def _envelope() -> type[msgspec.Struct]:
    """Every field of every request, each optional with its declared type: what any request's
    fields are checked against, so that a field of another op is refused when its type is wrong
    as it is when it belongs to the op (one field, one type, whichever op declares it)."""
    types: dict[str, Any] = {}
    for row in CONTROL:
        for field in msgspec.structs.fields(row.request):
            types.setdefault(field.name, field.type)
    return msgspec.defstruct("AnyRequest", [(name, kind | None, None) for name, kind in types.items()])


_ENVELOPE = _envelope()


def op_of(request: rq.ControlRequest) -> str:
    """The op of a request record."""
    return _OPS_BY_TYPE[type(request)]


def required(op: str) -> list[str]:
    """The fields ``op``'s request cannot do without."""
    return list(_REQUIRED[op])


#: op -> its required fields, read once (``msgspec.structs.fields`` evaluates the annotations at
#: every call: most of a request's cost when it ran per request)
_REQUIRED: dict[str, tuple[str, ...]] = {
    row.token: tuple(field.name for field in msgspec.structs.fields(row.request) if field.required)
    for row in CONTROL}


def routed_by_device(op: str) -> bool:
    """Whether ``device`` is optional for ``op`` and only routes it (``now``, ``advance``: one
    clock per process)."""
    return "device" in CONTROL.rows[op].request.__struct_fields__ and "device" not in required(op)


def run(runtime: Runtime, request: rq.ControlRequest) -> Any:
    """Carry out one typed request (in process; thread-safe)."""
    return CONTROL[op_of(request)](runtime, request)


#: (op, (field, type, value), ...) -> the typed request made from them: a poller asks the same
#: thing again and again, and checking it costs more than the read it asks for
_DECODED: dict[tuple[Any, ...], rq.ControlRequest] = {}
_DECODED_MAX = 1024


def decode(op: Any, fields: Mapping[str, Any]) -> rq.ControlRequest:
    """The typed request for ``op`` from the fields of a JSON request; :class:`BadRequest` when
    the op is unknown, a field unknown, of the wrong type, or a needed one missing.  Requests are
    records (frozen): one made from the same fields before is given again."""
    given = dict(fields)
    given.pop("id", None)
    try:  # (built in C: a generator here cost as much as the read)
        key: tuple[Any, ...] | None = (op, tuple(given.items()), tuple(map(type, given.values())))
        found = _DECODED.get(key)  # type: ignore[arg-type]
    except TypeError:  # a list or an object among the values: made each time
        key, found = None, None
    if found is not None:
        return found
    request = _decode(op, fields)
    if key is not None:
        if len(_DECODED) >= _DECODED_MAX:
            _DECODED.clear()
        _DECODED[key] = request
    return request


def _decode(op: Any, fields: Mapping[str, Any]) -> rq.ControlRequest:
    if not isinstance(op, str) or op not in CONTROL:
        raise BadRequest(f"op: unknown op {clip(repr(op), 80)} (ops: {', '.join(row.token for row in CONTROL)})")
    unknown = sorted(set(fields) - _FIELDS)
    if unknown:
        raise BadRequest(f"{clip(unknown[0], 80)}: not a field of any control request")
    kind: type[rq.ControlRequest] = CONTROL.rows[op].request
    try:
        msgspec.convert({k: v for k, v in fields.items() if k not in ("id", "op")}, _ENVELOPE, strict=False)
    except msgspec.ValidationError as exc:
        raise BadRequest(clip(str(exc))) from None
    given = {name: fields[name] for name in kind.__struct_fields__ if name in fields}
    for name in _REQUIRED[op]:
        if given.get(name) in (None, ""):
            raise BadRequest(f"{op} needs {name!r}")
    try:
        return msgspec.convert(given, kind, strict=False)
    except msgspec.ValidationError as exc:
        raise BadRequest(clip(str(exc))) from None


# -- JSON lines (the control server and the fleet member) --------------------------------------
def answer(runtime: Runtime, raw: bytes | str) -> OkResponse | ErrorResponse:
    """Answer one JSON request line."""
    try:
        payload = json.loads(raw)
    except RecursionError:
        return ErrorResponse(error=f"request nested deeper than {MAX_DEPTH} levels", type="BadRequest")
    except ValueError as exc:
        return ErrorResponse(error=f"not JSON: {clip(str(exc))}", type="BadRequest")
    return answer_parsed(runtime, payload)


def answer_parsed(runtime: Runtime, payload: Any) -> OkResponse | ErrorResponse:
    """Answer one request already parsed from its JSON (the fleet member parses it once)."""
    if _depth(payload) > MAX_DEPTH:
        return ErrorResponse(error=f"request nested deeper than {MAX_DEPTH} levels", type="BadRequest")
    if not isinstance(payload, dict):
        return ErrorResponse(error="request: a JSON object with an 'op'", type="BadRequest")
    req_id = payload.get("id")
    if not isinstance(req_id, (int, str)) or isinstance(req_id, bool):  # (a tuple: `int | str` is made per call)
        if req_id is not None:
            return ErrorResponse(error="id: a number or a string", type="BadRequest")
        req_id = None
    try:
        request = decode(payload.get("op"), payload)
    except BadRequest as exc:
        return ErrorResponse(id=req_id, error=str(exc), type="BadRequest")
    try:
        return OkResponse(id=req_id, result=run(runtime, request))
    except Exception as exc:  # every failure becomes a typed error response
        return ErrorResponse(id=req_id, error=clip(error_text(exc)), type=type(exc).__name__)


def encode(response: OkResponse | ErrorResponse) -> bytes:
    """One response as a JSON line."""
    if isinstance(response, OkResponse):
        data: dict[str, Any] = {"id": response.id, "ok": True, "result": jsonable(response.result)}
    else:
        data = {"id": response.id, "ok": False, "error": response.error, "type": response.type}
    return (json.dumps(data, separators=(",", ":")) + "\n").encode("utf-8")


def jsonable(value: Any) -> Any:
    """Make results JSON-safe (tuples, sets, bytes, enums, records, non-finite floats)."""
    if value is None or isinstance(value, (bool, int, str)):  # (tuples: a union is made on each call)
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [jsonable(v) for v in value]
    if isinstance(value, bytes | bytearray):
        return value.decode("latin-1")
    if isinstance(value, msgspec.Struct):  # a record or a configuration: its fields
        return {name: jsonable(getattr(value, name)) for name in value.__struct_fields__}
    if isinstance(value, enum.Enum):
        return jsonable(value.value)
    return str(value)


def error_text(exc: BaseException) -> str:
    if isinstance(exc, KeyError) and len(exc.args) == 1 and isinstance(exc.args[0], str):
        return exc.args[0]  # KeyError's str() would add quotes
    return str(exc) or type(exc).__name__


def clip(text: str, limit: int = 300) -> str:
    """Error texts never echo a huge request back."""
    return text if len(text) <= limit else text[: limit - 3] + "..."


_CONTAINERS = frozenset((dict, list))  # what msgspec's JSON decoder makes of an object and an array


def _depth(value: Any) -> int:
    """Nesting depth of parsed JSON, iteratively (no recursion on hostile input)."""
    # a plain request (no object or list inside) is the common case (looked at without a loop in Python)
    if isinstance(value, dict) and _CONTAINERS.isdisjoint(map(type, value.values())):
        return 1
    deepest = 0
    stack = [(value, 1)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, dict | list):
            deepest = max(deepest, depth)
            if depth > MAX_DEPTH:
                return depth
            stack.extend((child, depth + 1) for child in (node.values() if isinstance(node, dict) else node))
    return deepest
