"""Fleet addresses and topic names (no network here).

A fleet is reached by a URL ``mqtt://[USER[:PASSWORD]@]HOST[:PORT][/NAME]`` (port 1883 by
default).  All its topics live under one root, ``devsim-fleet`` (``devsim-fleet/NAME`` when the
URL names a fleet, so several fleets can share one broker)::

    ROOT/process/PROCESS            retained announcement of a process and its devices (JSON);
                                    its last will: the same with "online": false
    ROOT/process/PROCESS/request    control-API requests for that process's devices (JSON)
    ROOT/client/CLIENT/reply        answers to one client's requests
    ROOT/client/CLIENT/sync         the client's own marker: all retained announcements are in
    ROOT/client/CLIENT/watching     retained "1" while the client watches; cleared by its last will
    ROOT/client/CLIENT/watch/N      the items of one watch stream (``devsim ctl --fleet URL watch``)

``PROCESS`` is ``HOST-PID-XXXX`` (four random hex digits, so that processes in containers that
share a host name and a pid stay apart; a host name's ``/``, ``+``, ``#`` and spaces become
``_``).
"""

from __future__ import annotations

import os
import re
import secrets
import socket
from urllib.parse import unquote, urlsplit

import msgspec

__all__ = ["FleetUrl", "FleetUrlError", "Topics", "fleet_problem", "parse_fleet_url", "process_id"]

ROOT = "devsim-fleet"
_UNSAFE = re.compile(r"[/+#\s\x00]")


class FleetUrlError(ValueError):
    """A fleet URL that cannot be used."""


class FleetUrl(msgspec.Struct, frozen=True):
    host: str
    port: int = 1883
    fleet: str | None = None  # the NAME of mqtt://HOST/NAME
    username: str | None = None
    password: str | None = None

    def __str__(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"mqtt://{host}:{self.port}" + (f"/{self.fleet}" if self.fleet else "")

    @property
    def root(self) -> str:
        return f"{ROOT}/{self.fleet}" if self.fleet else ROOT


def parse_fleet_url(text: str) -> FleetUrl:
    """``mqtt://[USER[:PASSWORD]@]HOST[:PORT][/NAME]`` → :class:`FleetUrl`."""
    parts = urlsplit(text.strip())
    if parts.scheme != "mqtt":
        raise FleetUrlError(f"{text!r}: expected mqtt://HOST[:PORT][/NAME]")
    try:
        port = parts.port or 1883
    except ValueError:
        raise FleetUrlError(f"{text!r}: the port must be a number 1 … 65535") from None
    if not parts.hostname:
        raise FleetUrlError(f"{text!r}: no broker host (expected mqtt://HOST[:PORT][/NAME])")
    if parts.query or "#" in text:
        raise FleetUrlError(f"{text!r}: expected mqtt://HOST[:PORT][/NAME], no ?query or #")
    fleet = parts.path.strip("/") or None
    if fleet is not None and (_UNSAFE.search(fleet) or len(fleet) > 64):
        raise FleetUrlError(f"{text!r}: a fleet name is one topic level without + # / or spaces")
    return FleetUrl(
        host=parts.hostname,
        port=port,
        fleet=fleet,
        username=unquote(parts.username) if parts.username else None,
        password=unquote(parts.password) if parts.password else None,
    )


def fleet_problem(url: str) -> str | None:
    """Why ``--fleet URL`` cannot be used here (a bad URL), or None.  (The fleet needs no
    extra package: :mod:`devsim.facades.mqtt_link` is devsim's own MQTT 5 client.)"""
    try:
        parse_fleet_url(url)
    except FleetUrlError as exc:
        return str(exc)
    return None


def process_id(host: str | None = None, pid: int | None = None) -> str:
    """A new ``HOST-PID-XXXX`` for a member of this process, safe as one topic level."""
    host = host or socket.gethostname() or "localhost"
    return f"{_UNSAFE.sub('_', host)}-{os.getpid() if pid is None else pid}-{secrets.token_hex(2)}"


class Topics(msgspec.Struct, frozen=True):
    """The topic names of one fleet (``root``)."""

    root: str

    @property
    def announcements(self) -> str:
        """The filter that matches every process's announcement."""
        return f"{self.root}/process/+"

    def announcement(self, process: str) -> str:
        return f"{self.root}/process/{process}"

    def request(self, process: str) -> str:
        return f"{self.root}/process/{process}/request"

    def reply(self, client: str) -> str:
        return f"{self.root}/client/{client}/reply"

    def sync(self, client: str) -> str:
        return f"{self.root}/client/{client}/sync"

    def watching(self, client: str) -> str:
        """Retained ``1`` while ``client`` watches (its last will clears it): the members serve
        its streams as long as it is there."""
        return f"{self.root}/client/{client}/watching"

    def stream(self, client: str, number: int | str) -> str:
        """The topic of a client's watch stream ``number`` (``+``: the filter of all of them)."""
        return f"{self.root}/client/{client}/watch/{number}"

    @property
    def presences(self) -> str:
        """The filter that matches every client's ``watching``."""
        return f"{self.root}/client/+/watching"

    def client_of(self, topic: str) -> str | None:
        """The CLIENT of a ``ROOT/client/CLIENT/...`` topic, or None."""
        head = f"{self.root}/client/"
        if not topic.startswith(head):
            return None
        client, slash, _rest = topic[len(head):].partition("/")
        return client if client and slash else None

    def process_of(self, topic: str) -> str | None:
        """The PROCESS of an announcement topic, or None."""
        head = f"{self.root}/process/"
        if topic.startswith(head) and "/" not in topic[len(head):]:
            return topic[len(head):]
        return None
