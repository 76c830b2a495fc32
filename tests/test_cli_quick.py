"""`devsim run` without click (devsim.cli.quick): the parameters it reads are click's, on the
command lines it takes; it takes the plain ones; a plain `devsim run` imports no click; a mistake
still gets click's line and status."""

from __future__ import annotations

import subprocess
import sys

import click
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devsim.cli.main import cli
from devsim.cli.quick import DEFAULTS, OPTIONS, _float, _non_negative, run_params
from tests.support.process import ROOT, collect_lines, devsim_env, next_match, stop

RUN = cli.commands["run"]
FACADES = {"--modbus", "--canopen", "--opcua", "--opcua-period", "--modbus-map", "--mqtt", "--mqtt-convention",
           "--mqtt-rate", "--mqtt-plant", "--mqtt-primary-host", "--fleet", "--web"}  # left to click


def click_params(args: list[str]) -> dict[str, object]:
    """What click gives the run command for ``devsim ARGS``."""
    with RUN.make_context("run", list(args[1:])) as ctx:
        return dict(ctx.params)


def shown(params: dict[str, object] | None) -> dict[str, str] | None:
    """The parameters compared by their repr and type (NaN equals NaN; 1 is not 1.0)."""
    return None if params is None else {key: f"{type(value).__name__} {value!r}" for key, value in params.items()}


def test_the_options_read_without_click_are_the_run_commands_own() -> None:
    kinds = {"flag": lambda o: o.is_flag and not o.count, "count": lambda o: o.count,
             "multiple": lambda o: o.multiple, "value": lambda o: not o.is_flag and not o.count and not o.multiple}
    seen = set()
    for param in RUN.params:
        if isinstance(param, click.Argument):
            assert param.name == "kind"
            continue
        assert isinstance(param, click.Option)
        names = [*param.opts, *param.secondary_opts]
        if set(names) <= FACADES:
            continue
        for name in names:
            assert name in OPTIONS, name
            dest, kind, convert = OPTIONS[name]
            assert dest == param.name and kinds[kind](param), name
            if isinstance(param.type, click.FloatRange):
                assert (param.type.min, param.type.max, param.type.min_open) == (0, None, False)
                assert convert is _non_negative
            elif isinstance(param.type, click.types.FloatParamType):
                assert convert is _float
            else:
                assert convert is None or param.type == click.STRING
            seen.add(name)
    assert seen == set(OPTIONS)
    assert {"kind": "sers", **DEFAULTS} == click_params(["run", "sers"])


PLAIN = [
    ["run", "sers"],
    ["run", "sers", "--pty"],
    ["run", "--tcp", "5000", "gms96"],
    ["run", "sers", "--tcp=127.0.0.1:0", "-vq", "-v", "--quiet"],
    ["run", "sers", "--link", "/tmp/x", "--state-dir", "s", "--speed", "2.5", "--trace", "t.pcap"],
    ["run", "sers", "--no-control", "--control-allow-remote", "--pacing", "--virtual", "--idle-drop", "0"],
    ["run", "pcd4h3", "--port", "ether=udp:0", "--port=main=pty", "--drives", "1,2", "--addresses", "3"],
    ["run", "sers", "--config", "c.yaml", "--motion-log", "m.csv", "--motion-resolution", "1e-3", "--control", "5"],
    ["run", "sers", "--speed", "nan", "--idle-drop", "inf", "--link="],
]

NOT_PLAIN = [
    ["run"],
    ["ctl", "devices"],
    ["run", "sers", "--help"],
    ["run", "sers", "-h"],
    ["run", "sers", "gms96"],
    ["run", "sers", "--tcp"],
    ["run", "sers", "--speed", "fast"],
    ["run", "sers", "--speed", "-1"],
    ["run", "sers", "--idle-drop=-1"],
    ["run", "sers", "--pty=yes"],
    ["run", "sers", "--modbus", "tcp:0"],
    ["run", "sers", "--mqtt"],
    ["run", "sers", "-x"],
    ["run", "sers", "-vx"],
    ["run", "sers", "--", "--pty"],
    ["run", "-", "--pty"],
    ["--version", "run", "sers"],
]


