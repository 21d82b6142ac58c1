"""The golden views: one characteristic picture per effect, plus a whole frame per camera with everything on.

Each view is built with the stable public API only — ``Scene(ctx, size, settings, seed=, gpu_timing=False)``,
``Settings``/``set_value`` paths, ``step``/``render``/``image``/``release`` — so a refactor that keeps that
surface is checked against pictures rendered before it. Small size, fixed seed, fixed 1/30 s steps, and every
frame rendered (the effects simulate in their update pass). What could depend on the machine is pinned: the
weather levels (``rain.wetness/cracks/puddles``), GPU timing off, and the ripple solver's backend (``"auto"``
would time numpy against the GPU and pick the faster — see ``_pin_ripple_backend``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

SIZE = (160, 90)  # w, h
FPS = 30.0
EFFECTS = ("road", "ripples", "rainfall", "spray", "windshield", "atmosphere", "drips", "lightning", "rainbow")

# Cheap quality for every view: the pictures are 160×90, so full-size simulations would only cost time.
_QUALITY = {"quality.ripple_grid": 128, "quality.windshield_resolution": 128, "quality.particle_budget": 20_000,
            "spray.budget": 4000, "windshield.drop_budget": 2000}


def _only(*names: str) -> dict:
    """``enabled`` for every effect: on for ``names``, off for the others."""
    return {f"{e}.enabled": e in names for e in EFFECTS}


@dataclass(frozen=True)
class View:
    doc: str
    settings: dict = field(default_factory=dict)
    steps: int = 20  # 1/30 s steps, each rendered
    seed: int = 1
    camera: tuple | None = None  # (eye m, target m, vertical fov deg) of a fixed camera; None: the scene's own


_WET = {"rain.wetness": 1.0, "rain.cracks": 1.0, "rain.puddles": 1.0, "road.puddle_amount": 0.8}

VIEWS: dict[str, View] = {
    "road": View("wet road with puddles reflecting the street, late afternoon, chase camera; road effect only",
                 {**_only("road"), **_WET, "rain.rate_mm_h": 0.0, "time_of_day.hour": 17.5,
                  "camera.mode": "chase", "traffic.count": 0}, steps=4),
    "ripples": View("chase view at night of the wheels' wakes and rain rings in standing water (lamps reflected); "
                    "road + ripples",
                    {**_only("road", "ripples"), **_WET, "road.puddle_amount": 1.0, "rain.rate_mm_h": 4.0,
                     "time_of_day.hour": 21.0, "camera.mode": "chase", "traffic.count": 0,
                     "ripples.extent_m": 12.0, "ripples.wheel_strength": 4.0, "ripples.rain_strength": 4.0},
                    steps=12, seed=3),
    "rainfall": View("heavy rain streaks against a dusk street, chase camera; rainfall only",
                     {**_only("rainfall"), "rain.rate_mm_h": 50.0, "time_of_day.hour": 19.0,
                      "camera.mode": "chase", "traffic.count": 0}, steps=6),
    "spray": View("spray and mist behind traffic on a wet road, chase camera; road + spray",
                  {**_only("road", "spray"), "rain.wetness": 1.0, "rain.cracks": 0.0, "rain.puddles": 0.0,
                   "rain.rate_mm_h": 8.0, "time_of_day.hour": 12.0, "camera.mode": "chase",
                   "traffic.count": 8}, steps=12),
    "windshield": View("driver view through drops on the glass in moderate rain, wipers off; windshield only",
                       {**_only("windshield"), "rain.rate_mm_h": 10.0, "wipers.mode": "off",
                        "time_of_day.hour": 12.0, "camera.mode": "driver", "traffic.count": 0}, steps=15),
    "atmosphere": View("heavy rain fog and glow around lamps and headlights at night; atmosphere only",
                       {**_only("atmosphere"), "rain.rate_mm_h": 60.0, "time_of_day.hour": 22.0,
                        "camera.mode": "chase", "traffic.count": 4}, steps=4),
    "drips": View("streams pouring off the bridge deck's south edge in the rain, looked up at from 3 m; drips only",
                  {**_only("drips"), "rain.rate_mm_h": 8.0, "time_of_day.hour": 15.0, "traffic.count": 0},
                  steps=4, camera=((-2.0, 1.6, 309.0), (-2.0, 4.5, 306.0), 40.0)),
    "kerb_streams": View("water running along the kerb to the drains at 30 mm/h; road only",
                         {**_only("road"), "rain.rate_mm_h": 30.0, "rain.wetness": 1.0, "rain.cracks": 0.0,
                          "rain.puddles": 0.0, "time_of_day.hour": 15.0, "traffic.count": 0},
                         steps=4, camera=((4.0, 1.6, 520.0), (7.0, 0.0, 500.0), 50.0)),
    "rainbow": View("primary and secondary bow on the rain, sun 16° behind, from above the roofs; rainbow only",
                    {**_only("rainbow"), "rain.rate_mm_h": 1.0, "time_of_day.hour": 17.0, "traffic.count": 0},
                    steps=3, camera=((-1.75, 40.0, 700.0), (94.84, 76.4, 674.12), 80.0)),
    "lightning": View("a flash 620 m away at night, the sky lit and the bolt in view (seed 145's first near "
                      "flash, 3.2 s in); lightning only",
                      {**_only("lightning"), "rain.rate_mm_h": 20.0, "time_of_day.hour": 22.0, "traffic.count": 0,
                       "lightning.flashes_per_min": 10.0},
                      steps=97, seed=145, camera=((-5.75, 40.0, 600.0), (-12.75, 54.0, 500.25), 70.0)),
    "frame_driver": View("whole frame from the driver's seat, every effect on, rain at dusk",
                         {**_only(*EFFECTS), **_WET, "rain.rate_mm_h": 12.0, "time_of_day.hour": 18.5,
                          "camera.mode": "driver", "traffic.count": 5}, steps=12),
    "frame_chase": View("whole frame from the chase camera, every effect on, rain at dusk",
                        {**_only(*EFFECTS), **_WET, "rain.rate_mm_h": 12.0, "time_of_day.hour": 18.5,
                         "camera.mode": "chase", "traffic.count": 5}, steps=12),
}


def make_settings(view: View):
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for path, value in {**_QUALITY, **view.settings}.items():
        set_value(settings, path, value)
    return settings


def _pin_ripple_backend(scene, backend: str = "numpy32") -> None:
    """The ripple solver's default backend "auto" times numpy against the GPU and picks the faster, so the
    picture would depend on the machine's load. No setting selects it, so pin the effect's attribute (it is read
    when the field is first built, at the first render)."""
    for effect in scene.effects:
        if getattr(effect, "name", "") == "ripples" and hasattr(effect, "backend"):
            effect.backend = backend


def render_view(ctx, name: str, *, seed: int | None = None, steps: int | None = None,
                settings_override: dict | None = None, ripple_backend: str = "numpy32") -> np.ndarray:
    """The view's tone-mapped picture (h, w, 3) uint8. seed/steps/settings_override perturb it (for measuring
    the metric's noise and breakage margins)."""
    from rain_core.scene import Scene
    from rain_core.settings import set_value

    view = VIEWS[name]
    settings = make_settings(view)
    for path, value in (settings_override or {}).items():
        set_value(settings, path, value)
    scene = Scene(ctx, SIZE, settings, seed=view.seed if seed is None else seed, gpu_timing=False)
    try:
        _pin_ripple_backend(scene, ripple_backend)
        camera = None
        if view.camera is not None:
            from rain_core.camera import look_at

            camera = look_at(view.camera[0], view.camera[1], fov_y_deg=view.camera[2])
        for _ in range(view.steps if steps is None else steps):
            scene.step(1.0 / FPS)
            scene.render(camera)
        return np.ascontiguousarray(scene.image()[..., :3])
    finally:
        scene.release()
