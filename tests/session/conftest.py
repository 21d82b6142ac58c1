"""Small, cheap sessions for the API tests (llvmpipe is slow: tiny frames, few steps)."""

from __future__ import annotations

import pytest

SIZE = (64, 40)
CHEAP = {"quality.ripple_grid": 64, "quality.windshield_resolution": 128, "quality.particle_budget": 20_000,
         "spray.budget": 3000, "windshield.drop_budget": 1000, "traffic.count": 2}


def cheap_settings(**values):
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for key, value in {**CHEAP, **values}.items():
        set_value(settings, key, value)
    return settings


@pytest.fixture
def session(gl_ctx):
    """session(**kwargs) → a Session on the test context with cheap settings; closed after the test."""
    from rain_core import Session

    made = []

    def make(size=SIZE, settings=None, **kwargs):
        sim = Session(size=size, settings=settings or cheap_settings(), ctx=gl_ctx, **kwargs)
        made.append(sim)
        return sim

    yield make
    for sim in made:
        sim.close()
