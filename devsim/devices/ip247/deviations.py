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
)
