"""Atmosphere benchmark: visibility per rain preset (model and rendered), the cost of the effect with and without
rain, glow cost against its resolution scale with the error against the full-resolution glow, the cost of
the per-pixel light scattering against the number of lights traced, and what its skipped lights save against
the displayed change (every light traced, the fixed budget, the fixed budget plus a share of each pixel's light).

``python -m rain_core.bench atmosphere [--quick] [--out DIR]`` prints the tables and writes DIR/atmosphere.md
and DIR/atmosphere.png. On llvmpipe (CPU-emulated GL) compare ratios, not absolute milliseconds.
"""

from __future__ import annotations

import math
import statistics
from types import SimpleNamespace

import numpy as np
import trimesh
from PIL import Image, ImageDraw

from rain_core import physics
from rain_core.bench._common import markdown_table, parser, write_output
from rain_core.camera import look_at
from rain_core.effects import atmosphere as atm
from rain_core.gfx.context import create_headless_context
from rain_core.gfx.frame import Frame
from rain_core.gfx.renderer import Renderer
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.lighting import lighting_for_hour
from rain_core.mesh import MAT_CONCRETE, from_trimesh
from rain_core.settings import Settings

LUMA = np.array([0.2126, 0.7152, 0.0722])


# --- visibility -------------------------------------------------------------------------------------------


