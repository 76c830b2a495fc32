"""A fleet member's answers: the control API's JSON answer (:func:`encode_answer`) and the fast
path of the requests a fleet asks most (:class:`ResolvedRequests`), a read of a declared point
and a set, answered byte for byte as :func:`devsim.runtime.ops.answer_parsed` answers them.

A poller asks the same thing again and again (``{"id": "c-7", "op": "read", "device": "d003",
"name": "input.I1", "reply_to": …}``).  The first such request is resolved – the device and the
point, found as :meth:`devsim.core.points.PointTable.read` and ``set`` find them – and kept; the
later ones go straight to the point, past the control API's generic decode, its cache key and
its checks.  At every use the device is looked up again by name, so a device removed or replaced
under its name is resolved anew, and the point acts on the device's model of that moment (a
power cycle keeps the model and changes its state: the next read shows it).

Anything else – another op, a field more, an ``id`` that is neither a number nor a string, a
device or a name that does not resolve, a ``line.*`` name, a set without a value or with a list
or an object – is declined (None) and goes the generic way, which gives the answer it always
gave (the errors among them).  Used in the runtime's loop, where the member takes its requests.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import msgspec

from devsim.core.changes import CHANGES
from devsim.core.device import Device
from devsim.core.points import Point
from devsim.runtime import Runtime
from devsim.runtime.ops import ErrorResponse, OkResponse, clip, error_text, jsonable

__all__ = ["ResolvedRequests", "encode_answer", "encode_result"]

RESOLVED_MAX = 1024  # (op, device, name) kept at most; then the table starts again
_json_encode = msgspec.json.Encoder().encode
_SCALARS = frozenset((bool, int, float, str, type(None)))  # what a JSON value is when it is no list or object
_UNSET = msgspec.UNSET
_JSON_AS_IS = frozenset((bool, int, str, type(None)))  # results jsonable() returns unchanged


class _Answered(msgspec.Struct, gc=False):
    """An answer as the control API writes it (:func:`devsim.runtime.ops.encode`): its keys in
    that order (a struct is encoded faster than a dict)."""

    id: Any
    ok: bool
    result: Any


class _Refused(msgspec.Struct, gc=False):
    """An error answer as the control API writes it."""

    id: Any
    ok: bool
    error: str
    type: str


def encode_answer(response: OkResponse | ErrorResponse) -> bytes:
    """The control API's JSON line for ``response`` (:func:`devsim.runtime.ops.encode`), encoded
    by msgspec (UTF-8 as it is, where :mod:`json` escapes it)."""
    if isinstance(response, OkResponse):
        return encode_result(response.id, response.result)
    return _json_encode(_Refused(response.id, False, response.error, response.type)) + b"\n"


def encode_result(answer_id: Any, result: Any) -> bytes:
    """:func:`encode_answer` of ``OkResponse(id=answer_id, result=result)``, without making it."""
    if type(result) not in _JSON_AS_IS:
        result = jsonable(result)
    return _json_encode(_Answered(answer_id, True, result)) + b"\n"


class Asked(msgspec.Struct, forbid_unknown_fields=True, gc=False):
    """The shape of a request the fast path takes (any other shape is declined): the control
    API's fields of ``read`` and ``set`` and the member's ``reply_to``."""

    op: str
    device: str
    name: str
    id: int | str | None = None  # (a bool, a float: not this shape; the generic way refuses them)
    value: Any = msgspec.UNSET
    reply_to: Any = msgspec.UNSET


_decode_asked = msgspec.json.Decoder(Asked).decode


def _failed(asked: Asked, exc: Exception) -> bytes:
    """The answer of the generic way when the op's handler raised ``exc``."""
    return encode_answer(ErrorResponse(id=asked.id, error=clip(error_text(exc)), type=type(exc).__name__))


def _read(asked: Asked, device: Device, point: Point) -> bytes | None:
    """``read``: :meth:`devsim.core.points.PointTable.read` with the point found."""
    if asked.value is not _UNSET:
        return None
    assert point.get is not None  # (resolved only when it has one)
    try:
        result = point.get(device.model)
    except Exception as exc:  # the error response of the generic way
        return _failed(asked, exc)
    return encode_result(asked.id, result)


def _set(asked: Asked, device: Device, point: Point) -> bytes | None:
    """``set``: :meth:`devsim.core.points.PointTable.set` with the point found."""
    value = asked.value
    if type(value) not in _SCALARS:  # none (UNSET), a list, an object
        return None
    assert point.put is not None  # (resolved only when it has one)
    try:
        parsed = point.checked(value)
        CHANGES.count += 1  # (what PointTable.set does with the point: a door, devsim.core.changes)
        point.put(device.model, parsed)
    except Exception as exc:  # the error response of the generic way
        return _failed(asked, exc)
    return encode_result(asked.id, None)


class FastOp(NamedTuple):
    """An op the fast path takes: which points it resolves to, and what it does with one."""

    takes: Callable[[Point], bool]
    run: Callable[[Asked, Device, Point], bytes | None]


#: op -> how the fast path answers it (the control API's ``read`` and ``set``)
FAST_OPS: dict[str, FastOp] = {
    "read": FastOp(lambda point: point.get is not None, _read),
    "set": FastOp(lambda point: point.put is not None, _set),
}


class ResolvedRequests:
    """The requests of a member resolved once (see the module docstring)."""

    def __init__(self, runtime: Runtime) -> None:
        self._devices = runtime.devices  # (the runtime's own table: devices added and removed show)
        self._resolved: dict[tuple[str, str, str], tuple[Device, Point, FastOp]] = {}

    def answer(self, raw: bytes) -> tuple[Any, bytes] | None:
        """(the request's ``reply_to``, or UNSET without one; the JSON answer line), or None:
        not a request of the fast path."""
        try:
            asked = _decode_asked(raw)
        except (msgspec.DecodeError, RecursionError):  # (a ValidationError is a DecodeError)
            return None
        key = (asked.op, asked.device, asked.name)
        found = self._resolved.get(key)
        if found is None or self._devices.get(asked.device) is not found[0]:
            found = self._resolve(*key)
            if found is None:
                return None
        device, point, op = found
        body = op.run(asked, device, point)
        return None if body is None else (asked.reply_to, body)

    def _resolve(self, op_name: str, device_name: str, name: str) -> tuple[Device, Point, FastOp] | None:
        op = FAST_OPS.get(op_name)
        device = self._devices.get(device_name)
        if op is None or device is None or not name or name.startswith("line."):  # line.*: the line's status
            return None
        point = device.points.find(name)
        if point is None or not op.takes(point):
            return None
        if len(self._resolved) >= RESOLVED_MAX:
            self._resolved.clear()
        found = self._resolved[(op_name, device_name, name)] = (device, point, op)
        return found
