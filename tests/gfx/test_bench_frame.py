"""The whole-frame benchmark's core (``python -m rain_core.bench frame``): two frames at a tiny size give
positive, finite counters for the frame and its passes (no timing asserts: timings belong to the benchmark)."""

from __future__ import annotations

import math
import sys

import moderngl
import pytest

from rain_core.bench.frame import (
    GLCounter,
    case_table,
    header,
    heavy_rain_settings,
    measure_case,
    parse_args,
    with_overrides,
)


def test_measure_case_counts_gl_calls_bytes_and_cpu(gl_ctx):
    with GLCounter() as counter:
        # Two warm-up frames: the timer queries are read two frames late (PassTimer.LAG), so GPU ms from the third.
        result = measure_case(gl_ctx, (48, 27), budget=2000, speed_kmh=100.0, frames=2, warmup=2, counter=counter)
    frame = result["frame"]
    assert frame["gl_calls"] > 0 and frame["upload_kb"] + frame["uniform_kb"] > 0
    for key in ("cpu_ms", "gl_ms", "wall_ms", "process_cpu_ms", "gl_calls", "upload_kb", "uniform_kb"):
        assert math.isfinite(frame[key]) and frame[key] >= 0.0, key
    assert frame["cpu_ms"] > 0.0 and frame["wall_ms"] >= frame["cpu_ms"]
    assert frame["cpu_ms_max"] >= frame["cpu_ms"]  # the worst of the measured frames: at least their median
    # Every thread's CPU holds at least the main thread's outside and inside GL (clock ticks aside).
    assert frame["process_cpu_ms"] >= 0.9 * (frame["cpu_ms"] + frame["gl_ms"])
    assert "scene" in result["rows"] and result["rows"]["scene"]["gl_calls"] > 0
    # uniform writes are GL calls too (the scene pass writes at least each mesh's model matrix)
    assert 0 < result["rows"]["scene"]["uniform_writes"] < result["rows"]["scene"]["gl_calls"]
    assert result["rows"]["sim: scene.step"]["cpu_ms"] > 0.0
    for row in result["rows"].values():
        assert all(math.isfinite(v) for v in row.values())
        assert row["gpu_ms"] >= 0.0
    # the rain's own GPU time is part of the frame's (one frame late: finite once a second frame was timed)
    assert 0.0 <= frame["rain_gpu_ms"] <= frame["gpu_ms"]
    assert math.isfinite(counter.overhead_ns) and counter.overhead_ns >= 0.0


def _three_lines():
    a = 1
    b = a + 1
    return b


def test_trace_python_counts_each_line_and_call_in_the_bucket_running_it():
    """Per frame: run's own lines and calls land in the bucket set when they run (a line event comes before its
    line runs); the bench's own functions (here _effect_of) are not counted."""
    from rain_core.bench.frame import _effect_of, trace_python

    counter = GLCounter()  # not entered: only its bucket is used

    def run():
        counter.bucket = "x"  # (counted in "y": the bucket before this line)
        _three_lines()
        counter.bucket = "y"
        _three_lines()
        _effect_of("spray.update")  # the bench's: neither its call nor its line counts
        _three_lines()

    counter.bucket = "y"
    lines, calls = trace_python(counter, run, frames=2)
    assert lines == {"y": 1 + 1 + 3 + 1 + 1 + 3, "x": 1 + 3 + 1}
    assert calls == {"y": 1 + 2, "x": 1}
    assert counter.bucket == "y"

    # Each bucket's median over the frames: a one-off in one frame of three (a bucket of its own) is left out.
    frames = iter(range(3))

    def run_once_odd():
        counter.bucket = "x"
        _three_lines()
        if next(frames) == 1:
            counter.bucket = "once"
            _three_lines()
        counter.bucket = "y"

    lines, calls = trace_python(counter, run_once_odd, frames=3)
    assert lines == {"y": 1, "x": 1 + 3 + 1 + 1, "once": 0} and calls["once"] == 0 and sys.gettrace() is None


