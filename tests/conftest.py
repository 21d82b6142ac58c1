"""Shared fixtures: one headless GL context for the whole session (EGL on llvmpipe in CI)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def gl_ctx():
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    yield ctx
    ctx.release()


@pytest.fixture(scope="session")
def shaders(gl_ctx):
    from rain_core.gl import ShaderLibrary

    return ShaderLibrary(gl_ctx)
