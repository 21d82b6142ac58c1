"""``python -m app --headless``: the same scene without a window, autopilot driving, frames to PNG or MP4.

A thin user of ``rain_core.Session``: step, capture (with the label images under ``--labels``), write. On a
terminal a progress line (frames, frames/s, ETA) is rewritten in place, and a long run (more than
LONG_RUN_FRAMES frames) first says how long it will take from the pace of frames 2–5 (the first one compiles
shaders); not on a terminal (logs, CI) it stays quiet. Ctrl-C stops it cleanly: the PNGs and label lines written
so far stay, and a video is finalised with every frame written so far (exit 130). ``--quality offline`` steps
each frame's shutter in ``--subframes`` slices and records their average (rain_core.session.offline). A run that
keeps only a screenshot draws only its last frame: the frames before advance the simulations undrawn
(``Session.step(draw=False)``).
"""

from __future__ import annotations

import sys
import time

from app.recording import Progress, describe_duration, is_video_path, labels_folder, open_recorder, save_png
from rain_core.gl import GLUnavailableError
from rain_core.interrupts import CtrlC

LONG_RUN_FRAMES = 300  # above this many frames a run on a terminal says how long it will take
PACE_FRAMES = 4  # frames after the first one that set the estimate

__all__ = ["LONG_RUN_FRAMES", "describe_duration", "frame_count", "plan_line", "run_headless"]


def frame_count(seconds: float, fps: float) -> int:
    """Frames a run of ``seconds`` simulated seconds renders at ``fps`` (at least one)."""
    return max(1, round(seconds * fps))


def plan_line(frames: int, fps: float, size: tuple[int, int], seconds_per_frame: float) -> str:
    """The line a long run prints first: how many frames, and about how long they will take."""
    return (f"rainroad: {frames} frames ({frames / fps:g} s at {fps:g} frames/s, {size[0]}x{size[1]}); "
            f"about {describe_duration(frames * seconds_per_frame)} at {seconds_per_frame:.3g} s a frame "
            f"(Ctrl-C stops)")


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def _close_all(*things) -> None:
    for thing in things:
        if thing is not None:
            thing.close()


def run_headless(args, settings) -> int:
    from rain_core.session import DatasetWriter, Session

    mode = settings.camera.mode
    try:
        # "free" needs a user at the keys; headless it is the chase view, as in the window without input.
        sim = Session(args.size, seed=args.seed, camera="chase" if mode == "free" else mode, settings=settings)
    except GLUnavailableError as exc:
        _say(f"rainroad: {exc}")
        return 1
    from rain_core import jit

    cold = jit.cold_count() if jit.active() else 0  # the scene's effects (and their kernels) exist now
    if cold:
        _say(f"rainroad: compiling {cold} CPU kernel{'s' if cold > 1 else ''} on first use (up to a second each, "
             f"once: they are cached; {jit.ENV_VAR}=0 runs without them, python -m rain_core.warmup compiles "
             "them ahead)")
    with sim:
        return _run(args, sim, DatasetWriter)


def _run(args, sim, DatasetWriter) -> int:
    record, labels = args.record, getattr(args, "labels", False)
    recorder = writer = None
    try:
        if record is not None:
            recorder = open_recorder(record, args.fps, args.size, labels=labels)
            if labels:
                video = record if is_video_path(record) else None
                writer = DatasetWriter(labels_folder(record), args.fps, images=video is None, video=video)
    except (OSError, ValueError) as exc:  # checked by the command line; this is a folder that changed since
        _say(f"rainroad: argument --record: cannot write {record}: {getattr(exc, 'strerror', None) or exc}")
        _close_all(recorder, writer)
        return 1
    panel = None
    if args.panel:
        from app.panel import RainManagerPanel

        panel = RainManagerPanel(sim.ctx, args.size, sim.scene)
    every_frame = recorder is not None or writer is not None or panel is not None
    dt = 1.0 / args.fps
    subframes = args.subframes if getattr(args, "quality", "realtime") == "offline" else 1
    frames = frame_count(args.seconds, args.fps)
    progress = Progress(frames)
    status = 0
    done = 0
    first_done = time.perf_counter()
    ctrl_c = CtrlC()
    try:
        ctrl_c.__enter__()
        for index in range(frames):
            ctrl_c.check()  # a Ctrl-C a finaliser dropped (while Numba loaded a kernel) stops the run here
            # A frame nobody keeps is not drawn (a screenshot alone needs the last): the simulations advance the
            # same (Session.step's draw).
            drawn = every_frame or index == frames - 1
            sim.step(dt, subframes=subframes, draw=drawn)
            if drawn:
                if panel is not None:
                    panel.draw(dt, sim.scene.renderer.ldr)
                cap = sim.capture(labels=labels)
                if recorder is not None:
                    recorder.add(cap.rgb)
                if writer is not None:
                    writer.add(cap)
            if index == frames - 1 and args.screenshot:
                path = save_png(cap.rgb, args.screenshot)
                print(f"rainroad: wrote {path}")
            done = index + 1
            if index == 0:
                first_done = time.perf_counter()
            elif progress.enabled and frames > LONG_RUN_FRAMES and index == PACE_FRAMES:
                progress.finish()
                _say(plan_line(frames, args.fps, args.size, (time.perf_counter() - first_done) / PACE_FRAMES))
            progress.update(done)
    except KeyboardInterrupt:
        progress.finish()
        _say(f"rainroad: stopped after {done} of {frames} frames")
        status = 130
    except OSError as exc:  # the disk filled up, or a folder changed under the run
        progress.finish()
        _say(f"rainroad: cannot write a frame: {exc.strerror or exc}")
        status = 1
    finally:
        ctrl_c.__exit__()
        progress.finish()
        _close_all(recorder, writer)  # finalises the video: every frame written so far decodes
        if panel is not None:
            panel.layer.shutdown()
    if recorder is not None or writer is not None:
        count = (writer or recorder).count
        print(f"rainroad: wrote {count} frames to {record}" + (f" (labels in {labels_folder(record)})"
                                                               if writer is not None else ""))
    return status
