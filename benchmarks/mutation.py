"""Mutation testing, one module at a time against its own tests (issue 35).

mutmut (3.x, the ``[mutation]`` extra) changes one thing at a time in a module (a comparison
flipped, a constant moved by one, a statement removed) and runs the tests that exercise it: a
mutant the tests notice is *killed*, one they miss *survived*.  A survivor is either a blind spot
(write the test that states the boundary) or *equivalent*: it changes nothing a user could see,
and then it is listed in ``benchmarks/mutation_equivalent.toml`` with the reason.

Each module runs in its own work directory, ``.mutation/<module>/`` (the module's
``[tool.mutmut]`` settings in a copy of ``pyproject.toml``, the sources and tests linked), so the
results of one module stay while another runs.  Runs are niced and one mutant at a time; the
per-mutant timeout is mutmut's CPU-time limit (a multiple of the tests' own time).

    python benchmarks/mutation.py                       # every module in MODULES
    python benchmarks/mutation.py --module sers/codec   # one (a unique part of its path)
    python benchmarks/mutation.py --module sers/codec --survivors   # re-run only last survivors
    python benchmarks/mutation.py --report --list-survivors         # no run: last results, diffs
    python benchmarks/mutation.py --module sers/codec --tests-from main   # the tests of a revision

Not part of the default CI run (minutes per module).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WORK = ROOT / ".mutation"
EQUIVALENTS = Path(__file__).resolve().with_name("mutation_equivalent.toml")

#: Module -> the tests that exercise it (the smallest subset that does).
MODULES: dict[str, tuple[str, ...]] = {
    "devsim/devices/sers/codec.py": (
        "tests/sers/test_codec_boundaries.py",
        "tests/sers/test_fuzz.py::test_framer_accepts_any_bytes",
        "tests/sers/test_line_limit.py",
        "tests/sers/test_noise_paths.py",
        "tests/sers/test_interface.py",
        "tests/sers/test_manual_syntax.py",
    ),
    # the SERS face's one-step noise path, against the byte-by-byte path (helper s8-noise)
    "devsim/devices/sers/noise.py": (
        "tests/sers/test_noise_paths.py",
    ),
    "devsim/devices/gms96/codec.py": (
        "tests/gms96/test_codec.py",
        "tests/gms96/test_frame_limit.py",
        "tests/gms96/test_codec_boundaries.py",
        "tests/gms96/test_poll_path.py",  # the poll fast path: the K answer bytes, the whole-frame chunks
    ),
    "devsim/devices/pcd4h3/sbus.py": (
        "tests/pcd4h3/test_sbus.py",
        "tests/pcd4h3/test_link_vectors.py",
        "tests/pcd4h3/test_sbus_boundaries.py",
    ),
    "devsim/devices/ip247/as511.py": (
        "tests/ip247/test_as511.py",
        "tests/ip247/test_as511_boundaries.py",
    ),
    "devsim/devices/poselesta/tape.py": (
        "tests/poselesta/test_tape.py",
        "tests/poselesta/test_tape_boundaries.py",
        "tests/poselesta/test_tape_text.py",
    ),
    # the facade maps and the kit (helper mut-core)
    "devsim/facades/modbus_map.py": (
        "tests/facades/test_modbus_map.py",
    ),
    "devsim/facades/modbus_pdu.py": (
        "tests/facades/test_modbus_pdu.py",
    ),
    "devsim/core/points.py": (
        "tests/core/test_points.py",
    ),
    "devsim/core/axis.py": (
        "tests/core/test_axis.py",
        "tests/core/test_path.py",
    ),
    "devsim/core/clock.py": (
        "tests/core/test_clock.py",
    ),
    "devsim/core/settings.py": (  # not test_settings.py's two import checks: mutmut imports dataclasses
        "tests/core/test_settings_reference.py",
        "tests/test_settings.py::test_defaults_conversions_and_values",
        "tests/test_settings.py::test_each_problem_is_named",
        "tests/test_settings.py::test_problems_in_a_file_name_their_line",
        "tests/test_settings.py::test_rows_document_every_key",
    ),
    "devsim/facades/mqtt_topics.py": (
        "tests/facades/test_mqtt_topics.py",
    ),
    "devsim/facades/opcua_space.py": (
        "tests/facades/test_opcua_space.py",
    ),
    "devsim/facades/canopen_od.py": (
        "tests/facades/test_canopen.py",
    ),
    # the framings record, replay and the telegram tap take from a kind's ports, the member's MQTT
    # packets and the pcap records (helper mut-framing)
    "devsim/core/framing.py": (
        "tests/core/test_framing.py",
        "tests/replay/test_session.py",
    ),
    "devsim/devices/sers/framing.py": (
        "tests/sers/test_framing.py",
        "tests/replay/test_session.py",
    ),
    "devsim/devices/gms96/framing.py": (
        "tests/gms96/test_framing.py",
        "tests/replay/test_session.py",
    ),
    "devsim/devices/pcd4h3/framing.py": (
        "tests/pcd4h3/test_framing.py",
        "tests/replay/test_session.py",
    ),
    "devsim/facades/mqtt_wire.py": (
        "tests/facades/test_mqtt_wire.py",
        "tests/facades/test_mqtt_wire_boundaries.py",
    ),
    "devsim/transports/pcap.py": (
        "tests/transports/test_pcap.py",
        "tests/transports/test_pcap_boundaries.py",
    ),
    # pure codecs found beside them: the POSELESTA's ISO/ASCII and baud-rate codes, the IP247's
    # BCD values and records to and from the PLC
    "devsim/devices/poselesta/codes.py": (
        "tests/poselesta/test_codes.py",
    ),
    "devsim/devices/ip247/values.py": (
        "tests/ip247/test_values.py",
        "tests/ip247/test_values_boundaries.py",
    ),
    "devsim/devices/ip247/pg_profile.py": (
        "tests/ip247/test_pg_profile.py",
        "tests/ip247/test_pg_profile_boundaries.py",
    ),
    "devsim/devices/ip247/s5_services.py": (
        "tests/ip247/test_s5_services.py",
    ),
    "devsim/core/words.py": (
        "tests/core/test_words.py",
    ),
    "devsim/fleet/topics.py": (  # the fleet URL and topic names
        "tests/fleet/test_topics.py",
        "tests/fleet/test_topics_boundaries.py",
    ),
    # the facade codecs (helper mut-facades)
    "devsim/facades/canopen_sdo.py": (
        "tests/facades/test_canopen_sdo.py",
    ),
    "devsim/facades/mqtt_sparkplug.py": (
        "tests/facades/test_sparkplug_payloads.py",
    ),
    "devsim/facades/cia402.py": (
        "tests/facades/test_cia402_machine.py",
    ),
    "devsim/facades/mqtt_events.py": (
        "tests/facades/test_sample_on_event.py",
    ),
}

#: mutmut's exit-code meanings, folded into the columns printed.
_STATUS = {1: "killed", 3: "killed", 0: "survived", 5: "no tests", 33: "no tests", 34: "skipped",
           36: "timeout", -24: "timeout", 24: "timeout", 152: "timeout", 255: "timeout", None: "not run"}
COLUMNS = ("killed", "timeout", "survived", "equivalent", "no tests", "other")


@dataclass
class Mutant:
    name: str  # mutmut's key, e.g. devsim.devices.sers.codec.xǁFramerǁfeed__mutmut_3
    status: str
    function: str = ""  # Framer.feed
    original: str = ""  # the first line the mutant changes, stripped
    mutated: str = ""
    diff: str = ""


@dataclass
class Result:
    module: str
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(COLUMNS, 0))
    survivors: list[Mutant] = field(default_factory=list)

    @property
    def rate(self) -> float | None:
        """Killed (a timeout is a kill: the mutant hangs where the code does not) over the
        non-equivalent mutants that ran."""
        caught = self.counts["killed"] + self.counts["timeout"]
        total = caught + self.counts["survived"] + self.counts["no tests"] + self.counts["other"]
        return None if total == 0 else caught / total


def slug(module: str) -> str:
    return module.removeprefix("devsim/").removesuffix(".py").replace("/", ".")


def pick(names: list[str]) -> list[str]:
    """The modules named (a unique part of the path each), or all."""
    if not names:
        return list(MODULES)
    chosen = []
    for name in names:
        found = [m for m in MODULES if name in m]
        if len(found) != 1:
            raise SystemExit(f"--module {name}: matches {found or 'no module'} of {list(MODULES)}")
        chosen.append(found[0])
    return chosen


def _pyproject(module: str, work: Path) -> str:
    """The project's pyproject.toml with this module's [tool.mutmut] instead of any other (its
    tests that exist in ``work``: a revision's tests may not have them all yet)."""
    text = (ROOT / "pyproject.toml").read_text()
    text = re.sub(r"(?ms)^\[tool\.mutmut\].*?(?=^\[|\Z)", "", text)
    present = [t for t in MODULES[module] if (work / t.partition("::")[0]).exists()]
    for missing in sorted(set(MODULES[module]) - set(present)):
        print(f"{module}: {missing} is not in these tests, left out")
    tests = ", ".join(json.dumps(t) for t in present)
    return text.rstrip() + f"""

[tool.mutmut]
source_paths = ["devsim"]
only_mutate = [{json.dumps(module)}]
pytest_add_cli_args = ["-x", "-q", "-p", "no:cacheprovider", "-p", "no:randomly"]
pytest_add_cli_args_test_selection = [{tests}]
timeout_multiplier = 5.0
timeout_constant = 5.0
use_git_change_detection = false
also_copy = ["docs"]
"""


def prepare(module: str, fresh: bool, tests_from: str | None = None) -> Path:
    """The module's work directory: its pyproject, a link to the sources, and the tests: a link
    to the checkout's, or (``tests_from``) those of a git revision, for figures before a change."""
    work = WORK / slug(module)
    if fresh and (work / "mutants").exists():
        shutil.rmtree(work / "mutants")
    work.mkdir(parents=True, exist_ok=True)
    for name in ("devsim", "docs"):  # docs: tests compare generated files with it (docs/eds/)
        source = work / name
        if not source.is_symlink():
            source.symlink_to(ROOT / name, target_is_directory=True)
    tests = work / "tests"
    if tests.is_symlink():
        tests.unlink()
    elif tests.exists():
        shutil.rmtree(tests)
    if tests_from is None:
        tests.symlink_to(ROOT / "tests", target_is_directory=True)
    else:
        archive = subprocess.run(["git", "archive", tests_from, "tests"], cwd=ROOT, check=True,
                                 capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(work)], input=archive, check=True)
    (work / "pyproject.toml").write_text(_pyproject(module, work))
    return work


