"""`devsim check FILES` names every mistake of every file in one pass (schema errors and
misspelled names together, one `file:line: field: message` line each, steps and devices counted
as the file reads them, from 1), through the real command."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from devsim.cli import exits
from tests.support.process import ROOT, devsim_env

SCENARIO = """\
devices:
  - name: x
    kind: sers
    config: {address: 1, baud: 9601}
    state:
      input.limit_rigth: true
  - name: y
    kind: toaster
steps:
  - at: 1s
    send: "#ON"
  - after: soon
    log: x
  - set: {device: x, values: {quantity.supply_voltage: hello}}
  - fault: {device: x, kind: smoke}
  - expect_state: {device: z, name: axis.position, equals: 0}
  - when: {device: x, name: axis.positon, ge: 0}
  - sned: a
  - pulse: {device: x, input: I99}
"""

PLANT = """\
devices:
  - name: a
    kind: sers
    transport: {bus: line}
  - name: a
    kind: gms96
    state: {axis.positon: 3}
"""

GOOD = "devices:\n  - {name: x, kind: sers}\nsteps:\n  - wait: 1s\n"


def check(*paths: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "devsim", "check", *map(str, paths)], cwd=ROOT, env=devsim_env(),
                          capture_output=True, text=True, timeout=60)


def mistakes(tmp_path: Path, text: str) -> tuple[Path, list[str]]:
    """``text`` as a file that `devsim check` refuses (status 3): the file and the lines it says."""
    bad = tmp_path / "bad.yaml"
    bad.write_text(text, encoding="utf-8")
    done = check(bad)
    assert done.returncode == exits.BAD_FILE, done.stdout
    return bad, done.stderr.splitlines()


def up_refuses(bad: Path) -> str:
    """`devsim up` refuses the file as `check` does (status 3, one line, no traceback): its stderr."""
    done = subprocess.run([sys.executable, "-m", "devsim", "up", str(bad)], cwd=ROOT, env=devsim_env(),
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == exits.BAD_FILE and "Traceback" not in done.stderr, done.stderr
    return done.stderr


def test_every_mistake_of_every_file_in_one_pass(tmp_path: Path) -> None:
    scenario, plant, good = tmp_path / "s.yaml", tmp_path / "plant.yaml", tmp_path / "good.yaml"
    scenario.write_text(SCENARIO)
    plant.write_text(PLANT)
    good.write_text(GOOD)
    done = check(scenario, good, plant)
    assert done.returncode == exits.BAD_FILE
    assert done.stdout == f"{good}: ok (scenario, 1 step, 1 device)\n"
    lines = [line.replace(str(tmp_path) + "/", "") for line in done.stderr.splitlines()]
    assert lines == [
        "s.yaml:4: devices.1.config.baud: baud must be one of 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200",
        "s.yaml:6: devices.1.state.input.limit_rigth: x has no 'input.limit_rigth'"
        " (did you mean input.limit_right, input.limit_left?)",
        "s.yaml:8: devices.2.kind: unknown device kind 'toaster' (known: gms96, ip247, pcd4h3, poselesta, sers)",
        "s.yaml:12: steps.2.after: `after` must be a duration like 2s or 150ms",
        "s.yaml:14: steps.3.set.values.quantity.supply_voltage: quantity.supply_voltage: expects a number, not 'hello'",
        "s.yaml:15: steps.4.fault.kind: sers has no fault 'smoke' (declared: blocked_axis, emergency_stop, power,"
        " power_cycle, power_cycle_wipe, power_off, power_on)",
        "s.yaml:16: steps.5.expect_state.device: no device named 'z'",
        "s.yaml:17: steps.6.when.name: x has no 'axis.positon' (did you mean axis.position, position, axis.moving?)",
        "s.yaml:18: steps.7.sned: unknown field",
        lines[9],  # the pulse's input, worded by the kind
        "plant.yaml:4: devices.1.transport.bus: device 'a' is on bus 'line', which is not defined",
        "plant.yaml:5: devices.2.name: the name 'a' is used twice",
        lines[12],
    ]
    assert lines[9].startswith("s.yaml:19: steps.8.pulse.input: x has no 'input.I99'")
    assert lines[12].startswith("plant.yaml:7: devices.2.state.axis.positon: a has no 'axis.positon'")


def test_the_shipped_scenarios_pass() -> None:
    files = sorted((ROOT / "scenarios").rglob("*.yaml"))
    done = check(*files)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert [line.split(": ok (")[0] for line in done.stdout.splitlines()] == list(map(str, files))


def test_up_and_scenario_run_refuse_a_bad_file_with_every_mistake(tmp_path: Path) -> None:
    plant = tmp_path / "plant.yaml"
    plant.write_text(PLANT)
    for command in (["up", str(plant)], ["scenario", "run", str(plant)]):
        done = subprocess.run([sys.executable, "-m", "devsim", *command], cwd=ROOT, env=devsim_env(),
                              capture_output=True, text=True, timeout=60)
        assert done.returncode == exits.BAD_FILE
        lines = done.stderr.replace(str(tmp_path) + "/", "").splitlines()
        assert [line.split(": ")[0:2] for line in lines] == [
            ["Error", "plant.yaml:4"], ["plant.yaml:5", "devices.2.name"], ["plant.yaml:7", "devices.2.state.axis.positon"]]


def test_a_device_that_fails_the_schema_still_counts_for_the_steps(tmp_path: Path) -> None:
    """Steps are checked against every device named in the file: a device that failed the schema
    is no reason to call it missing, nor to leave a misspelled one unreported."""
    path = tmp_path / "partial.yaml"
    path.write_text("devices:\n  - {name: x, kind: sers, axis: {limit_right: hello}}\n  - {name: 1bad, kind: sers}\n"
                    "steps:\n  - set: {device: x, values: {input.I1: 2}}\n"
                    "  - set: {device: 1bad, values: {input.I1: true}}\n"
                    "  - set: {device: nobody, values: {input.I1: true}}\n")
    done = check(path)
    assert done.returncode == exits.BAD_FILE
    assert [line.split(": ")[0:2] for line in done.stderr.replace(str(tmp_path) + "/", "").splitlines()] == [
        ["partial.yaml:2", "devices.1.axis.limit_right"], ["partial.yaml:3", "devices.2.name"],
        ["partial.yaml:5", "steps.1.set.values.input.I1"], ["partial.yaml:7", "steps.3.set.device"]]


def test_devices_that_are_no_list_are_one_mistake(tmp_path: Path) -> None:
    """(Fuzzed: ``devices: -1.0e+308`` made `devsim check` and `devsim scenario run` end in a
    traceback, ``TypeError: 'float' object is not iterable``.)  The steps' devices are not called
    missing: the file names none that could be read."""
    for value in ("-1.0e+308", "true", "7"):
        bad, lines = mistakes(tmp_path, f"devices: {value}\nsteps:\n  - set: {{device: x, values: {{input.I1: true}}}}\n")
        assert lines == [f"{bad}:1: devices: Input should be a valid list"]


def test_a_plant_given_as_data_counts_from_1_too() -> None:
    """The Python API (a plant or scenario as a dict) numbers list items as a file does."""
    import pytest

    from devsim.core.typed import Invalid
    from devsim.scenario.schema import PlantSpec, scenario_from_dict

    with pytest.raises(Invalid, match=r"^devices\.2\.colour: unknown field$"):
        PlantSpec.parse({"devices": [{"name": "a", "kind": "sers"}, {"name": "b", "kind": "sers", "colour": 1}]})
    with pytest.raises(Invalid, match=r"^steps\.2\.fault\.device: no device named 'b'$"):
        scenario_from_dict({"devices": [{"name": "a", "kind": "sers"}],
                            "steps": [{"wait": "1s"}, {"fault": {"device": "b", "kind": "power_off"}}]})


def test_each_part_of_a_step_is_checked_against_its_own_devices_kind(tmp_path: Path) -> None:
    """A step that waits on a GMS96 and checks a SERS: each name against its own device's kind,
    not both against the first's (which refused memory_status, a GMS96 name, and let input.I3
    on the GMS96 through)."""
    good = tmp_path / "good.yaml"
    good.write_text("devices:\n  - {name: s, kind: sers}\n  - {name: g, kind: gms96}\nsteps:\n"
                    "  - when: {device: s, name: energized, equals: false}\n"
                    "    expect_state: {device: g, name: memory_status, equals: 0}\n")
    done = check(good)
    assert done.returncode == 0, done.stderr
    bad, [line] = mistakes(tmp_path, "devices:\n  - {name: s, kind: sers}\n  - {name: g, kind: gms96}\nsteps:\n"
                           "  - when: {device: s, name: input.I3, equals: false}\n"
                           "    expect_state: {device: g, name: input.I3, equals: true}\n")
    assert line.startswith(f"{bad}:6: steps.1.expect_state.name: g has no 'input.I3'"), line


def test_a_traffic_regex_and_a_character_that_is_no_byte_are_mistakes_of_the_file(tmp_path: Path) -> None:
    """Both passed `check` and then stopped the run with a traceback (re.error, UnicodeEncodeError)."""
    bad, lines = mistakes(tmp_path, 'devices:\n  - {name: x, kind: sers}\nsteps:\n  - send: "#1\\r"\n'
                          '  - expect_traffic: {regex: "P11=(", direction: device}\n  - expect: {bytes: "\u20ac"}\n'
                          '  - send: "\u20ac"\n')
    assert lines == [
        f"{bad}:5: steps.2.expect_traffic: bad regex: missing ), unterminated subpattern at position 4",
        f"{bad}:6: steps.3.expect: '\u20ac' is no byte: the line's text is latin-1 (one character a byte, \\xNN for any byte)",
        f"{bad}:7: steps.4.send: '\u20ac' is no byte: the line's text is latin-1 (one character a byte, \\xNN for any byte)",
    ]


def test_an_expectation_that_cannot_fail_is_a_mistake_of_the_file(tmp_path: Path) -> None:
    """An empty answer, or a regex that matches nothing at all, passed whatever the device said (a
    user's ``expect: ""`` for "no answer" passed after the drive had answered)."""
    bad, lines = mistakes(tmp_path, 'devices:\n  - {name: x, kind: sers}\nsteps:\n  - send: "#1 ON\\r"\n'
                          '  - expect: ""\n  - expect: {regex: "(ok)?"}\n  - expect_traffic: {regex: "", count: 0}\n'
                          '  - expect_traffic: {regex: "ok", direction: device, count: 0}\n')
    silence = "(that it says nothing: expect_traffic with direction: device and count: 0)"
    assert lines == [
        f"{bad}:5: steps.2.expect: an empty answer is there at once, whatever the device says {silence}",
        f"{bad}:6: steps.3.expect: the regex matches nothing at all, so it holds at once, whatever the device says "
        f"{silence}",
        f"{bad}:7: steps.4.expect_traffic: the regex matches nothing at all: it would count the gaps between bytes",
    ]


def test_what_the_loader_fills_in_is_no_key_of_the_file(tmp_path: Path) -> None:
    """A step's ``line`` and a scenario's ``path`` (its place, filled in by the loader): a
    ``- line: "#E"`` step was told to be an integer, a ``path:`` was taken and overwritten."""
    bad, lines = mistakes(tmp_path, 'path: /etc/passwd\ndevices:\n  - {name: x, kind: sers}\nsteps:\n'
                          '  - line: "#E"\n  - wait: 1s\n    line: 5\n')
    assert lines == [f"{bad}:1: path: unknown field", f"{bad}:5: steps.1.line: unknown field",
                     f"{bad}:7: steps.2.line: unknown field"]


def test_an_empty_link_is_a_mistake_of_the_file(tmp_path: Path) -> None:
    """It passed `check`, and `up` and `scenario run` ended with a traceback."""
    bad = tmp_path / "bad.yaml"
    bad.write_text('devices:\n  - {name: x, kind: sers, transport: {pty: {link: ""}}}\n')
    done = check(bad)
    assert done.returncode == exits.BAD_FILE
    assert done.stderr == f"{bad}:2: devices.1.transport.pty.link: String should have at least 1 character\n"


def test_two_ports_on_one_link_or_one_tcp_port_are_a_mistake_of_the_file(tmp_path: Path) -> None:
    """They passed `check`; `up` then said the link was held by a live process (itself) and to
    choose another --link (no option of up), or 'Address already in use' (status 6)."""
    link = tmp_path / "tty1"
    bad, lines = mistakes(tmp_path, f"devices:\n  - {{name: a, kind: sers, transport: {{tcp: {{port: 23456}}}}}}\n"
                          f"  - {{name: b, kind: sers, transport: {{tcp: {{port: 23456}}}}}}\n"
                          f"  - {{name: c, kind: sers, transport: {{pty: {{link: {link}}}}}}}\n"
                          f"  - {{name: d, kind: sers, transport: {{pty: {{link: {link}}}}}}}\n"
                          "  - {name: e, kind: sers, transport: {tcp: {port: 0}}}\n"
                          "  - {name: f, kind: sers, transport: {tcp: {port: 0}}}\n")
    assert lines == [
        f"{bad}:3: devices.2.transport: tcp port 127.0.0.1:23456 is taken by devices.1.transport already",
        f"{bad}:5: devices.4.transport: link {link} is taken by devices.3.transport already",
    ]


def test_a_plant_file_may_say_what_it_is(tmp_path: Path) -> None:
    """`description:`, which a scenario file takes, was an unknown field in a plant file."""
    plant = tmp_path / "plant.yaml"
    plant.write_text("name: cell\ndescription: two drives on a bench\ndevices:\n  - {name: x, kind: sers}\n")
    done = check(plant)
    assert done.returncode == 0 and done.stdout.strip() == f"{plant}: ok (plant, 1 device)", done.stderr


def test_every_bad_parameter_of_a_config_at_its_own_line(tmp_path: Path) -> None:
    """A range rule on each entry of a mapping (Keys' entry): every parameter out of its range,
    at its own line and name (only the first was named, at the params: line, and none while
    another key was unknown)."""
    bad, lines = mistakes(tmp_path, "devices:\n  - name: y\n    kind: sers\n    config:\n      params:\n"
                          "        V: -5\n        A: -7\n        P9999: 1\n  - name: g\n    kind: gms96\n"
                          "    config: {params: {N10: 99999999, N11: 1}}\n")
    assert lines == [
        f"{bad}:6: devices.1.config.params.V: -5 is below the minimum 0",
        f"{bad}:7: devices.1.config.params.A: -7 is below the minimum 2",
        f"{bad}:8: devices.1.config.params.P9999: no such parameter",
        f"{bad}:11: devices.2.config.params.N10: 99999999 is outside 1 … 3000",
        f"{bad}:11: devices.2.config.params.N11: 1 is outside 50 … 255",
    ]


BUS_PLANT = """\
devices:
  - {{name: a, kind: sers, transport: {{bus: line}}, config: {{address: {a}}}}}
  - {{name: b, kind: sers, transport: {{bus: line}}, config: {{address: {b}}}}}
  - {{name: c, kind: sers, transport: {{bus: other}}, config: {{address: {a}}}}}
  - {{name: d, kind: sers, config: {{address: {a}}}}}
  - {{name: g1, kind: gms96, transport: {{bus: cards}}, config: {{dil: {{address: {a}}}}}}}
  - {{name: g2, kind: gms96, transport: {{bus: cards}}, config: {{dil: {{address: {b}}}}}}}
  - {{name: p1, kind: pcd4h3, transport: {{bus: plcs}}, config: {{station: {a}}}}}
  - {{name: p2, kind: pcd4h3, transport: {{bus: plcs}}, config: {{station: {b}}}}}
buses:
  - {{name: line}}
  - {{name: other}}
  - {{name: cards}}
  - {{name: plcs}}
"""


def test_two_devices_at_one_address_on_one_bus_are_a_mistake_of_the_file(tmp_path: Path) -> None:
    """Two stations set to one address on one RS-485 line both take the telegrams meant for it and
    answer together (SERS manual §4.1: "Nach dem Senden der Adresse sind alle folgenden Kommandos
    und Parameter-Zuweisungen dem entsprechenden Antrieb zugeordnet. Alle anderen angeschlossenen
    Antriebe ignorieren die Kommandos"; GMS96 manual §2.2: "Die ersten 4 Steller ermöglichen die
    Adresswahl zwischen 0 und 15", §2.3: "<Adresszeichen><Befehlszeichen>").  `devsim check` and
    `devsim up` took such a plant; `devsim run --drives 1,1` refused it.  The address is where the kind's port declares it (SERS `address`, GMS96
    `dil.address`, PCD4.H3 `station`), its default when the file gives none; the same address on
    another bus, or on a device with a line of its own, is no mistake."""
    bad, lines = mistakes(tmp_path, BUS_PLANT.format(a=3, b=3))
    assert lines == [
        f"{bad}:3: devices.2.config.address: devices 'a' and 'b' are both at address 3 on bus 'line'",
        f"{bad}:7: devices.6.config.dil.address: devices 'g1' and 'g2' are both at dil.address 3 on bus 'cards'",
        f"{bad}:9: devices.8.config.station: devices 'p1' and 'p2' are both at station 3 on bus 'plcs'",
    ]
    defaults = "devices:\n" + "".join(f"  - {{name: g{n}, kind: gms96, transport: {{bus: cards}}}}\n" for n in (1, 2, 3))
    bad, lines = mistakes(tmp_path, defaults + "buses:\n  - {name: cards}\n")
    assert lines == [f"{bad}:3: devices.2.config: devices 'g1' and 'g2' are both at dil.address 3 on bus 'cards'",
                     f"{bad}:4: devices.3.config: devices 'g1' and 'g3' are both at dil.address 3 on bus 'cards'"]
    good = tmp_path / "good.yaml"
    good.write_text(BUS_PLANT.format(a=3, b=4), encoding="utf-8")
    done = check(good)
    assert done.returncode == 0 and done.stdout == f"{good}: ok (plant, 8 devices)\n", done.stderr
    assert "devices 'g1' and 'g2' are both at dil.address 3" in up_refuses(bad)


def test_devices_on_one_bus_by_ports_of_different_names_are_a_mistake_of_the_file(tmp_path: Path) -> None:
    """A device is on a bus by its first port (a SERS's `main`, a PCD4.H3's `sbus`); a bus serves
    one port of its devices, of one name: a PCD4.H3 on a bus with SERS drives was left out of the
    bus without a word."""
    bad, lines = mistakes(tmp_path, "devices:\n  - {name: a, kind: sers, transport: {bus: line}}\n"
                          "  - {name: p, kind: pcd4h3, transport: {bus: line}}\nbuses:\n  - {name: line}\n")
    assert lines == [f"{bad}:3: devices.2.kind: device 'p' is on bus 'line' by its port 'sbus', device 'a' by 'main':"
                     " the devices of a bus share one port of one name"]


def test_a_modbus_map_the_kind_cannot_serve_is_a_mistake_of_the_file(tmp_path: Path) -> None:
    """Found fuzzing the Modbus facade's options: a map naming a point the kind does not have, an
    address past 65535, a scale of 0, a table that does not fit the point, or entries for the
    mirror layout passed `check`, and `up` ended with a ValueError traceback as it made the map."""
    bad, lines = mistakes(tmp_path, "devices:\n"
                          "  - {name: a, kind: sers, modbus: {rtu: {}, map: {nosuch.point: {address: 5}}}}\n"
                          "  - {name: b, kind: sers, modbus: {rtu: {}, map: {quantity.supply_voltage: {address: 70000}}}}\n"
                          "  - {name: c, kind: sers, modbus: {rtu: {}, map: {quantity.supply_voltage: {scale: 0}}}}\n"
                          "  - {name: d, kind: sers, modbus: {rtu: {}, map: {quantity.supply_voltage: {table: coil}}}}\n"
                          "  - {name: e, kind: pcd4h3, modbus: {rtu: {}, layout: mirror, map: {station: null}}}\n"
                          "  - {name: f, kind: sers, modbus: {rtu: {}, map: {quantity.supply_voltage: {address: 100}}}}\n")
    assert lines == [
        f"{bad}:2: devices.1.modbus.map: modbus map: the device has no point 'nosuch.point'",
        f"{bad}:3: devices.2.modbus.map: modbus map: quantity.supply_voltage: address 70000 is not 0 … 65535",
        f"{bad}:4: devices.3.modbus.map: modbus map: quantity.supply_voltage: scale 0 must be a positive number",
        f"{bad}:5: devices.4.modbus.map: modbus map: quantity.supply_voltage: table 'coil' does not fit a float point",
        f"{bad}:6: devices.5.modbus.map: the mirror layout takes no map overrides",
    ]
    up_refuses(bad)


def test_a_modbus_facade_on_a_link_or_tcp_port_taken_already_is_a_mistake_of_the_file(tmp_path: Path) -> None:
    """Found fuzzing the Modbus facade's plant options: a device's ``modbus: {rtu: {link}}`` on its own
    port's link or another facade's, or ``modbus: {tcp: {port}}`` on a device's TCP port, passed
    `check`; `up` then said the link was held by a live process (itself) and to choose another
    --link, or could not bind."""
    one, two = tmp_path / "tty1", tmp_path / "tty2"
    bad, lines = mistakes(tmp_path, f"devices:\n  - {{name: a, kind: gms96, transport: {{pty: {{link: {one}}}}},"
                          f" modbus: {{rtu: {{link: {one}}}}}}}\n"
                          f"  - {{name: b, kind: gms96, modbus: {{rtu: {{link: {two}}}}}}}\n"
                          f"  - {{name: c, kind: gms96, modbus: {{rtu: {{link: {two}}}}}}}\n"
                          "  - {name: d, kind: sers, transport: {tcp: {port: 23461}}, modbus: {tcp: {port: 23461}}}\n"
                          "  - {name: e, kind: sers, modbus: {tcp: {port: 0}}}\n"
                          "  - {name: f, kind: sers, modbus: {tcp: {port: 0}}}\n")
    assert lines == [
        f"{bad}:2: devices.1.modbus: link {one} is taken by devices.1.transport already",
        f"{bad}:4: devices.3.modbus: link {two} is taken by devices.2.modbus already",
        f"{bad}:5: devices.4.modbus: tcp port 127.0.0.1:23461 is taken by devices.4.transport already",
    ]


def test_a_canopen_node_id_used_twice_on_one_network_is_a_mistake_of_the_file(tmp_path: Path) -> None:
    """Found probing the facades' plant options: two devices as CANopen node 5 on one network (a
    socketcand server's or a SocketCAN channel) passed `check`, and `up` ended with a ValueError
    traceback; the same node on another network, or in another part (process), is no clash."""
    bad, lines = mistakes(tmp_path, "devices:\n"
                          "  - {name: a, kind: sers, canopen: {node: 5}}\n"
                          "  - {name: b, kind: gms96, canopen: {node: 5}}\n"
                          "  - {name: c, kind: sers, canopen: {node: 5, network: 'socketcan:vcan0'}}\n"
                          "  - {name: d, kind: sers, canopen: {node: 5, network: 'socketcan:vcan0'}}\n"
                          "  - {name: e, kind: sers, canopen: {node: 5, network: 'socketcan:vcan1'}}\n"
                          "  - {name: f, kind: sers, part: two, canopen: {node: 5, network: 'socketcan:vcan0'}}\n")
    assert lines == [
        f"{bad}:3: devices.2.canopen.node: CANopen node 5 on 127.0.0.1:29536 is taken by devices.1.canopen already",
        f"{bad}:5: devices.4.canopen.node: CANopen node 5 on socketcan:vcan0 is taken by devices.3.canopen already",
    ]
    up_refuses(bad)


def test_a_facade_server_on_a_tcp_port_taken_already_is_a_mistake_of_the_file(tmp_path: Path) -> None:
    """Found probing the facades' plant options: a CANopen network's socketcand server, the OPC UA
    server or the MQTT broker's url on a TCP port another port of the plant holds passed `check`;
    `up` could not bind (or waited 10 s for its own device port to answer MQTT).  One network
    written two ways is two socketcand servers on one port; devices sharing a network share its
    server."""
    bad, lines = mistakes(tmp_path, "devices:\n"
                          "  - {name: a, kind: sers, transport: {tcp: {port: 23462}}, canopen: {node: 1, network: '23462'}}\n"
                          "  - {name: b, kind: sers, modbus: {tcp: {port: 23463}}, canopen: {node: 1, network: '23464'}}\n"
                          "  - {name: c, kind: sers, canopen: {node: 2, network: '23464'}}\n"
                          "  - {name: d, kind: sers, canopen: {node: 3, network: '127.0.0.1:23464'}}\n"
                          "  - {name: e, kind: sers, transport: {tcp: {port: 23465}}}\n"
                          "opcua: {port: 23463}\n"
                          "mqtt: {url: 'mqtt://127.0.0.1:23465'}\n")
    assert lines == [
        f"{bad}:2: devices.1.canopen.network: tcp port 127.0.0.1:23462 is taken by devices.1.transport already",
        f"{bad}:5: devices.4.canopen.network: tcp port 127.0.0.1:23464 is taken by devices.2.canopen.network already",
        f"{bad}:7: opcua.port: tcp port 127.0.0.1:23463 is taken by devices.2.modbus already",
        f"{bad}:8: mqtt.url: tcp port 127.0.0.1:23465 is taken by devices.5.transport already",
    ]
    good = tmp_path / "good.yaml"
    good.write_text("devices:\n  - {name: a, kind: sers, canopen: {node: 1}}\n  - {name: b, kind: sers, canopen: {node: 2}}\n"
                    "opcua: {port: 0}\nmqtt: {url: 'mqtt://127.0.0.1:1883'}\n", encoding="utf-8")
    assert check(good).returncode == 0, check(good).stderr


def test_a_port_on_every_address_takes_it_on_each_of_them(tmp_path: Path) -> None:
    """Found probing the facades' plant options: a device's TCP port on 0.0.0.0 (or localhost) and
    a Modbus facade or the OPC UA server on that port at 127.0.0.1 passed `check` (the hosts were
    compared as words); `up` could not bind the second.  0.0.0.0 beside an IPv6 address, or two
    other hosts, do not clash."""
    bad, lines = mistakes(tmp_path, "devices:\n"
                          "  - {name: a, kind: sers, transport: {tcp: {host: 0.0.0.0, port: 23466}},"
                          " modbus: {tcp: {port: 23466}}}\n"
                          "  - {name: b, kind: sers, transport: {tcp: {host: localhost, port: 23467}}}\n"
                          "  - {name: c, kind: sers, transport: {tcp: {host: '::1', port: 23466}}}\n"
                          "  - {name: d, kind: sers, transport: {tcp: {host: 10.0.0.1, port: 23467}}}\n"
                          "opcua: {port: 23467}\n")
    assert lines == [
        f"{bad}:2: devices.1.modbus: tcp port 127.0.0.1:23466 is taken by devices.1.transport (on 0.0.0.0:23466)"
        " already",
        f"{bad}:6: opcua.port: tcp port 127.0.0.1:23467 is taken by devices.2.transport (on localhost:23467) already",
    ]


def test_a_default_port_that_is_no_name_is_a_mistake_of_the_file(tmp_path: Path) -> None:
    """Found by mutating the shipped scenarios for `check`: ``host: {port: []}`` (or a mapping)
    ended devsim check with a TypeError traceback (unhashable, looked up among the port names)."""
    bad, lines = mistakes(tmp_path, "devices:\n  - {name: x, kind: sers}\nhost:\n  port: []\nsteps:\n  - wait: 1s\n")
    assert lines == [f"{bad}:4: host.port: [] is not a device or bus with its own port"]
    bad, lines = mistakes(tmp_path, "devices:\n  - {name: x, kind: sers}\nhost: {port: {a: 1}}\nsteps: []\n")
    assert lines == [f"{bad}:3: host.port: {{'a': 1}} is not a device or bus with its own port"]


def test_a_host_that_is_no_host_name_or_a_port_past_65535_is_a_mistake_of_the_file(tmp_path: Path) -> None:
    """Found probing plant files with long host names: a host with a label over 63 characters in
    a TCP transport, a Modbus TCP facade, a CANopen network, the OPC UA server or the MQTT url
    passed `check`, and `up` ended with a UnicodeError traceback (getaddrinfo's IDNA encoding); a
    CANopen network on port 99999 with an OverflowError traceback (the bind)."""
    long = "x" * 64
    bad, lines = mistakes(tmp_path, "devices:\n"
                          f"  - {{name: a, kind: sers, transport: {{tcp: {{host: {long}, port: 1}}}}}}\n"
                          f"  - {{name: b, kind: sers, modbus: {{tcp: {{host: {long}, port: 0}}}}}}\n"
                          f"  - {{name: c, kind: sers, canopen: {{node: 1, network: '{long}:0'}}}}\n"
                          "  - {name: d, kind: sers, canopen: {node: 2, network: '99999'}}\n"
                          f"opcua: {{host: {long}, port: 0}}\n"
                          f"mqtt: {{url: 'mqtt://{long}'}}\n")
    name = f"{long!r} is no host name (a label empty or longer than 63 characters)"
    assert lines == [
        f"{bad}:2: devices.1.transport.tcp: {name}",
        f"{bad}:3: devices.2.modbus.tcp: {name}",
        f"{bad}:4: devices.3.canopen: {name}",
        f"{bad}:5: devices.4.canopen: the socketcand port is 0 … 65535, not 99999",
        f"{bad}:6: opcua: {name}",
        f"{bad}:7: mqtt.url: 'mqtt://{long}': {name}",
    ]
    up_refuses(bad)
