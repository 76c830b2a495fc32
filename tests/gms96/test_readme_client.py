"""The GMS96 client example of its guide (docs/kinds/gms96.md) runs against a simulated card."""

from __future__ import annotations

import re
from pathlib import Path

from devsim.runtime import Runtime
from devsim.transports.pty import PtyTransport

README = Path(__file__).resolve().parents[2] / "docs" / "kinds" / "gms96.md"


def test_readme_client_example() -> None:
    text = README.read_text(encoding="utf-8")
    match = re.search(r"```python\n(import serial\nfrom devsim\.devices\.gms96\.client.*?)```", text, re.S)
    assert match is not None
    runtime = Runtime(virtual=True).start()
    try:
        card = runtime.add_device("gms96", "card", {"boot_time": 0})
        transport = PtyTransport()
        runtime.serve_sync(card, transport)
        namespace: dict[str, object] = {}
        exec(match.group(1).replace("/dev/pts/5", transport.address), namespace)  # noqa: S102
        assert namespace["k"] & 0x80  # BUSY: the move is running
        assert namespace["message"] is None
        assert namespace["identifier"] == ord("@")
        runtime.advance(10)
        assert runtime.read("card", "position_counter") == 10000
    finally:
        runtime.stop()
