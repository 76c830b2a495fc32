"""The SERS's inputs, outputs and simulated quantities, declared once (manual §2.1, §3.3, §3.5)."""

from __future__ import annotations

from devsim.core.kit import SignalDef

__all__ = ["SIGNALS", "SUPPLY_DEFAULT"]

SUPPLY_DEFAULT = -1.0  # replaced by 80 % of the supply class's threshold, or the configured value

SIGNALS: tuple[SignalDef, ...] = (
    SignalDef("limit_left", "input", False, "left limit switch actuated (NC contact open)", "§2.1.2"),
    SignalDef("limit_right", "input", False, "right limit switch actuated (NC contact open)", "§2.1.2"),
    SignalDef("stop", "input", False, "STOP input actuated (NC contact open)", "§2.1.2"),
    SignalDef("reference", "input", False, "the drive stands on the reference switch", "§4.8.4.5"),
    SignalDef("service_ext", "input", False, "external service switch active", "§3.1.2"),
    *(SignalDef(f"I{n}", "input", False, f"digital input I{n}", "§3.3") for n in range(1, 17)),
    *(SignalDef(f"O{n}", "output", False, f"digital output O{n}", "§3.3") for n in range(1, 17)),
    SignalDef("READY", "output", False, "ready relay closed", "§2.1.3"),
    SignalDef("supply_voltage", "quantity", SUPPLY_DEFAULT, "main supply", "§2.1.4", "V", minimum=0, maximum=200),
    SignalDef("heatsink_temperature", "quantity", 25.0, "heat-sink temperature", "§3.5", "°C", minimum=-40, maximum=200),
    SignalDef("short_circuit", "quantity", False, "short circuit in motor or power stage", "§3.5", type="bool"),
    SignalDef("adc_volts", "quantity", 0.0, "voltage at the analog input ADC", "§4.8.1.3", "V", minimum=0, maximum=5),
    SignalDef("stall", "quantity", False, "load torque above motor torque: the rotor stands still", "§4.8.6.6",
              type="bool"),
    SignalDef("pulse_frequency", "quantity", 0.0, "frequency of the pulses at I3 / ENC (P1053=9/10, P1143=5)",
              "§4.8.6.6", "Hz", minimum=0, maximum=1e6),
)
