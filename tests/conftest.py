"""Shared fixtures: one headless GL context for the whole session (EGL on llvmpipe in CI)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def gl_ctx():
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    with ctx:
        yield ctx
    ctx.release()


@pytest.fixture(autouse=True)
def _gl_current(request):
    """Make the session context current for every test that uses it: a test that opens a window (or another
    context) leaves that one current, and GL calls would then go to the wrong context."""
    if {"gl_ctx", "shaders"} & set(request.fixturenames):
        with request.getfixturevalue("gl_ctx"):
            yield
    else:
        yield


@pytest.fixture(scope="session")
def shaders(gl_ctx):
    from rain_core.gl import ShaderLibrary

    return ShaderLibrary(gl_ctx)
