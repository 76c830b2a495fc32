"""Transports – where a host's bytes come from – and the line in front of a device.

* :class:`PtyTransport` – a raw-mode pseudo-terminal with an optional stable symlink;
* :class:`TcpTransport` – a raw TCP port, like a serial device server (``socket://``);
* :class:`Rfc2217Transport` – a TCP port speaking RFC 2217, line settings included
  (``rfc2217://``);
* :class:`UdpTransport` – a UDP port, one telegram per datagram (``udp://``), answers to the
  latest sender;
* :class:`Line` – pacing, line-settings mismatch and tracing between a transport and a device
  or bus; :func:`open_trace` opens the wire trace: :class:`Tracer` writes text,
  :class:`SerialPcapTracer` a serial line's pcap file for Wireshark (``*.pcap``, devsim's serial
  encapsulation), :class:`PcapTracer` a network port's (IPv4/UDP).

Each transport serves one :class:`Endpoint` (in practice a :class:`Line`) and knows no device.
"""

from importlib import import_module
from typing import Any

_HOME = {
    "Endpoint": "base",
    "Transport": "base",
    "Line": "line",
    "garble": "line",
    "settings_match": "line",
    "PtyTransport": "pty",
    "Rfc2217Transport": "rfc2217",
    "TcpTransport": "tcp",
    "UdpTransport": "udp",
    "PcapTracer": "pcap",
    "SerialPcapTracer": "pcap",
    "Tracer": "trace",
    "render": "trace",
    "open_trace": "tracing",
}

__all__ = sorted(_HOME)


def __getattr__(name: str) -> Any:
    """Each name is imported from its module when first used (``devsim run`` starts faster)."""
    module = _HOME.get(name)
    if module is None:
        raise AttributeError(f"module 'devsim.transports' has no attribute {name!r}")
    return getattr(import_module(f"devsim.transports.{module}"), name)
