"""The Siemens SIMATIC S5 IP247 stepper positioning module (spec ip247.md): work in progress.

So far: the PG port's link layer (:mod:`devsim.devices.ip247.as511`) and the machine-data
record with its checks and ramp (:mod:`devsim.devices.ip247.machine_data`).  The kind is not
registered yet.
"""