def _mutmut(work: Path, *args: str) -> int:
    exe = Path(sys.executable).with_name("mutmut")
    command = ["nice", "-n", "15", str(exe), *args]
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    return subprocess.call(command, cwd=work, env=env)


def run(module: str, survivors_only: bool, tests_from: str | None = None) -> None:
    if not survivors_only:
        _mutmut(prepare(module, fresh=True, tests_from=tests_from), "run", "--max-children", "1")
        return
    names = [m.name for m in collect(module).survivors]
    if not names:
        print(f"{module}: no survivors to re-run")
        return
    # Only the survivors run again (against the tests as they are now: mutmut copies them
    # afresh).  mutmut forgets every verdict when the test selection changed; a mutant killed
    # before stays killed by more tests, so the earlier verdicts of the others are kept.
    earlier = json.loads(_meta(module).read_text())["exit_code_by_key"]
    work = prepare(module, fresh=False, tests_from=tests_from)
    _mutmut(work, "run", "--max-children", "1", *names)
    meta = _meta(module)
    data = json.loads(meta.read_text())
    for name, code in earlier.items():
        if name not in names and data["exit_code_by_key"].get(name) is None:
            data["exit_code_by_key"][name] = code
    meta.write_text(json.dumps(data, indent=4))


def _meta(module: str) -> Path:
    return WORK / slug(module) / "mutants" / (module + ".meta")


