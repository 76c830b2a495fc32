"""One kind of mistake, one exit status, whichever command meets it (devsim.cli.exits,
docs/cli.md): every row of the table through the real CLI (`python -m devsim` subprocesses),
for each command the mistake can reach, and the table in the docs held to the constants."""

from __future__ import annotations

import re
import socket
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from devsim.cli import exits
from devsim.core.extras import install_command
from tests.support.process import ROOT, DevsimProcess, devsim_env, free_port

PLANT = "devices:\n  - name: x\n    kind: sers\n    config: {address: 1}\n    transport: {tcp: {port: 0}}\n"
SCENARIO_FAILS = (
    "devices:\n  - {name: x, kind: sers}\nsteps:\n"
    "  - expect_state: {device: x, name: energized, equals: true}\n"
)
#: A POSELESTA whose plant stores a program the control refuses: its type (text) passes the file's
#: check, the block's value does not fit the format in force (spec §2.6.3), so the device says no.
REFUSED_STATE = "devices:\n  - {name: cnc, kind: poselesta, state: {program.P20: \"L500\"}}\n"
SESSION = '{"format": "devsim-session", "kind": "sers"}\n'
TRACE = '12.345678 H>D 23 4f 0d "#O\\r"\n'


@pytest.fixture(scope="module")
def files() -> Iterator[Path]:
    """Good and bad files of every sort a command reads, and a module that hides an extra."""
    with tempfile.TemporaryDirectory(prefix="dsx") as name:
        path = Path(name)
        (path / "plant.yaml").write_text(PLANT)
        (path / "bad_plant.yaml").write_text(PLANT.replace("address: 1", "address: 500"))
        (path / "bad_config.yaml").write_text("address: 1\nbaud: 9601\n")
        (path / "bad_scenario.yaml").write_text(SCENARIO_FAILS.replace("equals: true", "equals: [1"))
        (path / "fails.yaml").write_text(SCENARIO_FAILS)
        (path / "refused_state.yaml").write_text(REFUSED_STATE)
        (path / "refused_state_scenario.yaml").write_text(REFUSED_STATE + "steps:\n  - after: 1s\n")
        (path / "session.devsim").write_text(SESSION)
        (path / "bad.devsim").write_text('{"hello": 1}\n')
        (path / "trace.txt").write_text(TRACE)
        (path / "bad.csv").write_text("hello\n")
        for extra in ("matplotlib", "pymodbus"):  # `import X` fails: the extra is "not installed"
            (path / "hide" / extra).mkdir(parents=True)
            (path / "hide" / extra / "__init__.py").write_text("raise ImportError('hidden by the test')\n")
        yield path


@pytest.fixture(scope="module")
def sim() -> Iterator[str]:
    """A running `devsim run sers` to refuse requests; its control address."""
    with tempfile.TemporaryDirectory(prefix="dsx") as name:
        address = f"unix:{name}/c.sock"
        proc = DevsimProcess("run", "sers", "--tcp", "0", "--virtual", "--control", address)
        try:
            proc.next_match(proc.out, lambda line: line.startswith("control: "), 30, "the control line")
            yield address
        finally:
            assert proc.interrupt() == 0


