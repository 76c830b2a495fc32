"""``devsim check``, ``devsim scenario run`` and ``devsim up`` (imported lazily by :mod:`devsim.cli.main`).

* ``devsim check FILE...`` validates scenario and plant files without running them.
* ``devsim scenario run FILE... [--virtual | --realtime] [--speed F] [--junit OUT.xml]`` runs
  scenarios, prints a report per scenario and exits non-zero if any failed; ``--motion-log
  FILE.csv`` logs the axes, ``--plot DIR`` draws a picture per scenario
  (:mod:`devsim.scenario.pictures`).
* ``devsim up PLANT.yaml`` starts every device of a plant, prints each port, serves until Ctrl-C;
  ``--part NAME`` only the devices with that ``part:``, ``--fleet URL`` joins a fleet.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import click

from devsim.cli import exits
from devsim.cli.options import FLOAT, AsciiFloatRange, AsciiIntRange, check_fleet
from devsim.cli.statuses import file_failure, make_dirs
from devsim.cli.usage import check_dirs
from devsim.core.config import ConfigError
from devsim.core.console import say, stop_on_signals, warn
from devsim.core.nvram import UNUSABLE as _UNUSABLE_MEMORY
from devsim.observe.live_log import DEFAULT_LEVEL, attach_log, level_of, log_options
from devsim.transports import fdlimit

__all__ = ["check", "scenario", "up"]


def _count(number: int, thing: str) -> str:
    """``1 device``, ``2 devices``."""
    return f"{number} {thing}{'' if number == 1 else 's'}"


@click.command("check")
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
def check(files: tuple[str, ...]) -> None:
    """Validate scenario and plant FILES without running them: every mistake of every file, one
    line each (file:line: field: message); exit status 3 if there is any."""
    from devsim.scenario.schema import inspect_file

    bad = 0
    for path in files:
        spec, messages = inspect_file(path)
        if spec is None:
            bad += 1
            for message in messages:
                click.echo(message, err=True)
            continue
        steps = getattr(spec, "steps", None)
        what = f"scenario, {_count(len(steps), 'step')}" if steps is not None else "plant"
        click.echo(f"{path}: ok ({what}, {_count(len(spec.devices), 'device')})")  # type: ignore[attr-defined]
    if bad:
        sys.exit(exits.BAD_FILE)


@click.group("scenario")
def scenario() -> None:
    """Run scenario files."""


@scenario.command("run")
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("--virtual", "virtual", is_flag=True, help="Virtual time (default when the host is scripted).")
@click.option("--realtime", "realtime", is_flag=True, help="Real time (default for an external host).")
@click.option("--speed", type=FLOAT, default=None, metavar="F", help="Real-time speed factor.")
@click.option("--junit", metavar="OUT.xml", help="Also write the results as JUnit XML.")
@click.option("--state-dir", metavar="DIR", help="Where the devices' non-volatile memory is kept.")
@click.option("--trace-dir", metavar="DIR", help="Write a trace of every port's traffic here.")
@click.option("--motion-log", metavar="FILE.csv", help="Log every axis's motion as CSV (several scenarios:"
              " FILE-SCENARIO.csv).")
@click.option("--motion-resolution", type=FLOAT, default=0.01, show_default=True, metavar="SECONDS",
              help="How often (device time) the motion log samples the axes, besides every event.")
@click.option("--plot", "plot_dir", metavar="DIR", help="Draw one picture per scenario here (extra [plot]).")
@click.option("--plot-format", type=click.Choice(["png", "svg", "html"]), default="png", show_default=True,
              help="The format of the --plot pictures.")
@click.option("--control", metavar="ADDR",
              help="Serve the control API while a scenario runs (devsim monitor, devsim ctl watch).")
@click.option("--web", metavar="[HOST:]PORT", help="Also serve the web page there: the plant and the scenario's steps (extra [web]; host"
              " 127.0.0.1 unless named, another host gets a token).")
def scenario_run(
    files: tuple[str, ...],
    virtual: bool,
    realtime: bool,
    speed: float | None,
    junit: str | None,
    state_dir: str | None,
    trace_dir: str | None,
    motion_log: str | None,
    motion_resolution: float,
    plot_dir: str | None,
    plot_format: str,
    control: str | None,
    web: str | None,
) -> None:
    """Run scenario FILES; exit status 1 if any expectation failed (3: a file is wrong)."""
    from devsim.core.clock import speed_problem
    from devsim.scenario.report import write_junit
    from devsim.scenario.schema import load_scenario

    if speed is not None and (problem := speed_problem(speed)) is not None:
        raise click.UsageError(f"--speed: {problem}")
    check_dirs({"--state-dir": state_dir, "--trace-dir": trace_dir, "--plot": plot_dir})
    if virtual and realtime:  # (the last one won)
        raise click.UsageError("--virtual and --realtime exclude each other")
    if virtual and speed is not None:  # (the speed was ignored, as devsim up refuses the pair)
        raise click.UsageError("--speed and --virtual exclude each other")
    mode = "virtual" if virtual else "realtime" if realtime else None
    pictures = None
    if motion_log is not None or plot_dir is not None:
        from devsim.observe.motion_log import motion_log_problem
        from devsim.scenario.pictures import ScenarioPictures

        if (problem := motion_log_problem(motion_resolution)) is not None:
            raise click.UsageError(problem)
        if plot_dir is not None:
            from devsim.cli.plot import require_matplotlib

            require_matplotlib()
        pictures = ScenarioPictures(motion_log=motion_log, resolution=motion_resolution, plot_dir=plot_dir,
                                    plot_format=plot_format, trace_dir=trace_dir, count=len(files))
    if control is not None:
        from devsim.runtime.control import ControlAddressError, parse_address

        try:
            if not parse_address(control).is_loopback():
                raise click.UsageError(f"--control: refusing non-loopback host {control!r}")
        except ControlAddressError as exc:
            raise click.UsageError(f"--control: {exc}") from None
    listen = None
    if web is not None:
        from devsim.cli.web import web_option

        listen = web_option(web)
        if control is None:
            from devsim.cli.running import default_control

            control = str(default_control("scenario"))
    scenarios = []
    for path in files:
        try:
            scenarios.append(load_scenario(path))
        except ConfigError as exc:
            raise exits.BadFile("\n".join(exc.messages)) from None  # every mistake, one line each
    try:  # (/proc/td: '{scenario}: cannot run the scenario: [Errno 2] ...', no option named)
        make_dirs({"--state-dir": state_dir, "--trace-dir": trace_dir, "--plot": plot_dir})
    except exits.StartFailure as exc:
        raise exits.failure(exc.status, str(exc)) from None
    from devsim.scenario.progress import Progress

    progress = Progress(len(scenarios))
    try:
        with _page(control, listen), _signals_interrupt():
            results = _run_files(scenarios, files, mode, speed, state_dir, trace_dir, pictures, progress, control)
    except KeyboardInterrupt:  # Ctrl-C, SIGTERM, SIGHUP: the plant is stopped (its ports, links) on the way out
        warn("devsim: scenario run interrupted")
        sys.exit(exits.INTERRUPTED)
    if junit is not None:
        try:
            write_junit(results, junit)
        except OSError as exc:  # (the results are printed already: the file alone is missing)
            raise exits.SystemFailure(f"--junit {junit}: {exc.strerror or exc}") from None
    failed = [r for r in results if not r.passed]
    if len(results) > 1:
        click.echo(f"{len(results) - len(failed)} of {len(results)} scenarios passed")
    if failed:
        sys.exit(exits.FAILED)


@contextlib.contextmanager
def _signals_interrupt() -> Iterator[None]:
    """SIGTERM and SIGHUP stop a scenario run as Ctrl-C does (they ended the process at once: no
    word, a pty link left behind)."""
    import signal

    def interrupt(_signum: int, _frame: object) -> None:
        raise KeyboardInterrupt

    previous = {sig: signal.signal(sig, interrupt) for sig in (signal.SIGTERM, signal.SIGHUP)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _page(control: str | None, listen: object) -> contextlib.AbstractContextManager[None]:
    """The web page beside the run (``--web``), or nothing."""
    if listen is None:
        return contextlib.nullcontext()
    from devsim.cli.web import page_beside

    return page_beside(control, listen)


def _run_files(scenarios: list[Any], files: tuple[str, ...], mode: str | None, speed: float | None,
               state_dir: str | None, trace_dir: str | None, pictures: Any, progress: Any,
               control: str | None) -> list[Any]:
    """Run each scenario file in turn, its report on stdout: the results."""
    from devsim.scenario.plant import StateRefused
    from devsim.scenario.report import format_report
    from devsim.scenario.runner import run_scenario
    from devsim.transports.trace import TraceFileError

    results = []
    for item, path in zip(scenarios, files, strict=True):
        chosen = mode or item.mode()
        realtime = chosen == "realtime"
        progress.begin(path, item, realtime=realtime, speed=speed if speed is not None else item.speed)

        def announce(plant: object, chosen: str = chosen) -> None:
            if pictures is not None:
                pictures.start(plant)
            if chosen == "realtime":
                for row in plant.describe():  # type: ignore[attr-defined]
                    say(row)  # (a serving process's line, as `devsim up`'s: a reader gone is no failure)

        try:
            item_trace_dir = pictures.begin(item.path) if pictures is not None else trace_dir  # (makes --plot DIR)
            results.append(
                run_scenario(item, mode=chosen, speed=speed, state_dir=state_dir, trace_dir=item_trace_dir,
                             announce=announce, on_step=progress.step if realtime else None, control=control)
            )
        except TraceFileError as exc:  # (the motion log was said as the scenario's: '{path}: cannot run ...')
            if pictures is None or exc.filename != str(pictures.log_path):
                raise exits.SystemFailure(f"{path}: cannot run the scenario: {exc}") from None
            failure = file_failure("--motion-log" if pictures.motion_log is not None else "--plot", exc)
            raise exits.failure(failure.status, str(failure)) from None
        except (OSError, *_UNUSABLE_MEMORY) as exc:  # a port in use, a directory that cannot be made
            raise exits.SystemFailure(f"{path}: cannot run the scenario: {exc}") from None
        except StateRefused as exc:  # a device refused a value of its state: (a program's text)
            raise exits.BadFile(f"{path}: {exc}") from None
        finally:
            progress.end()
        click.echo(format_report(results[-1]))
        if pictures is not None and (line := pictures.finish(item_trace_dir)) is not None:
            click.echo(line)
    return results


@click.command("up")
@click.argument("plant_file", type=click.Path(dir_okay=False))
@click.option("--state-dir", metavar="DIR", help="Where the devices' non-volatile memory is kept.")
@click.option("--speed", type=FLOAT, default=1.0, show_default=True, metavar="F", help="Time speed factor.")
@click.option("--control", metavar="ADDR", help="Serve the control API on unix:/path.sock or [HOST:]PORT (default:"
              " NAME-PID.sock in the runtime directory, see 'devsim ps').")
@click.option("--no-control", is_flag=True, help="Serve no control API.")
@click.option("--trace-dir", metavar="DIR", help="Write a trace of every port's traffic here.")
@click.option("--virtual", is_flag=True, help="Virtual time: it moves only through 'devsim ctl advance'.")
@click.option("--workers", type=AsciiIntRange(1, 64), default=1, show_default=True, metavar="N",
              help="Spread the plant's devices over N processes (real or sped-up time).")
@click.option("--fleet", metavar="mqtt://BROKER[:PORT][/NAME]",
              help="Join a fleet: announce the devices on the broker, take control requests from it.")
@click.option("--part", metavar="NAME", help="Start only the devices with 'part: NAME' (one part of a fleet's plant).")
@click.option("--motion-log", metavar="FILE.csv", help="Log every axis's motion as CSV, for 'devsim plot'.")
@click.option("--motion-resolution", type=FLOAT, default=0.01, show_default=True, metavar="SECONDS",
              help="How often (device time) the motion log samples the axes, besides every event.")
@click.option("--idle-drop", type=AsciiFloatRange(min=0), default=None, metavar="SECONDS",
              help="Drop a TCP host idle this long when another client finds its port full (default 30).")
@click.option("--web", metavar="[HOST:]PORT", help="Also serve the plant's web page there (extra [web]; host"
              " 127.0.0.1 unless named, another host gets a token).")
@log_options
def up(
    plant_file: str,
    state_dir: str | None,
    speed: float,
    control: str | None,
    no_control: bool,
    trace_dir: str | None,
    virtual: bool,
    workers: int,
    fleet: str | None,
    part: str | None,
    motion_log: str | None,
    motion_resolution: float,
    idle_drop: float | None,
    web: str | None,
    verbose: int,
    quiet: int,
) -> None:
    """Start every device of PLANT_FILE (with --part: those of one part), print every port and
    NAME: ready when a device has booted, serve until Ctrl-C.  Host connects, disconnects, line
    mismatches and device errors are logged to stderr (-v: more, -q: less)."""
    from devsim.cli.running import control_option
    from devsim.scenario.plant import StateRefused
    from devsim.scenario.schema import load_plant

    try:
        spec = load_plant(plant_file)
    except ConfigError as exc:
        raise exits.BadFile("\n".join(exc.messages)) from None  # every mistake, one line each
    if part is not None:
        try:
            spec = spec.only_part(part)
        except ValueError as exc:
            raise click.UsageError(f"--part: {plant_file}: {exc}") from None
    if fleet is not None:
        check_fleet(fleet)
    from devsim.core.clock import speed_problem

    if (problem := speed_problem(speed)) is not None:
        raise click.UsageError(f"--speed: {problem}")
    if virtual and speed != 1.0:
        raise click.UsageError("--speed and --virtual exclude each other")
    check_dirs({"--state-dir": state_dir, "--trace-dir": trace_dir})
    if idle_drop is not None:
        from devsim.transports.hosts import idle_drop_problem

        if (problem := idle_drop_problem(idle_drop)) is not None:
            raise click.UsageError(f"--idle-drop: {problem}")
    name = getattr(spec, "name", None) or Path(plant_file).stem
    if part is not None:
        name = f"{name}.{part}"
    address = control_option(control, no_control, name)
    listen = None
    if web is not None:
        from devsim.cli.web import web_option

        if address is None:
            raise click.UsageError("--web shows the plant through its control API: not with --no-control")
        listen = web_option(web)
    if motion_log is not None:
        from devsim.observe.motion_log import motion_log_problem

        if (problem := motion_log_problem(motion_resolution)) is not None:
            raise click.UsageError(problem)
    if workers > 1:
        # What needs the whole plant in one process: (it applies, why), the first one said.
        one_process = (
            (virtual, "under virtual time a plant stays in one process"),
            (spec.mqtt is not None, "a plant with an mqtt: section stays in one process"),
            (motion_log is not None, "the motion log needs the plant in one process"),
            (spec.opcua is not None, "the plant's OPC UA server needs the plant in one process"),
        )
        reason = next((why for applies, why in one_process if applies), None)
        if reason is not None:
            if level_of(verbose, quiet) >= 1:  # a warning
                click.echo(f"devsim: {reason} (--workers ignored)", err=True)
            workers = 1
    if workers > 1:
        from devsim.scenario.workers import run_workers

        try:
            with _page(str(address), listen):
                status = asyncio.run(run_workers(spec, workers, control=address, name=name, state_dir=state_dir, speed=speed, trace_dir=trace_dir,
                            fleet=fleet, verbose=verbose, quiet=quiet, idle_drop=idle_drop))
        except KeyboardInterrupt:
            sys.exit(exits.INTERRUPTED)
        sys.exit(exits.SYSTEM if status else exits.OK)  # a worker could not start or ended
    try:
        motion = (motion_log, motion_resolution) if motion_log is not None else None
        with _page(str(address), listen):
            asyncio.run(_up(spec, state_dir, speed, address, trace_dir, virtual, fleet, part, motion,
                            level_of(verbose, quiet), name, idle_drop))
    except KeyboardInterrupt:
        sys.exit(exits.INTERRUPTED)
    except (OSError, *_UNUSABLE_MEMORY) as exc:
        raise exits.failure(exits.start_status(exc), f"cannot start the plant: {exc}") from None
    except StateRefused as exc:  # a device refused a value of its state: (a program's text)
        raise exits.BadFile(f"{plant_file}: {exc}") from None
    except exits.StartFailure as exc:
        raise exits.failure(exc.status, str(exc)) from None
    finally:
        gc.enable()  # (_up keeps it off while it builds the plant)


async def _up(
    spec: object, state_dir: str | None, speed: float, address: object, trace_dir: str | None, virtual: bool,
    fleet: str | None = None, part: str | None = None, motion: tuple[str, float] | None = None,
    log_level: int = 2, name: str = "devsim", idle_drop: float | None = None,
) -> None:
    from devsim.runtime import Runtime
    from devsim.runtime.control import ControlServer
    from devsim.scenario.plant import build_plant

    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    unsignal = stop_on_signals(loop, stop.set)
    from devsim.scenario.workers import end_with_parent

    end_with_parent(loop, stop.set)  # a worker of `devsim up --workers` ends with it
    make_dirs({"--state-dir": state_dir, "--trace-dir": trace_dir})  # (/proc/td: 'cannot start the plant: ...')
    limit = fdlimit.fd_limit()
    control = address is not None  # (its clients' share of the descriptors is kept from the ports)
    if log_level >= DEFAULT_LEVEL:  # (-q: warnings and errors only)
        warn(f"devsim: the file descriptor limit {limit} allows about {fdlimit.capacity(limit, control=control)} ports")
    async with Runtime(virtual=virtual, speed=speed, state_dir=state_dir, name=name) as runtime:
        runtime.idle_drop = idle_drop
        # (building a plant makes many objects and frees few: no collection until it serves, as
        # `devsim run` does; a 1,000-device worker otherwise paused 60-180 ms in full collections)
        gc.disable()  # (enabled again once frozen, or by `up` whatever happens)
        plant = await build_plant(runtime, spec, trace_dir=trace_dir, keep_going=True, control=control)  # type: ignore[arg-type]
        if plant.refused and log_level >= 1:  # a warning (-qq: nothing but fatal errors)
            causes = sorted(set(plant.refused.values()))
            warn(f"devsim: {len(plant.refused)} ports not opened ({'; '.join(causes)}; ulimit -n {limit}):"
                 f" {', '.join(list(plant.refused)[:5])}{' ...' if len(plant.refused) > 5 else ''}")
        if motion is not None:
            from devsim.observe.motion_log import start_motion_log
            from devsim.transports.trace import TraceFileError

            try:
                start_motion_log(runtime, list(plant.devices.values()), *motion)
            except TraceFileError as exc:  # (it was 'cannot start the plant: [Errno 21] ...')
                raise file_failure("--motion-log", exc) from None
        server = None
        if address is not None:
            server = ControlServer(runtime, address)  # type: ignore[arg-type]
            shown = await server.start()
        member = None
        if fleet is not None:
            from devsim.fleet.member import FleetClash, join_fleet

            about = {"plant": getattr(spec, "name", None), "part": part}
            try:
                member = await join_fleet(runtime, fleet, about={k: v for k, v in about.items() if v is not None})
            except (FleetClash, ConnectionError) as exc:
                if server is not None:
                    await server.close()
                raise exits.StartFailure(f"cannot join the fleet {fleet}: {exc}", exits.start_status(exc)) from None
        for row in plant.describe():
            say(row)
        if server is not None:
            say(f"control: {shown}")
        if member is not None:
            say(f"fleet: {member.url} as {member.process}")
        for device in plant.devices.values():
            device.on_ready(lambda name=device.name: say(f"{name}: ready"))
        logs = attach_log(runtime, log_level)
        title = f"plant {spec.name!r} up" if getattr(spec, "name", None) else "plant up"
        if log_level >= DEFAULT_LEVEL:
            warn(f"devsim: {title} ({_count(len(plant.devices), 'device')}); Ctrl-C to stop")
        # As `devsim run` does: what exists now lives as long as the process, so keep it out of
        # the garbage collector's scans.  Unfrozen, a full collection of a 1,000-device worker
        # takes about 70 ms, and every device of the worker misses a poll meanwhile.
        gc.freeze()
        gc.enable()
        try:
            await stop.wait()
        finally:
            for log in logs:  # the repeat counts not yet written are written now
                log.stop()
            if server is not None:
                await server.close()
    unsignal()

