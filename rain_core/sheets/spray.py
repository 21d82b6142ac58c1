"""Contact sheet of the spray effect: ``python -m rain_core.sheets spray`` writes docs/sheets/spray.png.

Frames: a chase camera beside a car entering a puddle at 30, 60 and 100 km/h; the driver's view behind a lorry
at 100 km/h on a wet road (no standing water), by day and by night; the lorry's rooster tail against a low sun.
The scenario builders here are also what ``python -m rain_core.bench spray`` measures.

The puddle is the road's own standing water (``rain_core.water_film.film_depth_mm`` with the flood levels pinned
full), or a 30 m sheet of 8 mm water placed across the road if no puddle entry is found.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from rain_core import layout
from rain_core.camera import look_at
from rain_core.effects.spray import KMH, SprayEffect
from rain_core.sheets import DEFAULT_OUT, save_sheet
from rain_core.traffic import Autopilot
from rain_core.vehicles import TRUCK_SPEC, Vehicle
from rain_core.water_film import film_depth_mm

FRAME_SIZE = (320, 180)
DT_S = 1.0 / 30.0
PUDDLE_SEARCH_START_M = 100.0  # m, first world z looked at for a puddle entry (clear of the bridge at 300 m)
LORRY_COLOUR = (0.05, 0.09, 0.25)  # a dark blue box: a white one vanishes against the bright horizon
FALLBACK_PUDDLE = (8.0, 30.0)  # mm deep, m long: the sheet's own puddle when the road has no puddle entry


def rain_settings(hour: float = 12.0, puddles: bool = False, budget: int | None = None):
    """Settings for the spray scenes: moderate rain, a fully wet road, floods pinned full or empty."""
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = 4.0
    s.rain.wetness = 1.0
    s.rain.cracks = 1.0 if puddles else 0.0
    s.rain.puddles = 1.0 if puddles else 0.0
    s.road.puddle_amount = 1.0 if puddles else s.road.puddle_amount
    s.traffic.count = 0
    s.time_of_day.hour = hour
    if budget is not None:
        s.spray.budget = budget
    return s


def scene_with_spray(ctx, size, settings, seed: int = 1, film_depth_fn=None):
    """A Scene drawing the registered effects with this SprayEffect (``film_depth_fn``, if given, replaces the
    road's film under the wheels) in place of the registered one."""
    from rain_core.effects import default_effects
    from rain_core.scene import Scene

    effect = SprayEffect(ctx, settings, seed=seed)
    effect.emitter.film_depth_fn = film_depth_fn
    others = []
    for e in default_effects(ctx, settings):
        if e.name == "spray":
            e.release()  # replaced by ``effect``
        else:
            others.append(e)
    scene = Scene(ctx, size, settings, seed=seed, effects=[*others, effect])
    return scene, effect


def find_puddle_entry(settings, start_z: float = PUDDLE_SEARCH_START_M) -> tuple[int, float, float] | None:
    """(lane, world z m, length m) of the best puddle entry for a car heading −Z: ≥ 8 m of road without
    standing water, then ≥ 3 mm under both wheel tracks for ≥ 3 m; the longest such stretch of ≥ 2 mm wins.
    None if there is no such entry."""
    fn = film_depth_mm
    step = 0.1
    z = np.arange(start_z, start_z + 900.0, step)
    best = None
    for lane in (0, 1):  # the −Z-bound lanes
        xs = layout.LANE_CENTRES_X[lane] + np.array([-0.79, 0.79])
        depth = np.min([fn(np.full_like(z, x), z, settings.rain.cracks, settings.rain.puddles,
                           puddle_amount=settings.road.puddle_amount, seed=settings.road.puddle_seed, wetness=0.0)
                        for x in xs], axis=0)
        dry = depth < 0.5
        # Heading −Z, "before" is larger z: dry over [i + 5, i + 85), water over (i − 30, i].
        for i in range(200, len(z) - 90):
            if dry[i + 5: i + 85].all() and depth[i - 30: i + 1].min() >= 3.0:
                run = int(np.argmin(depth[i::-1] >= 2.0))  # steps until the water gets shallower than 2 mm
                if best is None or run > best[0]:
                    best = (run, lane, float(z[i]), run * step)
    return None if best is None else best[1:]


def puddle_scene(ctx, kmh: float, size=FRAME_SIZE, hour: float = 12.0, seconds_in: float = 0.3, seed: int = 1):
    """The ego car at ``kmh`` (km/h) whose front wheels entered a puddle ``seconds_in`` s ago (less in a
    short puddle at speed: at most 60 % of its length in). Returns
    (scene, spray effect, camera beside and behind the car)."""
    settings = rain_settings(hour, puddles=True)
    found = find_puddle_entry(settings)
    film = None
    lane, entry, length = found if found is not None else (0, 600.0, FALLBACK_PUDDLE[1])
    if found is None:
        depth, length = FALLBACK_PUDDLE
        film = lambda x, z: np.where((np.asarray(z) <= entry) & (np.asarray(z) > entry - length)  # noqa: E731
                                     & (np.abs(np.asarray(x)) <= layout.ROAD_HALF_WIDTH_M), depth, 0.0)
    scene, effect = scene_with_spray(ctx, size, settings, seed=seed, film_depth_fn=film)
    v = kmh * KMH
    lead_in_s = 1.2  # driven on the wet road before the puddle, so the spray of the film is there too
    seconds_in = min(seconds_in, 0.6 * length / v)  # keep the front wheels inside a short puddle
    # Heading −Z with the front axle wheelbase/2 ahead of the centre: it crosses ``entry`` after lead_in_s.
    scene.ego.position[:] = [layout.LANE_CENTRES_X[lane], 0.0,
                             entry + scene.ego.spec.wheelbase_m / 2.0 + v * lead_in_s]
    scene.ego.speed_m_s = v
    scene.ego.previous_wheel_contacts = scene.ego.wheel_contacts()
    scene.autopilot = Autopilot(lane_index=lane, target_speed_m_s=v, seed=seed, wander_m=0.0)
    run(scene, lead_in_s + seconds_in)
    e = scene.ego
    eye = e.position + e.right() * 3.6 - e.forward() * 4.5 + np.array([0.0, 1.4, 0.0])
    target = e.position + e.forward() * 0.6 + np.array([0.0, 0.45, 0.0])
    return scene, effect, look_at(eye, target, fov_y_deg=58.0)


def truck_scene(ctx, kmh: float = 100.0, gap_m: float = 22.0, size=FRAME_SIZE, hour: float = 12.0,
                seconds: float = 3.0, seed: int = 1, budget: int | None = None, lane: int = 0):
    """The ego car following a lorry at ``kmh`` with a fixed bumper gap ``gap_m`` (m) on a wet road without
    standing water; both run ``seconds`` s. Returns (scene, spray effect, gap keeper)."""
    settings = rain_settings(hour, puddles=False, budget=budget)
    settings.traffic.count = 1
    scene, effect = scene_with_spray(ctx, size, settings, seed=seed)
    v = kmh * KMH
    truck = Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[lane], 0.0, 600.0), layout.LANE_YAW[lane], v,
                    LORRY_COLOUR)
    scene.traffic.vehicles, scene.traffic.lanes, scene.traffic.desired_speeds_m_s = [truck], [lane], [v]
    keeper = GapKeeper(scene, truck, gap_m)
    keeper.place()
    run(scene, seconds, after_step=keeper.place)
    return scene, effect, keeper


