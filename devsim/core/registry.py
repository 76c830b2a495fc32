"""Device kinds, found through the ``devsim.devices`` entry-point group: one registration per kind.

devsim's own kinds are the entry points of its distribution (``devsim-motion``'s
``pyproject.toml``; a source checkout has them once ``pip install -e .`` wrote its metadata).
Another package can add a kind by declaring, in its own ``pyproject.toml``::

    [project.entry-points."devsim.devices"]
    mykind = "mypackage.mydevice:MyDevice"

where ``MyDevice`` subclasses :class:`devsim.core.device.Device`.  Looking a kind up reads
devsim's own distribution first and scans every installed package only for a kind it does not
name (scanning takes a while; ``devsim run sers`` should start fast).

Without installing anything, the environment variable ``DEVSIM_EXTRA_KINDS`` adds kinds too
(tests use it): ``DEVSIM_EXTRA_KINDS="echo=tests.support.echo:EchoDevice,other=pkg.mod:Cls"``.
"""

from __future__ import annotations

import functools
import os
import sys

from devsim.core.device import Device
from devsim.core.framing import PLAIN, Framing

__all__ = ["DISTRIBUTION", "ENV_EXTRA_KINDS", "GROUP", "UnknownKind", "device_class", "kinds", "port_framing"]

GROUP = "devsim.devices"
ENV_EXTRA_KINDS = "DEVSIM_EXTRA_KINDS"
#: The distribution whose entry points name devsim's own kinds.
DISTRIBUTION = "devsim-motion"


class UnknownKind(LookupError):
    pass


def _extra() -> dict[str, str]:
    found = {}
    for item in os.environ.get(ENV_EXTRA_KINDS, "").replace(";", ",").split(","):
        kind, sep, target = item.strip().partition("=")
        if sep and kind.strip() and ":" in target:
            found[kind.strip()] = target.strip()
    return found


@functools.cache
def _own() -> dict[str, str]:
    """The kinds of devsim's own distribution (read once: its metadata does not change)."""
    found = _own_entry_points()
    if found is not None:
        return found
    from importlib.metadata import PackageNotFoundError, distribution  # importing it costs ~25 ms

    try:
        points = distribution(DISTRIBUTION).entry_points
    except PackageNotFoundError:
        return {}
    return {ep.name: ep.value for ep in points if ep.group == GROUP}


def _own_entry_points() -> dict[str, str] | None:
    """The ``devsim.devices`` entry points in the first ``devsim_motion-*.dist-info`` on
    ``sys.path`` (where :mod:`importlib.metadata` finds it), read without importing that;
    None when there is none."""
    prefix = DISTRIBUTION.replace("-", "_") + "-"
    for entry in sys.path:
        try:
            names = os.listdir(entry or ".")
        except OSError:
            continue
        for name in names:
            if name.startswith(prefix) and name.endswith(".dist-info"):
                try:
                    with open(os.path.join(entry or ".", name, "entry_points.txt"), encoding="utf-8") as file:
                        text = file.read()
                except OSError:
                    return {}
                return _section(text, GROUP)
    return None


def _section(text: str, group: str) -> dict[str, str]:
    """``name = value`` lines of one ``[group]`` of an entry_points.txt."""
    found: dict[str, str] = {}
    current = None
    for raw in text.splitlines():
        line = raw.strip()
        if line.startswith("[") and line.endswith("]"):
            current = line[1:-1].strip()
        elif current == group and "=" in line and not line.startswith(("#", ";")):
            name, _, value = line.partition("=")
            found[name.strip()] = value.strip()
    return found


def _targets() -> dict[str, str]:
    from importlib.metadata import entry_points  # scanning installed packages takes a while

    found = dict(_own())
    for ep in entry_points(group=GROUP):
        found[ep.name] = ep.value
    found.update(_extra())
    return found


def _target(kind: str) -> str | None:
    """A kind of devsim's own or of ``DEVSIM_EXTRA_KINDS`` without scanning the installed packages."""
    return _extra().get(kind) or _own().get(kind) or _targets().get(kind)


def kinds() -> dict[str, str]:
    """Kind name → ``module:Class`` of every registered device kind."""
    return dict(sorted(_targets().items()))


def device_class(kind: str) -> type[Device]:
    target = _target(kind)
    if target is None:
        raise UnknownKind(f"unknown device kind {kind!r} (known: {', '.join(kinds())})")
    module_name, _, attr = target.partition(":")
    module = __import__(module_name, fromlist=[attr])
    cls = getattr(module, attr)
    if not (isinstance(cls, type) and issubclass(cls, Device)):
        raise UnknownKind(f"{target} is not a devsim Device")
    return cls


def port_framing(kind: str | None, port: str = "main") -> Framing:
    """The framing ``port`` of ``kind`` declares (:attr:`devsim.core.kit.PortDef.framing`);
    :data:`~devsim.core.framing.PLAIN` for a port that declares none, or an unknown kind or port."""
    if not kind:
        return PLAIN
    try:
        cls = device_class(kind)
    except UnknownKind:
        return PLAIN
    for spec in cls.ports:
        if spec.name == port:
            return spec.framing or PLAIN
    return PLAIN