@pytest.fixture(scope="module")
def busy() -> Iterator[int]:
    """A TCP port on loopback that someone holds."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        yield int(sock.getsockname()[1])


def devsim(*args: str, hide: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = devsim_env()
    if hide is not None:
        env["PYTHONPATH"] = f"{hide}:{env['PYTHONPATH']}"
    return subprocess.run([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=60, stdin=subprocess.DEVNULL)


Case = Callable[[Path, str, int], list[str]]  # (files, control address, busy port) -> arguments

#: (status, what the mistake is, the arguments) for every command the mistake can reach.
CASES: list[tuple[int, str, Case]] = [
    # -- the command line
    (exits.USAGE, "run: unknown kind", lambda f, a, b: ["run", "nokind"]),
    (exits.USAGE, "run: bad option value", lambda f, a, b: ["run", "sers", "--speed", "0"]),
    (exits.USAGE, "up: bad option value", lambda f, a, b: ["up", str(f / "plant.yaml"), "--speed", "0"]),
    (exits.UNREACHABLE, "ctl: no address and none running", lambda f, a, b: ["ctl", "now"]),
    (exits.USAGE, "ctl: bad address", lambda f, a, b: ["ctl", "--control", "unix:", "now"]),
    (exits.USAGE, "ctl: bad port", lambda f, a, b: ["ctl", "--control", "99999", "now"]),
    (exits.UNREACHABLE, "ctl: no simulator of that name", lambda f, a, b: ["ctl", "--control", "nowhere", "now"]),
    (exits.USAGE, "ctl: unknown command", lambda f, a, b: ["ctl", "--control", a, "jump"]),
    (exits.USAGE, "monitor: output not a terminal", lambda f, a, b: ["monitor", "--control", a]),
    (exits.USAGE, "check: no argument", lambda f, a, b: ["check"]),
    (exits.USAGE, "scenario: bad option", lambda f, a, b: ["scenario", "run", str(f / "fails.yaml"), "--speed", "0"]),
    (exits.USAGE, "scenario: virtual and realtime", lambda f, a, b: ["scenario", "run", str(f / "fails.yaml"),
                                                                     "--virtual", "--realtime"]),
    (exits.USAGE, "scenario: virtual and speed", lambda f, a, b: ["scenario", "run", str(f / "fails.yaml"),
                                                                  "--virtual", "--speed", "2"]),
    (exits.USAGE, "doc: unknown kind", lambda f, a, b: ["doc", "nokind"]),
    (exits.USAGE, "plot: bad output", lambda f, a, b: ["plot", str(f / "trace.txt"), "-o", str(f / "x.gif")]),
    (exits.USAGE, "record: two ports", lambda f, a, b: ["record", "--port", "/x", "--out", "o", "--link", "l",
                                                        "--tcp", "1"]),
    (exits.USAGE, "replay: bad option", lambda f, a, b: ["replay", str(f / "session.devsim"), "--speed", "0"]),
    (exits.USAGE, "monitor: bad option", lambda f, a, b: ["monitor", "--control", a, "--period", "0"]),
    # -- a file: missing, or wrong inside
    (exits.BAD_FILE, "run: bad config", lambda f, a, b: ["run", "sers", "--config", str(f / "bad_config.yaml")]),
    (exits.BAD_FILE, "run: no config", lambda f, a, b: ["run", "sers", "--config", str(f / "nope.yaml")]),
    (exits.BAD_FILE, "up: bad plant", lambda f, a, b: ["up", str(f / "bad_plant.yaml")]),
    (exits.BAD_FILE, "up: no plant", lambda f, a, b: ["up", str(f / "nope.yaml")]),
    (exits.BAD_FILE, "up: a state the device refuses", lambda f, a, b: ["up", str(f / "refused_state.yaml")]),
    (exits.BAD_FILE, "check: bad plant", lambda f, a, b: ["check", str(f / "plant.yaml"), str(f / "bad_plant.yaml")]),
    (exits.BAD_FILE, "check: no file", lambda f, a, b: ["check", str(f / "nope.yaml")]),
    (exits.BAD_FILE, "scenario: bad scenario", lambda f, a, b: ["scenario", "run", str(f / "bad_scenario.yaml")]),
    (exits.BAD_FILE, "scenario: a state the device refuses", lambda f, a, b: [
        "scenario", "run", str(f / "refused_state_scenario.yaml")]),
    (exits.BAD_FILE, "scenario: no scenario", lambda f, a, b: ["scenario", "run", str(f / "nope.yaml")]),
    (exits.BAD_FILE, "plot: bad input", lambda f, a, b: ["plot", str(f / "bad.csv"), "-o", str(f / "x.png")]),
    (exits.BAD_FILE, "plot: no input", lambda f, a, b: ["plot", str(f / "nope.csv"), "-o", str(f / "x.png")]),
    (exits.BAD_FILE, "replay: bad session", lambda f, a, b: ["replay", str(f / "bad.devsim")]),
    (exits.BAD_FILE, "replay: no session", lambda f, a, b: ["replay", str(f / "nope.devsim")]),
    (exits.BAD_FILE, "replay: bad config", lambda f, a, b: ["replay", str(f / "session.devsim"), "--fallback", "live",
                                                            "--config", str(f / "bad_config.yaml")]),
    # -- the simulator says no
    (exits.REFUSED, "ctl: out of range", lambda f, a, b: ["ctl", "--control", a, "set", "sers",
                                                          "quantity.supply_voltage", "500"]),
    (exits.REFUSED, "ctl: wrong type", lambda f, a, b: ["ctl", "--control", a, "set", "sers",
                                                        "quantity.supply_voltage", "hello"]),
    (exits.REFUSED, "ctl: read-only", lambda f, a, b: ["ctl", "--control", a, "set", "sers", "axis.position", "1"]),
    (exits.REFUSED, "ctl: unknown name", lambda f, a, b: ["ctl", "--control", a, "read", "sers", "axis.positon"]),
    (exits.REFUSED, "ctl: unknown device", lambda f, a, b: ["ctl", "--control", a, "state", "nobody"]),
    (exits.REFUSED, "ctl: unknown fault", lambda f, a, b: ["ctl", "--control", a, "fault", "sers", "fire", "on"]),
    # -- nobody answers
    (exits.UNREACHABLE, "ctl: no simulator", lambda f, a, b: ["ctl", "--control", f"unix:{f}/none.sock", "now"]),
    (exits.UNREACHABLE, "ctl: no broker", lambda f, a, b: ["ctl", "--fleet", f"mqtt://127.0.0.1:{free_port()}",
                                                           "devices"]),
    (exits.UNREACHABLE, "monitor: no simulator", lambda f, a, b: ["monitor", "--control", f"unix:{f}/none.sock"]),
    (exits.UNREACHABLE, "record: no device", lambda f, a, b: ["record", "--port", str(f / "ttyNONE"),
                                                              "--out", str(f / "o.devsim")]),
    (exits.UNREACHABLE, "run: no broker", lambda f, a, b: ["run", "sers", "--fleet", f"mqtt://127.0.0.1:{free_port()}"]),
    (exits.UNREACHABLE, "up: no broker", lambda f, a, b: ["up", str(f / "plant.yaml"), "--fleet",
                                                          f"mqtt://127.0.0.1:{free_port()}"]),
    # -- this machine
    (exits.SYSTEM, "run: port in use", lambda f, a, b: ["run", "sers", "--tcp", str(b)]),
    (exits.SYSTEM, "replay: port in use", lambda f, a, b: ["replay", str(f / "session.devsim"), "--tcp", str(b)]),
    (exits.SYSTEM, "scenario: cannot write", lambda f, a, b: ["scenario", "run", str(f / "fails.yaml"), "--trace-dir",
                                                             str(f / "trace.txt" / "dir")]),
    (exits.SYSTEM, "scenario: junit cannot write", lambda f, a, b: ["scenario", "run", str(f / "fails.yaml"), "--junit",
                                                                   str(f / "trace.txt" / "out.xml")]),
    (exits.SYSTEM, "plot: cannot write", lambda f, a, b: ["plot", str(f / "trace.txt"), "-o", str(f / "no/x.png")]),
    # (a FileExistsError's traceback: --plot's directory was made outside the scenario's own OSError guard)
    (exits.SYSTEM, "scenario: plot dir cannot be made", lambda f, a, b: ["scenario", "run", str(f / "fails.yaml"),
                                                                        "--plot", str(f / "trace.txt")]),
    # -- a scenario that does not pass
    (exits.FAILED, "scenario: expectation", lambda f, a, b: ["scenario", "run", str(f / "fails.yaml")]),
]


@pytest.mark.parametrize(("status", "what", "case"), CASES, ids=[what for _, what, _ in CASES])
def test_each_kind_of_mistake_has_its_status(files: Path, sim: str, busy: int, status: int, what: str,
                                             case: Case) -> None:
    done = devsim(*case(files, sim, busy))
    assert done.returncode == status, done.stderr
    assert "Traceback" not in done.stderr
    if status == exits.FAILED:  # the report says which expectation failed
        assert "FAIL" in done.stdout
    elif what.startswith("check: bad") or what == "check: no file":  # one line per mistake, file:line first
        assert done.stderr.startswith(str(files / "bad_plant.yaml" if "bad" in what else files / "nope.yaml"))
    else:  # one error line, the last (after what a server logged while it started)
        errors = [line for line in done.stderr.splitlines() if line.startswith("Error: ")]
        assert len(errors) == 1 and done.stderr.endswith(errors[0] + "\n"), done.stderr
        if "refuses" in what:  # the file, where in it, and the device's own message
            assert errors[0].endswith(".yaml: devices.1.state.program.P20: WERTBEREICHES-UEBERLAUF: L500: beyond the "
                                      "format"), errors[0]


@pytest.mark.parametrize(("args", "extra"), [
    (["plot", "{f}/trace.txt", "-o", "{f}/x.png"], "plot"),
    (["scenario", "run", "{f}/fails.yaml", "--plot", "{f}/plots"], "plot"),
    (["run", "sers", "--modbus", "tcp:0"], "modbus"),
])
def test_a_missing_extra_is_this_machine(files: Path, args: list[str], extra: str) -> None:
    done = devsim(*(arg.format(f=files) for arg in args), hide=files / "hide")
    assert done.returncode == exits.SYSTEM, done.stderr
    assert done.stderr.startswith("Error: ") and install_command(extra) in done.stderr  # the checkout's or the distribution's
    assert done.stderr.count("\n") == 1


def test_the_docs_table_is_the_constants() -> None:
    """docs/cli.md lists every status of devsim.cli.exits with its number, and no other."""
    text = (ROOT / "docs" / "cli.md").read_text()
    rows = dict(re.findall(r"^\| (\d+) \| `([A-Z_]+)` \|", text, flags=re.M))
    assert {name: int(code) for code, name in rows.items()} == exits.EXIT_CODES
