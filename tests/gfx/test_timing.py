"""PassTimer's lagged GPU times: each measurement comes back LAG (2) calls late, the same whether the renderer
collects the queries before its passes or ``measure`` reads them; the renderer reads every query before its first
pass."""

import moderngl
import pytest

from rain_core.gfx.renderer import Renderer
from rain_core.gfx.timing import PassTimer
from rain_core.scene import Scene
from rain_core.settings import Settings, set_value


class FakeQuery:
    """A timer query whose elapsed time is set by the test; counts its reads."""

    def __init__(self, log):
        self.log = log
        self.ns = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.ns = self.log["next_ns"]

    @property
    def elapsed(self):
        self.log["reads"].append(self.log["phase"])
        return self.ns


def lagged_timer():
    log = {"reads": [], "phase": None, "next_ns": 0}
    timer = PassTimer(None, gpu=False, lagged=True)
    timer._queries = [FakeQuery(log) for _ in range(PassTimer.LAG + 1)]
    return timer, log


def run(timer, log, ns_values, collect):
    out = []
    for ns in ns_values:
        if collect:
            log["phase"] = "collect"
            timer.collect()
        log["phase"] = "measure"
        log["next_ns"] = ns
        out.append(timer.measure(lambda: None, True)[1])
    return out


@pytest.mark.parametrize("collect", [False, True])
def test_each_gpu_time_comes_back_two_measurements_late(collect):
    timer, log = lagged_timer()
    ns = [1_000_000, 2_000_000, 3_000_000, 4_000_000, 5_000_000, 6_000_000]
    assert run(timer, log, ns, collect) == [None, None, 1.0, 2.0, 3.0, 4.0]
    # Collected before the pass, a measurement reads no query: the renderer's passes never wait for the driver.
    assert set(log["reads"]) == ({"collect"} if collect else {"measure"})
    assert len(log["reads"]) == 4


def test_collecting_twice_reads_once_and_forget_drops_what_was_collected():
    timer, log = lagged_timer()
    run(timer, log, [5_000_000, 6_000_000], collect=False)
    timer.collect()
    timer.collect()
    assert len(log["reads"]) == 1
    timer.forget()
    assert run(timer, log, [7_000_000], collect=False) == [None]


def test_a_query_the_driver_could_not_time_is_none_when_collected():
    timer, log = lagged_timer()
    assert run(timer, log, [0xFFFFFFFF, 7_000_000, 8_000_000, 9_000_000], collect=True) == [None, None, None, 7.0]


def test_the_renderer_reads_its_timer_queries_before_its_first_pass(gl_ctx, monkeypatch):
    settings = Settings()
    set_value(settings, "rain.rate_mm_h", 8.0)
    scene = Scene(gl_ctx, (64, 36), settings=settings, seed=1, gpu_timing=True)
    try:
        for _ in range(PassTimer.LAG):
            scene.step(1 / 30)
            scene.render()
        events = []
        timed = Renderer._timed
        monkeypatch.setattr(Renderer, "_timed", lambda self, name, fn: (events.append("pass"), timed(self, name, fn)))
        elapsed = moderngl.Query.elapsed
        monkeypatch.setattr(moderngl.Query, "elapsed", property(lambda q: (events.append("read"), elapsed.fget(q))[1]))
        scene.step(1 / 30)
        scene.render()
        assert events.count("pass") > 10 and events.count("read") >= events.count("pass") - 2
        assert "read" not in events[events.index("pass"):]
        assert any(stat.gpu_ms is not None for stat in scene.renderer.stats)
    finally:
        scene.release()
