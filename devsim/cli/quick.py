"""The ``devsim`` command's entry point, and ``devsim run`` without click when its command line
is plain (issue 31: start-up to a usable port).

Importing click costs about as much as building a device, so a ``devsim run`` command line made
only of the options in :data:`OPTIONS`, each written plainly, is read here (:func:`run_params`)
into exactly the parameters click would give :func:`devsim.cli.main.run`, planned and served
(:mod:`devsim.cli.serve`) without click.  Anything else goes to click as before: another command,
``--help``, a facade option, an option this reader does not know or an odd spelling of one (a
value that starts with ``-``, ``--``), and any mistake the plan finds: click then reads the whole
command line again and says the mistake with its usual line and exit status (docs/cli.md), so
the two ways cannot differ in their errors.  ``tests/test_cli_quick.py`` checks the parameters
against click's on many command lines.
"""

from __future__ import annotations

import errno
import gc
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

from devsim.cli.statuses import INTERRUPTED, StartFailure

__all__ = ["DEFAULTS", "OPTIONS", "main", "run_params"]

#: click's shell completion asks through this variable (``_{PROG}_COMPLETE``): click answers it.
COMPLETE_VAR = "_DEVSIM_COMPLETE"


def _float(text: str) -> float:
    """``FLOAT`` (:mod:`devsim.cli.options`): ``float`` of ASCII text (``float`` reads '٣' as 3)."""
    if not text.isascii():
        raise ValueError(text)
    return float(text)


def _non_negative(text: str) -> float:
    """``click.FloatRange(min=0)``: a float not below 0; NaN is left to click, which takes it, for
    :func:`devsim.cli.serve.plan_run` to refuse (``--idle-drop: must be a number of seconds``)."""
    value = _float(text)
    if not value >= 0:
        raise ValueError(text)
    return value


def _text(text: str) -> str:
    return text


#: The options of ``devsim run`` read here: option → (parameter, kind, conversion), kind one of
#: ``flag`` (True when given), ``count`` (+1 each time), ``value`` (the last one given) and
#: ``multiple`` (a tuple of every one given).  The facade options are left to click.
OPTIONS: dict[str, tuple[str, str, Callable[[str], Any] | None]] = {
    "--pty": ("use_pty", "flag", None),
    "--virtual": ("virtual", "flag", None),
    "--no-control": ("no_control", "flag", None),
    "--control-allow-remote": ("control_allow_remote", "flag", None),
    "--pacing": ("pacing", "flag", None),
    "--link": ("link", "value", _text),
    "--tcp": ("tcp", "value", _text),
    "--rfc2217": ("rfc2217", "value", _text),
    "--config": ("config_file", "value", _text),
    "--state-dir": ("state_dir", "value", _text),
    "--speed": ("speed", "value", _float),
    "--trace": ("trace", "value", _text),
    "--control": ("control", "value", _text),
    "--drives": ("drives", "value", _text),
    "--addresses": ("drives", "value", _text),
    "--idle-drop": ("idle_drop", "value", _non_negative),
    "--motion-log": ("motion_log", "value", _text),
    "--motion-resolution": ("motion_resolution", "value", _float),
    "--port": ("port_options", "multiple", _text),
    "-v": ("verbose", "count", None),
    "--verbose": ("verbose", "count", None),
    "-q": ("quiet", "count", None),
    "--quiet": ("quiet", "count", None),
}

#: Every parameter of :func:`devsim.cli.main.run` as click gives it when its option is not given.
DEFAULTS: dict[str, Any] = {
    "use_pty": False, "link": None, "tcp": None, "rfc2217": None, "config_file": None, "state_dir": None,
    "speed": 1.0, "virtual": False, "trace": None, "control": None, "no_control": False,
    "control_allow_remote": False, "drives": None, "pacing": False, "idle_drop": None, "port_options": (),
    "modbus": None, "canopen": None, "opcua": None, "opcua_period": 0.1, "modbus_map": "points", "mqtt": None,
    "mqtt_convention": "devsim", "mqtt_rate": 1.0, "mqtt_plant": None, "mqtt_primary_host": None, "fleet": None, "web": None, "motion_log": None,
    "motion_resolution": 0.01, "verbose": 0, "quiet": 0,
}


