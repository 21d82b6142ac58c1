"""OpenGL contexts: a standalone EGL one for headless use, with a clear error below OpenGL 3.3 core, and Mesa's
driver thread asked for before the first one.

The main path targets OpenGL 3.3 core so the app runs on every desktop; nothing in ``gfx`` needs more.
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

import moderngl

MIN_GL_VERSION = 330

# Mesa's option (driconf, read from the environment) that runs its GL driver on a thread of its own: GL calls are
# queued for that thread and return, as a desktop GPU's driver does its work on its own threads. Mesa reads it when
# a process makes its first context; drivers other than Mesa ignore it.
DRIVER_THREAD_OPTION = "mesa_glthread"
_ON = ("true", "1", "yes", "on")


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


def request_driver_thread(environ: MutableMapping[str, str] = os.environ) -> bool:
    """Ask Mesa to run the GL driver on its own thread ("glthread"), unless ``mesa_glthread`` is set already (the
    user's choice, e.g. ``mesa_glthread=false``, is kept). Call it before the process's first GL context; the window
    and ``create_headless_context`` do. Returns whether the option is on.

    Why: on llvmpipe a draw runs its vertex work on the calling thread, which left this thread's caches cold for
    the Python after it (``bench frame``, 320×180, CPU outside GL: 6.0 → 4.6 ms parked, 6.5 → 5.6 ms at
    100 km/h). Every test passes either way, and the pixels are the same (``tests/gfx/test_context.py``)."""
    if DRIVER_THREAD_OPTION not in environ:
        environ[DRIVER_THREAD_OPTION] = "true"
        # Mesa prints "ATTENTION: default value of option mesa_glthread overridden by environment" unless
        # MESA_DEBUG says silent; in Mesa's release builds "silent" changes nothing else (it is the default).
        environ.setdefault("MESA_DEBUG", "silent")
    return driver_thread_requested(environ)


def driver_thread_requested(environ: MutableMapping[str, str] = os.environ) -> bool:
    """Whether the environment asks Mesa for its driver thread (``mesa_glthread``; Mesa's own default otherwise)."""
    return environ.get(DRIVER_THREAD_OPTION, "").strip().lower() in _ON


def describe_driver(ctx: moderngl.Context) -> str:
    """The GL driver in words, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), Mesa 22.3.6, driver thread on": its renderer,
    Mesa's version where it is Mesa, and then whether the environment asked Mesa for its driver thread."""
    renderer = ctx.info.get("GL_RENDERER", "unknown renderer")
    version = str(ctx.info.get("GL_VERSION", ""))
    mesa = version.find("Mesa")
    if mesa < 0:
        return renderer
    thread = "on" if driver_thread_requested() else "off"
    return f"{renderer}, {version[mesa:]}, driver thread {thread}"


def create_headless_context() -> moderngl.Context:
    """A standalone context with no window: EGL first (works without a display), then the platform default. Asks
    for Mesa's driver thread first (``request_driver_thread``)."""
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
