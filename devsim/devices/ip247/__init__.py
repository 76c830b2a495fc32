"""The Siemens SIMATIC S5 IP247 stepper positioning module (spec ip247.md): work in progress.

So far the pure pieces, each tested with the spec's vectors: the PG port's link layer
(:mod:`devsim.devices.ip247.as511`) and a PG-side client for it
(:mod:`devsim.devices.ip247.client`), the PG profile's requests and responses
(:mod:`devsim.devices.ip247.pg_profile`), the axis attribute byte and the PLC endpoint's framing
(:mod:`devsim.devices.ip247.attributes`), the machine-data record with its checks and ramp
(:mod:`devsim.devices.ip247.machine_data`), a move with the exponential ramp on the shared axis
(:mod:`devsim.devices.ip247.motion`), the traverse-program record with its language check
(:mod:`devsim.devices.ip247.program`), the program memory (:mod:`devsim.devices.ip247.store`),
binary/BCD values and the small records (:mod:`devsim.devices.ip247.values`), the error and mode
tables (:mod:`devsim.devices.ip247.tables`), the preconditions of an operator job
(:mod:`devsim.devices.ip247.jobs`), and the zero and tool offsets
(:mod:`devsim.devices.ip247.coordinates`).  The kind itself (the per-axis state and the
modes' actions of §4.1/§4.2, program execution, the PG and PLC faces, points, config)
is not built or registered yet.
"""
