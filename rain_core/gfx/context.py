"""OpenGL contexts: a standalone EGL one for headless use, with a clear error below OpenGL 3.3 core, and Mesa's
driver thread asked for before the first one.

The main path targets OpenGL 3.3 core so the app runs on every desktop; nothing in ``gfx`` needs more.
"""

from __future__ import annotations

import moderngl

from rain_core.gfx.driver import request_driver_thread

MIN_GL_VERSION = 330


class GLUnavailableError(RuntimeError):
    """No OpenGL ≥ 3.3 context could be created (or the one given is too old)."""


def _check_version(ctx: moderngl.Context) -> moderngl.Context:
    if ctx.version_code < MIN_GL_VERSION:
        found = ctx.info.get("GL_VERSION", ctx.version_code)
        renderer = ctx.info.get("GL_RENDERER", "unknown renderer")
        ctx.release()
        raise GLUnavailableError(
            f"OpenGL 3.3 core is required, this driver offers {found} ({renderer}). "
            "Update the graphics driver, or on a machine without a GPU install Mesa (llvmpipe)."
        )
    return ctx


def create_headless_context() -> moderngl.Context:
    """A standalone context with no window: EGL first (works without a display), then the platform default. Asks
    for Mesa's driver thread first (``gfx.driver.request_driver_thread``: sets ``mesa_glthread`` in the process's
    environment unless it is set; ``mesa_glthread=false`` keeps the driver on the calling thread)."""
    request_driver_thread()
    errors = []
    for kwargs in ({"backend": "egl"}, {}):
        try:
            return _check_version(moderngl.create_standalone_context(require=MIN_GL_VERSION, **kwargs))
        except GLUnavailableError:
            raise
        except Exception as exc:  # each backend fails in its own way (missing libEGL, no display, ...)
            errors.append(f"{kwargs.get('backend', 'default')}: {exc}")
    raise GLUnavailableError(
        "could not create a headless OpenGL 3.3 context (" + "; ".join(errors) + "). "
        "On Linux install Mesa's EGL (e.g. apt install libegl1 libgl1-mesa-dri)."
    )
