"""``python -m app --headless``: the same scene without a window, autopilot driving, frames to PNG."""

from __future__ import annotations

import math
import sys

from app.recording import Recorder, save_png
from rain_core.gl import GLUnavailableError, create_headless_context
from rain_core.scene import MAX_FRAME_DT_S, Scene


def run_headless(args, settings) -> int:
    try:
        ctx = create_headless_context()
    except GLUnavailableError as exc:
        print(f"rainroad: {exc}", file=sys.stderr)
        return 1
    scene = Scene(ctx, args.size, settings=settings, seed=args.seed)
    panel = None
    if args.panel:
        from app.panel import RainManagerPanel

        panel = RainManagerPanel(ctx, args.size, scene)
    recorder = Recorder(args.record) if args.record else None
    dt = 1.0 / args.fps
    frames = max(1, round(args.seconds * args.fps))
    substeps = max(1, math.ceil(dt / MAX_FRAME_DT_S))  # Scene.step clamps a frame to MAX_FRAME_DT_S
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
    if recorder is not None:
        print(f"rainroad: wrote {recorder.count} frames to {recorder.folder}")
    if panel is not None:
        panel.layer.shutdown()
    scene.release()
    return 0
