"""Every pass leaves the HDR target finite and non-negative at extreme *valid* settings (issue 18).

The cases are the audit's: the defaults plus 80 mm/h at 22 h with 5 cars and the ego car flat out at 200 km/h
in 1/15 s steps, where the scene pass wrote NaN (the wet road's highlight Fresnel took pow(1 − V·H, 5) with V·H
rounded above 1 for a headlight right beside the eye; the windshield then spread it), and dense rain with the
glow at 4×, where atmosphere.post wrote negative radiance (its halo removed k·w > 1 of a pixel's light).
The HDR target is read after every pass that draws into it (the renderer's ``_timed`` is wrapped: the passes have
no other hook).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from rain_core.scene import Scene
from rain_core.settings import Settings, set_value

FLAT_OUT = SimpleNamespace(throttle=1.0, brake=0.0, steer=0.0, reverse=False)


def hdr_rgba(renderer) -> np.ndarray:
    w, h = renderer.size
    data = renderer.hdr.fbo.read(components=4, dtype="f4", alignment=1)
    return np.frombuffer(data, dtype=np.float32).reshape(h, w, 4)[..., :3]


def render_checked(ctx, settings: Settings, size, frames: int, dt: float = 1 / 15, ego_speed_m_s=None,
                   seed: int = 1) -> list[str]:
    """Render ``frames`` frames; return one line per pass that left a NaN, inf or negative value in the HDR."""
    scene = Scene(ctx, size, settings, seed=seed, gpu_timing=False)
    renderer = scene.renderer
    problems: list[str] = []
    timed = renderer._timed
    frame_index = [0]

    def checked(name, fn):
        timed(name, fn)
        if name != "scene" and name.rpartition(".")[2] not in ("transparent", "post", "overlay"):
            return  # passes that do not draw into the HDR target (update, prepare, shadow, tonemap)
        a = hdr_rgba(renderer)
        bad = ~np.isfinite(a)
        neg = a < 0
        if bad.any() or neg.any():
            problems.append(f"frame {frame_index[0]} after {name}: {int(bad.any(-1).sum())} non-finite, "
                            f"{int(neg.any(-1).sum())} negative pixels (min {np.nanmin(a):.3g})")

    renderer._timed = checked
    try:
        if ego_speed_m_s is not None:
            scene.ego.speed_m_s = ego_speed_m_s
        for i in range(frames):
            frame_index[0] = i
            scene.step(dt, FLAT_OUT if ego_speed_m_s is not None else None)
            scene.render()
    finally:
        scene.release()
    return problems


def _settings(**values) -> Settings:
    s = Settings()
    for path, value in values.items():
        set_value(s, path.replace("__", "."), value)
    return s


def test_night_rain_at_top_speed_has_no_nan(gl_ctx):
    """The audit's case: a NaN from the scene pass within the first frames (chase camera, 320×180)."""
    s = _settings(rain__rate_mm_h=80.0, time_of_day__hour=22.0, traffic__count=5, camera__mode="chase")
    problems = render_checked(gl_ctx, s, (320, 180), frames=7, ego_speed_m_s=200 / 3.6)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("camera", ["driver", "chase"])
def test_dense_rain_with_strong_glow_is_never_negative(gl_ctx, camera):
    s = _settings(rain__rate_mm_h=500.0, time_of_day__hour=22.0, atmosphere__glow=4.0, atmosphere__fog_scale=4.0,
                  atmosphere__haze_per_km=60.0, atmosphere__light_scattering=4.0, camera__mode=camera)
    problems = render_checked(gl_ctx, s, (160, 90), frames=4, ego_speed_m_s=200 / 3.6)
    assert not problems, "\n".join(problems)
