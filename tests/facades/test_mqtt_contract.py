"""Contract of the MQTT facade over every registered kind (issue 14): each kind's birth lists all
its declared points with type, unit and access, a set sent with mosquitto_pub round-trips to
its state topic, and every readable point has a retained state."""

from __future__ import annotations

from devsim.core.device import Device
from devsim.core.registry import kinds
from devsim.facades.mqtt import start_mqtt
from devsim.runtime import Runtime
from tests.facades.test_mqtt import mosquitto  # noqa: F401 - the module's broker fixture
from tests.support.broker import Broker
from tests.support.mqtt import Sub, pub

KINDS = sorted(kinds())


def flip_point(device: Device) -> str:
    """A readable and settable boolean input of the device (every kind has inputs)."""
    return next(p.name for p in device.points
                if p.settable and p.readable and p.type == "bool" and p.name.startswith("input."))


def test_every_kind_has_a_birth_and_a_set_round_trips(mosquitto: Broker) -> None:  # noqa: F811
    runtime = Runtime(virtual=True).start()
    try:
        devices = [runtime.add_device(kind, f"d-{kind}") for kind in KINDS]
        runtime.run(start_mqtt(runtime, devices, mosquitto.url, plant="contract", rate=0.5), timeout=30)
        with Sub(mosquitto.port, "devsim/contract/#") as sub:
            for device in devices:
                base = f"devsim/contract/{device.name}"
                birth = sub.wait(f"{base}/birth").json()
                assert birth["kind"] == device.kind
                listed = {p["name"]: (p["type"], p["unit"], p["access"]) for p in birth["points"]}
                assert listed == {p.name: (p.type, p.unit, p.access) for p in device.points}
                assert all(not set(name) & set("/+#") for name in listed), "a point name is not one topic level"

                name = flip_point(device)
                before = runtime.read(device.name, name)
                assert sub.wait(f"{base}/state/{name}").json() is before
                pub(mosquitto.port, f"{base}/set/{name}", "true" if not before else "false")
                assert sub.wait(f"{base}/state/{name}", lambda m, want=not before: m.json() is want)
                assert runtime.read(device.name, name) is (not before)
                with Sub(mosquitto.port, f"{base}/state/#") as late:  # every readable point, retained
                    for point in device.points:
                        if point.readable:
                            assert late.wait(f"{base}/state/{point.name}").retain
    finally:
        runtime.stop()

