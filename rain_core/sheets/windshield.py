"""Contact sheet of the windshield effect (issue 8), and the committed frame sequence.

``python -m rain_core.sheets windshield`` writes ``docs/sheets/windshield.png`` (parked, 60 and 120 km/h,
heavy rain with slow and fast wipers, a wiper stroke, night glints, the glass camera's close-up) and
``docs/sequences/windshield/sequence.png``: 24 frames from the driver's seat in moderate rain, accelerating
from 0 to 120 km/h with the wipers on intermittent. ``--only sheet`` / ``--only sequence`` renders one of
them.

Each shot runs the water simulation on the CPU for a while (the glass fills as it would), then renders the
last frames so the GPU film texture has its history (trails, streaks, beading).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rain_core.camera import glass_camera
from rain_core.car_mesh import DRIVER_EYE_LOCAL
from rain_core.sheets import DEFAULT_OUT, save_sheet

SIZE = (320, 180)
SEQUENCE_OUT = Path("docs") / "sequences" / "windshield"


def _scene(
    ctx,
    rate_mm_h: float,
    wipers: str,
    hour: float = 12.0,
    speed_kmh: float = 0.0,
    seed: int = 1,
    interval_s: float = 4.0,
    size=SIZE,
    traffic: int | None = None,
):
    from rain_core.effects.windshield import WindshieldEffect
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = rate_mm_h
    s.wipers.mode = wipers
    s.wipers.interval_s = interval_s
    s.time_of_day.hour = hour
    s.camera.mode = "driver"
    if traffic is not None:
        s.traffic.count = traffic
    effect = WindshieldEffect(ctx, s, seed=seed)
    scene = Scene(ctx, size, s, seed=seed, effects=[effect], gpu_timing=False)
    scene.ego.speed_m_s = speed_kmh / 3.6
    scene.autopilot.target_speed_m_s = speed_kmh / 3.6
    return scene, effect


def _advance(scene, seconds: float, render_last_s: float = 0.5, fps: float = 30.0, camera=None):
    """Step ``seconds``, drawing only the frames of the last ``render_last_s``: the ones before advance undrawn
    (``Scene.render(draw=False)``: every simulation, and the glass's water texture, as in a drawn frame)."""
    frames = int(round(seconds * fps))
    drawn = int(round(render_last_s * fps))
    for k in range(frames):
        scene.step(1.0 / fps)
        scene.render(camera(scene) if camera else None, draw=k >= frames - drawn)
    return scene.image()


def _until_stroke(scene, effect, phase: float, fps: float = 30.0, limit_s: float = 10.0):
    """Render frame by frame until the wipers next cross cycle ``phase`` (0 … 1) from below."""
    before = effect.sim.wipers.phase
    for _ in range(int(limit_s * fps)):
        scene.step(1.0 / fps)
        scene.render()
        p = effect.sim.wipers.phase
        if p is not None and p >= phase and (before is None or before < phase):
            break
        before = p
    return scene.image()


def render_sheet(ctx, out_dir=DEFAULT_OUT) -> Path:
    shots, labels = [], []

    def shot(label, image):
        shots.append(image)
        labels.append(label)

    scene, _ = _scene(ctx, 2.0, "off")
    shot("parked, 2 mm/h, 40 s, wipers off", _advance(scene, 40.0))
    scene.release()
    scene, _ = _scene(ctx, 2.0, "off", speed_kmh=60.0)
    shot("60 km/h, 2 mm/h, wipers off", _advance(scene, 20.0))
    scene.release()
    scene, _ = _scene(ctx, 2.0, "off", speed_kmh=120.0)
    shot("120 km/h: drops stream up", _advance(scene, 20.0))
    scene.release()
    for mode in ("low", "high"):  # both with the blades at the same point of their up-stroke
        scene, effect = _scene(ctx, 8.0, mode, speed_kmh=60.0, seed=2)
        _advance(scene, 10.0, render_last_s=0.5)
        _until_stroke(scene, effect, 0.4)
        shot(f"heavy 8 mm/h, 60 km/h, wipers {mode}", scene.image())
        scene.release()
    scene, effect = _scene(ctx, 8.0, "low", speed_kmh=50.0, seed=3)
    _advance(scene, 6.0, render_last_s=0.3)
    shot("8 mm/h, a stroke: blade, bead, streaks", _until_stroke(scene, effect, 0.7))
    scene.release()
    scene, _ = _scene(ctx, 4.0, "intermittent", hour=22.0, speed_kmh=40.0, seed=4)
    shot("night, 4 mm/h: glints and smears", _advance(scene, 10.0))
    scene.release()
    scene, _ = _scene(ctx, 4.0, "off", hour=22.0, speed_kmh=0.0, seed=4)
    shot("night, parked: lamps in the drops", _advance(scene, 25.0))
    scene.release()
    scene, effect = _scene(ctx, 2.0, "off", seed=5)

    look = effect.glass.point_ahead_of(DRIVER_EYE_LOCAL)

    def close_up(sc):  # the glass camera (camera.mode "glass", G in the app): focused on the glass
        return glass_camera(sc.ego, DRIVER_EYE_LOCAL, look)

    shot("glass close-up (12° view, focused on the glass), parked 2 mm/h",
         _advance(scene, 30.0, camera=close_up))
    scene.release()
    return save_sheet(shots, labels, "windshield", out_dir, columns=3)


class _Drive:
    """Full throttle up to a target speed, the autopilot's steering (a DriveInput for Scene.step)."""

    def __init__(self, scene, target_m_s: float):
        self.scene, self.target = scene, target_m_s
        self.throttle = self.brake = self.steer = 0.0
        self.reverse = False

    def update(self, dt: float) -> _Drive:
        ego = self.scene.ego
        _, _, self.steer = self.scene.autopilot.controls(ego, dt)
        hold = ego.spec.resistance(ego.speed_m_s) / ego.spec.engine_accel(ego.speed_m_s)
        self.throttle = 1.0 if ego.speed_m_s < self.target - 0.3 else min(1.0, hold)
        return self


def render_sequence(ctx, out_dir=SEQUENCE_OUT, frames: int = 24, seconds: float = 18.0) -> Path:
    """0 → 120 km/h at full throttle in moderate rain (2 mm/h), wipers intermittent (4 s): ``frames`` evenly
    spaced frames of ``seconds``, from the driver's seat."""
    from PIL import Image

    from rain_core.sheets import contact_sheet

    scene, effect = _scene(ctx, 2.0, "intermittent", speed_kmh=0.0, seed=6, traffic=0)  # a free road ahead
    drive = _Drive(scene, 120.0 / 3.6)
    fps = 30.0
    total = int(round(seconds * fps))
    keep = set(np.linspace(0, total - 1, frames).round().astype(int).tolist())
    images, labels = [], []
    for k in range(total):
        scene.step(1.0 / fps, drive.update(1.0 / fps))
        scene.render(draw=k in keep)  # the frames between advance undrawn
        if k in keep:
            images.append(scene.image())
            kmh = scene.ego.speed_m_s * 3.6
            labels.append(f"{scene.time_s:4.1f} s {kmh:3.0f} km/h {effect.sim.count} drops")
    scene.release()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "sequence.png"
    # 256 colours: the grain of water on glass compresses badly; a third of the size, no visible change.
    sheet = Image.fromarray(contact_sheet(images, labels, columns=6))
    small = sheet.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    small.save(path, optimize=True)
    return path


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m rain_core.sheets windshield", description=__doc__.splitlines()[0]
    )
    p.add_argument("--out", default=str(DEFAULT_OUT), help="folder for windshield.png")
    p.add_argument("--sequence-out", default=str(SEQUENCE_OUT), help="folder for the frame sequence")
    p.add_argument("--only", choices=("sheet", "sequence"), help="render just one of the two")
    args = p.parse_args(argv)
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    if args.only != "sequence":
        print(render_sheet(ctx, args.out))
    if args.only != "sheet":
        print(render_sequence(ctx, args.sequence_out))
    return 0
