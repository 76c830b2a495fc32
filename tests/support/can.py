"""canopen networks for the tests.

python-can's notifier thread, which a ``canopen.Network`` starts on ``connect``, waits up to
``NOTIFIER_CYCLE`` seconds (canopen's default 1 s) for a frame before it looks whether it was
stopped, and ``disconnect`` waits for it: two networks cost a test up to 2 s of idle wall time.
The tests' networks look every 10 ms instead.
"""

from __future__ import annotations

import canopen

#: s: how long a test network's notifier waits for a frame before it looks whether it was stopped.
NOTIFIER_CYCLE = 0.01


def network() -> canopen.Network:
    """A ``canopen.Network`` (not yet connected) whose ``disconnect`` returns within about 10 ms."""
    net = canopen.Network()
    net.NOTIFIER_CYCLE = NOTIFIER_CYCLE
    return net
