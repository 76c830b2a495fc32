"""The CANopen object dictionary of a device kind, as an EDS (CiA 306) generated from its declared
points (issue 13): the communication objects every node has (device type, error register,
the SYNC's COB-ID, heartbeat producer time, identity, the EMCY's COB-ID) and, from index 2000h on, one manufacturer object per
``bool``/``int``/``float`` point in table order (BOOLEAN, INTEGER32, REAL64; read-only where the
point is), named after the point; 4 RPDOs and 4 TPDOs (communication and mapping records, the predefined connection set's
COB-IDs); for a kind that is a drive (``Device.drive``) also the CiA 402 objects (controlword,
statusword, modes and the supported ones, actual and target values, the following error and
position windows and the positioning option code of profile position mode, the velocity window and
threshold of profile velocity mode, with the power-on values of those a master writes), and for
a drive whose kind declares its own reference run (``DriveActions.homing``) those of homing mode
(607Ch, 6098h, the record 6099h, 609Ah).  ``devsim doc KIND --eds`` prints it,
``docs/eds/KIND.eds`` holds it.  Pure text.
"""

from __future__ import annotations

from collections.abc import Iterable

from devsim.core.points import Point
from devsim.facades.cia402 import DEFAULTS

__all__ = ["DEVICE_TYPE", "DRIVE_OBJECTS", "HOMING_OBJECTS", "HOMING_SPEEDS", "FIRST_POINT_INDEX", "SYNC_COB_ID", "VENDOR_ID", "eds", "point_objects"]

FIRST_POINT_INDEX = 0x2000
SYNC_COB_ID = 0x80  # 1005h's power-on value: the predefined connection set's SYNC
VENDOR_ID = 0x00000000  # no CiA vendor id: a simulator
DEVICE_TYPE = 0x00020192  # CiA 402 drive profile (192h), additional information: servo drive (0002h)
TYPES = {"bool": (0x0001, "BOOLEAN"), "int": (0x0004, "INTEGER32"), "float": (0x0011, "REAL64")}


def point_objects(points: Iterable[Point]) -> list[tuple[int, Point]]:
    """(index, point) of every point with a CANopen form, from 2000h on."""
    mapped = [p for p in points if p.type in TYPES]
    return [(FIRST_POINT_INDEX + i, p) for i, p in enumerate(mapped)]


def _product_code(kind: str) -> int:
    import zlib

    return zlib.crc32(kind.encode()) & 0xFFFF_FFFF


def _var(index: int, sub: int | None, name: str, data_type: int, access: str, default: str | int = "",
         pdo: bool = False) -> list[str]:
    head = f"[{index:04X}]" if sub is None else f"[{index:04X}sub{sub:X}]"
    lines = [head, f"ParameterName={name}", "ObjectType=0x7", f"DataType=0x{data_type:04X}", f"AccessType={access}"]
    if default != "":
        lines.append(f"DefaultValue={default if isinstance(default, str) else f'0x{default:X}'}")
    lines += [f"PDOMapping={int(pdo)}", ""]
    return lines


#: CiA 402 objects of a drive (index, name, data type, access, PDO-mappable, power-on value of
#: the objects a master writes: :data:`devsim.facades.cia402.DEFAULTS`).
DRIVE_OBJECTS: tuple[tuple[int, str, int, str, bool, int | str], ...] = (
    (0x603F, "Error code", 0x0006, "ro", True, ""),
    (0x6040, "Controlword", 0x0006, "rw", True, DEFAULTS["controlword"]),
    (0x6041, "Statusword", 0x0006, "ro", True, ""),
    (0x6060, "Modes of operation", 0x0002, "rw", True, DEFAULTS["mode"]),
    (0x6061, "Modes of operation display", 0x0002, "ro", True, ""),
    (0x6064, "Position actual value", 0x0004, "ro", True, ""),
    (0x6065, "Following error window", 0x0007, "rw", True, DEFAULTS["following_error_window"]),
    (0x6066, "Following error time out", 0x0006, "rw", True, DEFAULTS["following_error_time_out"]),
    (0x6067, "Position window", 0x0007, "rw", True, DEFAULTS["position_window"]),
    (0x6068, "Position window time", 0x0006, "rw", True, DEFAULTS["position_window_time"]),
    (0x606C, "Velocity actual value", 0x0004, "ro", True, ""),
    (0x606D, "Velocity window", 0x0006, "rw", True, DEFAULTS["velocity_window"]),
    (0x606E, "Velocity window time", 0x0006, "rw", True, DEFAULTS["velocity_window_time"]),
    (0x606F, "Velocity threshold", 0x0006, "rw", True, DEFAULTS["velocity_threshold"]),
    (0x6070, "Velocity threshold time", 0x0006, "rw", True, DEFAULTS["velocity_threshold_time"]),
    (0x607A, "Target position", 0x0004, "rw", True, DEFAULTS["target_position"]),
    (0x6081, "Profile velocity", 0x0007, "rw", True, DEFAULTS["profile_velocity"]),
    (0x60F2, "Positioning option code", 0x0006, "rw", True, DEFAULTS["positioning_option_code"]),
    (0x60F4, "Following error actual value", 0x0004, "ro", True, ""),
    (0x60FF, "Target velocity", 0x0004, "rw", True, DEFAULTS["target_velocity"]),
    (0x6502, "Supported drive modes", 0x0007, "ro", False, ""),
)

