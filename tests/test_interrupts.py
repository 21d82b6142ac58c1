"""rain_core.interrupts.CtrlC: a Ctrl-C that lands in a finaliser (Python drops it there) is not lost."""

from __future__ import annotations

import gc
import os
import signal
import threading

import pytest

from rain_core.interrupts import CtrlC


class _InterruptedFinaliser:
    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)  # the handler runs here, inside __del__: Python drops its exception
        for _ in range(1000):  # bytecode for the pending signal to be handled in
            pass


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_ctrl_c_dropped_by_a_finaliser_is_raised_at_the_check():
    before = signal.getsignal(signal.SIGINT)
    with CtrlC() as ctrl_c:
        ctrl_c.check()  # nothing pressed yet
        _InterruptedFinaliser()  # made and finalised at once: the KeyboardInterrupt is dropped
        gc.collect()
        assert ctrl_c.pressed
        with pytest.raises(KeyboardInterrupt):
            ctrl_c.check()
    assert signal.getsignal(signal.SIGINT) is before  # the previous handler is back


def test_a_ctrl_c_elsewhere_still_raises_at_once():
    with CtrlC() as ctrl_c, pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):
            pass
    assert ctrl_c.pressed


def test_outside_the_main_thread_it_does_nothing():
    seen = []

    def run():
        with CtrlC() as ctrl_c:
            ctrl_c.check()
            seen.append(ctrl_c._installed)

    t = threading.Thread(target=run)
    t.start()
    t.join()
    assert seen == [False]
