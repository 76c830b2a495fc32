"""A test kind with two serial ports, to show the kit's ports: ``a`` and ``b``.

Port ``a`` echoes what it receives and counts it in the model; port ``b`` answers any line
(ending in CR) with the count, ``<n>\\r``.  The ``jam`` fault mutes port ``a``.  Register with
``DEVSIM_EXTRA_KINDS="twoport=tests.support.twoport:TwoPortDevice"``.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device, Face
from devsim.core.kit import Fault, FaultTable, PortDef
from devsim.core.model import Model
from devsim.core.points import Point, PointTable


class TwoPortModel(Model):
    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.count = 0
        self.jammed = False


class EchoCountFace(Face):
    """Port a: echo and count."""

    model: TwoPortModel

    def feed(self, data: bytes) -> None:
        self.model.count += len(data)
        if not self.model.jammed:
            self.send(data)


class CountFace(Face):
    """Port b: a CR-terminated line asks for the count."""

    model: TwoPortModel

    def __init__(self, model: Any, port: Any) -> None:
        super().__init__(model, port)
        self.pending = bytearray()

    def feed(self, data: bytes) -> None:
        self.pending += data
        while b"\r" in self.pending:
            del self.pending[: self.pending.index(b"\r") + 1]
            self.send(f"{self.model.count}\r".encode())


def _jam(model: TwoPortModel, active: bool) -> None:
    model.jammed = active


class TwoPortDevice(Device):
    kind: ClassVar[str] = "twoport"
    description: ClassVar[str] = "Two serial ports on one model (test device)"
    ports = (PortDef("a", "echoes and counts"), PortDef("b", "answers the count"))
    model_class = TwoPortModel
    face_classes: ClassVar[dict[str, Any]] = {"a": EchoCountFace, "b": CountFace}
    points = PointTable.of(
        [
            Point("count", "int", "bytes received on port a", get=lambda m: m.count, in_state=True),
            Point("jammed", "bool", "port a is muted", get=lambda m: m.jammed, in_state=True),
        ]
    )
    faults = FaultTable([Fault("jam", "port a stops echoing", "", _jam)])
