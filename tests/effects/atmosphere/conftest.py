"""Helpers of the atmosphere's rendered tests: tiny worlds (≤ 160×90) built here, so each test sees one thing."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import trimesh

from rain_core.effects import atmosphere as atm
from rain_core.gfx.frame import Frame
from rain_core.gfx.renderer import Renderer
from rain_core.lighting import lighting_for_hour
from rain_core.mesh import MAT_CONCRETE, concat, from_trimesh

LUMA = np.array([0.2126, 0.7152, 0.0722])


def _box(center, extents, albedo, material=MAT_CONCRETE):
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(center)
    return from_trimesh(mesh, np.asarray(albedo, np.float32), 0.9, 0.0, material)


def _world(parts, lamps=()):
    return SimpleNamespace(vertices=concat(parts), lamps=list(lamps))


def _frame(camera, world, settings, rate, hour):
    lighting = lighting_for_hour(hour, atm.sky_overcast(settings.atmosphere, rate))
    return Frame(0.0, 0.0, camera, lighting, world, weather=SimpleNamespace(rate_mm_h=rate), settings=settings)


def _renderer(ctx, shaders, world, size, effect=True):
    """A renderer with the atmosphere effect; ``effect=False``: clear air; ``effect=None``: no air at all."""
    effects = {True: [atm.AtmosphereEffect(ctx, shaders=shaders)], False: [], None: [atm.NoAirEffect()]}[effect]
    return Renderer(ctx, size, world, effects=effects, shaders=shaders, gpu_timing=False)


def _release(*renderers):
    """Release renderers and bind the default framebuffer: a released framebuffer left bound would make every
    later framebuffer creation on the shared context fail with GL_INVALID_OPERATION."""
    for r in renderers:
        r.release()
    renderers[0].ctx.detect_framebuffer(0).use()


def _bottom_first(renderer):
    """HDR colour and depth of the last frame, bottom row first (as GL stores them)."""
    w, h = renderer.size
    depth = np.frombuffer(renderer.hdr.depth.read(alignment=1), dtype=np.float32).reshape(h, w)
    return renderer.hdr_image()[::-1].astype(np.float64), depth


@pytest.fixture
def kit():
    """The helpers above: box, world, frame, renderer, release, bottom_first."""
    return SimpleNamespace(box=_box, world=_world, frame=_frame, renderer=_renderer, release=_release,
                           bottom_first=_bottom_first)
