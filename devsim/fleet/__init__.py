"""The fleet: many devsim processes on many machines forming one plant through an MQTT broker
(issue 14).

* :mod:`devsim.fleet.topics` – the fleet URL (``mqtt://[USER:PASS@]HOST[:PORT][/NAME]``), the
  topic names and the process id; nothing here talks to the network.
* :mod:`devsim.fleet.member` – the server side: a ``devsim run`` / ``devsim up`` process with
  ``--fleet URL`` announces its devices (retained, with a last will that marks them offline) and
  answers control-API requests that arrive over the broker (tasks in the runtime's loop).
* :mod:`devsim.fleet.client` – the client side: :class:`~devsim.fleet.client.FleetClient` lists
  every device of every process and reaches any of them by name, with the methods of
  :class:`devsim.runtime.client.ControlClient` (``devsim ctl --fleet URL ...``).
* :mod:`devsim.fleet.streams` – ``watch`` over the broker: a member's streams, addressed and kept
  alive by topics.

Needs nothing beyond the core: members and clients speak MQTT 5 themselves
(:mod:`devsim.facades.mqtt_link`).
"""
