"""``devsim extcap``: Wireshark's external capture interface to running simulators.

Wireshark (and tshark) run every program in their extcap folders to list capture interfaces
(the extcap interface, https://www.wireshark.org/docs/wsdg_html_chunked/ChCaptureExtcap.html);
``devsim wireshark --install`` puts a launcher there that runs this one with devsim's interpreter.
Each port on a line of each running simulator (found as ``devsim ps`` finds them,
:func:`devsim.runtime.discovery.running`) is one interface, ``devsim-PID-KEY`` (``KEY`` the port
key: ``sers``, ``cnc.v7``, ``drive.modbus``):

* ``--extcap-interfaces``: the ``extcap`` line and one ``interface`` line per port;
* ``--extcap-interface I --extcap-dlts``: the port's link type: USER0 (147, devsim's serial
  encapsulation, :mod:`devsim.transports.pcap`) for a serial line, raw IPv4 (228) for the others;
* ``--extcap-interface I --extcap-config``: no options (nothing to configure);
* ``--capture --extcap-interface I --fifo F``: writes a pcap stream to ``F`` (the same records as
  ``--trace FILE.pcap``, from the control op ``capture``, :mod:`devsim.runtime.capture_stream`)
  until Wireshark closes the fifo or stops the program, or the simulator ends.

The pure part (:func:`interfaces`, :func:`parse_interface`, :func:`interface_lines`,
:func:`dlt_line`) turns the simulators' ``info`` into those lines; :func:`main` does the I/O.
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Sequence
from typing import Any, TextIO

from devsim import __version__
from devsim.core.points import ascii_digits
from devsim.runtime.discovery import Simulator, running
from devsim.transports.pcap import LINKTYPE_IPV4, LINKTYPE_USER0, PcapTracer, SerialPcapTracer

__all__ = ["PREFIX", "Interface", "dlt_line", "interface_lines", "interfaces", "main", "parse_interface"]

#: Every interface's name starts so (``devsim-4242-sers``).
PREFIX = "devsim"
_LINK_NAMES = {LINKTYPE_USER0: ("USER0", "devsim serial line (USER0)"), LINKTYPE_IPV4: ("IPV4", "Raw IPv4")}


class Interface:
    """One capture interface: a port (``key``) of the simulator with ``pid`` at ``address``."""

    def __init__(self, simulator: Simulator, key: str, capture: dict[str, Any]) -> None:
        self.simulator = simulator
        self.key = key
        self.link = int(capture.get("link", LINKTYPE_IPV4))
        self.protocol = int(capture.get("protocol", 0))
        self.port_byte = int(capture.get("port_byte", 0))

    @property
    def name(self) -> str:
        return f"{PREFIX}-{self.simulator.pid}-{self.key}"

    @property
    def display(self) -> str:
        what = "serial line" if self.link == LINKTYPE_USER0 else "network port"
        return f"devsim {self.key} ({what} of {self.simulator.name}, pid {self.simulator.pid})"

    def device_port(self) -> tuple[str, str]:
        """The device and port names of the key (``cnc.v7`` → ``("cnc", "v7")``), by the
        simulator's own device names (a device name may hold a dot)."""
        for device in sorted(self.simulator.devices, key=len, reverse=True):
            if self.key == device:
                return device, "main"
            if self.key.startswith(device + "."):
                return device, self.key[len(device) + 1 :]
        device, _, port = self.key.rpartition(".")
        return (device, port) if device else (self.key, "main")


def interfaces(simulators: Sequence[Any]) -> list[Interface]:
    """Every captured port of every answering simulator (``info`` with ``captures``)."""
    found = []
    for simulator in simulators:
        if not getattr(simulator, "answering", True) or simulator.pid is None:
            continue
        for key, capture in sorted((getattr(simulator, "captures", None) or {}).items()):
            found.append(Interface(simulator, key, capture))
    return found


def parse_interface(name: str) -> tuple[int, str]:
    """``devsim-4242-cnc.v7`` → ``(4242, "cnc.v7")``; ``ValueError`` for any other name."""
    prefix, _, rest = name.partition("-")
    pid, _, key = rest.partition("-")
    if prefix != PREFIX or not ascii_digits(pid) or not key:
        raise ValueError(f"not a devsim capture interface: {name!r} (they are {PREFIX}-PID-PORT)")
    return int(pid), key


def _escape(text: str) -> str:
    """An extcap value may not hold the braces that delimit it."""
    return text.replace("{", "(").replace("}", ")")