@pytest.mark.parametrize("args", PLAIN)
def test_a_plain_command_line_is_read_as_click_reads_it(args: list[str]) -> None:
    params = run_params(args)
    assert params is not None
    assert shown(params) == shown(click_params(args))


@pytest.mark.parametrize("args", NOT_PLAIN)
def test_anything_else_is_left_to_click(args: list[str]) -> None:
    assert run_params(args) is None


WORDS = st.sampled_from([
    "sers", "gms96", "--pty", "--link", "--tcp", "--rfc2217", "--config", "--state-dir", "--speed", "--virtual",
    "--trace", "--control", "--no-control", "--control-allow-remote", "--drives", "--addresses", "--pacing",
    "--idle-drop", "--port", "--motion-log", "--motion-resolution", "-v", "-q", "--verbose", "--quiet", "-vq",
    "-qqv", "1", "0.5", "-1", "1e3", "nan", "x", "", "tcp:0", "main=pty", "--help", "--modbus", "--speed=2",
    "--tcp=5000", "--pty=1", "--port=main=pty", "-", "--", "1_0", " 2 ", "-vx", "--idle-drop=0",
])


@settings(max_examples=400, deadline=None)
@given(st.lists(WORDS, max_size=8))
def test_whatever_it_reads_click_reads_the_same(words: list[str]) -> None:
    args = ["run", *words]
    params = run_params(args)
    if params is not None:
        assert shown(params) == shown(click_params(args))


def test_a_plain_run_serves_without_ever_importing_click() -> None:
    code = ("import sys, devsim.cli.serve as serve\n"
            "say = serve._say\n"
            "serve._say = lambda line: say(f\"{line} click={'click' in sys.modules}\")\n"
            "from devsim.cli import main\n"
            "main(['run', 'sers', '--pty', '--no-control', '-q'])\n")
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        line = next_match(collect_lines(proc.stdout), lambda line: True, 30, "the port line")
    finally:
        assert stop(proc) == 0
    assert line.startswith("sers: pty /dev/") and line.endswith(" click=False")


#: What a plain `devsim run` (control on, as by default) has no use for before its port line: the
#: control API's op table (imported by the first connection), pathlib and json (a state dir, a
#: --link, a request need them), urllib and ipaddress (pathlib's), click; the multidrop bus of
#: devices that share a line, and resource (the descriptor limit is asked when ports run short)
#: (issue 31).
NOT_AT_START = ("click", "devsim.runtime.ops", "devsim.runtime.requests", "devsim.runtime.watch_stream", "pathlib",
                "json", "urllib.parse", "ipaddress", "devsim.core.bus", "resource")


def test_a_plain_run_reaches_its_port_line_without_what_it_does_not_use() -> None:
    code = ("import sys, devsim.cli.serve as serve\n"
            "say = serve._say\n"
            f"serve._say = lambda line: say(f\"{{line}} {{sorted(m for m in {NOT_AT_START!r} if m in sys.modules)}}\")\n"
            "from devsim.cli import main\n"
            "main(['run', 'sers', '--pty'])\n")
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        lines = collect_lines(proc.stdout)
        port = next_match(lines, lambda line: True, 30, "the port line")
        control = next_match(lines, lambda line: True, 30, "the control line")
    finally:
        assert stop(proc) == 0
    assert port.startswith("sers: pty /dev/") and port.endswith(" []")
    assert control.startswith("control: unix:") and control.endswith(" []")


def test_a_mistake_found_by_the_plan_is_said_by_click() -> None:
    proc = subprocess.run([sys.executable, "-m", "devsim", "run", "sers", "--pty", "--speed", "0"], cwd=ROOT,
                          env=devsim_env(), capture_output=True, text=True, timeout=60)
    assert (proc.returncode, proc.stdout) == (2, "")
    assert proc.stderr == "Error: --speed: must be positive (see 'devsim run --help')\n"