#: The homing mode's objects (CiA 402-2, homing mode), for a drive whose kind declares its
#: reference run (``DriveActions.homing``): 607Ch, 6098h and 609Ah here, the record 6099h apart.
HOMING_OBJECTS: tuple[tuple[int, str, int, str, bool, int | str], ...] = (
    (0x607C, "Home offset", 0x0004, "rw", True, DEFAULTS["home_offset"]),
    (0x6098, "Homing method", 0x0002, "rw", True, DEFAULTS["homing_method"]),
    (0x609A, "Homing acceleration", 0x0007, "rw", True, DEFAULTS["homing_acceleration"]),
)
HOMING_SPEEDS = 0x6099


def _homing_speeds() -> list[str]:
    """6099h, homing speeds (CiA 402-2): sub 1 during search for switch, sub 2 during search for zero."""
    return _record(HOMING_SPEEDS, "Homing speeds", [
        ("Highest sub-index supported", 0x0005, "const", 2),
        ("Speed during search for switch", 0x0007, "rw", DEFAULTS["homing_speed_switch"]),
        ("Speed during search for zero", 0x0007, "rw", DEFAULTS["homing_speed_zero"])])


PDOS = 4  # RPDOs and TPDOs, each with a communication and a mapping record


def _record(index: int, name: str, subs: list[tuple[str, int, str, str | int]]) -> list[str]:
    lines = [f"[{index:04X}]", f"ParameterName={name}", "ObjectType=0x9", f"SubNumber={len(subs)}", ""]
    for sub, (sub_name, code, access, default) in enumerate(subs):
        lines += _var(index, sub, sub_name, code, access, default)
    return lines


def _pdo_objects() -> list[str]:
    """The communication (1400h/1800h) and mapping (1600h/1A00h) records of 4 RPDOs and 4 TPDOs,
    with the predefined connection set's COB-IDs."""
    lines: list[str] = []
    for n in range(PDOS):
        for base, cob, kind in ((0x1400, 0x200, "RPDO"), (0x1800, 0x180, "TPDO")):
            subs: list[tuple[str, int, str, str | int]] = [
                ("Highest sub-index supported", 0x0005, "const", 5),
                (f"COB-ID used by {kind}", 0x0007, "rw", f"$NODEID+0x{cob + 0x100 * n:X}"),
                ("Transmission type", 0x0005, "rw", 255),
                ("Inhibit time", 0x0006, "rw", 0),
                ("Compatibility entry", 0x0005, "rw", 0),
                ("Event timer", 0x0006, "rw", 0),
            ]
            lines += _record(base + n, f"{kind} communication parameter {n + 1}", subs)
        for base, kind in ((0x1600, "RPDO"), (0x1A00, "TPDO")):
            mapping: list[tuple[str, int, str, str | int]] = [("Number of mapped objects", 0x0005, "rw", 0)]
            mapping += [(f"Mapping entry {i}", 0x0007, "rw", 0) for i in range(1, 9)]
            lines += _record(base + n, f"{kind} mapping parameter {n + 1}", mapping)
    return lines


def _pdo_indices() -> list[int]:
    return [base + n for base in (0x1400, 0x1600, 0x1800, 0x1A00) for n in range(PDOS)]