def interface_lines(found: Sequence[Interface]) -> list[str]:
    """What ``--extcap-interfaces`` prints."""
    lines = [f"extcap {{version={__version__}}}"]
    lines += [f"interface {{value={_escape(i.name)}}}{{display={_escape(i.display)}}}" for i in found]
    return lines


def dlt_line(link: int) -> str:
    """What ``--extcap-dlts`` prints for a port captured with link type ``link``."""
    name, display = _LINK_NAMES[link]
    return f"dlt {{number={link}}}{{name={name}}}{{display={display}}}"


# -- the program --------------------------------------------------------------------------------
def _find(name: str) -> Interface:
    pid, key = parse_interface(name)
    for interface in interfaces(running()):
        if interface.simulator.pid == pid and interface.key == key:
            return interface
    raise LookupError(f"no running simulator with pid {pid} captures a port {key!r} (see 'devsim ps')")


def _stop(signum: int, _frame: Any) -> None:
    raise SystemExit(0)


def capture(interface: Interface, fifo: str) -> int:
    """Write ``interface``'s chunks to ``fifo`` as pcap until the reader or the simulator goes."""
    from devsim.runtime.client import CaptureSubscription

    device, port = interface.device_port()
    with CaptureSubscription(interface.simulator.address, device, port) as stream:
        info = stream.info
        settings: dict[str, Any] = {"baud": 0, "bits": 0, "parity": "", "stop": 0, "mismatch": False}
        tracer: Any
        if int(info["link"]) == LINKTYPE_USER0:
            tracer = SerialPcapTracer(fifo, protocol=int(info["protocol"]), port=int(info["port_byte"]),
                                      settings=lambda: settings, wait=True)
        else:  # the transport's real addresses where it knows them (a UDP or TCP port), as a --trace pcap
            peers: list[Any] = [None]
            tracer = PcapTracer(fifo, name=interface.key, wait=True,
                                peers=lambda: tuple(tuple(end) for end in peers[0]) if peers[0] else None)
        try:
            for item in stream:
                if item.get("type") != "chunk":
                    continue  # "dropped": Wireshark read too slowly; a pcap has no place for it
                settings = item.get("settings") or settings
                if "peers" in item:  # (only an IPv4 capture's chunks carry them)
                    peers[0] = item["peers"]
                tracer.record(item["dir"], bytes.fromhex(item["data"]), float(item["t"]))
                if tracer.closed:
                    break  # Wireshark closed the fifo: the capture is over
        finally:
            tracer.close()
    return 0


def main(argv: Sequence[str] | None = None, out: TextIO | None = None) -> int:
    """The extcap program: Wireshark's options in, its lines (or a pcap stream) out."""
    out = out or sys.stdout
    parser = argparse.ArgumentParser(prog="devsim extcap", description="Wireshark extcap for devsim's ports.")
    parser.add_argument("--extcap-interfaces", action="store_true")
    parser.add_argument("--extcap-interface")
    parser.add_argument("--extcap-dlts", action="store_true")
    parser.add_argument("--extcap-config", action="store_true")
    parser.add_argument("--extcap-version")
    parser.add_argument("--capture", action="store_true")
    parser.add_argument("--fifo")
    parser.add_argument("--extcap-capture-filter")
    args, _unknown = parser.parse_known_args(argv)
    if args.extcap_interfaces:
        try:
            found = interfaces(running())
        except OSError as exc:  # an unsafe runtime directory: no interfaces, and why
            print(f"devsim extcap: {exc}", file=sys.stderr)
            found = []
        out.write("\n".join(interface_lines(found)) + "\n")
        return 0
    if not args.extcap_interface:
        parser.error("give --extcap-interfaces, or --extcap-interface with --extcap-dlts, --extcap-config or --capture")
    if args.extcap_config:
        return 0  # nothing to configure
    try:
        interface = _find(args.extcap_interface)
    except (ValueError, LookupError) as exc:
        print(f"devsim extcap: {exc}", file=sys.stderr)
        return 1
    if args.extcap_dlts:
        out.write(dlt_line(interface.link) + "\n")
        return 0
    if args.capture:
        if not args.fifo:
            parser.error("--capture needs --fifo")
        signal.signal(signal.SIGTERM, _stop)  # Wireshark ends a capture so: the fifo is closed on the way out
        return capture(interface, args.fifo)
    parser.error("give --extcap-dlts, --extcap-config or --capture with --extcap-interface")
    return 2
