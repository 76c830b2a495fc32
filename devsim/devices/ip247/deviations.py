"""Where the ip247 simulator knowingly differs from its manual, and why (``devsim doc ip247``
prints these rows as the *Deviations* section of docs/devices/ip247.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = (
    # -- chapters 1, 2 and 4 ---------------------------------------------------------------------------
    Deviation(
        "§2.5.1.1",
        "the pulse output T idles low or high and is active on the edge the polarity datum selects; each "
        "pulse lasts the pulse duration (§2.5.1.2, output in 2 µs steps)",
        "there is no T signal: the motion is computed in closed form from the pulse frequency; only the "
        "direction output RP follows the polarity",
        "a signal per step (up to 100 kHz) would flood the signal bank and the traces; the pulse count and "
        "frequency are what positions and velocities show",
    ),
    Deviation(
        "§2.5.4.2",
        "the lowest frequency f_min lies in 1 … 15.25 Hz, set by the ramp table the module generates",
        "f_min is 1 Hz for every machine-data set (spec ip247.md §4.9.2 [DECISION])",
        "the manual does not say how the ramp table yields f_min",
    ),
    Deviation(
        "§2.6.6.3",
        "under load a flying change can abort with 57 'Satz ist noch nicht fertig interpretiert'",
        "error 57 never occurs",
        "the simulator interprets a block in no time; the firmware's run-time limit is not documented",
    ),
    Deviation(
        "§4.3.1",
        "the program interpreter runs some blocks ahead, so an error in a later block can be reported "
        "before that block is reached",
        "a block is interpreted when the program reaches it; only a G10 chain is interpreted as a whole "
        "when it starts (its error 52 or 47 comes then)",
        "how far the firmware runs ahead is not documented",
    ),
    Deviation(
        "§2.6.6.9",
        "example: reference coordinate 0, zero offset +500 mm, tool offset 20 mm: after G74 the actual value "
        "is 480 mm",
        "the actual value is −480 mm",
        "§2.6.6.7 and §4.3.6 say a positive zero offset makes every coordinate more negative, and §2.5.5.1 "
        "that a positive tool offset adds to the tip's coordinate; the example's sign contradicts both",
    ),
    Deviation(
        "§4.3.8",
        "'BA15 −80 mm Rückwärts' is a tool offset of 60 mm forward",
        "it is a tool offset of 80 mm forward",
        "the same sentence says the value's sign counts; 60 is a misprint",
    ),
    Deviation(
        "§2.7.6",
        "jobs without motion (coordinate transformations, data transfers) set the axis state to 'läuft' "
        "until they are done",
        "they are done before the job is answered: a host never sees 'läuft' for them",
        "the simulator carries them out in no time",
    ),
    # -- chapter 3 (hardware) ------------------------------------------------------------------
    Deviation("§3.1.4", "technical data: output and input voltages and currents (5 V / 24 V / Us), input "
              "thresholds, 120 mA outputs, supply and battery currents, dimensions, temperatures",
              "signals are booleans (input.ANF1 … output.PE3, RS, RP); nothing electrical is modelled",
              "a software twin has no electrical side"),
    Deviation("§3.3.3", "the power-unit outputs T, RP, RS (and inverted) at 5 V differential, 5 V/24 V opto or "
              "a special voltage Us, chosen with jumpers X30/X31; the clock T is a pulse train of up to 100 kHz",
              "RP and RS are boolean outputs; the pulse train is not a signal: position and velocity are "
              "computed in closed form (axis.N.machine_position, axis.N.velocity)",
              "edges at 100 kHz would cost CPU for nothing a host can see; the physics is event-driven"),
    Deviation("§3.3.1", "switch S1 and jumpers X14 … X18 set the address space F400H … F7FFH of the 4 kbyte "
              "dual-port RAM in which the CPU reaches the four pages",
              "the PLC side is the length-framed endpoint 'ag' (spec §3.7) with absolute page numbers "
              "from base_page (S2); there is no address space",
              "a dual-port RAM on the S5 bus cannot be offered to a host program; the endpoint carries the "
              "same jobs and answers"),
    Deviation("§3.3.5", "the PG interface X8 is a 20 mA current loop at 9600 bit/s set by pins 2, 3, 4, 17 of "
              "the PG's connector; on AG 135U/155U it can also run over the backplane and the coordinator",
              "the port 'pg' is a pty (or socket) carrying the AS511 bytes; a pty has no current loop, its "
              "baud rate is not enforced, and Linux ptys drop the parity bit; no backplane PG access",
              "a pty cannot carry a current loop nor 8E1 framing"),
    # -- chapter 5 (COM247) ----------------------------------------------------------------------
    Deviation("§5.1–§5.11", "COM247 on the PG: its screens, function keys, presets, files (.247) on floppy or "
              "hard disk, the PG's own memory, printing, installation under S5-DOS/PCP/M, its limits (250 "
              "programs per file, 16 machine-data sets per axis and file, 48 entries per directory page) and "
              "the PG keyboard's repeat buffer",
              "not simulated: the simulator is the module behind the PG port; what COM247 sends (BA24 at "
              "BEGINN, BA70 at ONLINE, BA20/22 with the overwrite question, BA17 on leaving the test screen, "
              "operator jobs, OBSERVE) is answered as the module answers it",
              "a host program emulating COM247 talks to the module; the twin of COM247 is that host"),
    Deviation("§5.6.1.2", "COM247's machine-data page 4: the tool length must be smaller than the range the "
              "software limit switches allow",
              "a linear axis's tool length is checked against ±100 m only (MD error 14 as §7.2.1 and §2.5.5.1 "
              "define it); a rotary axis's against its range",
              "the sentence describes COM247's input field; the module's own check is the one §7.2.1 gives"),
    Deviation("§5.4, §6.3.8.3", "module number 0 … 99, slot 0 … 255, page 0 … 252 (BA24)",
              "BA24 takes any byte for each; the module number is frozen by correct machine data (12)",
              "the manual gives the ranges for COM247's screen and FB165's data block, not a module error "
              "for values outside them"),
    # -- chapter 6 (FB164 / FB165) ---------------------------------------------------------------
    Deviation("§6.1–§6.2.5, §6.2.7–§6.2.8, §6.3.1–§6.3.7, §6.3.9",
              "FB164 and FB165 run in the PLC: call parameters SSNR, DBNR, DWNR, BA, STAR … UEBN edges, BCD, "
              "ANST, Q-DB/QANF/Z-DB/ZANF; their parameter checks (PAFE, MB255); the work areas DB164 DW8–15 "
              "and DB165 DW3–47; the axis data block DW n … n+19 (n+14); indirect parametrization; the "
              "handling blocks SEND/RECEIVE/FETCH/SYNCHRON and BLGR; flag bytes MB200–MB255; run times",
              "not simulated: the endpoint 'ag' takes the jobs the blocks hand to the module (page, mode, "
              "command, byte/word/double-word parameters; record transfers) and answers with what the "
              "module shows them (ack, error, BTR, RMLD, MFKT, records)",
              "the simulator plays the module; the function blocks are PLC software a PLC replacement "
              "implements over the endpoint"),
    Deviation("§6.2.4, §6.2.9", "observe functions 71/73 are read cyclically by FB164 into ANZG (BA74 stops it), "
              "converted to BCD when the parameter BCD is 1; the module's negative acknowledgement shows at "
              "FB164 as PAFE with the SEND/RECEIVE error C1H",
              "OBSERVE (62H) returns actual value and residual distance (binary) at any time; a refused job "
              "is ack 80H; there is no ANZG or PAFE, and an OPERATE with BA74 is taken (ack 00H) and changes "
              "nothing (there is no cyclic reading to stop)",
              "cyclic observation, the BCD output and PAFE are FB164's, not the module's"),
    Deviation("§6.2.6", "TBIT is FB164's output, set by the FB when it hands over a job and reset when the module "
              "reports the job finished, with a reliable edge even for jobs shorter than a PLC cycle",
              "emulated as the point axis.N.tbit from the endpoint's jobs; set while a job from the PLC side "
              "runs; there is no PLC cycle, so a job that ends at once never shows TBIT set",
              "TBIT belongs to FB164; the point lets PLC-replacement tests see what it would be"),
    Deviation("§6.3.8.5", "a program directory longer than the target DB continues in DBx+1 from DW0, up to DW255 "
              "of both; it is cut or the job ends with an error when it does not fit",
              "BA65 returns the directory as one record of up to 510 words",
              "placing it in PLC data blocks is FB165's work"),
    Deviation("§6.3.8.6, §7.2", "with BCD conversion a value beyond ±9999999 stays binary and MB249 bits 0/1 tell "
              "which one",
              "BA66 with the BCD flag converts what it can and leaves the rest binary; there is no MB249",
              "MB249 is FB165's flag byte"),
    Deviation("§6.3.8.2", "a program DB is at most 512 words long",
              "a program of 1023 characters (§2.6.1, §5.6.2.1) is a record of 517 words (5 header words and "
              "the text); BA22 takes and BA69 gives it",
              "the manual allows 1023 characters per program elsewhere; 512 words hold only 1014"),
    Deviation("§6.3.8.1", "machine data can be transferred, read and deleted only over the axis's own page",
              "BA67 also reads them over the data channel while all DB numbers differ",
              "§6.3.4 and §4.3.15 allow that; only transfer and delete are tied to the axis's page"),
    Deviation("§6.3.10", "after switching on, module, slot and page number are preset to 0",
              "they are 0 (or the config's sys_id) only when the battery RAM is empty; with the battery "
              "they are kept like the machine data",
              "machine data stay valid across a restart with the battery (§7.3.3), which they could not if "
              "the module number fell back to 0 (their module number must equal the SYS-ID's)"),
    Deviation("§6.1.3, §7.3.2", "several CPUs must not operate the same axis (it leads to program errors)",
              "any number of hosts may use the endpoint and the PG port; jobs are taken in arrival order",
              "what goes wrong in a multi-processor PLC is the PLC's, not the module's"),
    Deviation("§6.4", "the example PLC programs (OB1, OB20–22, FB51–FB54, DB assignments, flag bytes)",
              "not simulated", "PLC software; the simulator plays the module"),
    # -- chapter 7 (errors, service) -------------------------------------------------------------
    Deviation("§7.2", "MB250 interface errors (handling blocks: offset too large, DB missing, wrong ORG, "
              "areas too small …) and MB255 parameter errors",
              "not produced; the endpoint answers 80H (refused), 81H (job list full) or a module error",
              "they are the function blocks' and handling blocks' diagnostics in the PLC"),
    Deviation("§7.2", "COM247's own messages: editor errors 10H–2FH/D0H–D1H, mass storage 30H–3FH, AS511 "
              "errors 40H–5FH, general F0H–FFH; module errors shown as F80H + number",
              "the module never sends them; answers carry the module error number as the PLC sees it",
              "they are COM247's texts on the PG; a host emulating COM247 adds 80H itself"),
    Deviation("§7.2, §7.2.2", "error 34 'Impulsgenerator defekt' (a hardware fault) and 56 'Fehlerhafter Zugriff "
              "auf Rampentabelle'",
              "never raised; no fault injects them", "the manual names no cause a host could provoke"),
    Deviation("§7.2", "errors 35, 36, 37, 40, 41, 42, 44, 45 found by the interpreter while a program runs",
              "the module checks a program's syntax when it is stored (BA22: error 48, the syntax error in "
              "DW n+3) and refuses to start a faulty one (48), so the interpreter never meets them",
              "every cause these errors name is a syntax error the store already reports"),
    Deviation("§7.2.2, §7.2.1", "error 54 'Fehlerhafte Generierung der Rampentabelle' (MD error 16): no ramp can "
              "be made from f_max, f_ss and the frequency increase",
              "never raised: MD errors 3, 6 and 22 already refuse every combination the exponential ramp "
              "cannot use", "the ramp is closed-form; nothing is generated that could fail"),
    Deviation("§7.2.1", "error 3: the maximum frequency lies within 0.012 … 100.000 kHz",
              "40 Hz … 100 kHz (below 40 Hz: MD error 3)",
              "§2.5.3.5, COM247's screen (§5.6.1.2) and §7.1.4 say 40 Hz; spec §4.4 decides for them"),
    Deviation("§7.2.1", "error 17: the reference velocity's frequency must be above f_ss and below f_max",
              "f_ss < f_ref ≤ f_max: the reference velocity may reach f_max",
              "the manual's own example record (§6.3.8.1: 3000 mm/min at 10 µm per pulse = 5000 Hz = f_max) "
              "is valid, and COM247's machine-data page 2 (§5.6.1.2) says 'kleiner oder gleich der "
              "Maximalfrequenz'"),
    Deviation("§7.2", "error 33 'Zykluszeit überschritten' (no cause given)",
              "raised when 10,000 blocks run without a traverse or dwell taking time (an endless loop "
              "without motion): the program ends, the module keeps answering",
              "a real module's cycle watchdog; the simulator must not spin"),
    Deviation("§7.1.3, §7.1.1", "the motor is chosen from its torque characteristic: load torque, start/stop "
              "frequency and the frequency up to which it keeps its torque",
              "a motor has only the configured max_start_hz and pullout_hz (axes.N): above them steps are "
              "lost; no torque or load model",
              "enough to show step loss, which is what a host can observe"),
)
