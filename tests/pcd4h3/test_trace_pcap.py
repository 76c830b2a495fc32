"""The guide's tshark check, run as it reads (docs/kinds/pcd4h3.md, last section): ``devsim run
pcd4h3 --trace x.pcap`` in its own process, a host on the Ether-S-Bus UDP port, then the guide's
``tshark -r … -d udp.port==…,sbus`` on the file the guide names."""

from __future__ import annotations

import re
import socket
import subprocess
from pathlib import Path

from tests.pcd4h3.helpers import hexbytes
from tests.support.process import ROOT, DevsimProcess, free_port
from tests.support.programs import needs_program

GUIDE = ROOT / "docs" / "kinds" / "pcd4h3.md"
STATUS = "00 00 00 0D 01 00 00 01 00 01 1B 08 DA"  # read PCD status, station 1 (spec EV14)


def documented() -> tuple[list[str], list[str]]:
    """The run and the tshark command as the guide writes them (one line each)."""
    text = " ".join(GUIDE.read_text(encoding="utf-8").split())
    run = re.search(r"`devsim run pcd4h3 (--trace [^`]+)`", text) or re.search(r"`(--trace [^`]+)`", text)
    decode = re.search(r"`tshark (-r [^`]+)`", text)
    assert run is not None and decode is not None, "the guide no longer shows the tshark check"
    return run[1].split(), decode[1].split()


def test_the_guides_trace_command_gives_a_file_tshark_decodes(tmp_path: Path) -> None:
    tshark = needs_program("tshark")
    run, decode = documented()
    port = free_port()  # the guide's 5050, moved out of the way of other simulators
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", port))  # free for UDP as well
    run[run.index("--trace") + 1] = str(tmp_path / run[run.index("--trace") + 1])
    sim = DevsimProcess("run", "pcd4h3", *run,
                        "--port", f"ether_udp=udp:{port}", "--port", f"ether_tcp=tcp:{port}")
    try:
        sim.next_match(sim.out, lambda line: "ready" in line, 30, "the ready line")
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as host:
            host.settimeout(5)
            host.sendto(hexbytes(STATUS), ("127.0.0.1", port))
            assert host.recv(512) == hexbytes("00 00 00 0C 01 00 00 01 01 52 69 7D")  # 'R'
    finally:
        assert sim.interrupt() == 0
    arguments = [a.replace("5050", str(port)) for a in decode]
    arguments[arguments.index("-r") + 1] = str(tmp_path / arguments[arguments.index("-r") + 1])
    result = subprocess.run([tshark, *arguments, "-T", "fields", "-e", "sbus.cmd", "-e", "sbus.att"],
                            capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:2] == ["0x1b\t0x00", "\t0x01"], result.stdout  # the request, the response