def _option(params: dict[str, Any], option: str, value: str | None) -> bool:
    """Take one option (``value``: what followed ``=`` or the next word); False: not plain."""
    name, kind, convert = OPTIONS[option]
    if kind in ("flag", "count"):
        if value is not None:
            return False
        params[name] = True if kind == "flag" else params[name] + 1
        return True
    if value is None or value.startswith("-") or convert is None:
        return False
    try:
        converted = convert(value)
    except ValueError:
        return False
    params[name] = (*params[name], converted) if kind == "multiple" else converted
    return True


def run_params(args: Sequence[str]) -> dict[str, Any] | None:
    """The parameters click gives :func:`devsim.cli.main.run` for ``devsim ARGS`` (``kind`` and
    every option), or None when ``args`` is not a plain ``run`` command line of :data:`OPTIONS`."""
    if len(args) < 2 or args[0] != "run":
        return None
    params: dict[str, Any] = dict(DEFAULTS)
    kinds: list[str] = []
    words = list(args[1:])
    while words:
        word = words.pop(0)
        if not word.startswith("-"):
            kinds.append(word)
        elif word.startswith("--"):
            option, sep, value = word.partition("=")
            if option not in OPTIONS:
                return None
            if sep:
                given: str | None = value
            elif OPTIONS[option][1] in ("value", "multiple"):
                given = words.pop(0) if words else None
            else:
                given = None
            if not _option(params, option, given):
                return None
        elif len(word) > 1 and all(letter in "vq" for letter in word[1:]):  # -v, -qq, -vq ...
            for letter in word[1:]:
                _option(params, f"-{letter}", None)
        else:
            return None
    if len(kinds) != 1:
        return None
    return {"kind": kinds[0], **params}


def main(args: Sequence[str] | None = None, prog_name: str = "devsim") -> None:
    """Entry point of the ``devsim`` command and of ``python -m devsim``."""
    argv = sys.argv[1:] if args is None else list(args)
    params = None if COMPLETE_VAR in os.environ else run_params(argv)
    if params is not None and _run(params):
        return
    from devsim.cli.main import cli

    cli.main(argv, prog_name=prog_name)


def _run(params: dict[str, Any]) -> bool:
    """Plan and serve ``devsim run`` without click; False (nothing started) when the plan finds a
    mistake, for click to say it.  Once planned, the outcome is the click command's: a server
    that cannot start is one ``Error:`` line and its status.  A stdout whose reader goes away is
    handed to the null device where the server prints (:mod:`devsim.core.console`); an EPIPE
    from anywhere else exits with 1, as click does."""
    gc.disable()  # start-up makes many objects and frees few: no collection until serving starts
    try:
        from devsim.cli.serve import plan_run, serve

        plan = plan_run(**params)
    except Exception:  # a mistake on the command line, in a file, a kind that cannot be loaded ...
        gc.enable()
        return False
    except KeyboardInterrupt:  # Ctrl-C while starting: click's "aborted"
        print(file=sys.stderr)
        _fail("aborted", INTERRUPTED)
    try:
        serve(plan)
    except StartFailure as exc:
        _fail(str(exc), exc.status)
    except KeyboardInterrupt:
        print(file=sys.stderr)
        _fail("aborted", INTERRUPTED)
    except OSError as exc:  # what click does when stdout is a closed pipe: exit 1, no more output
        if exc.errno != errno.EPIPE:
            raise
        from devsim.core.console import to_null

        to_null(sys.stdout)
        sys.exit(1)
    return True


def _fail(message: str, status: int) -> NoReturn:
    """As :func:`devsim.cli.main._fail`: one ``Error:`` line on stderr, exit ``status``."""
    print(f"Error: {message}", file=sys.stderr, flush=True)
    sys.exit(status)