def _function(name: str) -> str:
    """``devsim.x.codec.xǁFramerǁfeed__mutmut_3`` -> ``Framer.feed``; ``x_address_value`` ->
    ``address_value``."""
    local = name.rpartition(".")[2].rpartition("__mutmut_")[0]
    if local.startswith("xǁ"):
        return ".".join(local[2:].split("ǁ"))
    return local.removeprefix("x_")


def _diff(module: str, name: str) -> str:
    from mutmut.mutation.diff_apply import get_diff_for_mutant

    work = WORK / slug(module)
    cwd = os.getcwd()
    os.chdir(work)
    try:
        return get_diff_for_mutant(name, path=module)
    finally:
        os.chdir(cwd)


def _changed_lines(diff: str) -> tuple[str, str]:
    removed = [line[1:].strip() for line in diff.splitlines() if line.startswith("-") and not line.startswith("---")]
    added = [line[1:].strip() for line in diff.splitlines() if line.startswith("+") and not line.startswith("+++")]
    return (removed[0] if removed else ""), (added[0] if added else "")


def equivalents() -> list[dict[str, str]]:
    if not EQUIVALENTS.exists():
        return []
    return tomllib.loads(EQUIVALENTS.read_text()).get("equivalent", [])


def collect(module: str) -> Result:
    """The last run's results of ``module``, equivalents taken out."""
    result = Result(module)
    meta = _meta(module)
    if not meta.exists():
        return result
    codes = json.loads(meta.read_text())["exit_code_by_key"]
    listed = [e for e in equivalents() if e["module"] == module]
    for name, code in sorted(codes.items(), key=lambda kv: _natural(kv[0])):
        status = _STATUS.get(code, "other")
        if status in ("skipped", "not run"):
            continue
        if status in ("survived", "no tests"):
            mutant = Mutant(name, status, _function(name))
            mutant.diff = _diff(module, name)
            mutant.original, mutant.mutated = _changed_lines(mutant.diff)
            if any(_matches(e, mutant) for e in listed):
                status = "equivalent"
            else:
                result.survivors.append(mutant)
        result.counts[status] += 1
    return result


