"""``devsim plot`` (devsim/observe/plot.py, devsim/observe/plot_data.py) and ``devsim scenario run --plot DIR``.

The pictures are checked by readers nobody here wrote: Pillow opens and verifies the PNG,
the standard library's XML parser reads the SVG.  The README's picture (docs/motion-plot.png) is
made here, so it is always what the current code draws."""

from __future__ import annotations

import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner
from PIL import Image

from devsim.cli import cli, exits
from devsim.core.extras import install_command
from devsim.observe.plot import MARGIN, PANEL_HEIGHT, WIDTH
from devsim.observe.plot_data import MotionData, Traffic, load, read_motion_log
from devsim.transports.pcap import PcapTracer
from devsim.transports.trace import Tracer
from tests.support.process import devsim_env

ROOT = Path(__file__).resolve().parents[1]
SERS = ROOT / "scenarios" / "sers" / "absolute_positioning.yaml"
GMS96 = ROOT / "scenarios" / "gms96" / "following_error_blocked_axis.yaml"
README_PICTURE = ROOT / "docs" / "motion-plot.png"
SVG = "{http://www.w3.org/2000/svg}"


def invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(cli, list(args), prog_name="devsim")
    return result.exit_code, result.stdout, result.stderr


def png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


@pytest.fixture(scope="module")
def sers_files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The SERS scenario run with --plot: its motion log and its trace."""
    out = tmp_path_factory.mktemp("sers")
    code, stdout, stderr = invoke("scenario", "run", str(SERS), "--plot", str(out))
    assert code == 0, stdout + stderr
    assert f"plot: {out / 'absolute_positioning.png'}" in stdout
    return out / "absolute_positioning.csv", out / "absolute_positioning.traces" / "x.trace"


def test_png_is_a_valid_image_of_the_expected_size(sers_files: tuple[Path, Path], tmp_path: Path) -> None:
    out = tmp_path / "move.png"
    code, stdout, stderr = invoke("plot", *map(str, sers_files), "-o", str(out))
    assert code == 0, stderr
    assert stdout.strip() == str(out)
    # position, velocity, traffic (a stepper has no following error)
    assert png_size(out) == (WIDTH, 3 * PANEL_HEIGHT + MARGIN) == (1000, 760)
    with Image.open(out) as image:
        image.verify()
    with Image.open(out) as image:
        assert image.size == (1000, 760)
        colours = image.convert("RGB").getcolors(maxcolors=1 << 20)
        assert colours is not None and len(colours) > 50  # drawn, not a blank page


def _texts(root: ET.Element) -> list[str]:
    return ["".join(element.itertext()) for element in root.iter(f"{SVG}text")]


def test_svg_parses_and_names_its_axes(sers_files: tuple[Path, Path], tmp_path: Path) -> None:
    out = tmp_path / "move.svg"
    code, _, stderr = invoke("plot", *map(str, sers_files), "-o", str(out), "--title", "SERS 90°")
    assert code == 0, stderr
    texts = _texts(ET.parse(out).getroot())
    for label in ("position (inc)", "velocity (inc/s)", "line traffic", "time (s)", "SERS 90°", "x axis",
                  "x main host→dev", "x main dev→host"):
        assert label in texts, label
    assert any("move_end" in text for text in texts)
    assert "following error" not in texts
    assert "#P51?" in texts and "P51=90°" in texts and "ok1" in texts  # the drive's lines, as the host reads them


def test_html_is_a_page_around_the_svg(sers_files: tuple[Path, Path], tmp_path: Path) -> None:
    out = tmp_path / "move.html"
    code, _, stderr = invoke("plot", str(sers_files[0]), "-o", str(out))
    assert code == 0, stderr
    page = out.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and page.rstrip().endswith("</html>")
    assert "<script" not in page
    svg = page[page.index("<svg"): page.index("</svg>") + len("</svg>")]
    texts = _texts(ET.fromstring(svg))
    assert "position (inc)" in texts and "velocity (inc/s)" in texts and "line traffic" not in texts


@pytest.fixture(scope="module")
def gms96_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The GMS96 blocked-axis scenario run with --plot (the README's picture)."""
    out = tmp_path_factory.mktemp("gms96")
    code, stdout, stderr = invoke("scenario", "run", str(GMS96), "--plot", str(out))
    assert code == 0, stdout + stderr
    return out


def test_a_servo_gets_its_set_point_and_following_error(gms96_dir: Path, tmp_path: Path) -> None:
    log = read_motion_log(gms96_dir / "following_error_blocked_axis.csv")
    (series,) = log.axes
    assert series.has("setpoint") and series.has("following_error")
    assert max(series.following_error) > 500  # the blocked axis
    assert any(name == "fault:blocked_axis=on" for _, name in log.events["card"])
    code, _, stderr = invoke("plot", str(gms96_dir / "following_error_blocked_axis.csv"), "-o", str(tmp_path / "g.svg"))
    assert code == 0, stderr
    texts = _texts(ET.parse(tmp_path / "g.svg").getroot())
    assert "following error (inc)" in texts and "card axis set-point" in texts