def rendered_extinction_per_m(ctx, shaders, rate_mm_h: float, size=(160, 90)) -> float:
    """β (1/m) measured from rendered frames: the contrast of a dark slab against the horizon at distance d,
    relative to its contrast without atmosphere, is exp(−β·d) (Koschmieder); d is chosen near 1/β (≤ 1000 m)."""
    settings = Settings()
    settings.atmosphere.light_scattering = 0.0
    beta_model = atm.extinction_per_m(rate_mm_h)
    d = float(min(1000.0, 1.0 / beta_model))
    eye = np.array([0.0, 10.0, 600.0])
    mesh = trimesh.creation.box(extents=(0.25 * d, 0.25 * d, 1.0))
    mesh.apply_translation(eye - np.array([0.0, 0.0, d + 0.5]))
    world = SimpleNamespace(vertices=from_trimesh(mesh, np.full(3, 0.03, np.float32), 0.9, 0.0, MAT_CONCRETE),
                            lamps=[])
    camera = look_at(eye, eye + np.array([0.0, 0.0, -1.0]), fov_y_deg=30.0, far_m=5000.0)
    lighting = lighting_for_hour(12.0, atm.sky_overcast(settings.atmosphere, rate_mm_h))
    frame = Frame(0.0, 0.0, camera, lighting, world, weather=SimpleNamespace(rate_mm_h=rate_mm_h),
                  settings=settings)
    h, w = size[1], size[0]
    rows, centre = slice(h // 2 - 2, h // 2 + 3), slice(w // 2 - 2, w // 2 + 3)
    sky_cols = np.r_[w // 4 - 2: w // 4 + 1, 3 * w // 4: 3 * w // 4 + 3]
    fogged = Renderer(ctx, size, world, effects=[atm.AtmosphereEffect(ctx, shaders=shaders)], shaders=shaders,
                      gpu_timing=False)
    fogged.render(frame)
    img = fogged.hdr_image() @ LUMA
    plain = Renderer(ctx, size, world, effects=[atm.NoAirEffect()], shaders=shaders, gpu_timing=False)  # β = 0
    plain.render(frame)
    l0 = float(np.median((plain.hdr_image() @ LUMA)[rows, centre]))
    l_obj = float(np.median(img[rows, centre]))
    l_sky = float(np.median(img[rows][:, sky_cols]))
    fogged.release()
    plain.release()
    ctx.detect_framebuffer(0).use()  # never leave a released framebuffer bound
    ratio = (l_obj - l_sky) / (l0 - l_sky)
    return -math.log(ratio) / d


def visibility_rows(ctx, shaders, quick: bool) -> list[tuple]:
    rows = []
    for name, rate in physics.RAIN_PRESETS.items():
        beta_rain = float(atm.rain_extinction_per_m(rate))
        beta_mp = 0.365e-3 * rate**0.63
        beta = atm.extinction_per_m(rate)
        measured = rendered_extinction_per_m(ctx, shaders, rate) if (not quick or rate in (2.0, 28.0)) else None
        rows.append((name, rate, physics.rain_category(rate), beta_rain * 1e3, beta_mp * 1e3, beta * 1e3,
                     float(atm.visibility_m(beta)), float(atm.visibility_m(beta, 0.02)),
                     float(atm.visibility_m(measured)) if measured else "—",
                     f"{(measured / beta - 1) * 100:+.1f} %" if measured else "—"))
    return rows


# --- cost -------------------------------------------------------------------------------------------------


def _scene(ctx, size, hour: float):
    from rain_core.scene import Scene

    settings = Settings()
    settings.time_of_day.hour = hour
    settings.camera.mode = "chase"
    scene = Scene(ctx, size, settings, seed=1, effects=[atm.AtmosphereEffect(ctx)])
    return scene, settings


def _render(scene, settings, rate: float, frames: int, **atmosphere) -> dict[str, float]:
    """Render ``frames`` frames at rain rate R (mm/h) with atmosphere settings; median ms per pass name."""
    settings.rain.rate_mm_h = rate
    for key, value in atmosphere.items():
        setattr(settings.atmosphere, key, value)
    times: dict[str, list[float]] = {}
    for i in range(frames + 1):
        scene.step(1.0 / 30.0)
        frame = scene.frame()
        frame.lighting = lighting_for_hour(settings.time_of_day.hour, atm.sky_overcast(settings.atmosphere, rate))
        scene.renderer.render(frame)
        scene.ctx.finish()
        if i == 0:
            continue  # the first frame compiles shaders and allocates targets
        for s in scene.renderer.stats:
            if s.ran:
                times.setdefault(s.name, []).append(s.gpu_ms if s.gpu_ms is not None else s.cpu_ms)
        times.setdefault("frame", []).append(sum(v[-1] for k, v in times.items() if k != "frame"))
    return {k: statistics.median(v) for k, v in times.items()}


def cost_rows(scene, settings, frames: int) -> list[tuple]:
    cases = [("dry, no haze (effect skipped)", 0.0, {}),
             ("10 mm/h, fog only (glow 0, scattering 0)", 10.0, {"glow": 0.0, "light_scattering": 0.0}),
             ("10 mm/h, glow only", 10.0, {"glow": 1.0, "light_scattering": 0.0}),
             ("10 mm/h, glow + 8 lights scattered", 10.0, {"glow": 1.0, "light_scattering": 1.0,
                                                         "scatter_lights": 8})]
    rows = []
    for label, rate, kw in cases:
        t = _render(scene, settings, rate, frames, **kw)
        post = t.get("atmosphere.post", 0.0)
        rows.append((label, t.get("scene", 0.0), post, t.get("atmosphere.update", 0.0), t["frame"]))
    settings.atmosphere.glow, settings.atmosphere.light_scattering = 1.0, 1.0
    return rows


def _frame_at(scene, settings):
    """The scene's current frame (time frozen) with the rain-grey lighting the Scene will pass."""
    frame = scene.frame()
    rate = frame.rain_rate_mm_h
    frame.lighting = lighting_for_hour(settings.time_of_day.hour, atm.sky_overcast(settings.atmosphere, rate))
    return frame


def _post_ms(scene, frame, frames: int) -> tuple[float, np.ndarray]:
    """Median atmosphere.post time (ms) over ``frames`` renders of ``frame``, and the HDR image."""
    times = []
    for _ in range(frames):
        scene.renderer.render(frame)
        scene.ctx.finish()
        times.append(next((s.gpu_ms if s.gpu_ms is not None else s.cpu_ms)
                          for s in scene.renderer.stats if s.name == "atmosphere.post"))
    return statistics.median(times), scene.renderer.hdr_image().astype(np.float64)


def glow_rows(scene, settings, frames: int) -> list[tuple]:
    """Glow at each resolution scale vs the full-resolution glow, on one frozen frame at R = 50 mm/h."""
    _render(scene, settings, 50.0, 1, glow=0.0, light_scattering=0.0)  # steps the weather to 50 mm/h
    frame = _frame_at(scene, settings)  # one frame for all: the chase camera moves with every new one
    _, base = _post_ms(scene, frame, 1)
    rows, reference = [], None
    settings.atmosphere.glow = 1.0
    for scale in (1.0, 0.5, 0.25, 0.125, 0.0625):
        settings.atmosphere.glow_resolution = scale
        _post_ms(scene, frame, 1)  # new targets
        ms, img = _post_ms(scene, frame, frames)
        halo = np.nan_to_num((img - base) @ LUMA)  # a NaN the scene pass made stays one pixel: leave it out
        if reference is None:
            reference = halo
        err = halo - reference
        rms = float(np.sqrt(np.mean(err**2)) / np.sqrt(np.mean(reference**2)))
        peak = float(np.abs(err).max() / np.abs(reference).max())
        rows.append(("1" if scale == 1.0 else f"1/{round(1 / scale)}", ms, rms * 100, peak * 100))
    settings.atmosphere.glow_resolution = 0.25
    return rows


def scatter_rows(scene, settings, frames: int) -> list[tuple]:
    """Post-pass time against the number of lights traced per pixel (glow off, R = 10 mm/h)."""
    _render(scene, settings, 10.0, 1, glow=0.0, light_scattering=1.0)
    frame = _frame_at(scene, settings)
    rows = []
    for n in (0, 2, 4, 8, 16, 32):
        settings.atmosphere.scatter_lights = n
        rows.append((n, _post_ms(scene, frame, frames)[0]))
    settings.atmosphere.scatter_lights, settings.atmosphere.glow = 8, 1.0
    return rows


def skip_rows(scene, settings, frames: int) -> list[tuple]:
    """The light scattering's skipped lights by day and at night (R = 10 mm/h, glow on, 8 lights, the exposure
    fixed so the frames compare): post-pass time and the displayed 8-bit values that changed against tracing every
    light, for no skipping, the fixed budget (``scattering.SCATTER_SKIP``) and the fixed budget plus the share of
    each pixel's own light (``SCATTER_SKIP_RELATIVE``)."""
    from rain_core.effects.atmosphere.scattering import SCATTER_SKIP, SCATTER_SKIP_RELATIVE

    effect = next(e for e in scene.renderer.effects if e.name == "atmosphere")
    saved = (effect.scatter_skip, effect.scatter_skip_relative, settings.time_of_day.hour,
             settings.camera.auto_exposure)
    settings.camera.auto_exposure = False
    budgets = (("every light traced", 0.0, 0.0), ("fixed budget", SCATTER_SKIP, 0.0),
               ("fixed + share of the pixel's light", SCATTER_SKIP, SCATTER_SKIP_RELATIVE))
    rows = []
    try:
        for hour in (12.0, 22.0):
            settings.time_of_day.hour = hour
            _render(scene, settings, 10.0, 1, glow=1.0, light_scattering=1.0, scatter_lights=8)
            frame = _frame_at(scene, settings)
            exact = None
            for label, fixed, share in budgets:
                effect.scatter_skip, effect.scatter_skip_relative = fixed, share
                ms, _ = _post_ms(scene, frame, frames)
                shown = scene.renderer.image().astype(np.int16)
                exact = shown if exact is None else exact
                change = np.abs(shown - exact)
                rows.append((f"{hour:g} h", label, ms, float((change > 0).mean() * 100), int(change.max())))
    finally:
        effect.scatter_skip, effect.scatter_skip_relative, settings.time_of_day.hour = saved[:3]
        settings.camera.auto_exposure = saved[3]
    return rows


# --- plot -------------------------------------------------------------------------------------------------


def plot(path, vis_rows, glow) -> None:
    """Left: visibility (m) against R (mm/h), log-log, model curve and rendered points. Right: glow error (%)
    against post-pass time (ms) for each resolution scale."""
    w, h, pad = 900, 380, 60
    img = Image.new("RGB", (w, h), (255, 255, 255))
    d = ImageDraw.Draw(img)
    half = w // 2

    def axes(x0, x1, title, xl, yl):
        d.rectangle((x0, pad, x1, h - pad), outline=(0, 0, 0))
        d.text((x0, 10), title, fill=(0, 0, 0))
        d.text(((x0 + x1) // 2 - 40, h - 22), xl, fill=(0, 0, 0))
        d.text((x0 - 55, pad - 30), yl, fill=(0, 0, 0))

    # Visibility: R from 0.1 to 100 mm/h, V from 300 m to 30 km.
    x0, x1 = pad + 10, half - 20

    def vx(r):
        return x0 + (math.log10(r) + 1) / 3 * (x1 - x0)

    def vy(v):
        return h - pad - (math.log10(v) - math.log10(300)) / 2 * (h - 2 * pad)

    axes(x0, x1, "meteorological visibility (5 % contrast)", "R (mm/h), log", "V (m), log")
    for r in (0.1, 1, 10, 100):
        d.text((vx(r) - 8, h - pad + 4), f"{r:g}", fill=(0, 0, 0))
    for v in (300, 1000, 3000, 10000, 30000):
        d.text((x0 - 45, vy(v) - 6), f"{v:g}", fill=(0, 0, 0))
    rs = np.logspace(-1, 2, 200)
    for beta_fn, colour in ((lambda r: atm.extinction_per_m(r), (30, 90, 200)),
                            (lambda r: atm.CLEAR_AIR_EXTINCTION_PER_M + 0.365e-3 * r**0.63, (200, 120, 30))):
        pts = [(vx(r), vy(min(max(float(atm.visibility_m(beta_fn(r))), 300), 30000))) for r in rs]
        d.line(pts, fill=colour, width=2)
    for row in vis_rows:
        if isinstance(row[8], float):
            x, y = vx(row[1]), vy(row[8])
            d.ellipse((x - 4, y - 4, x + 4, y + 4), outline=(200, 0, 0), width=2)
    d.text((x0 + 8, pad + 6), "Weber 0.312 R^0.67 (used)", fill=(30, 90, 200))
    d.text((x0 + 8, pad + 20), "Marshall-Palmer optics 0.365 R^0.63", fill=(200, 120, 30))
    d.text((x0 + 8, pad + 34), "o rendered", fill=(200, 0, 0))

    # Glow: error vs time.
    x0, x1 = half + pad, w - 20
    tmax = max(r[1] for r in glow) * 1.1 or 1.0
    emax = max(max(r[2] for r in glow) * 1.2, 1.0)
    axes(x0, x1, "glow (R = 50 mm/h): error vs full resolution", "post pass (ms)", "RMS error (%)")

    def gx(t):
        return x0 + t / tmax * (x1 - x0)

    def gy(e):
        return h - pad - e / emax * (h - 2 * pad)

    pts = [(gx(r[1]), gy(r[2])) for r in glow]
    d.line(pts, fill=(30, 90, 200), width=2)
    for (x, y), r in zip(pts, glow, strict=True):
        d.ellipse((x - 4, y - 4, x + 4, y + 4), outline=(30, 90, 200), width=2)
        d.text((x + 6, y - 14), r[0], fill=(0, 0, 0))
    d.text((x0 - 20, h - pad + 4), "0", fill=(0, 0, 0))
    d.text((x1 - 30, h - pad + 4), f"{tmax:.0f}", fill=(0, 0, 0))
    d.text((x0 - 40, pad - 6), f"{emax:.1f}", fill=(0, 0, 0))
    img.save(path)


def main(argv=None) -> int:
    args = parser("atmosphere", __doc__.splitlines()[0]).parse_args(argv)
    ctx = create_headless_context()
    shaders = ShaderLibrary(ctx)
    frames = 5 if args.quick else 9
    size = (320, 180) if args.quick else (640, 360)

    vis = visibility_rows(ctx, shaders, args.quick)
    vis_md = markdown_table(["preset", "R (mm/h)", "category", "β rain Weber (1/km)", "β rain MP optics (1/km)",
                             "β total (1/km)", "V 5 % (m)", "V 2 % (m)", "V rendered (m)", "β rendered vs model"],
                            vis)
    print("Visibility (clear air 3.912/40 km included; rendered: contrast of a dark slab vs the horizon)")
    print(vis_md)

    scene, settings = _scene(ctx, size, 22.0)
    cost = cost_rows(scene, settings, frames)
    cost_md = markdown_table(["night street, chase camera", "scene (ms)", "atmosphere.post (ms)",
                              "atmosphere.update (ms)", "frame (ms)"], cost)
    print(f"\nCost at {size[0]}x{size[1]} ({scene.renderer.timing_source}; llvmpipe: compare ratios)")
    print(cost_md)

    glow = glow_rows(scene, settings, frames)
    glow_md = markdown_table(["glow resolution", "post pass (ms)", "RMS error of the halo (%)",
                              "peak error (% of the halo's peak)"], glow)
    print("\nGlow (night street, R = 50 mm/h, light scattering off) vs the full-resolution glow")
    print(glow_md)

    scatter = scatter_rows(scene, settings, frames)
    scatter_md = markdown_table(["lights traced", "post pass (ms)"], scatter)
    print("\nLight scattering (glow off, R = 10 mm/h, 8 quadrature nodes per light)")
    print(scatter_md)

    skip = skip_rows(scene, settings, frames)
    skip_md = markdown_table(["hour", "lights skipped", "post pass (ms)", "8-bit values changed (%)",
                              "largest change (levels)"], skip)
    print("\nSkipped lights (R = 10 mm/h, glow on, 8 lights) against tracing every light")
    print(skip_md)
    scene.release()

    md = "\n\n".join([
        "# Atmosphere benchmark",
        f"Frame size {size[0]}x{size[1]}, {'quick' if args.quick else 'full'} run; GL: "
        f"{ctx.info.get('GL_RENDERER', '?')}. On llvmpipe the milliseconds are CPU-emulated: compare ratios.",
        "## Visibility per rain preset\nV = −ln(0.05)/β (meteorological optical range, 5 % contrast); "
        "V 2 % = 3.912/β (Koschmieder). Rendered: β fitted from the HDR contrast of a dark slab at d ≈ 1/β.",
        vis_md, f"## Cost with and without rain ({size[0]}x{size[1]})", cost_md,
        "## Glow resolution vs error (R = 50 mm/h)", glow_md,
        "## Light scattering cost vs lights traced", scatter_md,
        "## Skipped lights: post pass against the displayed change (R = 10 mm/h, glow on, 8 lights)", skip_md])
    target = write_output(args.out, "atmosphere", md)
    plot(target.with_suffix(".png"), vis, glow)
    print(f"\nwrote {target} and {target.with_suffix('.png')}")
    return 0
