"""Opening a wire trace: the one factory that picks its form by the file name.

``FILE.pcap`` gets a libpcap trace (:class:`~devsim.transports.pcap.PcapTracer`, readable by
Wireshark and tshark); any other name the text trace (:class:`~devsim.transports.trace.Tracer`).
Both refuse to write through a symlink.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from devsim.transports.pcap import PcapTracer, Peers
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
) -> TraceSink:
    """A trace writer for ``path``: pcap for ``*.pcap`` (``peers`` gives the transport's real
    addresses, ``name`` the stable invented port, see :mod:`devsim.transports.pcap`), else text."""
    if is_pcap(path):
        return PcapTracer(path, peers=peers, name=name)
    return Tracer(path)
