"""The SERS's parameter values: the RAM image of the drive's parameters (manual §4.7, §4.8).

One value per row of :data:`~devsim.devices.sers.parameters.PARAMETER_TABLE`, weighted ones
(positions, velocities, accelerations) kept in motor increments, inc/s and inc/s² (§4.8.4.6);
the model reads them by the names below (``params.velocity`` is V, P91), the serial face by the
number the host sent (:attr:`values`).  What a write does beyond storing the value belongs to
the part that owns that behaviour.
"""

from __future__ import annotations

from typing import Any

from devsim.core.parameters import Parameters, accessor
from devsim.devices.sers.parameters import PARAMETER_TABLE
from devsim.devices.sers.units import Scaling

__all__ = ["HANDSHAKE_CELL", "LANGUAGE_CELL", "SersParameters"]

#: P76, P44, P160, P121, P122, P123: what the unit conversion is made of (§4.8.4.6).
_WEIGHTING = PARAMETER_TABLE.picker(76, 44, 160, 121, 122, 123)
#: P1125, P1126, P1131, P1132, P1036: the outputs that show the drive's state (§4.8.1.2).
_OUTPUT_SELECTORS = PARAMETER_TABLE.picker(1125, 1126, 1131, 1132, 1036)
#: P1040, P1041, P1044, P1025, P1027: what a motion watches (§4.8.6.12, §4.8.6.8, §4.8.1.2).
_WATCHED = PARAMETER_TABLE.picker(1040, 1041, 1044, 1025, 1027)
#: Where P1017, the handshake mode (§4.8.6.9), is among :attr:`SersParameters.values`' cells:
#: ``params.values.cells[HANDSHAKE_CELL]`` (a host's poll reads it every time; no call).
HANDSHAKE_CELL: int = PARAMETER_TABLE.positions[1017]
#: Where P265, the language of the messages (§4.8.3.1), is: every error message reads it.
LANGUAGE_CELL: int = PARAMETER_TABLE.positions[265]
#: P1032, P1005–P1008: the ramp shape and its sections (§4.8.4.4).
_RAMP = PARAMETER_TABLE.picker(1032, 1005, 1006, 1007, 1008)


