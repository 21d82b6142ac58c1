"""Command line of ``python -m app``: every flag validated where it enters, errors name the flag (exit code 2).

Everything is checked before any rendering starts: numbers and their ranges, the output paths (not a folder
where a file is meant, in a folder that exists and is writable, every name at most NAME_MAX_BYTES long) and the
scenario file. Numbers use ASCII digits only; a negative value may follow its flag with a space
(``--seconds -inf``) or an equals sign (``--seconds=-inf``) and is answered with the flag's range.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

from rain_core.checks import quote
from rain_core.path_checks import (  # noqa: F401  (the checks were here first: app.cli's names stay)
    NAME_MAX_BYTES,
    PATH_MAX_BYTES,
    check_input_file,
    check_output_file,
    check_output_folder,
)

CAMERA_MODES = ("driver", "chase", "free", "glass")
WINDOW_BACKENDS = ("pyglet", "glfw", "sdl2", "pygame2", "pyqt5", "pyside2", "tk", "headless")
MAX_SIZE = 8192

# ASCII only (no Unicode digits, no underscores): a decimal number, or inf / nan so that they get the range message.
_NUMBER = re.compile(r"\s*[+-]?(\d+\.?\d*(e[+-]?\d+)?|\.\d+(e[+-]?\d+)?|inf|infinity|nan)\s*", re.ASCII | re.I)
_INTEGER = re.compile(r"\s*[+-]?\d+\s*", re.ASCII)
_SIZE = re.compile(r"\s*(\d+)[xX](\d+)\s*", re.ASCII)

EPILOG = """\
accepted values:
  numbers      ASCII digits: 3, 0.5, 2e3 (no Unicode digits, no '_'); a negative value may follow
               its flag with a space or '=' (--seconds=-1) and is refused with the flag's range
  --size       WIDTHxHEIGHT in pixels, 'x' or 'X' between them (1280x720, 1280X720), each in [16, 8192]
  --screenshot a .png file in an existing, writable folder; not a folder itself
  --record     a folder (created if missing) in an existing, writable folder: PNG frames; or a
               FILE.mp4: H.264 video (needs PyAV: pip install 'rainroad[video]'; even width and height)
  --labels     with --record: depth, masks and labels of every frame (NPZ + one JSON line a frame) in
               the record folder, or in FILE.labels/ beside FILE.mp4 (layout: rain_core/session/dataset.py)
  file names   every part of a path at most 255 bytes long
  --quality    offline: each frame averages --subframes renders across the shutter (camera.exposure_s)
  --seconds    on a terminal a run shows its progress (frames, frames/s, time left) on stderr;
               not on a terminal (logs) it stays quiet