class GapKeeper:
    """Holds the ego car exactly ``gap_m`` (m, bumper to bumper) behind ``leader`` at its speed (kinematic)."""

    def __init__(self, scene, leader, gap_m: float):
        self.scene, self.leader, self.gap_m = scene, leader, gap_m

    def place(self) -> None:
        ego, lead = self.scene.ego, self.leader
        back = -lead.forward()
        distance = self.gap_m + (lead.spec.length_m + ego.spec.length_m) / 2.0
        ego.position = lead.position + back * distance
        ego.yaw, ego.speed_m_s, ego.steer_rad, ego.yaw_rate_rad_s = lead.yaw, lead.speed_m_s, 0.0, 0.0


def run(scene, seconds: float, after_step=None, render_last: int = 1) -> None:
    """Step ``seconds`` at 30 Hz, drawing only the last ``render_last`` frames: the ones before advance undrawn
    (``Scene.render(draw=False)``: the spray and every other simulation, as in a drawn frame)."""
    n = max(1, round(seconds / DT_S))
    for i in range(n):
        scene.step(DT_S)
        if after_step is not None:
            after_step()
        scene.render(draw=i >= n - render_last)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m rain_core.sheets spray", description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="folder for spray.png")
    args = parser.parse_args(argv)
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    images, labels = [], []
    for kmh in (30.0, 60.0, 100.0):
        scene, effect, camera = puddle_scene(ctx, kmh)
        scene.render(camera)
        images.append(scene.image())
        depth = float(effect.wheels[0].film_depth_mm[:2].mean())
        labels.append(f"puddle {kmh:.0f} km/h, {depth:.1f} mm, hydro {effect.ego_hydroplaning_risk:.2f}")
        scene.release()
    for hour, name in ((12.0, "noon"), (22.0, "night")):
        scene, effect, _ = truck_scene(ctx, hour=hour)
        images.append(scene.image())
        labels.append(f"driver behind lorry, 100 km/h, wet, {name}")
        scene.release()
    scene, effect, keeper = truck_scene(ctx, hour=17.0, gap_m=60.0, lane=1)
    lead = keeper.leader
    eye = lead.position + lead.right() * 4.5 - lead.forward() * 14.0 + np.array([0.0, 1.2, 0.0])
    scene.render(look_at(eye, lead.position - lead.forward() * 5.0 + np.array([0.0, 1.2, 0.0]), fov_y_deg=60.0))
    images.append(scene.image())
    labels.append("lorry's rooster tail, low sun 17 h")
    scene.release()
    path = save_sheet(images, labels, "spray", Path(args.out), columns=3)
    print(f"wrote {path}")
    return 0 if all(math.isfinite(float(np.mean(im))) for im in images) else 1