def test_measure_case_counts_python_lines_by_pass(gl_ctx):
    """One traced frame: the whole frame's lines are its passes', the step's and the renderer's between them; an
    effect's total is its passes'; the update of the windshield (a Python simulation) runs some."""
    with GLCounter() as counter:
        result = measure_case(gl_ctx, (48, 27), budget=2000, speed_kmh=100.0, frames=1, warmup=1, counter=counter,
                              ripples_backend="numpy32", py_frames=1)
    rows, frame = result["rows"], result["frame"]
    own = [r for name, r in rows.items() if not name.startswith("effect: ")]
    assert frame["py_lines"] == sum(r["py_lines"] for r in own) > 0
    assert frame["py_calls"] == sum(r["py_calls"] for r in own) > 0
    assert rows["sim: scene.step"]["py_lines"] > 0 and rows["windshield.update"]["py_lines"] > 0
    passes = [n for n in rows if n.startswith("windshield.")]
    assert rows["effect: windshield"]["py_lines"] == sum(rows[n]["py_lines"] for n in passes)
    with GLCounter() as counter:
        untraced = measure_case(gl_ctx, (48, 27), budget=2000, speed_kmh=0.0, frames=1, warmup=0, counter=counter,
                                ripples_backend="numpy32", py_frames=0)
    assert "py_lines" not in untraced["frame"] and "py_lines" not in untraced["rows"]["scene"]
    assert "| - |" in case_table(untraced)  # the column without a count


def test_skip_draws_counts_draws_without_making_them(gl_ctx):
    """--skip-draws: a draw is counted and never reaches the driver (the target keeps its clear colour); the other
    calls still do, and the case reports which ripples solver ran."""
    prog = gl_ctx.program(vertex_shader="#version 330\nvoid main(){gl_Position=vec4(vec2(gl_VertexID&1,"
                                        "gl_VertexID>>1)*4.0-1.0,0.0,1.0);}",
                          fragment_shader="#version 330\nout vec4 c;void main(){c=vec4(1.0);}")
    vao = gl_ctx.vertex_array(prog, [])
    fbo = gl_ctx.simple_framebuffer((4, 4))
    fbo.use()
    with GLCounter(skip_draws=True) as counter:
        fbo.clear(0.0, 0.0, 0.0, 1.0)
        vao.render(moderngl.TRIANGLES, vertices=3)
        tally = counter.tallies[counter.bucket]
        assert tally.by_kind["draw"] == 1 and tally.by_kind["state"] == 1
    assert fbo.read(components=1) == bytes(16)  # nothing drawn
    with GLCounter(skip_draws=True) as counter:
        result = measure_case(gl_ctx, (48, 27), budget=2000, speed_kmh=100.0, frames=1, warmup=1, counter=counter,
                              ripples_backend="numpy32")
    assert result["skip_draws"] and result["ripples_solver"] == "numpy32"
    assert result["rows"]["scene"]["gl_calls"] > 0 and result["frame"]["cpu_ms"] > 0.0
    for obj in (vao, prog, fbo):
        obj.release()


def test_pass_wall_times_each_pass_between_two_finishes(gl_ctx):
    """--pass-wall: each pass's "GPU ms" is its wall time between a ctx.finish() before and after it (no timer
    queries); the waits are neither GL calls of the passes nor their CPU, so those columns count what a run
    without it counts. It cannot be combined with --skip-draws."""
    cases = {}
    for wall in (False, True):
        with GLCounter() as counter:
            cases[wall] = measure_case(gl_ctx, (48, 27), budget=2000, speed_kmh=100.0, frames=2, warmup=1,
                                       gpu_timing=False, counter=counter, ripples_backend="numpy32",
                                       pass_wall=wall)
    timed = cases[True]
    assert timed["gpu_source"] == "finish" and timed["gpu_timing"] and not cases[False]["gpu_timing"]
    passes = [n for n in timed["passes"] if n in timed["rows"] and not n.startswith(("effect: ", "sim: ", "renderer"))]
    walls = [timed["rows"][n]["gpu_ms"] for n in passes]
    assert all(math.isfinite(w) and w >= 0.0 for w in walls)
    assert timed["rows"]["scene"]["gpu_ms"] > 0.0 and timed["rows"]["rainfall.transparent"]["gpu_ms"] > 0.0
    assert sum(walls) <= timed["frame"]["wall_ms"]  # the passes lie within the frame
    for key in ("gl_calls", "upload_kb"):
        assert timed["frame"][key] == cases[False]["frame"][key], key
    with pytest.raises(SystemExit):
        parse_args(["--pass-wall", "--skip-draws"])
    args = parse_args(["--pass-wall"])
    assert args.gpu_timing is False  # the finishes time the passes
    assert "wall time between a ctx.finish()" in header(args, 0.0)


