"""The scene's depth pre-pass (rain_core/gfx/scene_draw.py): the lit shader runs about once per pixel of the opaque
scene, not once per layer of the city, and the picture is the one drawn without it."""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core.bench.frame import heavy_rain_settings
from rain_core.gfx.renderer import Renderer
from rain_core.gfx.scene_draw import SceneDrawer
from rain_core.scene import Scene

SIZE = (96, 54)


def _lit_samples(gl_ctx, monkeypatch, prepass: bool) -> tuple[int, np.ndarray]:
    """Samples the main view's lit scene draws let through (one frame, driver's seat), and the frame's image."""
    scene = Scene(gl_ctx, SIZE, settings=heavy_rain_settings(2000), seed=1, gpu_timing=False)
    try:
        scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 20.0
        for _ in range(2):
            scene.step(1 / 30, None)
            scene.render()
        lit = scene.renderer.scene.scene_prog
        query = gl_ctx.query(samples=True)
        counted = [0]
        in_scene = [False]
        original_timed, original_render = Renderer._timed, moderngl.VertexArray.render

        def timed(self, name, fn):
            in_scene[0] = name == "scene"
            try:
                return original_timed(self, name, fn)
            finally:
                in_scene[0] = False

        def render(self, *args, **kwargs):
            if not (in_scene[0] and self.program.glo == lit.glo):
                return original_render(self, *args, **kwargs)
            with query:
                original_render(self, *args, **kwargs)
            counted[0] += query.samples

        monkeypatch.setattr(Renderer, "_timed", timed)
        monkeypatch.setattr(moderngl.VertexArray, "render", render)
        if not prepass:
            monkeypatch.setattr(SceneDrawer, "_depth_prepass", lambda *args: None)
        scene.step(1 / 30, None)
        scene.render()
        monkeypatch.undo()
        return counted[0], scene.image()
    finally:
        scene.release()


def test_lit_shader_runs_about_once_per_pixel_and_draws_the_same_picture(gl_ctx, monkeypatch):
    samples, image = _lit_samples(gl_ctx, monkeypatch, prepass=True)
    layered, reference = _lit_samples(gl_ctx, monkeypatch, prepass=False)
    pixels = SIZE[0] * SIZE[1]
    # ≤ 1 per pixel of the opaque scene (the sky's are not lit), plus the cars, which the pre-pass leaves out,
    # where they cover the world
    assert 0.3 * pixels < samples < 1.15 * pixels
    assert layered > 2.0 * pixels  # without it: the city, the cabin and the cars in front of each other
    # The same picture: only where two surfaces lie at the same depth does the later draw now win (a road marking
    # on the asphalt), and the exposure follows the frame's mean.
    diff = np.abs(image.astype(int) - reference.astype(int)).max(axis=-1)
    assert (diff > 8).mean() < 0.002 and diff.mean() < 0.5
