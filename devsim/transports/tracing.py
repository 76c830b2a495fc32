"""Opening a wire trace: the one factory that picks its form by the file name.

``FILE.pcap`` gets a libpcap trace readable by Wireshark and tshark: a serial line's (a port
with a capture tag, :class:`~devsim.core.kit.CaptureTag`) in devsim's serial encapsulation
(:class:`~devsim.transports.pcap.SerialPcapTracer`, link type USER0), any other port's as
IPv4/UDP (:class:`~devsim.transports.pcap.PcapTracer`); any other name gets the text trace
(:class:`~devsim.transports.trace.Tracer`).  All refuse to write through a symlink.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from devsim.core.kit import CaptureTag
from devsim.transports.pcap import LineState, PcapTracer, Peers, SerialPcapTracer
from devsim.transports.trace import Tracer, TraceSink

__all__ = ["PCAP_SUFFIX", "is_pcap", "open_trace"]

PCAP_SUFFIX = ".pcap"


def is_pcap(path: str | os.PathLike[str]) -> bool:
    """Whether a trace at ``path`` is written as pcap (its suffix is ``.pcap``, any case)."""
    return Path(path).suffix.lower() == PCAP_SUFFIX


def open_trace(
    path: str | os.PathLike[str],
    *,
    peers: Callable[[], Peers | None] | None = None,
    name: str = "",
    capture: CaptureTag | None = None,
    settings: Callable[[], LineState] | None = None,
) -> TraceSink:
    """A trace writer for ``path``: pcap for ``*.pcap``, else text.  A pcap trace of a serial
    line (``capture``: its tag) carries the line ``settings`` of the moment in each record;
    any other is IPv4/UDP (``peers`` gives the transport's real addresses, ``name`` the stable
    invented port, see :mod:`devsim.transports.pcap`)."""
    if is_pcap(path) and capture is not None:
        return SerialPcapTracer(path, protocol=capture.protocol, port=capture.port, settings=settings)
    if is_pcap(path):
        return PcapTracer(path, peers=peers, name=name)
    return Tracer(path)
