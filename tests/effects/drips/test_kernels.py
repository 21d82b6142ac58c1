"""The drips' compiled kernels (rain_core.effects.drips.kernels) against their NumPy twin, DripsEffect.update: the
roofs' flux uploaded and the drops landing this frame, bit for bit over frames of rain and of the roofs draining,
the camera walking along the street under the bridge and across the world's wrap."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from rain_core import jit
from rain_core.camera import look_at
from rain_core.effects.drips import kernels
from rain_core.gfx.frame import SharedResources

needs_numba = pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed (pip install 'rainroad[fast]')")


def _update(effect, frame, compiled: bool):
    """One update on either path: (landing rows handed to the ripples, landed, the flux bytes uploaded)."""
    uploads = []
    effect._upload = lambda flux: uploads.append(np.asarray(flux, np.float32).tobytes())
    rc = SimpleNamespace(shared=SharedResources())
    with jit.forced(compiled):
        effect.update(frame, rc)
    del effect._upload
    impacts = rc.shared.droplet_impacts
    # The compiled path uploads the flux only when the roofs' storage changed: its buffer holds what was uploaded.
    flux = uploads[0] if uploads else effect._kernel_args[5].tobytes()
    return (np.zeros((0, 3)) if impacts is None else impacts), effect.landed, flux


@needs_numba
def test_fluxes_and_landings_are_the_twins_bits_frame_after_frame(gl_ctx):
    from rain_core import layout
    from rain_core.effects.drips import DripsEffect
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = 25.0
    effect = DripsEffect(gl_ctx, seed=1)
    scene = Scene(gl_ctx, (64, 36), s, seed=1, effects=[effect], gpu_timing=False)
    try:
        landed = drained = wrapped = skipped = 0
        for i in range(150):
            if i == 75:
                scene.settings.rain.rate_mm_h = 0.0  # the roofs drain from here on
            scene.step(0.2 if i >= 75 else 1 / 30)
            z = 300.0 + 0.9 * (i - 75) + (layout.PERIOD_M - 330.0 if i % 7 == 0 else 0.0)  # now and then: the wrap
            frame = scene.frame(look_at(np.array([-3.5, 1.6, z]), np.array([0.0, 3.5, z - 13.0]), fov_y_deg=60.0))
            effect.observe(frame)
            if effect.roofs is None:
                continue
            settled = effect.roofs._is_settled_at(scene.settings.rain.rate_mm_h)
            twin = _update(effect, frame, compiled=False)
            ranges = list(effect._ranges)
            got = _update(effect, frame, compiled=True)
            assert effect._ranges == ranges
            assert got[0].dtype == np.float64 and got[0].tobytes() == twin[0].tobytes()
            assert got[1] == twin[1] and got[2] == twin[2]
            landed += int(twin[1] > 0)
            wrapped += int(len(ranges) > 1 and twin[1] > 0)
            drained += int(i >= 75 and twin[1] > 0)
            skipped += int(settled)
        assert landed > 60 and drained > 10  # drops landed in the rain and after it
        assert skipped > 30  # the steady rain's frames kept the roofs' storage (and the uploaded flux)
        assert wrapped > 3  # and seen from near the wrap, in two tiles
    finally:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()


def test_landing_kernel_logic_in_plain_python():
    # The landings kernel's plain Python version on a few sites: counts per (t0, t1], none off the ground, none
    # at the longest period, the tile's z offset added; the flux kernel's division.
    landing = getattr(kernels.landing_impacts, "py_func", kernels.landing_impacts)
    flux_kernel = getattr(kernels.roof_flux, "py_func", kernels.roof_flux)
    flux = np.empty(2)
    flux32 = np.empty(2, np.float32)
    flux_kernel(np.array([2e-4, 0.0]), np.array([20.0, 5.0]), np.array([4, 0]), flux, flux32)
    assert flux.tolist() == [2e-4 / 20.0 / 4, 0.0] and flux32[0] == np.float32(2.5e-6)
    drop_m3 = np.full(4, 2.5e-7)  # a period of 0.1 s at 2.5e-6 m³/s
    ground = np.array([True, False, True, True])
    roof = np.array([0, 0, 0, 1])  # the last one's roof is dry: no drops
    phase = np.array([0.0, 0.0, 0.5, 0.0])
    t_fall = np.full(4, 0.05)
    x, z, momentum = np.arange(4.0), 10.0 + np.arange(4.0), np.full(4, 1e-3)
    out = np.zeros((8, 3))
    ranges = np.array([[0.0, 4.0, 100.0], [2.0, 1.0, -200.0]])
    n = landing(ranges, 1.0, 1.35, 1e6, ground, drop_m3, flux, roof, phase, t_fall, x, z, momentum, out)
    # Site 0 lets go at 0.0, 0.1, … and lands 0.05 s later: 1.05, 1.15, 1.25, 1.35 in (1.0, 1.35]; site 2 half a
    # period later: 1.1, 1.2, 1.3.
    assert n == 3
    np.testing.assert_allclose(out[:3], [[0.0, 110.0, 4e-3], [2.0, 112.0, 3e-3], [2.0, -188.0, 3e-3]])