def test_a_motion_log_whose_last_line_is_cut_short_plots_the_lines_before(gms96_dir: Path, tmp_path: Path) -> None:
    """(As a pcap's or a session's cut end: the writer killed or the disk full; it was refused.)"""
    whole = (gms96_dir / "following_error_blocked_axis.csv").read_text()
    cut = tmp_path / "cut.csv"
    cut.write_text(whole[: whole.rindex("\n", 0, len(whole) - 1) + 20])  # the last line's first 19 characters
    (series,) = read_motion_log(cut).axes
    (complete,) = read_motion_log(gms96_dir / "following_error_blocked_axis.csv").axes
    assert series.time == complete.time[:-1]
    code, _, stderr = invoke("plot", str(cut), "-o", str(tmp_path / "cut.svg"))
    assert code == 0, stderr
    broken = tmp_path / "broken.csv"  # a short line that is not the last, or one with its line end: refused
    broken.write_text(whole[: whole.rindex("\n", 0, len(whole) - 1) + 20] + "\n")
    assert invoke("plot", str(broken), "-o", str(tmp_path / "b.svg"))[0] != 0


def test_text_and_pcap_traces_read_back(tmp_path: Path) -> None:
    chunks = [(0.5, "H>D", b"#1 ON\r"), (0.502, "D>H", b"ok0\n\r"), (1.25, "H>D", bytes(range(0, 256, 17)))]
    with Tracer(tmp_path / "line.trace") as tracer:
        tracer.note("host 9600 8N1", 0.1)
        for when, way, data in chunks:
            tracer.record(way, data, when)
    text = load(tmp_path / "line.trace")
    assert isinstance(text, Traffic) and text.name == "line"
    assert text.chunks == chunks and text.notes == [(0.1, "host 9600 8N1")]
    # invented addresses (a pty) and real ones (a UDP device port below the host's ephemeral port)
    for name, peers in (("pty", None), ("udp", (("127.0.0.1", 54321), ("127.0.0.1", 5050)))):
        with PcapTracer(tmp_path / f"{name}.pcap", peers=(lambda p=peers: p), name=name) as pcap:
            for when, way, data in chunks:
                pcap.record(way, data, when)
        read = load(tmp_path / f"{name}.pcap")
        assert isinstance(read, Traffic)
        assert [(pytest.approx(w, abs=1e-6), d, b) for w, d, b in read.chunks] == chunks, name


def test_a_trace_alone_is_a_traffic_timeline(tmp_path: Path, sers_files: tuple[Path, Path]) -> None:
    out = tmp_path / "line.png"
    code, _, stderr = invoke("plot", str(sers_files[1]), "-o", str(out))
    assert code == 0, stderr
    assert png_size(out) == (WIDTH, PANEL_HEIGHT + MARGIN)


@pytest.mark.parametrize(
    ("content", "output", "message", "status"),
    [
        ("time,device,axis\n", "x.png", "not a motion log", exits.BAD_FILE),
        ("hello\n", "x.png", "not a trace line", exits.BAD_FILE),
        ("", "x.gif", "-o: the output must end in .png, .svg or .html", exits.USAGE),
        # damaged motion logs (fuzzed): each was a traceback (UnicodeDecodeError, _csv.Error)
        (b"time,device,axis,setpoint,position,velocity,following_error,event,kind\n1.0,sers,\xb3\n", "x.png",
         "not a motion log (byte 80 is not UTF-8 text)", exits.BAD_FILE),
        ("time,device,axis,setpoint,position,velocity,following_error,event,kind\n1.0,sers,axis," + "9" * 200_000,
         "x.png", "not a motion log (field larger than field limit", exits.BAD_FILE),
    ],
)
def test_bad_input_is_one_line(tmp_path: Path, content: str | bytes, output: str, message: str, status: int) -> None:
    source = tmp_path / "in.csv"
    source.write_bytes(content) if isinstance(content, bytes) else source.write_text(content)
    code, _, stderr = invoke("plot", str(source), "-o", str(tmp_path / output))
    assert code == status and message in stderr and stderr.count("\n") == 1, stderr
    assert not (tmp_path / output).exists()


def test_scenario_run_plot_writes_one_picture_per_scenario(tmp_path: Path) -> None:
    scenarios = [SERS, ROOT / "scenarios" / "sers" / "homing_standard.yaml"]
    code, stdout, stderr = invoke("scenario", "run", *map(str, scenarios), "--plot", str(tmp_path / "plots"),
                                  "--motion-log", str(tmp_path / "log.csv"), "--motion-resolution", "0.005")
    assert code == 0, stdout + stderr
    pictures = sorted(p.name for p in (tmp_path / "plots").glob("*.png"))
    assert pictures == ["absolute_positioning.png", "homing_standard.png"]
    for name in pictures:
        assert png_size(tmp_path / "plots" / name)[0] == WIDTH
    # with several scenarios, --motion-log FILE becomes FILE-STEM per scenario, sampled at 5 ms
    for stem in ("absolute_positioning", "homing_standard"):
        log = load(tmp_path / f"log-{stem}.csv")
        assert isinstance(log, MotionData) and log.axes[0].position
        times = [t for t in log.axes[0].time if t not in {w for w, _ in log.events["x"]}]
        assert all(abs(t / 0.005 - round(t / 0.005)) < 1e-6 for t in times)


