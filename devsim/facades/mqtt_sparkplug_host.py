"""The Primary Host Application an edge node waits for (Sparkplug B 3.0, ``--mqtt-primary-host
ID``): its ``spBv1.0/STATE/<ID>`` messages read and judged.  Pure: payload bytes in, a verdict
out; the node's session (births, disconnect) is in :mod:`devsim.facades.mqtt`.

A STATE payload is JSON (§6, STATE, tck-id-payloads-state-birth-payload and
tck-id-payloads-state-will-message-payload: "two key/value pairs where one key MUST be 'online'
and it's value is a boolean … The other key MUST be 'timestamp' and the value MUST be a numeric
value representing the current UTC time in milliseconds since Epoch"); anything else is refused.
The topic's last token is the host id (tck-id-message-flow-edge-node-birth-publish-phid-wait-id).

The timestamps decide which messages count (§5):

* an online STATE counts when no STATE was taken before or its timestamp is "greater than or
  equal to the previous STATE message timestamp value"
  (tck-id-message-flow-edge-node-birth-publish-phid-wait-timestamp);
* an offline STATE counts when no online STATE was taken before ("it MUST honor the 'online'
  boolean status flag") or its timestamp is "greater than or equal to the timestamp value included
  in the prior 'online' STATE message" (tck-id-message-flow-edge-node-birth-publish-phid-offline,
  tck-id-operational-behavior-edge-node-termination-host-offline); an older one is the death of a
  host session that is already over, and "MUST NOT" end the node's session
  (tck-id-operational-behavior-edge-node-termination-host-offline-timestamp).

The timestamps taken outlive the node's MQTT sessions (they are the node's memory of the host);
whether the host is online does not: each new session waits for a STATE of its own
(tck-id-message-flow-edge-node-birth-publish-phid-wait: "MUST verify the Primary Host
Application is online via the STATE topic before publishing NBIRTH and DBIRTH").
"""

from __future__ import annotations

import json
import math

__all__ = ["PrimaryHost", "parse_state", "state_topic"]

NAMESPACE = "spBv1.0"  # (the Sparkplug B topic namespace: devsim.facades.mqtt_sparkplug takes it from here)


def state_topic(host_id: str) -> str:
    """``spBv1.0/STATE/<host_id>`` (§4, tck-id-host-topic-phid-birth-topic)."""
    return f"{NAMESPACE}/STATE/{host_id}"


def parse_state(payload: bytes) -> tuple[bool, float]:
    """A STATE payload's (online, timestamp); ValueError when it is not the JSON object §6 gives
    (an ``online`` boolean, a numeric ``timestamp`` of UTC milliseconds)."""
    try:
        body = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise ValueError("a STATE payload is JSON: {\"online\": true|false, \"timestamp\": MILLISECONDS}") from None
    if not isinstance(body, dict):
        raise ValueError("a STATE payload is a JSON object with 'online' and 'timestamp'")
    online, timestamp = body.get("online"), body.get("timestamp")
    if not isinstance(online, bool):
        raise ValueError(f"a STATE payload's 'online' is true or false, not {online!r}")
    if isinstance(timestamp, bool) or not isinstance(timestamp, int | float) or not math.isfinite(timestamp):
        raise ValueError(f"a STATE payload's 'timestamp' is a number of UTC milliseconds, not {timestamp!r}")
    return online, timestamp


class PrimaryHost:
    """What an edge node knows of its Primary Host Application (see the module docstring)."""

    def __init__(self, host_id: str) -> None:
        self.host_id = host_id
        self.topic = state_topic(host_id)
        self.online = False  # in this MQTT session: an online STATE was taken and no later offline one
        self.last: float | None = None  # the timestamp of the last STATE taken
        self.last_online: float | None = None  # ... of the last online STATE taken

    def new_session(self) -> None:
        """A new MQTT session: the host counts as offline until a STATE says otherwise."""
        self.online = False

    def take(self, payload: bytes) -> bool | None:
        """Judge a STATE message of this host: True (online) or False (offline) when it counts,
        None when its timestamp is older than the rules allow (ignored); ValueError when the
        payload is not a STATE payload (nothing changes)."""
        online, timestamp = parse_state(payload)
        if online:
            if self.last is not None and timestamp < self.last:
                return None
            self.last_online = timestamp
        elif self.last_online is not None and timestamp < self.last_online:
            return None
        self.last = timestamp if self.last is None else max(self.last, timestamp)
        self.online = online
        return online