class SersParameters(Parameters):
    """The parameter values of one SERS (§4.7), with the unit conversion their weighting gives
    (§4.8.4.6)."""

    target_address = accessor(1, "Z, P1: target address")
    homing_velocity = accessor(41, "P41: velocity homing (inc/s)")
    homing_acceleration = accessor(42, "P42: acceleration - homing (inc/s²)")
    velocity_weighting = accessor(44, "P44: velocity data weighting")
    position_setpoint = accessor(47, "W, P47: position setpoint (inc)")
    position_weighting = accessor(76, "P76: position data weighting")
    velocity = accessor(91, "V, P91: velocity - positioning (inc/s)")
    counter1 = accessor(100, "C1, P100: counter 1")
    modulo = accessor(103, "P103: modulo value for position setpoint (inc)")
    feedrate_override = accessor(108, "P108: feedrate override")
    gear_input = accessor(121, "P121: gear input revolutions")
    gear_output = accessor(122, "P122: gear output revolutions")
    feed_constant = accessor(123, "P123: feed constant")
    acceleration = accessor(138, "A, P138: acceleration - positioning (inc/s²)")
    homing_parameters = accessor(147, "P147: homing parameters")
    acceleration_weighting = accessor(160, "P160: acceleration data weighting")
    language = accessor(265, "P265: language selection")
    leave_zero_phase = accessor(1001, "P1001: leave zero phase")
    load_angle_window = accessor(1002, "P1002: load-angle monitoring window")
    homing_velocity_slow = accessor(1003, "P1003: velocity homing slow (inc/s)")
    ramp_acceleration1 = accessor(1005, "P1005: acceleration section 1")
    ramp_acceleration2 = accessor(1006, "P1006: acceleration section 2")
    ramp_velocity1 = accessor(1007, "P1007: velocity section 1")
    ramp_velocity2 = accessor(1008, "P1008: velocity section 2")
    phase_current = accessor(1010, "P1010: phase current")
    current_parameters = accessor(1011, "P1011: current parameters")
    boost_acceleration = accessor(1012, "P1012: acceleration for current boost (inc/s²)")
    positioning_mode = accessor(1014, "P1014: positioning mode")
    handshake_mode = accessor(1017, "P1017: handshake mode")
    jog_acceleration = accessor(1018, "P1018: acceleration - jog (inc/s²)")
    jog_velocity_slow = accessor(1019, "P1019: velocity jog slow (inc/s)")
    jog_velocity_fast = accessor(1020, "P1020: velocity jog fast (inc/s)")
    input_enable = accessor(1021, "P1021: digital input enable")
    input_label_enable = accessor(1022, "P1022: digital input label enable")
    start_enable = accessor(1023, "P1023: start enable")
    compare_position1 = accessor(1024, "P1024: compare position 1 (inc)")
    compare_output1 = accessor(1025, "P1025: compare output 1")
    compare_position2 = accessor(1026, "P1026: compare position 2 (inc)")
    compare_output2 = accessor(1027, "P1027: compare output 2")
    list_option = accessor(1028, "P1028: list option")
    step_monitoring = accessor(1029, "P1029: step monitoring error/warning assignment")
    error_deceleration = accessor(1030, "P1030: acceleration on drive error (inc/s²)")
    ramp_shape = accessor(1032, "P1032: ramp shape")
    continuation_after_stop = accessor(1033, "P1033: continuation after stop")
    jog_timeout = accessor(1035, "P1035: jog with timeout")
    brake_output = accessor(1036, "P1036: brake output")
    backlash = accessor(1037, "P1037: backlash (inc)")
    overrun = accessor(1039, "P1039: overrun distance (inc)")
    limit_negative = accessor(1040, "P1040: limit position negative (inc)")
    limit_positive = accessor(1041, "P1041: limit position positive (inc)")
    standstill_distance = accessor(1044, "P1044: standstill monitoring (inc)")
    standstill_input = accessor(1045, "P1045: standstill monitoring input")
    accumulator = accessor(1047, "X, P1047: accumulator")
    pulse_input = accessor(1053, "P1053: option pulse input / electronic gear / hand wheel / encoder input / load-angle monitoring with tracking / frequency measurement")
    pulse_weight = accessor(1054, "P1054: weighting factor for input pulses")
    frequency_window = accessor(1055, "P1055: time window for frequency measurement")
    save_position_on_undervoltage = accessor(1058, "P1058: save position on undervoltage")
    external_service_switch = accessor(1092, "P1092: external service switch")
    stop_on_jog = accessor(1093, "P1093: a jog input interrupts (0) or aborts (1) a running program")
    jog_at_power_on = accessor(1095, "P1095: jog functions at power-on: 0 by level, 1 by edge")
    polynomial_deceleration = accessor(1096, "B, P1096: braking ramp polynomial end (inc/s²)")
    program_jump_enable = accessor(1098, "P1098: program jump enable")
    wait_until_positioned = accessor(1110, "P1110: wait until positioned")
    save_registers_too = accessor(1117, "P1117: save R0 to R5 and W")
    l65_flag = accessor(1118, "P1118: flag - L65 error handling")
    pulse_counter1 = accessor(1119, "P1119: pulse input counter 1")
    pulse_counter2 = accessor(1120, "P1120: pulse input counter 2")
    report_in_position = accessor(1121, "P1121: spontaneous message in position")
    output_in_position = accessor(1125, "P1125: output motor in position")
    output_program_running = accessor(1126, "P1126: output program running")
    slow_program_cycle = accessor(1127, "P1127: 500 µs program mode")
    report_program_end = accessor(1129, "P1129: spontaneous message program finished")
    reference_input = accessor(1130, "P1130: reference switch input assignment")
    output_error = accessor(1131, "P1131: output SERS error")
    output_warning = accessor(1132, "P1132: output SERS warning")
    direction_inverted = accessor(1134, "P1134: motor direction inverted (1)")
    adc_hysteresis = accessor(1135, "P1135: ADC hysteresis")
    posr_attempts = accessor(1138, "P1138: POSR attempts")
    posr_wait = accessor(1139, "P1139: POSR waiting time")
    posr_mode = accessor(1140, "P1140: POSR mode")
    delay_correction = accessor(1141, "P1141: time delay correction")
    pulse_input2 = accessor(1143, "P1143: option pulse input / electronic gear / hand wheel / encoder input / load-angle monitoring with tracking / frequency measurement (I3/I4)")
    pulse_weight2 = accessor(1144, "P1144: weighting factor for input pulses")
    frequency_window2 = accessor(1145, "P1145: time window for frequency measurement")
    adc_offset = accessor(1148, "P1148: ADC offset")
    servo_mode = accessor(1152, "P1152: SERVO mode")
    overload_output = accessor(1160, "P1160: overload output")
    use_catch_up_velocity = accessor(1162, "P1162: use catch-up speed in SERVO mode")
    catch_up_velocity = accessor(1163, "P1163: catch-up speed in SERVO mode (inc/s)")
    d2_time = accessor(1164, "D2, P1164: waiting time D2")
    d2_bit = accessor(1165, "DB, P1165: waiting time bit DB")

    def __init__(self) -> None:
        super().__init__(PARAMETER_TABLE)
        self._scaling: tuple[tuple[object, ...], Scaling] | None = None

    @property
    def scaling(self) -> Scaling:
        """The unit conversion of the weighting parameters as they are now (made again only when
        one of them changed: a position query needs it twice)."""
        key = _WEIGHTING(self.values.cells)  # type: ignore[attr-defined]
        made = self._scaling
        if made is not None and made[0] == key:
            return made[1]
        scaling = Scaling(int(key[0]), int(key[1]), int(key[2]), float(key[3]), float(key[4]), float(key[5]))
        self._scaling = (key, scaling)
        return scaling

    def output_selectors(self) -> tuple[Any, Any, Any, Any, Any]:
        """The outputs that show the drive's state (§4.8.1.2): in position P1125, program
        running P1126, error P1131, warning P1132, and the brake P1036 (read together: the
        outputs follow every error message)."""
        return _OUTPUT_SELECTORS(self.values.cells)  # type: ignore[attr-defined,no-any-return]

    def watched(self) -> tuple[Any, Any, Any, Any, Any]:
        """The software limits P1040/P1041, the standstill distance P1044 and the compare
        outputs P1025/P1027 as they are now, read together (every motion start asks)."""
        return _WATCHED(self.values.cells)  # type: ignore[attr-defined,no-any-return]

    def ramp_settings(self) -> tuple[Any, Any, Any, Any, Any]:
        """P1032 and P1005–P1008 as they are now (§4.8.4.4), read together: what a ramp
        profile is made of (a missing value shows as the table's ``MISSING``)."""
        return _RAMP(self.values.cells)  # type: ignore[attr-defined,no-any-return]

    def load(self, image: dict[int, object]) -> None:
        """Every value anew (power-on): ``image`` is the whole RAM image, nothing else is kept."""
        self.values.clear()
        self.values.update(image)