def test_the_readme_picture_is_current(gms96_dir: Path) -> None:
    """docs/motion-plot.png is drawn by this test from the GMS96 scenario (matplotlib output is
    not byte-stable across versions, so it is checked as an image, not compared byte for byte)."""
    made = gms96_dir / "following_error_blocked_axis.png"
    assert png_size(made) == (WIDTH, 4 * PANEL_HEIGHT + MARGIN)
    with Image.open(made) as image:
        image.verify()
    shutil.copyfile(made, README_PICTURE)
    assert png_size(README_PICTURE) == (1000, 980)


def test_without_matplotlib_the_command_says_what_to_install(
    monkeypatch: pytest.MonkeyPatch, sers_files: tuple[Path, Path], tmp_path: Path
) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib raises ImportError
    code, _, stderr = invoke("plot", str(sers_files[0]), "-o", str(tmp_path / "x.png"))
    hint = f"needs matplotlib: {install_command('plot')}"  # the checkout's or the distribution's extra: tests/test_extras.py
    assert code == exits.SYSTEM and hint in stderr
    code, _, stderr = invoke("scenario", "run", str(SERS), "--plot", str(tmp_path / "plots"))
    assert code == exits.SYSTEM and hint in stderr
    assert not (tmp_path / "plots").exists()


def _devsim(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=devsim_env(), capture_output=True,
                          text=True, timeout=120, stdin=subprocess.DEVNULL)


def test_a_real_run_s_plot_has_units_device_names_and_decoded_traffic(tmp_path: Path) -> None:
    """`devsim scenario run` of the GMS96 scenario writes a motion log and a trace of its FT1.2
    line; `devsim plot` of them names each panel's unit and the device, and labels the traffic
    with the decoded frames (the letters and E5), not their hex."""
    ran = _devsim("scenario", "run", str(GMS96), "--plot", str(tmp_path / "run"))
    assert ran.returncode == 0, ran.stdout + ran.stderr
    log, trace = tmp_path / "run" / "following_error_blocked_axis.csv", tmp_path / "run" / "following_error_blocked_axis.traces" / "card.trace"
    assert log.read_text().splitlines()[1].endswith(",gms96")  # the kind beside each row
    assert trace.read_text().splitlines()[0] == "0.000000 -- source card port main kind gms96"
    out = tmp_path / "plot.svg"
    drawn = _devsim("plot", str(log), str(trace), "-o", str(out))
    assert drawn.returncode == 0, drawn.stderr
    texts = _texts(ET.parse(out).getroot())
    for label in ("position (inc)", "velocity (inc/s)", "following error (inc)", "card axis", "card axis set-point",
                  "card main host→dev", "card main dev→host", "M 20000", "A 30000", "#1", "E5"):
        assert label in texts, label
    assert not [text for text in texts if text.startswith(("68 06", "e5", "h·"))], texts  # no raw chunk labels


def test_axes_of_kinds_with_different_units_say_theirs(tmp_path: Path) -> None:
    """A SERS (inc) and a PCD4.H3 (counts) in one log: the panels name the quantity, each axis its
    device and unit; a log from before the kind column draws with the quantities alone."""
    log = tmp_path / "two.csv"
    log.write_text("time,device,axis,setpoint,position,velocity,following_error,event,kind\n"
                   "0.0,x,axis,,0.0,0.0,,,sers\n1.0,x,axis,,10.0,5.0,,,sers\n"
                   "0.0,pcd,axis.1,0,0,0.0,0,,pcd4h3\n1.0,pcd,axis.1,20,20,7.0,1,,pcd4h3\n", encoding="utf-8")
    out = tmp_path / "two.svg"
    drawn = _devsim("plot", str(log), "-o", str(out))
    assert drawn.returncode == 0, drawn.stderr
    texts = _texts(ET.parse(out).getroot())
    for label in ("position", "velocity", "x axis (inc/s)", "pcd axis.1 (counts/s)", "pcd axis.1 (counts)"):
        assert label in texts, label
    old = tmp_path / "old.csv"
    old.write_text("\n".join(line.rsplit(",", 1)[0] for line in log.read_text().splitlines()) + "\n")
    drawn = _devsim("plot", str(old), "-o", str(out))
    assert drawn.returncode == 0, drawn.stderr
    texts = _texts(ET.parse(out).getroot())
    assert "velocity" in texts and "x axis" in texts and not any("(inc" in text for text in texts)
