"""The facade and fleet options of ``devsim run`` checked before anything starts (issues 13, 14):
each bad value is one usage-error line; a missing extra names the ``pip install`` that brings it
(:class:`devsim.cli.exits.MissingExtra`).
The libraries themselves are imported only to check that they are there."""

from __future__ import annotations

import math
from typing import Any

import click

from devsim.cli import exits
from devsim.cli.usage import host_port
from devsim.core.extras import install_command
from devsim.core.points import ascii_digits

__all__ = ["FLOAT", "INT", "AsciiFloatRange", "AsciiIntRange", "check_canopen", "check_fleet", "check_modbus", "check_mqtt", "check_opcua", "host_port", "modbus_for"]


class _AsciiNumber(click.ParamType):
    """A number option written in ASCII: click's FLOAT and INT take what ``float`` and ``int``
    take, the digits of every script too ('٣' is 3: ``--speed ٣`` ran at speed 3, ``--workers ٣``
    started three), which :func:`~devsim.core.points.ascii_digits` refuses everywhere else."""

    def convert(self, value: object, param: click.Parameter | None, ctx: click.Context | None) -> object:
        if isinstance(value, str) and not value.isascii():
            self.fail(f"{value!r} is not a number in ASCII digits", param, ctx)
        return super().convert(value, param, ctx)  # type: ignore[safe-super]


class _AsciiFloat(_AsciiNumber, click.types.FloatParamType):
    pass


class _AsciiInt(_AsciiNumber, click.types.IntParamType):
    pass


class AsciiFloatRange(_AsciiNumber, click.FloatRange):
    """``click.FloatRange`` in ASCII digits; ``finite=True`` also refuses 'nan' and 'inf', which a
    range lets through (NaN compares false with both bounds: ``--period nan`` reached the control
    server, whose error named its field 'period', not the option)."""

    def __init__(self, *args: Any, finite: bool = False, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.finite = finite

    def convert(self, value: object, param: click.Parameter | None, ctx: click.Context | None) -> object:
        number = super().convert(value, param, ctx)
        if self.finite and not math.isfinite(number):  # type: ignore[arg-type]
            self.fail(f"{number} is not a finite number", param, ctx)
        return number


class AsciiIntRange(_AsciiNumber, click.IntRange):
    """``click.IntRange`` in ASCII digits."""


#: ``type=float`` and ``type=int`` of a number option, in ASCII digits.
FLOAT = _AsciiFloat()
INT = _AsciiInt()


def check_modbus(spec: str) -> None:
    scheme, _, rest = spec.partition(":")
    if scheme == "tcp":
        host_port("--modbus", rest)
    elif scheme != "rtu":
        raise click.UsageError(f"--modbus: expected tcp:[HOST:]PORT, rtu or rtu:LINK, not {spec!r}")
    try:
        import pymodbus  # noqa: F401
    except ImportError:
        raise exits.MissingExtra(f"--modbus needs pymodbus: {install_command('modbus')}") from None


def check_canopen(spec: str) -> None:
    node, _, where = spec.partition("@")
    if not ascii_digits(node) or len(node) > 3 or not 1 <= int(node) <= 127:
        raise click.UsageError(f"--canopen: expected NODE[@[HOST:]PORT] or NODE@socketcan:CHANNEL with NODE 1 … 127, "
                               f"not {spec!r}")
    if where.startswith("socketcan:"):
        if not where.removeprefix("socketcan:"):
            raise click.UsageError("--canopen NODE@socketcan:CHANNEL needs a channel, e.g. vcan0")
    elif where:
        host_port("--canopen", where)
    try:
        import canopen  # noqa: F401
    except ImportError:
        raise exits.MissingExtra(f"--canopen needs canopen and python-can: {install_command('can')}") from None


def check_mqtt(url: str, convention: str, rate: float, plant: str | None, primary_host: str | None = None) -> None:
    try:  # (devsim speaks MQTT itself: devsim.facades.mqtt_link)
        if not url:
            import amqtt  # noqa: F401
        if convention == "sparkplug":
            import tahutils  # noqa: F401
    except ImportError:
        raise exits.MissingExtra(f"--mqtt needs amqtt (the embedded broker) and tahutils (Sparkplug B):"
                                 f" {install_command('mqtt')}") from None
    from devsim.facades.mqtt_topics import check_name, parse_url

    for option, check in (("--mqtt", lambda: parse_url(url) if url else None),
                          ("--mqtt-plant", lambda: check_name("plant", plant) if plant is not None else None)):
        try:
            check()
        except ValueError as exc:  # (a bad plant name was said as '--mqtt: ...')
            raise click.UsageError(f"{option}: {exc}") from None
    if not 0 < rate < math.inf:  # (inf passed 'rate > 0': the points were never sampled)
        raise click.UsageError("--mqtt-rate: must be a positive, finite number of seconds")
    if primary_host is not None:
        if convention != "sparkplug":
            raise click.UsageError("--mqtt-primary-host: a Sparkplug host application, only with"
                                   " --mqtt-convention sparkplug")
        try:
            check_name("primary host", primary_host)
        except ValueError as exc:
            raise click.UsageError(f"--mqtt-primary-host: {exc}") from None


def check_opcua(spec: str, period: float) -> None:
    from devsim.facades.opcua_space import endpoint_url

    try:
        endpoint_url(spec)
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None
    if not 0 < period < math.inf:  # (inf passed 'period > 0': subscriptions never saw a change)
        raise click.UsageError("--opcua-period: must be positive and finite")
    try:
        import asyncua  # noqa: F401
    except ImportError:
        raise exits.MissingExtra(f"--opcua needs asyncua: {install_command('opcua')}") from None


def check_fleet(url: str) -> None:
    """``--fleet URL``: a usable fleet URL (a usage error otherwise)."""
    from devsim.fleet.topics import FleetUrlError, fleet_problem, parse_fleet_url

    try:
        parse_fleet_url(url)
    except FleetUrlError as exc:
        raise click.UsageError(f"--fleet: {exc}") from None
    problem = fleet_problem(url)  # the URL is good: what is left is the missing extra
    if problem is not None:
        raise exits.MissingExtra(f"--fleet: {problem}")


def modbus_for(spec: str, index: int) -> str:
    """The Modbus port of the index-th device: TCP port numbers count up, RTU links get -N."""
    scheme, _, rest = spec.partition(":")
    if index == 0:
        return spec
    if scheme == "tcp":
        host, port = host_port("--modbus", rest)
        return f"tcp:{host}:{port + index if port else 0}"
    return f"rtu:{rest}-{index}" if rest else "rtu"
