"""Screenshots, numbered PNG sequences, H.264 video (PyAV) and the progress line of long headless runs.

Video: PyAV (``pip install av``, the ``video`` extra: ``pip install 'rainroad[video]'``) — its wheels carry their
own FFmpeg with libx264, so nothing else has to be installed (imageio-ffmpeg ships an ffmpeg executable and
pipes raw frames to it: a second process to manage and to finalise on Ctrl-C). ``VideoRecorder.close`` flushes
the encoder and writes the MP4 index, so a run stopped by Ctrl-C or an error leaves a video of every frame
written so far; callers close it in a ``finally``.
"""

from __future__ import annotations

import sys
import time
from fractions import Fraction
from pathlib import Path

import numpy as np
from PIL import Image

VIDEO_SUFFIXES = (".mp4",)
VIDEO_INSTALL = "pip install 'rainroad[video]'  (or: pip install av)"
VIDEO_CRF = 18  # x264 constant rate factor: visually lossless for rain streaks, ~10× smaller than PNGs


def save_png(image: np.ndarray, path: Path | str) -> Path:
    """Write a uint8 (H, W, 3) image; creates the parent folder."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.asarray(image, dtype=np.uint8)).save(path)
    return path


def is_video_path(path: Path | str) -> bool:
    return Path(path).suffix.lower() in VIDEO_SUFFIXES


def have_pyav() -> bool:
    import importlib.util

    return importlib.util.find_spec("av") is not None


def labels_folder(record: Path | str) -> Path:
    """Where ``--labels`` writes: the record folder itself, or ``out.labels/`` beside ``out.mp4``."""
    record = Path(record)
    return record.with_suffix(".labels") if is_video_path(record) else record


class Recorder:
    """Writes frame_00000.png, frame_00001.png, … into a folder (created if missing)."""

    def __init__(self, folder: Path | str):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.count = 0
        self.path = self.folder

    def add(self, image: np.ndarray) -> Path:
        path = save_png(image, self.folder / f"frame_{self.count:05d}.png")
        self.count += 1
        return path

    def close(self) -> None:
        pass


class VideoRecorder:
    """H.264 (yuv420p, constant frame rate ``fps``) in an MP4 at ``path``. ``size`` (W, H) must be even."""

    def __init__(self, path: Path | str, fps: float, size: tuple[int, int]):
        import av

        if size[0] % 2 or size[1] % 2:
            raise ValueError(f"size: H.264 needs an even width and height, got {size[0]}x{size[1]}")
        self.path = Path(path)
        self.count = 0
        self._container = av.open(str(self.path), mode="w")
        try:
            rate = Fraction(fps).limit_denominator(1001)
            self._stream = self._container.add_stream("libx264", rate=rate)
            self._stream.width, self._stream.height = size
            self._stream.pix_fmt = "yuv420p"
            self._stream.options = {"crf": str(VIDEO_CRF)}
        except BaseException:
            self._container.close()
            raise
        self._av = av

    def add(self, image: np.ndarray) -> None:
        frame = self._av.VideoFrame.from_ndarray(np.ascontiguousarray(image, dtype=np.uint8), format="rgb24")
        for packet in self._stream.encode(frame):
            self._container.mux(packet)
        self.count += 1

    def close(self) -> None:
        """Flush the encoder and finalise the container (the MP4 index). Safe to call twice."""
        if self._container is None:
            return
        try:
            for packet in self._stream.encode(None):
                self._container.mux(packet)
        finally:
            self._container.close()
            self._container = None


def open_recorder(path: Path | str, fps: float, size: tuple[int, int], labels: bool = False):
    """A VideoRecorder for an .mp4 path, else a PNG folder Recorder; with ``labels`` PNG frames are written by the
    labels writer instead (the folder layout of rain_core.session.dataset), so None is returned for a folder."""
    if is_video_path(path):
        return VideoRecorder(path, fps, size)
    return None if labels else Recorder(path)


def describe_duration(seconds: float) -> str:
    """A wall time in words: "45 s", "12 min 5 s", "3 h 20 min"."""
    s = max(0, round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60} s"
    return f"{s // 3600} h {s % 3600 // 60} min"


class Progress:
    """One line on a terminal, rewritten in place at most every ``every_s`` seconds: frames, frames/s, ETA.
    Silent when ``stream`` is not a terminal (logs, CI), so logs do not fill with carriage returns."""

    def __init__(self, total: int, stream=None, every_s: float = 0.5, clock=time.perf_counter):
        self.total, self.every_s, self.clock = total, every_s, clock
        self.stream = sys.stderr if stream is None else stream
        isatty = getattr(self.stream, "isatty", None)
        self.enabled = bool(isatty and isatty())
        self.start = clock()
        self._last = -float("inf")
        self._shown = False

    def line(self, done: int, now: float) -> str:
        elapsed = max(now - self.start, 1e-9)
        rate = done / elapsed
        left = (self.total - done) / rate if rate > 0 else float("inf")
        eta = describe_duration(left) if left != float("inf") else "?"
        return f"rainroad: frame {done}/{self.total}, {rate:.2f} frames/s, about {eta} left"

    def update(self, done: int) -> None:
        if not self.enabled:
            return
        now = self.clock()
        if now - self._last < self.every_s and done < self.total:
            return
        self._last = now
        self.stream.write("\r\x1b[K" + self.line(done, now))
        self.stream.flush()
        self._shown = True

    def finish(self) -> None:
        if self._shown:
            self.stream.write("\n")
            self.stream.flush()
            self._shown = False
