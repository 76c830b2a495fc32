"""The Siemens SIMATIC S5 IP247 stepper positioning module (spec ip247.md): work in progress.

So far only the PG port's link layer (:mod:`devsim.devices.ip247.as511`) exists; the kind is not
registered yet.
"""
