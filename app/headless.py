"""``python -m app --headless``: the same scene without a window, autopilot driving, frames to PNG.

A long run (more than LONG_RUN_FRAMES frames) prints one line on stderr after its first few frames — the frame
count and an estimate of the time it will take, from the pace of frames 2–5 (the first one compiles shaders) —
then a progress line every PROGRESS_EVERY_S seconds. Ctrl-C stops it
cleanly (the frames written so far stay).
"""

from __future__ import annotations

import math
import sys
import time

from app.recording import Recorder, save_png
from rain_core.gl import GLUnavailableError, create_headless_context
from rain_core.scene import MAX_FRAME_DT_S, Scene

LONG_RUN_FRAMES = 300  # above this many frames a run says how long it will take and shows its progress
PROGRESS_EVERY_S = 30.0  # s of wall time between progress lines
PACE_FRAMES = 4  # frames after the first one that set the estimate


def frame_count(seconds: float, fps: float) -> int:
    """Frames a run of ``seconds`` simulated seconds renders at ``fps`` (at least one)."""
    return max(1, round(seconds * fps))


def describe_duration(seconds: float) -> str:
    """A wall time in words: "45 s", "12 min 5 s", "3 h 20 min"."""
    s = max(0, round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60} s"
    return f"{s // 3600} h {s % 3600 // 60} min"


def plan_line(frames: int, fps: float, size: tuple[int, int], seconds_per_frame: float) -> str:
    """The line a long run prints first: how many frames, and about how long they will take."""
    return (f"rainroad: {frames} frames ({frames / fps:g} s at {fps:g} frames/s, {size[0]}x{size[1]}); "
            f"about {describe_duration(frames * seconds_per_frame)} at {seconds_per_frame:.3g} s a frame "
            f"(Ctrl-C stops)")


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def run_headless(args, settings) -> int:
    try:
        ctx = create_headless_context()
    except GLUnavailableError as exc:
        print(f"rainroad: {exc}", file=sys.stderr)
        return 1
    # No GPU timer queries: nobody reads them here (--panel turns them on while its table is drawn).
    scene = Scene(ctx, args.size, settings=settings, seed=args.seed, gpu_timing=False)
    panel = None
    if args.panel:
        from app.panel import RainManagerPanel

        panel = RainManagerPanel(ctx, args.size, scene)
    try:
        recorder = Recorder(args.record) if args.record else None
    except OSError as exc:  # checked by the command line; this is a folder that changed since
        _say(f"rainroad: argument --record: cannot create {args.record}: {exc.strerror or exc}")
        scene.release()
        return 1
    dt = 1.0 / args.fps
    frames = frame_count(args.seconds, args.fps)
    substeps = max(1, math.ceil(dt / MAX_FRAME_DT_S))  # Scene.step clamps a frame to MAX_FRAME_DT_S
    long_run = frames > LONG_RUN_FRAMES
    status = 0
    start = last_report = first_done = time.perf_counter()
    try:
        for index in range(frames):
            for _ in range(substeps):
                scene.step(dt / substeps)
            # Effects keep GPU state (ripples, glass water), so every simulated frame is rendered.
            scene.render()
            if panel is not None:
                panel.draw(dt, scene.renderer.ldr)
            if recorder is not None:
                recorder.add(scene.image())
            if index == frames - 1 and args.screenshot:
                path = save_png(scene.image(), args.screenshot)
                print(f"rainroad: wrote {path}")
            now = time.perf_counter()
            if index == 0:
                first_done = now
            elif long_run and index == PACE_FRAMES:
                _say(plan_line(frames, args.fps, args.size, (now - first_done) / PACE_FRAMES))
            elif long_run and now - last_report >= PROGRESS_EVERY_S:
                left = (now - start) / (index + 1) * (frames - index - 1)
                _say(f"rainroad: frame {index + 1}/{frames}, about {describe_duration(left)} left")
                last_report = now
    except KeyboardInterrupt:
        _say(f"rainroad: stopped after {index} of {frames} frames")
        status = 130
    except OSError as exc:  # the disk filled up, or a folder changed under the run
        _say(f"rainroad: cannot write a frame: {exc.strerror or exc}")
        status = 1
    if recorder is not None:
        print(f"rainroad: wrote {recorder.count} frames to {recorder.folder}")
    if panel is not None:
        panel.layer.shutdown()
    scene.release()
    return status
