"""Motion logs and plots of scenario runs (``devsim scenario run --motion-log FILE --plot DIR``).

Per scenario:

* ``--motion-log FILE.csv`` logs every axis of the scenario's plant
  (:mod:`devsim.observe.motion_log`); with several scenarios each gets its own file,
  ``FILE-STEM.csv`` (``STEM``: the scenario file's name without ``.yaml``);
* ``--plot DIR`` draws ``DIR/STEM.png`` (or ``.svg``/``.html``, ``--plot-format``) from the
  scenario's motion log and the traces of its ports (:mod:`devsim.observe.plot`).  What it is drawn from
  stays beside it: the motion log (``DIR/STEM.csv`` unless ``--motion-log`` names one) and, unless
  ``--trace-dir`` is given, the traces in ``DIR/STEM.traces/``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from devsim.observe.motion_log import start_motion_log

__all__ = ["ScenarioPictures"]


class ScenarioPictures:
    """Where one scenario run's motion log, traces and plot go, and the hooks that make them."""

    def __init__(
        self,
        *,
        motion_log: str | None,
        resolution: float,
        plot_dir: str | None,
        plot_format: str = "png",
        trace_dir: str | None,
        count: int,
    ) -> None:
        self.motion_log = motion_log
        self.resolution = resolution
        self.plot_dir = Path(plot_dir) if plot_dir is not None else None
        self.plot_format = plot_format
        self.user_trace_dir = trace_dir
        self.count = count
        self._stems: set[str] = set()
        self.stem = ""
        self.ports: list[str] = []

    def begin(self, scenario_path: str) -> str | None:
        """Choose the file names for the next scenario; returns its trace directory."""
        stem = Path(scenario_path).stem or "scenario"
        base, number = stem, 2
        while stem in self._stems:  # two scenarios of the same name in different directories
            stem, number = f"{base}-{number}", number + 1
        self._stems.add(stem)
        self.stem = stem
        self.ports = []
        if self.plot_dir is not None:
            self.plot_dir.mkdir(parents=True, exist_ok=True)
        if self.user_trace_dir is None and self.plot_dir is not None:
            return str(self.plot_dir / f"{stem}.traces")
        return self.user_trace_dir

    @property
    def log_path(self) -> Path | None:
        if self.motion_log is not None:
            if self.count == 1:
                return Path(self.motion_log)
            path = Path(self.motion_log)
            return path.with_name(f"{path.stem}-{self.stem}{path.suffix or '.csv'}")
        if self.plot_dir is not None:
            return self.plot_dir / f"{self.stem}.csv"
        return None

    def start(self, plant: Any) -> None:
        """In the runtime's loop, once the plant is built: start the motion log."""
        path = self.log_path
        if path is not None:
            start_motion_log(plant.runtime, list(plant.devices.values()), path, self.resolution)
        self.ports = list(plant.lines)

    def finish(self, trace_dir: str | None) -> str | None:
        """After the run (the runtime stopped, the log closed): draw the plot; returns the line
        to print (``plot: DIR/STEM.png``), or None without ``--plot``."""
        if self.plot_dir is None:
            return None
        from devsim.observe.plot import render
        from devsim.observe.plot_data import PlotInputError

        log = self.log_path
        files: list[Path] = [log] if log is not None and log.exists() else []
        if trace_dir is not None:
            for name in self.ports:
                for suffix in ("trace", "pcap"):
                    candidate = Path(trace_dir) / f"{name}.{suffix}"
                    if candidate.exists():
                        files.append(candidate)
        out = self.plot_dir / f"{self.stem}.{self.plot_format}"
        try:
            return f"plot: {render(files, out, title=self.stem)}"
        except PlotInputError as exc:
            return f"plot: {self.stem}: {exc}"
