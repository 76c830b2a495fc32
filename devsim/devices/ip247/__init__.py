"""The Siemens SIMATIC S5 IP247 stepper positioning module (spec ip247.md) as the kind ``ip247``.

The module (:mod:`.module`) is composed of parts: three axis pages (:mod:`.axis_unit`, with the
reference run of :mod:`.reference` and program execution of :mod:`.automatic`), the modes that
move them (:mod:`.modes`), the programs (:mod:`.programs`), the data channel with the records
(:mod:`.records`) and BASP (:mod:`.basp`); the faces
(:mod:`.face`) are the PG port (the AS511 link of :mod:`.as511` carrying the profile of
:mod:`.pg_profile`) and the PLC side (:mod:`.services`, framing in :mod:`.attributes`).  The pure
pieces: machine data (:mod:`.machine_data`), the ramp (:mod:`.motion`), programs
(:mod:`.program`, :mod:`.flow`, :mod:`.store`), values (:mod:`.values`), offsets
(:mod:`.coordinates`), job checks (:mod:`.jobs`) and tables (:mod:`.tables`); a PG-side client
in :mod:`.client`.
"""

from devsim.devices.ip247.device import Ip247Device

__all__ = ["Ip247Device"]
