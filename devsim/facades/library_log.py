"""The log lines of the protocol stacks behind the facades, rate-limited.

canopen logs a traceback for every SDO request shorter than eight bytes, python-can a line for every
error in a listener: a noisy or hostile host would fill the simulator's stderr.  :func:`limit` routes a library's logger through
:func:`devsim.transports.fdlimit.report`: one line per kind of message every ten seconds, with the
repeats counted, and nothing beyond its logger (``propagate`` off).
"""

from __future__ import annotations

import logging

from devsim.transports.fdlimit import report

__all__ = ["limit"]


class _RateLimited(logging.Handler):
    def __init__(self, label: str) -> None:
        super().__init__(logging.WARNING)
        self.label = label

    def emit(self, record: logging.LogRecord) -> None:
        lines = record.getMessage().splitlines() or [""]
        text = lines[0]
        if record.exc_info and record.exc_info[1] is not None and text != str(record.exc_info[1]):
            text += f": {record.exc_info[1]}"
        report(f"{self.label} {record.name} " + " ".join(text.split()[:3]), f"{self.label}: {text}")


def limit(name: str, label: str) -> None:
    """Rate-limit logger ``name`` (and its children), its lines headed ``devsim: LABEL:``."""
    log = logging.getLogger(name)
    if not any(isinstance(handler, _RateLimited) for handler in log.handlers):
        log.addHandler(_RateLimited(label))
        log.propagate = False
