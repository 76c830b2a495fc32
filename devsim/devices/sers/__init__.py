"""Stögra SERS stepper driver with positioning control (spec: shared/specs/sers.md)."""

from devsim.devices.sers.device import SersDevice

__all__ = ["SersDevice"]