def _natural(name: str) -> tuple[str, int]:
    base, _, number = name.rpartition("__mutmut_")
    return base, int(number) if number.isdigit() else 0


def _matches(entry: dict[str, str], mutant: Mutant) -> bool:
    """By function and changed line; where a function has the same line twice, the entry also
    names mutmut's number of the mutant (``number``, stable while the function is unchanged)."""
    number = mutant.name.rpartition("__mutmut_")[2]
    return (entry["function"] == mutant.function and entry["original"] == mutant.original
            and entry["mutated"] == mutant.mutated and str(entry.get("number", number)) == number)


def report(results: list[Result], list_survivors: bool) -> None:
    width = max(len(r.module) for r in results)
    print(f"{'module':<{width}}  " + "  ".join(f"{c:>10}" for c in COLUMNS) + "   kill rate")
    for r in results:
        rate = "-" if r.rate is None else f"{100 * r.rate:.1f} %"
        print(f"{r.module:<{width}}  " + "  ".join(f"{r.counts[c]:>10}" for c in COLUMNS) + f"   {rate:>9}")
    if list_survivors:
        for r in results:
            for m in r.survivors:
                print(f"\n# {r.module} {m.function} ({m.name.rpartition('__')[2]}, {m.status})")
                print("\n".join(m.diff.splitlines()[2:]))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--module", action="append", default=[], help="a unique part of a module's path (repeatable)")
    parser.add_argument("--report", action="store_true", help="no run: print the last results")
    parser.add_argument("--survivors", action="store_true", help="re-run only the last run's survivors")
    parser.add_argument("--list-survivors", action="store_true", help="print each surviving mutant's diff")
    parser.add_argument("--tests-from", metavar="REV",
                        help="run against the tests of a git revision (figures before a change)")
    args = parser.parse_args(argv)
    modules = pick(args.module)
    if not args.report:
        for module in modules:
            run(module, args.survivors, args.tests_from)
    report([collect(m) for m in modules], args.list_survivors)
    return 0


if __name__ == "__main__":
    sys.exit(main())
