"""Command line of ``python -m app``: every flag validated where it enters, errors name the flag (exit code 2)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

CAMERA_MODES = ("driver", "chase", "free")
WINDOW_BACKENDS = ("pyglet", "glfw", "sdl2", "pygame2", "pyqt5", "pyside2", "tk", "headless")
MAX_SIZE = 8192


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels (e.g. 1280x720), got {text!r}") from None
    if not (16 <= w <= MAX_SIZE and 16 <= h <= MAX_SIZE):
        raise argparse.ArgumentTypeError(f"width and height must be in [16, {MAX_SIZE}] pixels, got {text!r}")
    return w, h


def _finite(lo: float, hi: float, unit: str):
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number in [{lo}, {hi}] {unit}, got {text!r}") from None
        if not math.isfinite(value) or not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be a finite number in [{lo}, {hi}] {unit}, got {text!r}")
        return value

    return parse


def _int_in(lo: int, hi: int):
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer in [{lo}, {hi}], got {text!r}") from None
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be in [{lo}, {hi}], got {value}")
        return value

    return parse


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m app",
        description="Rainroad: drive through rain. Without --headless a window opens; --headless renders offscreen.")
    p.add_argument("--headless", action="store_true", help="render without a window (EGL), autopilot driving")
    p.add_argument("--size", type=_size, default=(1280, 720), help="frame size WIDTHxHEIGHT in pixels")
    p.add_argument("--seconds", type=_finite(0.0, 86400.0, "s"), default=3.0,
                   help="headless: simulated seconds to drive before the screenshot (s)")
    p.add_argument("--fps", type=_finite(1.0, 240.0, "frames/s"), default=30.0,
                   help="headless: simulation and recording frame rate (frames/s)")
    p.add_argument("--seed", type=_int_in(0, 2**31 - 1), default=1, help="world, traffic and rain seed")
    p.add_argument("--screenshot", type=Path, help="headless: write the last frame to this PNG")
    p.add_argument("--record", type=Path, metavar="DIR", help="headless: write every frame as DIR/frame_00000.png")
    p.add_argument("--camera", choices=CAMERA_MODES, help="camera mode (default: driver)")
    p.add_argument("--hour", type=_finite(0.0, 24.0, "h"), help="time of day in hours (12 noon, 22 night)")
    p.add_argument("--traffic", type=_int_in(0, 20), help="number of traffic vehicles")
    p.add_argument("--scenario", type=Path, help="scenario TOML file (see assets/scenarios/)")
    p.add_argument("--preset", help="named rain preset (drizzle, light, moderate, heavy, very_heavy, extreme)")
    p.add_argument("--rain-rate", type=_finite(0.0, 500.0, "mm/h"), help="rain rate in mm/h")
    p.add_argument("--panel", action="store_true", help="headless: draw the Rain Manager panel into the frames")
    p.add_argument("--frames", type=_int_in(1, 10**9), help="window: close after this many frames (smoke tests)")
    p.add_argument("--window", default="pyglet", choices=WINDOW_BACKENDS,
                   help="moderngl-window backend for the window")
    return p


def _check_folder(parser, flag: str, folder: Path) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        parser.error(f"argument {flag}: cannot create folder {folder}: {exc.strerror or exc}")


def parse_args(argv=None) -> argparse.Namespace:
    """Parse and validate; on bad input argparse prints the flag and the reason and exits with code 2."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not args.headless and (args.screenshot or args.record):
        parser.error("argument --screenshot/--record: only with --headless (press F12 in the window instead)")
    if args.scenario is not None and not args.scenario.is_file():
        parser.error(f"argument --scenario: no such file: {args.scenario}")
    # Output paths are checked before minutes of rendering, not after.
    if args.screenshot is not None:
        if args.screenshot.suffix.lower() != ".png":
            parser.error(f"argument --screenshot: must end in .png, got {args.screenshot}")
        _check_folder(parser, "--screenshot", args.screenshot.parent)
    if args.record is not None:
        if args.record.exists() and not args.record.is_dir():
            parser.error(f"argument --record: {args.record} exists and is not a folder")
        _check_folder(parser, "--record", args.record)
    args.parser = parser
    return args
