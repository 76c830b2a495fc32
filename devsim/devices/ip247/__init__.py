"""The Siemens SIMATIC S5 IP247 stepper positioning module (spec ip247.md): work in progress.

So far the pure pieces: the PG port's link layer (:mod:`devsim.devices.ip247.as511`) and a
PG-side client for it (:mod:`devsim.devices.ip247.client`), the PG
profile's requests and responses (:mod:`devsim.devices.ip247.pg_profile`), the machine-data
record with its checks and ramp (:mod:`devsim.devices.ip247.machine_data`), a move with the
exponential ramp on the shared axis (:mod:`devsim.devices.ip247.motion`), the traverse-program
record with its language check (:mod:`devsim.devices.ip247.program`), the program memory
(:mod:`devsim.devices.ip247.store`), binary/BCD values and the
small records (:mod:`devsim.devices.ip247.values`), and the error and mode tables
(:mod:`devsim.devices.ip247.tables`).  The kind (model, faces, points) is not built or
registered yet.
"""
