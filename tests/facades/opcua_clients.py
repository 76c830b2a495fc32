"""node-opcua's client (tests/facades/opcua_node/client.js) run by Node.js for the OPC UA tests:
an OPC UA client nobody on devsim wrote.  ``.ci/run`` installs Node.js and npm; the client's
packages are installed with ``npm ci`` on first use (a fresh checkout).

Loading node-opcua costs a Node.js process seconds of CPU, so a test process keeps one client
(``client.js --serve``) and hands it a plan at a time; each plan still connects, opens its own
session and disconnects, as a client started for it would."""

from __future__ import annotations

import atexit
import json
import queue
import subprocess
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tests.support.programs import needs_program

NODE_CLIENT = Path(__file__).parent / "opcua_node"


class _Served:
    """The one ``client.js --serve`` process of this test process, and its output lines."""

    def __init__(self, node: str) -> None:
        self.proc = subprocess.Popen([node, str(NODE_CLIENT / "client.js"), "--serve"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        self.lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line)
        self.lines.put(None)

    def ask(self, url: str, plan: list[dict[str, Any]], timeout: float,
            paused: Callable[[], None] | None) -> dict[str, Any]:
        """The plan's result; an AssertionError if it failed, the client ended or took longer than
        ``timeout``.  A step that pauses goes on when ``paused()`` has returned."""
        assert self.proc.stdin is not None
        self._say(json.dumps({"endpoint": url, "plan": plan}))
        while True:  # (node-opcua writes its own warnings to stdout too)
            try:
                line = self.lines.get(timeout=timeout)
            except queue.Empty:
                raise AssertionError(f"node-opcua's client gave no result within {timeout} s") from None
            assert line is not None, f"node-opcua's client ended (status {self.proc.wait()})"
            if line.strip() == "PAUSE":
                assert paused is not None, "a step paused with nothing to do meanwhile"
                paused()
                self._say("")
            elif line.startswith("RESULT "):
                return dict(json.loads(line[len("RESULT "):]))
            elif line.startswith("FAILED "):
                raise AssertionError(json.loads(line[len("FAILED "):]))

    def _say(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()  # (the client ends at the end of its input)
        try:
            self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


_served: _Served | None = None
_lock = threading.Lock()


def node_client(url: str, plan: list[dict[str, Any]], timeout: float = 120,
                paused: Callable[[], None] | None = None) -> list[dict[str, Any]]:
    """Run ``plan`` (the steps client.js documents) against the server at ``url``; a result per step.
    A step that pauses (``queue`` once, ``events`` twice) goes on each time ``paused()`` has returned."""
    global _served
    installed = (NODE_CLIENT / "node_modules" / "node-opcua-client").is_dir()
    node = needs_program("node", *(() if installed else ("npm",)))  # skipped here, a failure under CI
    with _lock:
        if not installed:  # a fresh checkout: install it
            npm = needs_program("npm")
            subprocess.run([npm, "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=NODE_CLIENT, check=True,
                           stdin=subprocess.DEVNULL, capture_output=True, timeout=600)
        if _served is None or _served.proc.poll() is not None:
            _served = _Served(node)
            atexit.register(_served.close)
        try:
            return list(_served.ask(url, plan, timeout, paused)["results"])
        except BaseException:  # (a failed plan, or a test's paused() that raised: not left waiting)
            _served.proc.kill()
            _served.close()  # (the next plan gets a new client)
            _served = None
            raise
