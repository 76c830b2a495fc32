"""A real mosquitto broker for the MQTT and fleet tests, started by the fixture itself on a free
loopback port (``.ci/run`` installs mosquitto and its clients with apt-get).

``Broker.start()`` writes a config into a temporary directory, starts ``mosquitto -c``, and
returns once the port accepts a connection (the broker is then ready).  Where mosquitto or its
clients are missing, making a ``Broker`` skips the test (fails it under CI=true:
:mod:`tests.support.programs`).  ``url`` is
``mqtt://127.0.0.1:PORT``; ``extra`` config lines (a bridge to a second broker, say) are appended.
"""

from __future__ import annotations

import shutil
import socket
import subprocess
import tempfile
import time
from pathlib import Path

from tests.support.process import free_port
from tests.support.process import stop as stop_process
from tests.support.programs import needs_program

__all__ = ["Broker"]


def _program(name: str) -> str:
    return needs_program(name)


class Broker:
    """One mosquitto process on 127.0.0.1."""

    def __init__(self, extra: str = "") -> None:
        needs_program("mosquitto", "mosquitto_sub", "mosquitto_pub")
        self.port = free_port()
        self.extra = extra
        self.directory = Path(tempfile.mkdtemp(prefix="devsim-mosquitto-"))
        self.process: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"mqtt://127.0.0.1:{self.port}"

    def start(self, timeout: float = 10.0) -> Broker:
        config = self.directory / "mosquitto.conf"
        config.write_text(
            f"listener {self.port} 127.0.0.1\nallow_anonymous true\npersistence false\n"
            f"log_dest file {self.directory / 'mosquitto.log'}\n{self.extra}\n"
        )
        self.process = subprocess.Popen([_program("mosquitto"), "-c", str(config)],
                                        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                        stderr=subprocess.PIPE)
        deadline = time.monotonic() + timeout
        while True:
            if self.process.poll() is not None:
                error = self.process.stderr.read().decode(errors="replace") if self.process.stderr else ""
                raise RuntimeError(f"mosquitto exited at start: {error.strip()}")
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.2):
                    return self
            except OSError:
                if time.monotonic() > deadline:
                    self.stop()
                    raise RuntimeError(f"mosquitto did not listen on port {self.port}") from None
                time.sleep(0.02)  # polling for the broker's port to open (a readiness check)

    def log(self) -> str:
        path = self.directory / "mosquitto.log"
        return path.read_text(errors="replace") if path.exists() else ""

    def stop(self) -> None:
        if self.process is not None:
            stop_process(self.process, timeout=5)
        if self.process is not None and self.process.stderr is not None:
            self.process.stderr.close()
        shutil.rmtree(self.directory, ignore_errors=True)