def eds(kind: str, description: str, points: Iterable[Point], drive: bool = False, homing: bool = False) -> str:
    """The EDS of a kind (with the CiA 402 objects when it is a ``drive``, and those of homing
    mode when it has a reference run of its own: ``homing``)."""
    objects = point_objects(points)
    lines = [
        "[FileInfo]", f"FileName={kind}.eds", "FileVersion=1", "FileRevision=0", "EDSVersion=4.0",
        f"Description=devsim {kind}: {description}"[:243], "CreatedBy=devsim (generated: devsim doc KIND --eds)", "",
        "[DeviceInfo]", "VendorName=devsim", f"VendorNumber=0x{VENDOR_ID:X}", f"ProductName=devsim {kind}",
        f"ProductNumber=0x{_product_code(kind):X}", "RevisionNumber=0x1", "OrderCode=", "BaudRate_125=1",
        "BaudRate_250=1", "BaudRate_500=1", "BaudRate_1000=1", "SimpleBootUpMaster=0", "SimpleBootUpSlave=1",
        "Granularity=8", "DynamicChannelsSupported=0", "GroupMessaging=0", f"NrOfRXPDO={PDOS}", f"NrOfTXPDO={PDOS}",
        "LSS_Supported=0", "",
        "[DummyUsage]", "Dummy0001=0", "Dummy0002=0", "Dummy0003=0", "Dummy0004=0", "Dummy0005=0", "Dummy0006=0",
        "Dummy0007=0", "",
        "[MandatoryObjects]", "SupportedObjects=3", "1=0x1000", "2=0x1001", "3=0x1018", "",
    ]
    lines += _var(0x1000, None, "Device type", 0x0007, "ro", DEVICE_TYPE)
    lines += _var(0x1001, None, "Error register", 0x0005, "ro", 0)
    lines += ["[1018]", "ParameterName=Identity object", "ObjectType=0x9", "SubNumber=5", ""]
    lines += _var(0x1018, 0, "Highest sub-index supported", 0x0005, "const", 4)
    lines += _var(0x1018, 1, "Vendor-ID", 0x0007, "ro", VENDOR_ID)
    lines += _var(0x1018, 2, "Product code", 0x0007, "ro", _product_code(kind))
    lines += _var(0x1018, 3, "Revision number", 0x0007, "ro", 1)
    lines += _var(0x1018, 4, "Serial number", 0x0007, "ro", 1)
    homing_objects = [*HOMING_OBJECTS, (HOMING_SPEEDS,)] if drive and homing else []
    optional = [0x1005, 0x1008, 0x1014, 0x1017, *_pdo_indices()] + ([index for index, *_ in DRIVE_OBJECTS] if drive else [])
    optional = sorted(optional + [index for index, *_ in homing_objects])
    lines += ["[OptionalObjects]", f"SupportedObjects={len(optional)}"]
    lines += [f"{n}=0x{index:04X}" for n, index in enumerate(optional, start=1)] + [""]
    lines += _var(0x1005, None, "COB-ID SYNC", 0x0007, "rw", SYNC_COB_ID)  # (CiA 301: the SYNC consumed)
    lines += _var(0x1008, None, "Manufacturer device name", 0x0009, "const", f"devsim {kind}")
    lines += _var(0x1014, None, "COB-ID EMCY", 0x0007, "ro", "$NODEID+0x80")  # (CiA 301: where EMCY is sent)
    lines += _var(0x1017, None, "Producer heartbeat time", 0x0006, "rw", 0)
    lines += _pdo_objects()
    if drive:  # the device profile area (CiA 402)
        for index, name, code, access, pdo, default in sorted(DRIVE_OBJECTS + (HOMING_OBJECTS if homing else ())):
            lines += _var(index, None, name, code, access, default, pdo=pdo)
            if homing and index == HOMING_SPEEDS - 1:
                lines += _homing_speeds()
    lines += ["[ManufacturerObjects]", f"SupportedObjects={len(objects)}"]
    lines += [f"{n}=0x{index:04X}" for n, (index, _p) in enumerate(objects, start=1)]
    lines.append("")
    for index, point in objects:
        code, _name = TYPES[point.type]
        access = "rw" if point.readable and point.settable else ("wo" if point.settable else "ro")
        lines += _var(index, None, point.name, code, access, pdo=point.type != "float")
    return "\n".join(lines)
