"""The whole-frame benchmark's core (``python -m rain_core.bench frame``): two frames at a tiny size give
positive, finite counters for the frame and its passes (no timing asserts: timings belong to the benchmark)."""

from __future__ import annotations

import math

import moderngl
import pytest

from rain_core.bench.frame import GLCounter, heavy_rain_settings, measure_case, parse_args, with_overrides


def test_measure_case_counts_gl_calls_bytes_and_cpu(gl_ctx):
    with GLCounter() as counter:
        result = measure_case(gl_ctx, (48, 27), budget=2000, speed_kmh=100.0, frames=2, warmup=1, counter=counter)
    frame = result["frame"]
    assert frame["gl_calls"] > 0 and frame["upload_kb"] + frame["uniform_kb"] > 0
    for key in ("cpu_ms", "gl_ms", "wall_ms", "gl_calls", "upload_kb", "uniform_kb"):
        assert math.isfinite(frame[key]) and frame[key] >= 0.0, key
    assert frame["cpu_ms"] > 0.0 and frame["wall_ms"] >= frame["cpu_ms"]
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
