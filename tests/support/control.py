"""A control socket served for a test's runtime, and a client on it: the control API as
``devsim ctl`` reaches it (the real server, a real Unix socket)."""

from __future__ import annotations

import tempfile
from collections.abc import Iterator
from contextlib import contextmanager

from devsim.runtime.client import ControlClient
from devsim.runtime.control import ControlServer
from devsim.runtime.process import Runtime


@contextmanager
def control_client(runtime: Runtime) -> Iterator[ControlClient]:
    """A :class:`ControlClient` on a control socket served for ``runtime`` until the block ends."""
    with tempfile.TemporaryDirectory(prefix="dsc") as path:  # (Unix socket paths are short)
        server = ControlServer(runtime, f"unix:{path}/ctl.sock")
        bound = server.start_sync()
        try:
            with ControlClient(str(bound)) as client:
                yield client
        finally:
            server.close_sync()