def test_skip_draws_resolves_auto_with_the_draws_made(gl_ctx, monkeypatch, tmp_path):
    """--skip-draws with the ripples solver on "auto": the choice is timed before the draws are skipped (skipped,
    the GPU solver's steps would look free and the case would time another solver than a run with draws)."""
    from rain_core.bench import frame as bench_frame
    from rain_core.effects.ripples import backend

    real_render = moderngl.VertexArray.render
    asked = []

    def choose(ctx, n, **kwargs):
        asked.append((n, moderngl.VertexArray.render is real_render))
        return "numpy32", {}

    monkeypatch.setattr(backend, "choose_backend", choose)
    class Stop(Exception):
        pass

    def measure(*args, ripples_backend, **kwargs):
        asked.append(ripples_backend)
        raise Stop  # only the choice is tested

    monkeypatch.setattr(bench_frame, "measure_case", measure)
    monkeypatch.setattr("rain_core.gl.create_headless_context", lambda: gl_ctx)
    with pytest.raises(Stop):
        bench_frame.main(["--skip-draws", "--budgets", "2000", "--speeds", "0", "--out", str(tmp_path)])
    # The default grid, timed with the real draws; the case then runs the chosen solver by name.
    assert asked == [(512, True), "numpy32"]


def test_counter_restores_moderngl():
    render = moderngl.VertexArray.render
    with GLCounter():
        assert moderngl.VertexArray.render is not render
    assert moderngl.VertexArray.render is render


def test_quick_options():
    args = parse_args(["--quick", "--size", "64x36"])
    assert args.size == (64, 36) and args.budgets == (10_000, 1_000_000) and args.frames < 30


def test_set_overrides_settings_by_path_and_rejects_bad_values(capsys):
    args = parse_args(["--set", "road.reflection_scale=0.25", "--set", "camera.mode=chase",
                       "--set", "atmosphere.scatter_lights = 2"])
    assert args.overrides == [("road.reflection_scale", 0.25), ("camera.mode", "chase"),
                              ("atmosphere.scatter_lights", 2)]
    settings = with_overrides(heavy_rain_settings(10_000), args.overrides)
    assert settings.road.reflection_scale == 0.25 and settings.camera.mode == "chase"
    assert settings.atmosphere.scatter_lights == 2 and settings.quality.particle_budget == 10_000
    # out of range, unknown, no value, and the window's render scale (the bench draws --size)
    for bad in ("road.reflection_scale=9", "quality.nope=1", "reflection_scale", "quality.render_scale=0.5"):
        with pytest.raises(SystemExit):
            parse_args(["--set", bad])
    err = capsys.readouterr().err
    assert "reflection_scale" in err and "--size" in err


def _fake_result(speed: float, cpu: float, scene_cpu: float) -> dict:
    """A measure_case result with the figures the report reads (a frame and two rows)."""
    frame = {"cpu_ms": cpu, "gl_ms": 1.0, "gl_calls": 10.0, "uniform_writes": 2.0, "upload_kb": 4.0,
             "uniform_kb": 1.0, "wall_ms": 9.0, "process_cpu_ms": 20.0, "gpu_ms": 0.0, "gpu_share": 100.0,
             "rain_gpu_ms": 0.0, "cpu_ms_max": cpu + 1.0}
    row = {"cpu_ms": scene_cpu, "gl_ms": 0.5, "gl_calls": 5.0, "queries": 0.0, "uniform_writes": 1.0,
           "upload_kb": 0.0, "uniform_kb": 0.5, "read_kb": 0.0, "gpu_ms": 0.0, "gpu_share": 0.0}
    return {"size": (48, 27), "budget": 2000, "speed_kmh": speed, "frames": 1, "ripples_backend": "numpy32",
            "ripples_solver": "numpy32", "skip_draws": False, "warmup": 0, "gpu_timing": False, "overhead_ns": 0.0,
            "clock": "thread", "passes": ["scene", "sim: scene.step"],
            "rows": {"scene": row, "sim: scene.step": dict(row, cpu_ms=0.1)}, "frame": frame}