"""


def _size(text: str) -> tuple[int, int]:
    m = _SIZE.fullmatch(text)
    if not m:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels with ASCII digits (e.g. 1280x720), "
                                         f"got {quote(text)}")
    # A number of more than 6 digits is out of range (and int() refuses one of 4300 digits).
    w, h = (int(g) if len(g.lstrip("0")) <= 6 else MAX_SIZE + 1 for g in m.groups())
    if not (16 <= w <= MAX_SIZE and 16 <= h <= MAX_SIZE):
        raise argparse.ArgumentTypeError(f"width and height must be in [16, {MAX_SIZE}] pixels, got {quote(text)}")
    return w, h


def _finite(lo: float, hi: float, unit: str):
    def parse(text: str) -> float:
        if not _NUMBER.fullmatch(text):
            raise argparse.ArgumentTypeError(f"expected a number (ASCII digits) in [{lo:g}, {hi:g}] {unit}, "
                                             f"got {quote(text)}")
        value = float(text)  # a 400-digit number reads as inf and is out of range
        if not math.isfinite(value) or not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be a finite number in [{lo:g}, {hi:g}] {unit}, "
                                             f"got {quote(text)}")
        return value

    return parse


def _int_in(lo: int, hi: int):
    def parse(text: str) -> int:
        if not _INTEGER.fullmatch(text):
            raise argparse.ArgumentTypeError(f"expected an integer (ASCII digits) in [{lo}, {hi}], "
                                             f"got {quote(text)}")
        digits = text.strip().lstrip("+-").lstrip("0")
        value = int(text) if len(digits) <= 30 else None  # int() refuses 4300 digits; 30 are out of any range
        if value is None or not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be in [{lo}, {hi}], got {quote(text)}")
        return value

    return parse


def _path(text: str) -> Path:
    if not text.strip():
        raise argparse.ArgumentTypeError("must not be empty (name a file or folder)")
    return Path(text)


def _keys_epilog() -> str:
    from app.controls import keys_help_text

    return "\nkeys in the window (F1 shows them there too):\n" + keys_help_text() + "\n"


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m app",
        description="Rainroad: drive through rain. Without --headless a window opens; --headless renders offscreen.",
        epilog=EPILOG + _keys_epilog(), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--headless", action="store_true", help="render without a window (EGL), autopilot driving")
    p.add_argument("--size", type=_size, default=(1280, 720),
                   help=f"frame size WIDTHxHEIGHT in pixels, each in [16, {MAX_SIZE}] (x or X)")
    p.add_argument("--seconds", type=_finite(0.0, 86400.0, "s"), default=3.0,
                   help="headless: simulated seconds to drive before the screenshot, in [0, 86400] s")
    p.add_argument("--fps", type=_finite(1.0, 240.0, "frames/s"), default=30.0,
                   help="headless: simulation and recording frame rate, in [1, 240] frames/s")
    p.add_argument("--seed", type=_int_in(0, 2**31 - 1), default=1, help="world, traffic and rain seed")
    p.add_argument("--screenshot", type=_path, help="headless: write the last frame to this PNG")
    p.add_argument("--record", type=_path, metavar="DIR|FILE.mp4",
                   help="headless: write every frame as DIR/frame_00000.png, or as H.264 video to FILE.mp4")
    p.add_argument("--quality", choices=("realtime", "offline"), default="realtime",
                   help="headless: offline averages --subframes sub-frames across the shutter per frame "
                        "(motion blur, anti-aliasing; N times slower)")
    p.add_argument("--subframes", type=_int_in(1, 256), default=16,
                   help="headless, --quality offline: sub-frames per frame, in [1, 256] (see rain_core.bench offline)")
    p.add_argument("--labels", action="store_true",
                   help="headless, with --record: write depth, masks and labels of every frame beside it")
    p.add_argument("--camera", choices=CAMERA_MODES, help="camera mode (default: driver)")
    p.add_argument("--hour", type=_finite(0.0, 24.0, "h"), help="time of day in hours, in [0, 24] (12 noon, 22 night)")
    p.add_argument("--traffic", type=_int_in(0, 20), help="number of traffic vehicles, in [0, 20]")
    p.add_argument("--scenario", type=_path, help="scenario TOML file (see assets/scenarios/)")
    p.add_argument("--openscenario", type=_path, metavar="FILE.xosc",
                   help="take the weather of an OpenSCENARIO file's Init (rain, time of day, wind, fog, road "
                        "wetness); applied after --scenario, before --preset and the single flags")
    p.add_argument("--preset", help="named rain preset (drizzle, light, moderate, heavy, very_heavy, extreme)")
    p.add_argument("--rain-rate", type=_finite(0.0, 500.0, "mm/h"), help="rain rate in mm/h, in [0, 500]")
    p.add_argument("--panel", action="store_true", help="headless: draw the Rain Manager panel into the frames")
    p.add_argument("--frames", type=_int_in(1, 10**9), help="window: close after this many frames (smoke tests)")
    p.add_argument("--window", default="pyglet", choices=WINDOW_BACKENDS,
                   help="moderngl-window backend for the window (default: pyglet; the others need their own "
                        "package, e.g. pip install glfw)")
    return p


def _is_number(text: str) -> bool:
    return bool(_NUMBER.fullmatch(text))


def join_negative_values(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """``--flag -x`` → ``--flag=-x`` where ``-x`` reads as a number and the flag takes a value.

    argparse takes a token that starts with '-' and is not a plain negative number (``-inf``, ``-nan``, ``-1e3``)
    for an option and answers "expected one argument"; joined, the value reaches the flag's own range check.
    """
    takes_value = {opt for a in parser._actions if a.nargs is None and a.option_strings for opt in a.option_strings}
    out: list[str] = []
    i = 0
    while i < len(argv):
        tok = argv[i]
        if tok in takes_value and i + 1 < len(argv) and argv[i + 1].startswith("-") and _is_number(argv[i + 1]):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
            continue
        if tok == "--":
            out.extend(argv[i:])
            break
        out.append(tok)
        i += 1
    return out


def check_record(args) -> str | None:
    """Why ``--record`` cannot be written (see check_output_file / check_output_folder), or None. An .mp4 needs
    PyAV and an even frame size; its labels go to a folder beside it, checked too."""
    from app.recording import VIDEO_INSTALL, have_pyav, is_video_path, labels_folder

    if not is_video_path(args.record):
        return check_output_folder(args.record)
    if not have_pyav():
        return f"writing {args.record.suffix} video needs PyAV, which is not installed: {VIDEO_INSTALL}"
    w, h = args.size
    if w % 2 or h % 2:
        return f"H.264 video needs an even width and height, got --size {w}x{h}"
    problem = check_output_file(args.record, args.record.suffix.lower())
    if problem is None and args.labels:
        problem = check_output_folder(labels_folder(args.record))
    return problem


def parse_args(argv=None) -> argparse.Namespace:
    """Parse and validate; on bad input argparse prints the flag and the reason and exits with code 2."""
    parser = build_parser()
    args = parser.parse_args(join_negative_values(parser, list(sys.argv[1:] if argv is None else argv)))
    if not args.headless and (args.screenshot or args.record):
        parser.error("argument --screenshot/--record: only with --headless (press F12 in the window instead)")
    if args.scenario is not None and (problem := check_input_file(args.scenario)):
        parser.error(f"argument --scenario: {problem}")
    # Output paths are checked before minutes of rendering, not after.
    if args.screenshot is not None and (problem := check_output_file(args.screenshot)):
        parser.error(f"argument --screenshot: {problem}")
    if args.record is not None and (problem := check_record(args)):
        parser.error(f"argument --record: {problem}")
    if args.labels and args.record is None:
        parser.error("argument --labels: only with --record (the labels are written beside the frames)")
    args.parser = parser
    return args
