"""The diagnostic pages of program P79 (manual §2.3.25, §2.3.26; spec poselesta.md §4.7, vector
§6.11): N5, the levels of all inputs as four ports of two bytes; N7, the feed and override pot
voltages as hex 00 … FF."""

from __future__ import annotations

from typing import Any

from devsim.core.signals import SignalBank

__all__ = ["INPUT_IMAGE", "input_image", "input_screen", "pots"]

#: P79 N5: port and half → the input of bit 7 … bit 0 (None: unused).
INPUT_IMAGE: dict[str, tuple[str | None, ...]] = {
    "1A": ("open_loop", "key_switch", "keyboard_external", "optional_stop", "xy_plotter", "program_lock_open",
           "block_abort", None),
    "1B": ("jog_step_10000", "jog_step_1000", "jog_step_100", "jog_step_10", "jog_step_1", "m10_ack", "rapid",
           "mst_ack"),
    "2A": ("limit_pos_d", "limit_pos_z", "limit_pos_y", "limit_pos_x", "limit_neg_d", "limit_neg_z", "limit_neg_y",
           "limit_neg_x"),
    "2B": ("jog_pos_d", "jog_pos_z", "jog_pos_y", "jog_pos_x", "jog_neg_d", "jog_neg_z", "jog_neg_y", "jog_neg_x"),
    "3A": (None, None, None, None, "handwheel_d", "handwheel_z", "handwheel_y", "handwheel_x"),
    "3B": (None,) * 8,
    "4A": ("tool_change_ack", "program_continue", "axis_enable", "inch", None, "block_skip_cancel", None, None),
    "4B": (None, None, "nc_start", "emergency_stop", "nc_stop", None, None, None),
}


def input_image(signals: SignalBank) -> dict[str, int]:
    """Each half-port as a byte: bit = 1 where the input is H."""
    image = {}
    for port, names in INPUT_IMAGE.items():
        value = 0
        for bit, name in zip(range(7, -1, -1), names, strict=True):
            if name is not None and signals.get(name):
                value |= 1 << bit
        image[port] = value
    return image


def input_screen(signals: SignalBank) -> str:
    """The page as the monitor shows it: ``Port 1 EIN 01000110 00000000`` …"""
    image = input_image(signals)
    return "\n".join(f"Port {n} EIN {image[f'{n}A']:08b} {image[f'{n}B']:08b}" for n in range(1, 5))


def pots(signals: SignalBank) -> list[Any]:
    """P79 N7: feed and override pot as ``round(V / 10 × 255)`` in hex."""
    return [f"{round(max(0.0, min(10.0, float(signals.get(name)))) / 10 * 255):02X}"
            for name in ("feed_pot_v", "override_pot_v")]
