"""What `devsim ctl` prints, through the real CLI (`python -m devsim` subprocesses against a
running `devsim run sers`): plain words and tables for people, `--json` for scripts (today's
JSON, characters unescaped), `names` grouped by family in the terminal's width."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator

import pytest
import serial

from devsim.cli import exits
from tests.support.process import ROOT, DevsimProcess, devsim_env, wait_until


@pytest.fixture(scope="module")
def sim() -> Iterator[tuple[str, str]]:
    """A running `devsim run sers`: its control address and its port's URL."""
    with tempfile.TemporaryDirectory(prefix="dso") as path:
        address = f"unix:{path}/c.sock"
        proc = DevsimProcess("run", "sers", "--tcp", "0", "--virtual", "--control", address)
        try:
            url = proc.next_match(proc.out, lambda line: line.startswith("sers: tcp "), 30, "the port").split()[2]
            proc.next_match(proc.out, lambda line: line.startswith("control: "), 30, "the control line")
            yield address, url
        finally:
            assert proc.interrupt() == 0


@pytest.fixture(scope="module")
def addr(sim: tuple[str, str]) -> str:
    return sim[0]


def devsim(*args: str, columns: int = 100) -> subprocess.CompletedProcess[str]:
    env = dict(devsim_env(), COLUMNS=str(columns))
    return subprocess.run([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=60, stdin=subprocess.DEVNULL)


def ok(*args: str, columns: int = 100) -> str:
    done = devsim(*args, columns=columns)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    return done.stdout


def test_plain_words_for_people(addr: str) -> None:
    assert ok("ctl", "--control", addr, "set", "sers", "quantity.supply_voltage", "48") == "ok\n"  # was "null"
    assert ok("ctl", "--control", addr, "read", "sers", "quantity.supply_voltage") == \
        "quantity.supply_voltage = 48 V\n"
    assert ok("ctl", "--control", addr, "read", "sers", "axis.velocity") == "axis.velocity = 0 inc/s\n"
    assert ok("ctl", "--control", addr, "read", "sers", "input.limit_right") == "input.limit_right = false\n"
    assert ok("ctl", "--control", addr, "fault", "sers", "blocked_axis", "off") == "ok\n"
    assert ok("ctl", "--control", addr, "line-fault", "sers", "noise", "off") == "ok\n"
    now = float(ok("ctl", "--control", addr, "--json", "now"))
    assert ok("ctl", "--control", addr, "advance", "0.25") == f"ok, time {now + 0.25:g} s\n"
    assert ok("ctl", "--control", addr, "now") == f"{now + 0.25:g} s\n"


def test_several_names_are_a_small_table(addr: str) -> None:
    lines = ok("ctl", "--control", addr, "read", "sers", "axis.position", "axis.velocity", "motion").splitlines()
    assert [line.split() for line in lines] == [
        ["name", "value", "unit"], ["axis.position", "0", "inc"], ["axis.velocity", "0", "inc/s"], ["motion", "false"],
    ]
    assert len({line.index(line.split()[1]) for line in lines}) == 1  # the values in one column


def test_state_and_devices_are_tables(addr: str) -> None:
    rows = {line.split()[0]: line.split()[1:] for line in ok("ctl", "--control", addr, "state", "sers").splitlines()}
    assert rows["axis.position"] == ["0", "inc"]  # nested state as dotted names, with units
    assert rows["quantity.supply_voltage"][1] == "V"
    assert rows["line.device.text"] == ["9600", "8N1"]
    lines = ok("ctl", "--control", addr, "devices").splitlines()
    assert lines[0].split() == ["name", "kind", "port", "faults"]
    assert lines[1].split()[:3] == ["sers", "sers", lines[1].split()[2]] and "blocked_axis," in lines[1]


def test_info_is_a_table_of_the_process(addr: str) -> None:
    """`ctl info` printed a KeyError's traceback: the op had no formatter."""
    info = json.loads(ok("ctl", "--control", addr, "--json", "info"))
    rows = {line.split()[0]: line.split()[1:] for line in ok("ctl", "--control", addr, "info").splitlines()}
    assert rows["pid"] == [str(info["pid"])]
    assert rows["clock"] == ["virtual"]
    assert rows["devices"] == ["sers"]


def test_every_answering_op_has_a_formatter() -> None:
    from devsim.cli.present import FORMATTERS
    from devsim.runtime.ops import CONTROL

    streams = {"watch", "capture"}  # ctl prints these line by line as they arrive
    assert {row.token for row in CONTROL if row.token not in FORMATTERS} == streams


def test_json_for_scripts_keeps_its_format(addr: str) -> None:
    """--json (on ctl or on the command) prints what ctl printed before: the bare result."""
    assert ok("ctl", "--control", addr, "--json", "set", "sers", "input.I3", "on") == "null\n"
    assert ok("ctl", "--control", addr, "read", "sers", "input.I3", "--json") == "true\n"
    state = ok("ctl", "--control", addr, "--json", "state", "sers")
    assert state.startswith('{\n  "kind": "sers",\n  "axis": {\n    "position": 0.0,')
    assert json.loads(state)["input"]["I3"] is True
    assert json.loads(ok("ctl", "--control", addr, "--json", "read", "sers", "input.I3", "axis.position")) == \
        {"input.I3": True, "axis.position": 0.0}
    assert json.loads(ok("ctl", "--control", addr, "--json", "devices"))[0]["name"] == "sers"


def test_unicode_is_printed_as_characters_in_both_modes(addr: str) -> None:
    raw = ok("ctl", "--control", addr, "--json", "names", "sers")
    assert "§4.8.2.3" in raw and "\\u00a7" not in raw and "≠" in raw
    assert json.loads(raw)[0] == {"name": "axis.position", "type": "float", "unit": "inc", "access": "r",
                                  "doc": json.loads(raw)[0]["doc"], "section": "§4.8.2.3"}
    text = ok("ctl", "--control", addr, "names", "sers", columns=200)
    assert "a drive error is active (P11 ≠ 0)" in text and "\\u" not in text


def test_names_are_grouped_by_family_in_the_terminal_width(addr: str) -> None:
    data = json.loads(ok("ctl", "--control", addr, "--json", "names", "sers"))
    for columns in (60, 120):
        text = ok("ctl", "--control", addr, "names", "sers", columns=columns)
        lines = text.splitlines()
        assert max(len(line) for line in lines) <= columns
        assert any(line.endswith("…") for line in lines)  # long descriptions are cut
        lines = lines[: len(lines) - len(_by_pattern(text))]  # (the aliases after the count)
        assert lines[-1].startswith(f"{len(data)} names in ")
        heads = [line for line in lines[:-1] if not line.startswith("  ")]
        assert "axis (5)" in heads and "input (21)" in heads and "param (188)" in heads
        members = [line.split()[0] for line in lines[:-1] if line.startswith("  ")]
        assert sorted(members) == sorted(row["name"] for row in data)  # each name once
        group = ""
        for line in lines[:-1]:
            if not line.startswith("  "):
                group = line.split()[0]
            elif group != "(single":  # a family's names start with it
                assert line.split()[0].split(".")[0] == group, line
    axis = ok("ctl", "--control", addr, "names", "sers", columns=200).split("axis (5)\n")[1].splitlines()[0]
    assert axis.split()[:4] == ["axis.position", "float", "inc", "r"]


def test_names_of_a_kind_without_a_simulator() -> None:
    """`devsim ctl names KIND` with no simulator to ask: the kind's declared names."""
    text = ok("ctl", "names", "gms96")
    assert "input (" in text and "output (" in text and "\n160 names in 9 groups" in text
    assert json.loads(ok("ctl", "names", "sers", "--json"))[0]["name"] == "axis.position"
    done = devsim("ctl", "names", "nokind")
    assert done.returncode == exits.UNREACHABLE and "no running simulator found" in done.stderr


def _by_pattern(text: str) -> list[str]:
    """The lines after the count of names ("262 names in 10 groups ..."): the kind's patterns
    and aliases."""
    lines = text.splitlines()
    end = next(i for i, line in enumerate(lines) if re.match(r"\d+ names in \d+ groups", line))
    return lines[end + 1:]


def _kinds_own(kind: str) -> tuple[list[list[str]], list[list[str]]]:
    """What `devsim doc KIND` shows of a kind's patterns (pattern, type, access) and of its
    aliases a control name takes (alias, the name it stands for), from the kind's own tables."""
    from devsim.core.registry import device_class

    cls = device_class(kind)
    patterns = [[f.pattern, f.type, f.access] for f in cls.points.families]
    table = cls.reference().parameter_table
    aliases = [] if table is None else [
        [f"param.{alias}", "for", f"param.{table.spell(p.key)}"] for p in table for alias in p.aliases
        if cls.points.find(f"param.{alias}") is not None]
    return patterns, aliases


def _assert_ends_with_the_kinds_own(text: str, kind: str) -> None:
    patterns, aliases = _kinds_own(kind)
    expected = (["also by pattern:", *(["  ", *p] for p in patterns)] if patterns else []) + (
        ["also by alias:", *(["  ", *a] for a in aliases)] if aliases else [])
    tail = _by_pattern(text)
    assert [line if not line.startswith("  ") else ["  ", *line.split()[:3]] for line in tail] == expected, tail
    assert patterns or aliases


def test_names_end_with_the_patterns_a_running_gms96_takes() -> None:
    """`devsim ctl names DEVICE` ends with the kind's patterns (GMS96 `marker.M<byte>.<bit>`,
    `register.<n>`): names that read and set but were in no list (only `devsim doc` had them);
    --json stays the list of declared names."""
    with tempfile.TemporaryDirectory(prefix="dso") as path:
        address = f"unix:{path}/c.sock"
        proc = DevsimProcess("run", "gms96", "--tcp", "0", "--virtual", "--control", address)
        try:
            proc.next_match(proc.out, lambda line: line.startswith("control: "), 30, "the control line")
            text = ok("ctl", "--control", address, "names", "gms96", columns=200)
            _assert_ends_with_the_kinds_own(text, "gms96")
            tail = _by_pattern(text)
            assert tail[0] == "also by pattern:" and any(line.split()[0] == "register.<n>" for line in tail)
            assert "  marker.M<byte>.<bit>  bool" in text and "marker bit, e.g. M7.0" in text
            listed = [row["name"] for row in json.loads(ok("ctl", "--control", address, "--json", "names", "gms96"))]
            assert "marker.M7.0" not in listed and not any("<" in name for name in listed)  # the op's list as it was
            assert ok("ctl", "--control", address, "set", "gms96", "marker.M7.0", "on") == "ok\n"
            assert json.loads(ok("ctl", "--control", address, "--json", "read", "gms96", "marker.M7.0",
                                 "register.2")) == {"marker.M7.0": True, "register.2": 0}
        finally:
            assert proc.interrupt() == 0


def test_names_end_with_the_aliases_a_running_sers_takes() -> None:
    """A SERS drive named `sers2` (multidrop): its kind comes from the devices listing, and its
    names end with the aliases (`param.V` for `param.P91`), each of which reads as its name."""
    with tempfile.TemporaryDirectory(prefix="dso") as path:
        address = f"unix:{path}/c.sock"
        proc = DevsimProcess("run", "sers", "--tcp", "0", "--virtual", "--addresses", "1,2", "--control", address)
        try:
            proc.next_match(proc.out, lambda line: line.startswith("control: "), 30, "the control line")
            text = ok("ctl", "--control", address, "names", "sers2", columns=200)
            _assert_ends_with_the_kinds_own(text, "sers")
            tail = _by_pattern(text)
            assert tail[0] == "also by alias:" and "also by pattern:" not in tail
            assert any(line.split()[:3] == ["param.V", "for", "param.P91"] for line in tail)
            readable = [line.split() for line in tail[1:] if line.split()[3] in ("r", "rw")]
            aliases, canonical = [words[0] for words in readable], [words[2] for words in readable]
            assert "param.V" in aliases and len(readable) > 10
            read = json.loads(ok("ctl", "--control", address, "--json", "read", "sers2", *aliases, *canonical))
            assert [read[name] for name in aliases] == [read[name] for name in canonical]
            assert isinstance(json.loads(ok("ctl", "--control", address, "--json", "names", "sers2")), list)
        finally:
            assert proc.interrupt() == 0


def test_names_of_a_kind_end_with_its_patterns_and_aliases() -> None:
    """Without a simulator, `devsim ctl names KIND` ends the same way (PCD4.H3 `R.<n>`, `F.<n>`;
    POSELESTA `program.P<nn>`; SERS `param.V`); a width cuts those lines too."""
    for kind in ("gms96", "pcd4h3", "poselesta", "sers", "ip247"):
        _assert_ends_with_the_kinds_own(ok("ctl", "names", kind, columns=200), kind)
    assert "  R.<n>" in ok("ctl", "names", "pcd4h3") and "  program.P<nn>" in ok("ctl", "names", "poselesta")
    lines = ok("ctl", "names", "pcd4h3", columns=60).splitlines()
    assert max(map(len, lines)) <= 60 and _by_pattern("\n".join(lines))[0] == "also by pattern:"
    assert not any("<" in row["name"] for row in json.loads(ok("ctl", "names", "gms96", "--json")))


def test_an_error_is_one_line_on_stderr(addr: str) -> None:
    for args, status, text in [
        (("set", "sers", "quantity.supply_voltage", "hello"), exits.REFUSED,
         "Error: BadValue: quantity.supply_voltage: expects a number, not 'hello'\n"),
        (("read", "sers", "axis.positon"), exits.REFUSED,
         "Error: UnknownName: sers has no 'axis.positon' (did you mean axis.position"),
    ]:
        for mode in ((), ("--json",)):
            done = devsim("ctl", "--control", addr, *mode, *args)
            assert (done.returncode, done.stdout) == (status, "")
            assert done.stderr.startswith(text) and done.stderr.count("\n") == 1


def test_watch_lines_print_characters() -> None:
    """`devsim ctl watch` prints a structured value's text as characters too (its formatter)."""
    from devsim.runtime.watch_stream import describe

    line = describe({"type": "change", "t": 1.5, "device": "sers", "name": "display", "value": {"char": "°"}})
    assert line == '1.500 sers display {"char": "°"}'
    assert describe({"type": "change", "t": 2, "device": "cnc", "name": "panel.message", "value": "ÜBERLAUF"}) == (
        "2.000 cnc panel.message ÜBERLAUF")  # plain text as it is
    forged = describe({"type": "change", "t": 2, "device": "cnc", "name": "program.P20", "value": "N1 X1\n2.000 cnc x 1"})
    assert forged == '2.000 cnc program.P20 "N1 X1\\n2.000 cnc x 1"'  # one item, one line (it printed two)


def test_telegrams_are_a_table(sim: tuple[str, str]) -> None:
    addr, url = sim
    assert ok("ctl", "--control", addr, "telegrams", "sers").startswith("(no telegrams yet")  # the tap starts
    with serial.serial_for_url(url, timeout=1) as port:
        port.write(b"#1P11?\r")
        deadline = time.monotonic() + 15
        while (lines := ok("ctl", "--control", addr, "telegrams", "sers").splitlines())[0].startswith("(no"):
            assert time.monotonic() < deadline, "the telegram did not arrive"
    assert lines[0].split() == ["time", "dir", "bytes", "decoded"]
    when, *rest = lines[1].split()
    assert re.fullmatch(r"\d+\.\d{3}", when) and rest == ["H>D", '"#1P11?\\r"', "#1P11?"]  # bytes, decoded


def test_decoded_messages_are_key_value_words() -> None:
    """A kind's framing decodes a telegram into fields (GMS96's FT1.2): shown as words."""
    from devsim.cli.present import render
    from devsim.runtime import requests as rq

    telegram = {"t": 0.5, "dir": "H>D", "hex": "10 40 01 41 16", "text": '"\\x10@\\x01A\\x16"',
                "decoded": [{"frame": "short", "C": "40", "A": 1}]}
    lines = render([(rq.Telegrams("gms96", "main", 1), [telegram])], json_output=False, width=100).splitlines()
    assert lines[1].endswith("frame=short C=40 A=1")


def test_a_fleet_answers_per_process() -> None:
    """With --fleet, now/advance answer for each process and devices name it: tables too."""
    from devsim.cli.present import render
    from devsim.runtime import requests as rq

    clocks = {"cell-a-12-ab12": 2.5, "cell-b-13-cd34": 3.0}
    assert render([(rq.Now(), clocks)], json_output=False, width=80).splitlines() == [
        "process         time", "cell-a-12-ab12  2.5 s", "cell-b-13-cd34  3 s"]
    assert render([(rq.Advance(1.0), clocks)], json_output=False, width=80).splitlines()[0] == "ok"
    assert render([(rq.Advance(0.1), 6.800000000000001)], json_output=False) == "ok, time 6.8 s"  # to the µs
    assert render([(rq.Now(), 0.1 + 0.2)], json_output=False) == "0.3 s"
    rows = [{"name": "press", "kind": "sers", "port": "/dev/pts/3", "ports": {"main": "/dev/pts/3"},
             "faults": [], "process": "cell-a-12-ab12", "host": "cell-a", "pid": 12, "online": True}]
    lines = render([(rq.Devices(), rows)], json_output=False, width=120).splitlines()
    assert lines[0].split() == ["name", "kind", "port", "faults", "process", "host", "pid", "online"]
    assert lines[1].split() == ["press", "sers", "/dev/pts/3", "-", "cell-a-12-ab12", "cell-a", "12", "true"]
    record = {"name": "check", "done": 1, "total": 2, "now": 0.5, "end": 2.0, "running": True, "steps": []}
    assert render([(rq.Scenario(), {"cell-b-13-cd34": None, "cell-a-12-ab12": record})], json_output=False,
                  width=80).splitlines() == [  # (it printed "scenario None: step None of None, ... failed")
        "cell-a-12-ab12: scenario check: step 1 of 2, 0.5 of 2 s, running", "cell-b-13-cd34: (no scenario runs)"]


def test_in_a_pipe_nothing_is_cut() -> None:
    """A pipe has no width: rows whole (cut to 80 columns, `ctl --fleet devices | grep false`
    found no offline device); COLUMNS still sets one."""
    env = {k: v for k, v in devsim_env().items() if k != "COLUMNS"}
    done = subprocess.run([sys.executable, "-m", "devsim", "ctl", "names", "sers"], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert not any(line.endswith("…") for line in lines) and max(map(len, lines)) > 100
    assert any(line.endswith("…") for line in devsim("ctl", "names", "sers", columns=80).stdout.splitlines())


def _reader_gone(*args: str) -> subprocess.Popen[bytes]:
    """``devsim ctl ARGS`` whose stdout's reader has gone before the first line (``| head``)."""
    proc = subprocess.Popen([sys.executable, "-m", "devsim", "ctl", *args], cwd=ROOT, env=devsim_env(),
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None
    proc.stdout.close()
    return proc


def test_a_watch_whose_reader_goes_away_ends_quietly_with_1(addr: str) -> None:
    """`devsim ctl watch sers | head -3` ends as every command does when its reader goes (status 1,
    nothing on stderr: docs/cli.md).  It said 'control connection to … failed: [Errno 32] Broken
    pipe', status 5 (UNREACHABLE), the stdout's EPIPE taken for the connection's.  (`ctl capture`
    prints through the same loop, ``devsim.cli.ctl._print_each``.)"""
    with _reader_gone("--control", addr, "watch", "sers") as proc:  # (the first sample: every value at once)
        err = proc.stderr.read() if proc.stderr is not None else b""
    assert (proc.returncode, err) == (exits.FAILED, b"")


def test_a_capture_whose_reader_goes_away_ends_quietly_with_1(sim: tuple[str, str]) -> None:
    """`devsim ctl capture sers | head -2` ends as `watch` does when its reader goes: status 1,
    nothing on stderr (docs/cli.md), at the first chunk a host sends once the capture runs."""
    from devsim.runtime.client import ControlClient

    addr, url = sim
    with _reader_gone("--control", addr, "capture", "sers") as proc:
        with ControlClient(addr) as control:
            wait_until(lambda: control.line("sers")["capturing"] or proc.poll() is not None, "capture running", 30.0)
        with serial.serial_for_url(url, timeout=1) as port:
            port.write(b"#1P11?\r")  # the chunk it prints
        err = proc.stderr.read() if proc.stderr is not None else b""
    assert (proc.returncode, err) == (exits.FAILED, b"")

