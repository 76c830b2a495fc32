"""node-opcua's client (tests/facades/opcua_node/client.js) run by Node.js for the OPC UA tests:
an OPC UA client nobody on devsim wrote.  ``.ci/run`` installs Node.js and npm; the client's
packages are installed with ``npm ci`` on first use (a fresh checkout)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

from tests.support.programs import needs_program

NODE_CLIENT = Path(__file__).parent / "opcua_node"


def node_client(url: str, plan: list[dict[str, Any]], timeout: float = 120) -> list[dict[str, Any]]:
    """Run ``plan`` (the steps client.js documents) against the server at ``url``; a result per step."""
    installed = (NODE_CLIENT / "node_modules" / "node-opcua-client").is_dir()
    node = needs_program("node", *(() if installed else ("npm",)))  # skipped here, a failure under CI
    if not installed:  # a fresh checkout: install it
        npm = needs_program("npm")
        subprocess.run([npm, "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=NODE_CLIENT, check=True,
                       stdin=subprocess.DEVNULL, capture_output=True, timeout=600)
    done = subprocess.run([node, str(NODE_CLIENT / "client.js"), url, json.dumps(plan)], capture_output=True,
                          text=True, timeout=timeout)
    assert done.returncode == 0, done.stderr[-2000:]
    line = next(line for line in done.stdout.splitlines() if line.startswith("RESULT "))
    return list(json.loads(line[len("RESULT "):])["results"])
