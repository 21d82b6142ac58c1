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
    context) leaves that one current, and GL calls would then go to the wrong context. Such a test must also
    leave no GL error behind: the tests share the context, and an error left (a released framebuffer left
    bound, say) would fail a later, unrelated test."""
    if {"gl_ctx", "shaders"} & set(request.fixturenames):
        ctx = request.getfixturevalue("gl_ctx")
        with ctx:
            yield
            error = ctx.error
        assert error == "GL_NO_ERROR", f"{request.node.nodeid} left {error} on the shared GL context"
    else:
        yield


@pytest.fixture(scope="session")
def shaders(gl_ctx):
    from rain_core.gl import ShaderLibrary

    return ShaderLibrary(gl_ctx)


@pytest.fixture(params=["numpy", "compiled"])
def kernel_path(request):
    """Run a test twice: with the CPU simulations' NumPy twins and with their compiled kernels (rain_core.jit);
    the compiled run is skipped only where Numba is missing (CI installs it with the test extra)."""
    from rain_core import jit

    if request.param == "compiled" and not jit.AVAILABLE:
        pytest.skip("Numba not installed (pip install 'rainroad[fast]')")
    with jit.forced(request.param == "compiled"):
        yield request.param
