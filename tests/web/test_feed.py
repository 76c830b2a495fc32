"""A browser's queue (:class:`devsim.web.feed.Subscriber`): a slow browser loses chart points,
counted, never an event; the latest value of each point is always kept."""

from __future__ import annotations

from devsim.web.feed import MAX_EVENTS, Feed, Subscriber


def change(name: str, value: float, t: float) -> dict[str, object]:
    return {"t": t, "device": "sers", "type": "change", "name": name, "value": value}


async def test_a_slow_browser_drops_chart_points_never_events() -> None:
    subscriber = Subscriber(max_points=100)
    feed = Feed("sers")
    feed.subscribers.add(subscriber)
    for i in range(1000):
        feed.apply(change("axis.position", float(i), i / 100), chart=True)
        if i % 10 == 0:
            feed.apply({"t": i / 100, "device": "sers", "type": "event", "name": f"e{i}"})
    feed.apply(change("P11", 5, 10.0))
    feed.apply(change("axis.velocity", 1.0, 10.0))  # a summary's sample: a value, no chart point
    batch = subscriber.take()
    assert [p["value"] for p in batch["points"]] == [float(i) for i in range(900, 1000)]  # the newest kept
    assert batch["dropped"] == 900
    assert [e["name"] for e in batch["events"]] == [f"e{i}" for i in range(0, 1000, 10)]  # every one
    assert {v["name"]: v["value"] for v in batch["values"]} == {"axis.position": 999.0, "P11": 5,
                                                                   "axis.velocity": 1.0}
    assert subscriber.take()["points"] == [] and not subscriber.ready.is_set()
    assert feed.values["axis.position"] == 999.0 and len(feed.recent) == 100


async def test_a_browser_that_lets_events_pile_up_is_told_to_reload() -> None:
    subscriber = Subscriber()
    for i in range(MAX_EVENTS + 1):
        assert not subscriber.overflow
        subscriber.put({"t": i, "device": "sers", "type": "fault", "name": "power", "active": bool(i % 2)})
    assert subscriber.overflow


async def test_the_feed_remembers_faults_and_hosts() -> None:
    feed = Feed("sers")
    feed.apply({"t": 1.0, "device": "sers", "type": "fault", "name": "power", "active": True})
    feed.apply({"t": 1.1, "device": "sers", "type": "connect", "port": "main", "text": "host connected"})
    assert feed.snapshot()["faults"] == ["power"] and feed.hosts == {"main": True} and feed.t == 1.1
    feed.apply({"t": 1.2, "device": "sers", "type": "fault", "name": "power", "active": False})
    assert feed.snapshot()["faults"] == []


async def test_a_browser_being_disconnected_gathers_nothing_more() -> None:
    subscriber = Subscriber()
    subscriber.overflow = True
    subscriber.put({"t": 1.0, "device": "sers", "type": "event", "name": "move_start"})
    subscriber.put(change("axis.position", 1.0, 1.0), chart=True)
    assert subscriber.take() == {"events": [], "values": [], "points": [], "dropped": 0}