def test_rounds_report_the_median_of_the_rounds_and_the_frames_range():
    from rain_core.bench.frame import combine_rounds, summary_table

    one = _fake_result(0.0, 4.0, 1.0)
    assert combine_rounds([one]) is one
    both = combine_rounds([_fake_result(0.0, 4.0, 1.0), _fake_result(0.0, 6.0, 3.0), _fake_result(0.0, 5.5, 2.0)])
    assert both["rounds"] == 3 and both["cpu_ms_range"] == (4.0, 6.0)
    assert both["frame"]["cpu_ms"] == 5.5 and both["rows"]["scene"]["cpu_ms"] == 2.0
    assert both["rows"]["sim: scene.step"]["cpu_ms"] == 0.1 and both["frame"]["gl_calls"] == 10.0
    assert both["frame"]["cpu_ms_max"] == 7.0  # the worst frame of all the rounds, not a median
    assert "| 5.50 [4.00–6.00] | 7.00 |" in summary_table([both])


def test_rounds_alternate_the_cases(gl_ctx, monkeypatch, tmp_path, capsys):
    """--rounds 2: every case once a round (a slow spell of a shared machine hits them all), then one table each."""
    from rain_core.bench import frame as bench_frame

    order = []

    def measure(ctx, size, budget, speed, *args, **kwargs):
        order.append(speed)
        return _fake_result(speed, 4.0 + len(order), 1.0)

    monkeypatch.setattr(bench_frame, "measure_case", measure)
    monkeypatch.setattr("rain_core.gl.create_headless_context", lambda: gl_ctx)
    monkeypatch.setattr(gl_ctx, "release", lambda: None)  # the session's context stays for the other tests
    assert bench_frame.main(["--rounds", "2", "--budgets", "2000", "--speeds", "0,100", "--ripples-backend",
                             "numpy32", "--out", str(tmp_path)]) == 0
    assert order == [0.0, 100.0, 0.0, 100.0]
    report = (tmp_path / "frame.md").read_text()
    assert "2 rounds" in report and "6.00 [5.00–7.00]" in report and "7.00 [6.00–8.00]" in report
    with pytest.raises(SystemExit):
        parse_args(["--rounds", "0"])


def test_fps_sets_each_frames_step_and_rejects_rates_outside_4_to_240(gl_ctx, monkeypatch, tmp_path):
    """--fps 60: each frame steps the scene 1/60 s (a window at its display's rate), and the header says so."""
    from rain_core.bench import frame as bench_frame

    steps = []

    def measure(ctx, size, budget, speed, *args, dt_s=None, **kwargs):
        steps.append(dt_s)
        return _fake_result(speed, 4.0, 1.0)

    monkeypatch.setattr(bench_frame, "measure_case", measure)
    monkeypatch.setattr("rain_core.gl.create_headless_context", lambda: gl_ctx)
    monkeypatch.setattr(gl_ctx, "release", lambda: None)
    assert bench_frame.main(["--fps", "60", "--budgets", "2000", "--speeds", "0", "--ripples-backend", "numpy32",
                             "--out", str(tmp_path)]) == 0
    assert steps == [1.0 / 60.0]
    assert "60 frames/s" in (tmp_path / "frame.md").read_text()
    assert parse_args([]).fps == 30.0  # the default: the tables of earlier notes
    for bad in ("3", "241", "nan"):  # below 4 frames/s the scene would clamp the step (MAX_FRAME_DT_S)
        with pytest.raises(SystemExit):
            parse_args(["--fps", bad])


def test_a_case_steps_the_scene_by_its_dt(gl_ctx, monkeypatch):
    """measure_case steps the scene by dt_s each frame (and records it)."""
    from rain_core.scene import Scene

    seen = []
    step = Scene.step

    def recording(self, dt_s, *args, **kwargs):
        seen.append(dt_s)
        return step(self, dt_s, *args, **kwargs)

    monkeypatch.setattr(Scene, "step", recording)
    result = measure_case(gl_ctx, (48, 27), 2000, 0.0, frames=1, warmup=0, gpu_timing=False, dt_s=1.0 / 60.0,
                          ripples_backend="numpy32", py_frames=0)
    assert seen and set(seen) == {1.0 / 60.0} and result["dt_s"] == 1.0 / 60.0
