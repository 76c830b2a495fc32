"""Where the pcd4h3 simulator knowingly differs from its manual, and why (``devsim doc pcd4h3``
prints these rows as the *Deviations* section of docs/devices/pcd4h3.md).

The manual is "Handbuch Positioniermodule für Servoantriebe PCD4.H3..", SAIA-Burgess 26/729 D2
(seed 002); its sections are cited as printed there.
"""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = (
    Deviation(
        "§2",
        "Electrical data: 24 V input levels (low 0 … 4 V, high 19 … 32 V), 10 mA input current, source or sink "
        "mode (jumper Q/S, §6.4), RS-422 inputs, no isolation, display outputs 1 … 100 mA, supply currents, "
        "temperatures, interference immunity.",
        "The switch, encoder and display lines are booleans and counts; the Q/S jumper (`jumpers.sink_mode`) "
        "is accepted and changes nothing.",
        "There is no electrical layer behind a pty or a socket.",
    ),
    Deviation(
        "§2",
        "Counting frequency at most 100 kHz.",
        "The decoder counts at any speed the motor reaches; no counts are lost above 100 kHz.",
        "Count loss is an electrical fault of a real encoder line; the spec leaves it to a scenario (G-17) "
        "and none is offered.",
    ),
    Deviation(
        "§2, §7.4 FLdVA",
        "Velocity and acceleration ranges printed as [−2^30 … 2^30 − 1] / k · 22348 · 10^−6 and "
        "… · 76206 · 10^−9.",
        "Veloc and Accel are converted as v · k · 65536 · 341 µs and a · k · 65536 · (341 µs)² and checked in "
        "the chip's units (0 … 3FFFFFFFh); beyond that the chip reports a command error (§8); "
        "`fb_sample_time_us` sets the 341 µs.",
        "The printed formulas are garbled (spec G-6); the chip's own ranges decide what it accepts.",
    ),
    Deviation(
        "§5.2",
        "Module addresses 0 … 7 (data bus), outputs 8 … 11 (WR, RD, PS, CS) carry the function blocks' "
        "traffic with the chips; outputs 12 … 15 (clock, data, enable X/Y) drive the PCA2.D14 displays.",
        "These inputs and outputs read 0 over S-Bus; the chips are reached through the library's functions, "
        "and what DP14 shows is the text `axis.N.display` (and the diagnostics registers).",
        "The bus strobes and the display's serial protocol are not documented in the manual (spec G-14, "
        "G-18); the host never needs them.",
    ),
    Deviation(
        "§6.4",
        "The limit switches LS1, LS2 and the reference switch change their inputs where the axis is.",
        "The switches sit on a shared axis that follows the motor from the LM628's batches of samples: "
        "through the motor's position at a batch's last sample, at its velocity, until the next batch (a PLC "
        "cycle's function, which may compute the chip up to the cycle's length ahead of the clock, or a "
        "host's look), so `axis.N.mechanical_position` and the switches are where the motor is within the "
        "travel of a straight line over one batch. While the PLC skips the cycles of an axis that only "
        "moves, a host finds the shared axis where it is with every cycle, and the skipping ends before a "
        "switch edge comes within a cycle's travel.",
        "The motor is computed in batches, not continuously, and a moving axis wakes the PLC only for its "
        "events (issue 31).",
    ),
    Deviation(
        "§6.6",
        "Jumper S/B per axis: the PWM output as SIGN and MAGNITUDE or through the logic for a bridge amplifier.",
        "The output is reported as a signed duty (`axis.N.output_volts` = duty · 10 V) either way; "
        "`axes.N.pwm_logic` is accepted and changes nothing.",
        "The bridge logic is a circuit in front of the amplifier; its timing is not documented (spec G-35).",
    ),
    Deviation(
        "§7.1.1, §7.1.2",
        "The library PCD9.H3E1 comes on floppy disks (H3DEF.SRC, H3FB.SRC), is assembled and linked with the "
        "user program (PUBLSYM/EXTNSYM, $INCLUDE).",
        "The library is part of the simulator; H3DEF.SRC's symbols are the `h3def` settings (BAFB and BAC are "
        "accepted and documented only).",
        "There is no PCD assembler or linker to feed.",
    ),
    Deviation(
        "§7.1.3, §7.1.5",
        "The function blocks use common registers and flags after the axis blocks and one counter (BAC) as "
        "scratch memory (sizes in H3DEF.LST: TRe, TFl, TCo).",
        "Nothing is kept there: those registers, flags and the counter read 0 unless a host writes them.",
        "Their contents are the FBs' private intermediate values, undocumented (spec G-13).",
    ),
    Deviation(
        "§7.2",
        "The user program: XOB 16 loads the registers and calls AxInit, a COB calls AxHndlg every cycle, a "
        "GRAFTEC block (SB) sequences the moves; ComErS (§8) may be programmed freely.",
        "The PLC runs AxInit at every cold start (registers from `init`), AxHndlg every `plc_cycle_ms`, "
        "the configured cyclic reads and DP14, and optionally one of the manual's three example programs "
        "(`user_program`); anything else a user program would do, a host does over S-Bus. ComErS is one of "
        "`comers_action` continue, halt or xob13_diag.",
        "A PCD instruction interpreter is beyond the module this kind simulates.",
    ),
    Deviation(
        "§7.4 DPB14",
        "DPB14 fills all digits of a PCA2.D14 with blanks.",
        "No user program calls DPB14: the display of an axis in `display` shows DP14's output every cycle, an "
        "axis not listed stays blank.",
        "Only the examples' user programs run inside the simulator, and they do not call DPB14.",
    ),
    Deviation(
        "§7.4 FRdAV, FRdSV",
        "RActV and RSetV range over [0 … 2^30 − 1] / k · 22348 · 10^−6: no sign.",
        "[SIM-CHOICE] They carry the direction: negative while the axis moves backwards (FBackw, velocity mode "
        "backwards, a move to a smaller target); `velocity_readback_unsigned: true` gives the printed reading.",
        "The LM628 reports its velocities in two's complement (RDRV, RDDV) and the FB divides them by k; the "
        "printed range repeats FLdVA's load range (spec G-11).",
    ),
    Deviation(
        "§7.4 FRdSR",
        "RSigB bit 12: 0 = forward, 1 = backward.",
        "1 = forward, as MCW bit 12 (§7.4 FSelOM: 1 = vorwärts) and the LM628 have it; "
        "`rsigb_bit12_inverted: true` gives the FRdSR text's reading.",
        "The manual contradicts itself (FSelOM and FRdSR); the spec decides for the chip (G-5).",
    ),
    Deviation(
        "§7.4 FRdSR, FMotOff",
        "RSigB bit 7 (control off) is set by FMotOff and by FStop with MCW bit 8 among others, and reset with the "
        "next FStart.",
        "[SIM-CHOICE] A FStart right after FMotOff or a motor-off FStop repeats that stop: the control stays off "
        "(bit 7 = 1) until FSelOM or a load of a target, velocity or acceleration has run before the FStart. After "
        "AxInit, FLdAA/FLdAR or a position error trip, FStart alone switches the control on.",
        "The manual says both: an interrupted move is resumed without a new parameter only after FSelOM (§7.4 "
        "FStop), and FMotOff is FStop with bit 8 (§7.4 FMotOff); the chip keeps a stop in its trajectory control "
        "word until the next LTRJ (spec G-3).",
    ),
    Deviation(
        "§7.4 FSetPE",
        "ExcPEr is set when the position error reaches PosEr (FSetPE; FResSF says: exceeds).",
        "ExcPEr is set when the error exceeds PosEr (strictly greater).",
        "The manual says both; the LM628 sets the flag on exceeding (spec G-9).",
    ),
    Deviation(
        "§8",
        "The H3 controller sets its command error flag when it cannot interpret a command or its data; the "
        "manual describes no S-Bus (the spec's host interface, §9.2, lists the PCD's NAK codes 0002h "
        "password, 0003h PGU port in reduced protocol and 0004h PGU port already used), and the LM628 behind "
        "the flag also reports busy (status bit 0) after each command byte and data word and a command error "
        "for a read where a write was expected (spec §3.5.2, §3.7).",
        "Never sent or set: a telegram the station cannot carry out is NAK 0001h; a chip command completes "
        "at once, so status bit 0 and the diagnostics flag 'chip busy' (F 8000 + 1) read 0; the command error "
        "comes from the manual's five causes (§8: a negative velocity, a conversion overflow, a factor above "
        "32 767, a relative load before the first start, `axis.N.bus_errors`) and the spec's range checks.",
        "The manual gives no situation for these codes: the simulated station has no password and no PGU port, "
        "and the chips are reached only through the library's functions (the bus-level access of spec §9.7 "
        "is not simulated), which wait for busy and never read where they write.",
    ),
)
