"""The keys of the front panel and of the external keyboard V8, the keyboard test P79 N3 and the
buzzer V16/6 (manual §2.3.25, §2.4.9, §2.6.4; spec poselesta.md §3.2.2, §3.10, §4.7).

A key pressed at the panel (``panel.key``) and a key code taken from V8 go the same way: the
code is shown to a host developer (events ``v8.key_name``, ``v8.key``), the keyboard test shows
it + 1, and the buzzer sounds for 100 ms unless P67 = 1.
"""

from __future__ import annotations

from collections.abc import Mapping
from string import hexdigits

from devsim.core.clock import Clock, Timer
from devsim.core.points import BadValue, ascii_upper, strip_blanks
from devsim.core.signals import SignalBank
from devsim.devices.poselesta.codes import KEY_CODES
from devsim.devices.poselesta.parameters import MachineParameters
from devsim.devices.poselesta.screen import Screen

__all__ = ["KEYBOARD_TEST_EXIT", "FrontPanel"]

KEYBOARD_TEST_EXIT = 0x2D  # the key that ends the keyboard test P79 N3 (spec §3.10)
BUZZER_PULSE = 0.1  # s


class FrontPanel:
    """The keys of one control (manual §2.6.4, §2.4.9; spec §3.10): ``keymap`` names key codes."""

    def __init__(self, clock: Clock, signals: SignalBank, params: MachineParameters, screen: Screen,
                 keymap: Mapping[int, str]) -> None:
        self._clock = clock
        self._signals = signals
        self._params = params
        self._screen = screen
        self._keymap = dict(keymap)
        self.last_key: int | None = None
        self.keyboard_test: str | None = None  # P79 N3 running: what the screen shows ("" before a key)
        self.page: int | None = None  # the diagnostic page P79 N5 or N7 on the screen
        self._buzzer_timer: Timer | None = None

    def code_of(self, key: str) -> int:
        """A key by its name in ``v8_keymap`` or its two-digit hex code (spec §3.2.2 ``panel.key``)."""
        names = {ascii_upper(name): code for code, name in self._keymap.items()}
        text = strip_blanks(key)  # (str.strip also took NBSP, U+3000, FS … US, NEL around the key)
        code = names.get(ascii_upper(text))  # (str.upper: 'exıt', with the dotless ı, was EXIT)
        if code is None:
            # hex digits only: int(key, 16) also read '0x48', '4_8', '+48' and the digits of other scripts
            # ([SIM-CHOICE]: the spec gives the code as '48', hex digits; it says nothing of a prefix)
            if not (text and text.isascii() and all(c in hexdigits for c in text)):
                raise BadValue(f"no key {key!r}: a name of v8_keymap ({', '.join(sorted(names))}) or a hex code")
            code = int(text, 16)
        if code not in KEY_CODES:
            raise BadValue(f"{code:02X} is not a key code of the keyboard (spec §3.10)")
        return code

    def key(self, code: int) -> None:
        """A key is taken (from the panel or V8)."""
        self.last_key = code
        self._screen.port_event("v8", "key_name", self._keymap.get(code, f"{code:02X}"))
        if self.keyboard_test is not None:  # P79 N3: the code + 1 on the screen; 2D ends the test
            self.keyboard_test = None if code == KEYBOARD_TEST_EXIT else f"{code + 1:02X}"
        self._screen.port_event("v8", "key", code)
        if self._params.buzzer_off == 0:
            self._signals.set("buzzer", True)
            if self._buzzer_timer is not None:
                self._buzzer_timer.cancel()
            self._buzzer_timer = self._clock.call_later(BUZZER_PULSE, lambda: self._signals.set("buzzer", False))

    def cancel(self) -> None:
        """The control is switched off: the buzzer's pulse ends with it."""
        if self._buzzer_timer is not None:
            self._buzzer_timer.cancel()
            self._buzzer_timer = None

    def show_page(self, number: int) -> None:
        """P79 N5 (the inputs, §2.3.25) or N7 (the pots, §2.3.26) takes the screen."""
        self.page = number

    def mode_key(self) -> None:
        """A mode key ends a diagnostic page (§2.3.25, §2.3.26: "Abschluss: Betriebsart")."""
        self.page = None

    def keyboard_test_on(self, on: bool) -> None:
        self.keyboard_test = "" if on else None
