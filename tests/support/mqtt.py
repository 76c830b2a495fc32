"""mosquitto's own command-line clients as the independent MQTT client of the MQTT tests.

:class:`Sub` runs ``mosquitto_sub`` on topic filters and collects what arrives (topic, payload
bytes, retain flag) through a reader thread; :meth:`Sub.wait` waits, bounded, for the first
message that matches.  :func:`pub` sends one message with ``mosquitto_pub``.
"""

from __future__ import annotations

import json
import queue
import subprocess
import threading
import time
import uuid
from collections.abc import Callable
from typing import Any

from tests.support.broker import _program
from tests.support.process import stop as stop_process

__all__ = ["Message", "Sub", "pub"]


class Message:
    def __init__(self, topic: str, payload: bytes, retain: bool) -> None:
        self.topic, self.payload, self.retain = topic, payload, retain

    @property
    def text(self) -> str:
        return self.payload.decode()

    def json(self) -> Any:
        return json.loads(self.payload)

    def __repr__(self) -> str:
        return f"Message({self.topic!r}, {self.payload[:80]!r}, retain={self.retain})"


class Sub:
    """``mosquitto_sub -t FILTER ...`` on 127.0.0.1:``port``; use as a context manager."""

    def __init__(self, port: int, *filters: str) -> None:
        self.port = port
        self.probe = f"devsim-test/ready/{uuid.uuid4().hex}"
        filters = (*filters, self.probe)
        args = [_program("mosquitto_sub"), "-h", "127.0.0.1", "-p", str(port), "-q", "1", "-F", "%r %t %x"]
        for pattern in filters:
            args += ["-t", pattern]
        self.proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        self.queue: queue.Queue[Message | None] = queue.Queue()
        self.seen: list[Message] = []
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            retain, topic, payload = line.rstrip("\n").split(" ", 2)
            self.queue.put(Message(topic, bytes.fromhex(payload), retain == "1"))
        self.queue.put(None)

    def wait(self, topic: str, where: Callable[[Message], bool] = lambda m: True, timeout: float = 10.0) -> Message:
        """The first message (seen before or arriving within ``timeout`` s) on ``topic`` for
        which ``where`` holds; it and the earlier ones on that topic are consumed (messages on
        other topics are kept for later waits)."""
        for index, message in enumerate(self.seen):
            if message.topic == topic and where(message):
                self.seen = [m for m in self.seen[:index] if m.topic != topic] + self.seen[index + 1:]
                return message
        deadline = time.monotonic() + timeout
        while True:
            try:
                message = self.queue.get(timeout=max(0.01, deadline - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"no message on {topic!r} within {timeout} s; "
                                     f"unmatched: {[m for m in self.seen if m.topic == topic][-5:]}") from None
            if message is None:
                raise AssertionError(f"mosquitto_sub ended: {self.close()}")
            if message.topic == topic and where(message):
                self.seen = [m for m in self.seen if m.topic != topic]  # (the earlier ones on it: consumed too)
                return message
            self.seen.append(message)

    def sync(self, timeout: float = 10.0) -> Sub:
        """Return once the subscriptions are in place (a retained probe has come back)."""
        pub(self.port, self.probe, "ready", retain=True)
        self.wait(self.probe, timeout=timeout)
        return self

    def close(self) -> str:
        stop_process(self.proc, timeout=5)
        return self.proc.stderr.read() if self.proc.stderr is not None else ""

    def __enter__(self) -> Sub:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def pub(port: int, topic: str, payload: bytes | str, *, retain: bool = False, qos: int = 1) -> None:
    """One message with ``mosquitto_pub`` (payload from stdin: any bytes), QoS 1 unless told (at
    QoS 0, mosquitto_pub's default, it sends and disconnects without waiting for the broker)."""
    data = payload.encode() if isinstance(payload, str) else payload
    args = [_program("mosquitto_pub"), "-h", "127.0.0.1", "-p", str(port), "-q", str(qos), "-t", topic,
            "-s" if data else "-n"]
    if retain:
        args.append("-r")
    result = subprocess.run(args, input=data, capture_output=True, timeout=15)
    assert result.returncode == 0, result.stderr.decode(errors="replace")
