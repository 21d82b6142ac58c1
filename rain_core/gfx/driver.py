"""Mesa's GL driver thread ("glthread"): asked for before the first context, and the driver described in words.

With the thread, GL calls are queued for a thread of the driver's own and return, as a desktop GPU's driver does
its work on its own threads; on llvmpipe a draw's vertex work then no longer runs on the main thread between the
passes' Python (docs/architecture.md, "The GL driver on its own thread", has the measurements). Mesa takes the
option from the environment when it sets up a display (the first context on it); later contexts on that display
keep what it read. Drivers other than Mesa ignore it. Processes started later inherit the environment, so a
sweep's or the warm-up's workers ask for the thread too.
"""

from __future__ import annotations

import os
import re
from collections.abc import MutableMapping

import moderngl

DRIVER_THREAD_OPTION = "mesa_glthread"  # Mesa's driconf option (a boolean: exactly "true" or "false")
# Bytes a buffer write may carry and still be queued: Mesa's thread copies a write into its command queue when the
# command (a small header and the data) fits its largest command, 8 KiB; a larger one waits for the thread to
# finish everything queued, and the calling thread runs what was not yet handed over itself.
QUEUED_WRITE_BYTES = 4096
_WORKER_NAME = re.compile(r"(.*:)?gl\d+")  # Mesa names the thread "<process>:gl0" (Linux task names)


def request_driver_thread(environ: MutableMapping[str, str] = os.environ) -> bool:
    """Ask Mesa to run the GL driver on its own thread, unless ``mesa_glthread`` is set already (the user's choice,
    e.g. ``mesa_glthread=false``, is kept). Changes ``environ`` (the process's environment); call it before the
    process's first GL context: the window and ``create_headless_context`` do. Returns whether it is asked for.

    Every test passes either way, and the pixels are the same (``tests/gfx/test_driver.py``)."""
    environ.setdefault(DRIVER_THREAD_OPTION, "true")
    # Mesa prints "ATTENTION: default value of option mesa_glthread overridden by environment" for an option set
    # in the environment unless MESA_DEBUG says silent: in release builds that silences the notice, and nothing
    # else is printed differently (without MESA_DEBUG they print nothing either).
    environ.setdefault("MESA_DEBUG", "silent")
    return driver_thread_requested(environ)


def driver_thread_requested(environ: MutableMapping[str, str] = os.environ) -> bool:
    """Whether the environment asks Mesa for its driver thread: Mesa reads a boolean option as exactly "true" or
    "false" after leading white space, and ignores any other value (with a warning)."""
    return environ.get(DRIVER_THREAD_OPTION, "").lstrip(" \t\n\r\f\v") == "true"


def driver_threads() -> int | None:
    """How many of this process's threads are Mesa's driver threads, or None where the system does not list a
    process's threads by name (``/proc/self/task``: Linux)."""
    tasks = "/proc/self/task"
    try:
        names = []
        for task in os.listdir(tasks):
            with open(f"{tasks}/{task}/comm") as comm:
                names.append(comm.read().strip())
    except OSError:
        return None
    return sum(1 for name in names if _WORKER_NAME.fullmatch(name))


def describe_driver(ctx: moderngl.Context) -> str:
    """The GL driver in words, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), Mesa 22.3.6, driver thread on": its renderer,
    then for Mesa its version and whether its driver thread runs (on Linux, where the threads can be listed; else
    whether the environment asks for it)."""
    renderer = ctx.info.get("GL_RENDERER", "unknown renderer")
    version = str(ctx.info.get("GL_VERSION", ""))
    mesa = version.find("Mesa")
    if mesa < 0:
        return renderer
    threads = driver_threads()
    if threads is None:
        thread = "asked for" if driver_thread_requested() else "not asked for"
    else:
        thread = "on" if threads else "off"
    return f"{renderer}, {version[mesa:]}, driver thread {thread}"


def write_queued(buffer: moderngl.Buffer, data, offset: int = 0) -> None:
    """``buffer.write(data, offset)`` (bytes) in pieces of at most QUEUED_WRITE_BYTES, each queued by Mesa's driver
    thread: a write after the frame's draws (the Rain Manager's vertices) then never has the calling thread do the
    draws not yet handed over (it may still sleep while the thread's queue is full). Where the writes come before
    any draw (the effects' uploads) one write is as good."""
    view = memoryview(data).cast("B")
    for start in range(0, len(view), QUEUED_WRITE_BYTES):
        buffer.write(view[start:start + QUEUED_WRITE_BYTES], offset=offset + start)
