"""Transports – where a host's bytes come from – and the line in front of a device.

* :class:`PtyTransport` – a raw-mode pseudo-terminal with an optional stable symlink;
* :class:`TcpTransport` – a raw TCP port, like a serial device server (``socket://``);
* :class:`Rfc2217Transport` – a TCP port speaking RFC 2217, line settings included
  (``rfc2217://``);
* :class:`Line` – pacing, line-settings mismatch and tracing between a transport and a device
  or bus; :class:`Tracer` writes the wire trace.

Each transport serves one :class:`Endpoint` (in practice a :class:`Line`) and knows no device.
"""

from devsim.transports.base import Endpoint, Transport
from devsim.transports.line import Line, garble, settings_match
from devsim.transports.pty import PtyTransport
from devsim.transports.rfc2217 import Rfc2217Transport
from devsim.transports.tcp import TcpTransport
from devsim.transports.trace import Tracer, render

__all__ = [
    "Endpoint",
    "Line",
    "PtyTransport",
    "Rfc2217Transport",
    "TcpTransport",
    "Tracer",
    "Transport",
    "garble",
    "render",
    "settings_match",
]
