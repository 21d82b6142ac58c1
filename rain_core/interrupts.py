"""Ctrl-C that is never lost in a long loop (a headless recording, a sweep).

Python raises KeyboardInterrupt wherever the main thread is when SIGINT lands. If that is inside a finaliser
(``__del__``), Python prints "Exception ignored" and drops it, and the loop runs on as if no key was pressed.
While Numba compiles or loads a kernel, llvmlite's finalisers run thousands of times, so this window is wide.
``CtrlC`` records every SIGINT as well as raising it, and its ``check()`` raises a dropped one at the loop's next
safe point (after a frame, after a finished sequence)."""

from __future__ import annotations

import signal
import threading


class CtrlC:
    """``with CtrlC() as ctrl_c: … ctrl_c.check()``. Outside the main thread (where no signal handler can be set)
    it does nothing and ``check`` never raises."""

    def __init__(self):
        self.pressed = False
        self._previous = None
        self._installed = False

    def __enter__(self) -> CtrlC:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handler)
            self._installed = True
        return self

    def __exit__(self, *exc) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)
            self._installed = False

    def _handler(self, signum, frame) -> None:
        self.pressed = True
        raise KeyboardInterrupt

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed (also one a finaliser dropped)."""
        if self.pressed:
            raise KeyboardInterrupt
