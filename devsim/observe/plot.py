"""A picture of a motion and its line traffic (``devsim plot LOG|TRACE... -o move.png|svg|html``,
the command in :mod:`devsim.cli.plot`).

The files are motion logs (``--motion-log``) and wire traces (``--trace``, text or pcap), in any
number and order (:func:`devsim.observe.plot_data.load` tells them apart).  The picture has, against one
time axis (seconds of the device clock, which logs and traces share):

* **position** of every axis (its set-point dashed, where the kind has one),
* **velocity**,
* **following error** (only when an axis has one),
* **line traffic**: one lane per port and direction (host → device above device → host), a tick
  per chunk; when there are few, each message beside it, decoded by the port's declared framing
  where the trace names its source (``M 20000``, ``E5`` for a GMS96, ``#P51?`` for a SERS), else
  each chunk's text,

each axis named by its device (``card axis``, ``cnc axis.x``), each panel's quantity with its
unit from the kind's declared points (``velocity (inc/s)``; a unit per axis in the legend where
the axes differ),

with the events of the log (``move_start``, ``move_end``, faults …) as dotted vertical lines,
named on the top panel.  The output format follows the suffix: ``.png`` (``--dpi``), ``.svg``
(text kept as text), ``.html`` (that SVG in a small page, no scripts).  matplotlib is the extra
``[plot]``; it is imported only when a picture is drawn, without pyplot (no GUI, no global state).
"""

from __future__ import annotations

import html
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from devsim.observe.plot_data import MotionData, PlotInputError, Traffic, load, messages

__all__ = ["FORMATS", "PANEL_HEIGHT", "WIDTH", "MissingMatplotlib", "output_format", "render", "require_matplotlib"]

#: Output formats by suffix.
FORMATS = ("png", "svg", "html")
#: The figure's size in pixels at the default 100 dpi: WIDTH wide, PANEL_HEIGHT per panel + MARGIN.
WIDTH = 1000
PANEL_HEIGHT = 220
MARGIN = 100
#: At most this many events are named on the top panel (all are drawn), and traffic chunks
#: get their text beside them only up to this many per lane.
MAX_EVENT_LABELS = 30
MAX_CHUNK_LABELS = 24



class MissingMatplotlib(ImportError):
    """matplotlib is not installed; the message names the ``pip install``."""


def require_matplotlib() -> None:
    """Raise :class:`MissingMatplotlib` if matplotlib is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        from devsim.core.extras import install_command

        raise MissingMatplotlib(f"devsim plot needs matplotlib: {install_command('plot')}") from None


def output_format(path: str | Path) -> str:
    """``png``, ``svg`` or ``html`` from the output's suffix (ValueError for anything else)."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in FORMATS:
        raise ValueError(f"the output must end in .png, .svg or .html, not {Path(path).name!r}")
    return suffix


def _short(data: bytes, limit: int = 16) -> str:
    """A chunk as a short label: its text, or its hex when it is mostly binary."""
    printable = sum(0x20 <= b < 0x7F or b in (0x0A, 0x0D) for b in data)
    if printable * 2 < len(data):
        text = data.hex(" ")
    else:
        text = "".join(chr(b) if 0x20 <= b < 0x7F else "·" for b in data)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _panels(logs: Sequence[MotionData], traces: Sequence[Traffic]) -> list[str]:
    axes = [a for log in logs for a in log.axes]
    panels = []
    if axes:
        panels += ["position", "velocity"]
        if any(a.has("following_error") for a in axes):
            panels.append("following_error")
    if traces:
        panels.append("traffic")
    return panels


_YLABELS = {"position": "position", "velocity": "velocity", "following_error": "following error",
            "traffic": "line traffic"}


def _units(panel: str, logs: Sequence[MotionData]) -> set[str]:
    """The units the axes drawn on ``panel`` have (the empty one where the kind is unknown)."""
    return {series.unit(panel) for log in logs for series in log.axes if series.has(panel)}


def _ylabel(panel: str, logs: Sequence[MotionData]) -> str:
    """``velocity (inc/s)`` when every axis on the panel has that unit, else the quantity alone."""
    units = _units(panel, logs) if panel != "traffic" else set()
    return f"{_YLABELS[panel]} ({units.pop()})" if len(units) == 1 and "" not in units else _YLABELS[panel]


def _draw_axes(ax: Any, panel: str, logs: Sequence[MotionData]) -> None:
    each_unit = len(_units(panel, logs) - {""}) > 1  # differing units: each axis says its own
    index = 0
    for log in logs:
        for series in log.axes:
            colour = f"C{index % 10}"
            index += 1
            label = series.label + (f" ({series.unit(panel)})" if each_unit and series.unit(panel) else "")
            if series.has(panel):
                ax.plot(series.time, getattr(series, panel), color=colour, linewidth=1.2, label=label)
            if panel == "position" and series.has("setpoint"):
                ax.plot(series.time, series.setpoint, color=colour, linewidth=0.9, linestyle="--",
                        label=f"{label} set-point")
    if ax.lines:
        ax.legend(loc="best", fontsize=7, frameon=False)


