"""Fleet URLs and topic names at their limits (devsim.fleet.topics): a fleet name of 64 characters
and one more, slashes around it, an IPv6 broker written back in brackets, each refusal's message
(``devsim ctl --fleet`` prints it), the process id of a host without a name, the CLIENT of a
topic."""

from __future__ import annotations

import re

import pytest

from devsim.fleet import topics as fleet_topics
from devsim.fleet.topics import FleetUrlError, Topics, fleet_problem, parse_fleet_url, process_id


@pytest.mark.parametrize("size, ok", [(1, True), (63, True), (64, True), (65, False)])
def test_a_fleet_name_of_at_most_64_characters(size: int, ok: bool) -> None:
    url = f"mqtt://h/{'n' * size}"
    if ok:
        assert parse_fleet_url(url).fleet == "n" * size
    else:
        with pytest.raises(FleetUrlError, match="a fleet name is one topic level"):
            parse_fleet_url(url)


@pytest.mark.parametrize("url, fleet", [("mqtt://h/", None), ("mqtt://h", None), ("mqtt://h//Xline7X//", "Xline7X"),
                                        ("mqtt://h/line7/", "line7"), ("  mqtt://h/a  ", "a")])
def test_the_slashes_around_a_fleet_name(url: str, fleet: str | None) -> None:
    assert parse_fleet_url(url).fleet == fleet


@pytest.mark.parametrize("url, message", [
    ("tcp://h", "'tcp://h': expected mqtt://HOST[:PORT][/NAME]"),
    ("mqtt://h:0x10", "'mqtt://h:0x10': the port must be a number 1 … 65535"),
    ("mqtt://:1883", "'mqtt://:1883': no broker host (expected mqtt://HOST[:PORT][/NAME])"),
    ("mqtt://h/a?b=1", "'mqtt://h/a?b=1': expected mqtt://HOST[:PORT][/NAME], no ?query or #"),
    ("mqtt://h/a+b", "'mqtt://h/a+b': a fleet name is one topic level without + # / or spaces"),
])
def test_each_refusal_says_why(url: str, message: str) -> None:
    with pytest.raises(FleetUrlError) as refused:
        parse_fleet_url(url)
    assert str(refused.value) == message
    assert fleet_problem(url) == message
    assert fleet_problem("mqtt://h/a") is None


def test_a_url_written_back() -> None:
    assert str(parse_fleet_url("mqtt://[::1]:1884/f")) == "mqtt://[::1]:1884/f"
    assert str(parse_fleet_url("mqtt://broker")) == "mqtt://broker:1883"


def test_a_process_id_is_one_topic_level(monkeypatch: pytest.MonkeyPatch) -> None:
    assert re.fullmatch(r"a_b_c_d-42-[0-9a-f]{4}", process_id("a/b+c#d", 42))
    assert re.fullmatch(rf"lab-{fleet_topics.os.getpid()}-[0-9a-f]{{4}}", process_id("lab"))
    monkeypatch.setattr(fleet_topics.socket, "gethostname", lambda: "")
    assert re.fullmatch(r"localhost-0-[0-9a-f]{4}", process_id(None, 0))  # pid 0 is a pid
    monkeypatch.setattr(fleet_topics.socket, "gethostname", lambda: "my host")
    assert re.fullmatch(r"my_host-7-[0-9a-f]{4}", process_id(pid=7))


@pytest.mark.parametrize("topic, client", [
    ("devsim-fleet/client/c1/reply", "c1"), ("devsim-fleet/client/c1/watch/3", "c1"),
    ("devsim-fleet/client/c1", None), ("devsim-fleet/client//reply", None), ("devsim-fleet/process/p/request", None),
    ("other/client/c1/reply", None), ("devsim-fleet/f/client/c1/reply", None),
])
def test_the_client_of_a_topic(topic: str, client: str | None) -> None:
    assert Topics("devsim-fleet").client_of(topic) == client
