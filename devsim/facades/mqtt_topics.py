"""The MQTT facade's topics and payloads in the ``devsim`` convention (pure: no I/O, no broker).

Every device of a plant lives under ``devsim/<plant>/<device>/``::

    birth              retained JSON: device, kind, its points (name, type, unit, access) and faults
    status             retained "online" / "offline" (the connection's last will)
    state/<name>       retained JSON value of each readable point, on change
    set/<name>         command: a JSON value, or plain text (read as the point's type)
    fault/<kind>       command: true / false (also on/off, 1/0)
    power_cycle        command: empty, or {"wipe": true}
    error              what a command was refused for: {"topic", "error", "type"} (not retained)

A command is the control op of its verb (:data:`devsim.runtime.ops.CONTROL`), run with the
typed request its payload is read into: the same validation and refusals as over the control
API.  See :mod:`devsim.facades.mqtt` for the connection that carries them.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from typing import Any
from urllib.parse import urlsplit

from devsim.core.device import Device
from devsim.core.points import parse_bool
from devsim.runtime import requests as rq
from devsim.runtime.ops import BadRequest

__all__ = [
    "COMMANDS",
    "Command",
    "DEFAULT_PORT",
    "birth",
    "command_filters",
    "decode_value",
    "encode",
    "error_payload",
    "parse_command",
    "parse_url",
    "prefix",
    "state_topic",
]

DEFAULT_PORT = 1883
ROOT = "devsim"


def parse_url(url: str) -> tuple[str, int]:
    """``mqtt://HOST[:PORT]`` (or ``HOST[:PORT]``) → (host, port); the port defaults to 1883."""
    text = url if "://" in url else f"mqtt://{url}"
    parts = urlsplit(text)
    if parts.scheme not in ("mqtt", "tcp"):
        raise ValueError(f"expected mqtt://HOST[:PORT], not {url!r}")
    try:
        port = parts.port
    except ValueError:
        raise ValueError(f"expected mqtt://HOST[:PORT], not {url!r}") from None
    if not parts.hostname or parts.path not in ("", "/"):
        raise ValueError(f"expected mqtt://HOST[:PORT], not {url!r}")
    from devsim.runtime.control import host_problem

    problem = host_problem(parts.hostname)
    if problem is not None:
        raise ValueError(f"{url!r}: {problem}")
    return parts.hostname, port if port is not None else DEFAULT_PORT


def check_name(what: str, name: str) -> str:
    """A plant or device name is one topic level: no ``/``, ``+``, ``#``, not empty."""
    if not name or any(c in name for c in "/+#\0"):
        raise ValueError(f"an MQTT {what} name is one topic level (no '/', '+', '#'), not {name!r}")
    return name


def prefix(plant: str, device: str) -> str:
    return f"{ROOT}/{plant}/{device}"


def state_topic(plant: str, device: str, name: str) -> str:
    return f"{prefix(plant, device)}/state/{name}"


def encode(value: Any) -> bytes:
    """A value as the JSON a state topic carries."""
    return json.dumps(value, separators=(",", ":")).encode()


#: The blanks JSON allows around a value (str.strip() also takes FS … US, NEL, NBSP and the other
#: Unicode spaces: '\xa012.5' was the number 12.5).
_JSON_BLANKS = " \t\n\r"


def decode_value(payload: bytes, point_type: str | None = None) -> Any:
    """A command's payload: JSON if it parses, else the plain text; for a text point, a JSON
    value that is not text is taken as the plain text it was sent as (``42`` → ``"42"``)."""
    text = payload.decode("utf-8", errors="replace").strip(_JSON_BLANKS)
    try:
        value = json.loads(text)
    except (ValueError, RecursionError):  # (nested deeper than the decoder goes: text too)
        return text
    if point_type == "str" and not isinstance(value, str):
        return text
    return value


def birth(device: Device, rate: float) -> dict[str, Any]:
    """The birth message: what the device is and every declared point (name, type, unit, access,
    doc), its faults, and the sampling period."""
    return {
        "device": device.name,
        "kind": device.kind,
        "rate": rate,
        "points": [{"name": p.name, "type": p.type, "unit": p.unit, "access": p.access, "doc": p.doc}
                   for p in device.points],
        "faults": list(device.faults.names()),
    }


def error_payload(topic: str, exc: BaseException) -> bytes:
    """What ``…/error`` carries for a refused command."""
    message = exc.args[0] if isinstance(exc, KeyError) and len(exc.args) == 1 else str(exc)
    return json.dumps({"topic": topic, "error": str(message)[:500], "type": type(exc).__name__}).encode()


# -- commands -------------------------------------------------------------------------------
#: How a command's payload becomes the typed request of its control op
#: (:data:`devsim.runtime.ops.CONTROL`): ``parse(device, argument, payload)``.
Command = Callable[[Device, str, bytes], rq.ControlRequest]


def _set(device: Device, name: str, payload: bytes) -> rq.Set:
    point = device.points.find(name)
    return rq.Set(device.name, name, decode_value(payload, point.type if point is not None else None))


def _fault(device: Device, kind: str, payload: bytes) -> rq.SwitchFault:
    return rq.SwitchFault(device.name, kind, parse_bool(decode_value(payload)))


def _power_cycle(device: Device, _arg: str, payload: bytes) -> rq.PowerCycle:
    value = decode_value(payload) if payload.strip() else {}
    if not isinstance(value, dict) or set(value) - {"wipe"}:
        raise BadRequest('power_cycle takes an empty payload or {"wipe": true}')
    return rq.PowerCycle(device.name, parse_bool(value.get("wipe", False)))


#: ``…/<op>[/<argument>]`` → how its payload is read, and whether it takes an argument level;
#: each verb is the control op it runs.
COMMANDS: dict[str, tuple[Command, bool]] = {
    "set": (_set, True),
    "fault": (_fault, True),
    "power_cycle": (_power_cycle, False),
}


def command_filters(plant: str, devices: Iterable[str]) -> list[str]:
    """The subscriptions that bring a plant's commands: each verb with every level below it
    (``…/set/#`` also brings ``…/set``), so that a command with a level too many or too few is
    answered on ``…/error`` rather than lost at the broker."""
    return [f"{prefix(plant, device)}/{verb}/#" for device in devices for verb in COMMANDS]


def _misshapen(verb: str, takes_arg: bool) -> Command:
    """The handler of a command topic of a known verb with the wrong number of levels: it refuses."""
    shape = f"{verb}/<{'point' if verb == 'set' else 'kind'}>" if takes_arg else verb

    def refuse(_device: Device, _arg: str, _payload: bytes) -> rq.ControlRequest:
        raise BadRequest(f"a {verb} command's topic ends in {shape}")

    return refuse


def parse_command(topic: str, plant: str) -> tuple[str, Command, str] | None:
    """``devsim/<plant>/<device>/<verb>[/<arg>]`` → (device, handler, arg), or None for a topic
    that is no command of the plant; a known verb with a level too many or too few gets a
    handler that refuses it (its error names the topic's shape)."""
    parts = topic.split("/")
    if len(parts) < 4 or parts[0] != ROOT or parts[1] != plant:
        return None
    entry = COMMANDS.get(parts[3])
    if entry is None:
        return None
    handler, takes_arg = entry
    if len(parts) != (5 if takes_arg else 4) or (takes_arg and not parts[4]):
        return parts[2], _misshapen(parts[3], takes_arg), ""
    return parts[2], handler, parts[4] if takes_arg else ""