def _cut(text: str, limit: int = 16) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _draw_traffic(ax: Any, traces: Sequence[Traffic]) -> None:
    ticks, names = [], []
    for index, traffic in enumerate(traces):
        decoded = messages(traffic)  # by the port's framing; [] where the trace does not say
        for offset, direction in ((1, "H>D"), (0, "D>H")):
            lane = 2 * (len(traces) - 1 - index) + offset
            ticks.append(lane)
            names.append(f"{traffic.label} {'host→dev' if direction == 'H>D' else 'dev→host'}")
            chunks = [(when, data) for when, way, data in traffic.chunks if way == direction]
            colour = "C0" if direction == "H>D" else "C3"
            if chunks:
                ax.vlines([w for w, _ in chunks], lane - 0.35, lane + 0.35, color=colour, linewidth=1.0)
            labels = ([(when, _cut(text)) for when, way, text in decoded if way == direction] if decoded
                      else [(when, _short(data)) for when, data in chunks])
            if len(labels) <= MAX_CHUNK_LABELS:
                for when, text in labels:
                    ax.annotate(text, (when, lane + 0.38), fontsize=6, rotation=30, color=colour,
                                annotation_clip=False)
        for when, _text in traffic.notes:
            ax.plot([when], [2 * (len(traces) - 1 - index) + 0.5], marker="d", color="0.5", markersize=4)
    ax.set_yticks(ticks, names, fontsize=7)
    ax.set_ylim(-0.8, 2 * len(traces) + 0.3)


def _mark_events(axes: Sequence[Any], logs: Sequence[MotionData]) -> None:
    devices = {device for log in logs for device in log.events}
    events = sorted({(when, f"{device}: {name}" if len(devices) > 1 else name)
                     for log in logs for device, items in log.events.items() for when, name in items})
    named: dict[float, list[str]] = {}  # events at one instant share a line and a label
    for when, name in events:
        if name not in named.setdefault(when, []):
            named[when].append(name)
    for ax in axes:
        for when in named:
            ax.axvline(when, color="0.45", linewidth=0.7, linestyle=":")
    top = axes[0]
    for when, names in list(named.items())[:MAX_EVENT_LABELS]:
        label = ", ".join(names)
        top.annotate(label if len(label) <= 32 else label[:31] + "…", (when, 1.0), xycoords=("data", "axes fraction"), xytext=(2, 2),
                     textcoords="offset points", fontsize=6, rotation=60, color="0.3", annotation_clip=False)


def render(files: Sequence[str | Path], out: str | Path, *, title: str | None = None, dpi: int = 100) -> Path:
    """Draw ``files`` (motion logs and traces) to ``out`` (.png, .svg or .html); returns ``out``."""
    kind = output_format(out)
    loaded = [load(path) for path in files]
    logs = [item for item in loaded if isinstance(item, MotionData)]
    traces = [item for item in loaded if isinstance(item, Traffic)]
    panels = _panels(logs, traces)
    if not panels:
        raise PlotInputError("nothing to draw: the files hold no axis and no traffic")

    import matplotlib
    from matplotlib.figure import Figure

    height = PANEL_HEIGHT * len(panels) + MARGIN
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "devsim"}):
        figure = Figure(figsize=(WIDTH / 100, height / 100), dpi=100, layout="constrained")
        axes = figure.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
        for ax, panel in zip(axes, panels, strict=True):
            if panel == "traffic":
                _draw_traffic(ax, traces)
            else:
                _draw_axes(ax, panel, logs)
            ax.set_ylabel(_ylabel(panel, logs), fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(True, linewidth=0.3, alpha=0.5)
        if logs:
            _mark_events(axes, logs)
        axes[-1].set_xlabel("time (s)", fontsize=8)
        figure.suptitle(title or ", ".join(Path(p).name for p in files), fontsize=9)
        target = Path(out)
        if kind == "png":
            figure.savefig(target, format="png", dpi=dpi, metadata={"Software": None})
        else:
            from io import StringIO

            buffer = StringIO()
            figure.savefig(buffer, format="svg", metadata={"Date": None})
            svg = buffer.getvalue()
            if kind == "svg":
                target.write_text(svg, encoding="utf-8")
            else:
                target.write_text(_html_page(svg, title or target.stem, files), encoding="utf-8")
    return target


def _html_page(svg: str, title: str, files: Sequence[str | Path]) -> str:
    """The SVG inline in a small page (no scripts): the picture and the files it was made from."""
    body = re.sub(r"^\s*<\?xml[^>]*>\s*(<!DOCTYPE[^>]*>\s*)?", "", svg)
    sources = "".join(f"<li>{html.escape(str(p))}</li>" for p in files)
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        f"<title>{html.escape(title)}</title>\n"
        "<style>body{font-family:sans-serif;margin:1em} svg{max-width:100%;height:auto}</style>\n"
        f"</head>\n<body>\n<h1>{html.escape(title)}</h1>\n{body}\n<p>From:</p>\n<ul>{sources}</ul>\n"
        "</body>\n</html>\n"
    )
