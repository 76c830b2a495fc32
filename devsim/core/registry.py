"""Device kinds, found through the ``devsim.devices`` entry-point group.

Another package can add a kind by declaring, in its own ``pyproject.toml``::

    [project.entry-points."devsim.devices"]
    mykind = "mypackage.mydevice:MyDevice"

where ``MyDevice`` subclasses :class:`devsim.core.device.Device`.

Without installing anything, the environment variable ``DEVSIM_EXTRA_KINDS`` adds kinds too
(tests use it): ``DEVSIM_EXTRA_KINDS="echo=tests.support.echo:EchoDevice,other=pkg.mod:Cls"``.
"""

from __future__ import annotations

import os

from devsim.core.device import Device
from devsim.core.framing import PLAIN, Framing

__all__ = ["ENV_EXTRA_KINDS", "GROUP", "UnknownKind", "device_class", "kinds", "port_framing"]

GROUP = "devsim.devices"
ENV_EXTRA_KINDS = "DEVSIM_EXTRA_KINDS"

# Kinds shipped with devsim, used when the distribution's metadata is not installed
# (e.g. running from a source checkout without `pip install -e`).
_BUILTIN = {
    "sers": "devsim.devices.sers:SersDevice",
    "gms96": "devsim.devices.gms96:Gms96Device",
    "poselesta": "devsim.devices.poselesta:PoselestaDevice",
    "ip247": "devsim.devices.ip247:Ip247Device",
    "pcd4h3": "devsim.devices.pcd4h3:Pcd4h3Device",
}


class UnknownKind(LookupError):
    pass


def _extra() -> dict[str, str]:
    found = {}
    for item in os.environ.get(ENV_EXTRA_KINDS, "").replace(";", ",").split(","):
        kind, sep, target = item.strip().partition("=")
        if sep and kind.strip() and ":" in target:
            found[kind.strip()] = target.strip()
    return found


def _targets() -> dict[str, str]:
    from importlib.metadata import entry_points  # scanning installed packages takes a while

    found = dict(_BUILTIN)
    for ep in entry_points(group=GROUP):
        found[ep.name] = ep.value
    found.update(_extra())
    return found


def _target(kind: str) -> str | None:
    """A shipped or ``DEVSIM_EXTRA_KINDS`` kind without scanning the installed packages."""
    return _extra().get(kind) or _BUILTIN.get(kind) or _targets().get(kind)


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
