"""The effect contract (rain_core.gfx.effect): every update is CPU work, and the renderer runs them all, then every
effect's upload (writes, no draws), before the frame's first draw; an effect's draws are in its other stages.

On llvmpipe a draw runs its vertex work on the calling thread and leaves Python's caches cold for whatever runs
after it: one GL pass in the middle of the updates made the rainfall's and the windshield's updates after it cost
~130 and ~150 µs more a frame. With Mesa's driver thread a write of more than 8 KiB, or a texture written from
memory, waits for the thread and runs every call not yet handed over on the calling thread: the spray's parcels
written after the shadow pass and the road's reflection ran ~28 ms of their vertex work on the main thread a frame.
So the ripples (numpy32: its height), the spray (its new parcels) and the windshield (its film and splat rows)
write in ``upload``, before the draws."""

from __future__ import annotations

from rain_core.bench.frame import GLCounter, measure_case


def test_no_effect_update_makes_a_gl_call_and_the_uploads_precede_every_draw(gl_ctx):
    with GLCounter() as counter:
        result = measure_case(gl_ctx, (48, 27), budget=2000, speed_kmh=100.0, frames=2, warmup=2, counter=counter,
                              ripples_backend="numpy32", gpu_timing=False)
        tallies = dict(counter.tallies)
    rows, passes = result["rows"], result["passes"]
    updates = [name for name in passes if name.endswith(".update")]
    assert {"spray.update", "ripples.update", "rainfall.update", "windshield.update"} <= set(updates)
    assert {name: rows[name]["gl_calls"] for name in updates} == dict.fromkeys(updates, 0)
    # What they publish is written in their upload: the ripples' height, the spray's new parcels, the
    # windshield's film and drop rows; an upload draws nothing.
    uploads = [name for name in passes if name.endswith(".upload")]
    assert {"spray.upload", "ripples.upload", "windshield.upload"} <= set(uploads)
    assert all(rows[name]["upload_kb"] > 0.0 for name in ("spray.upload", "ripples.upload", "windshield.upload"))
    assert all(tallies[name].by_kind.get("draw", 0) == 0 for name in uploads)
    # Every upload comes before the first pass that draws (the shadow, the road's reflection, the scene).
    drawing = [name for name in passes if name in tallies and tallies[name].by_kind.get("draw", 0)]
    assert "scene" in drawing and "ripples.prepare" in drawing  # (the normals pass)
    first_draw = min(passes.index(name) for name in drawing)
    assert max(passes.index(name) for name in uploads) < first_draw
    # After it, no pass writes more than the few KiB a driver thread takes without waiting (uniform-sized data).
    late = {name: rows[name]["upload_kb"] for name in passes[first_draw:] if name in tallies}  # (passes, not totals)
    assert late and max(late.values()) < 8.0, late


def test_no_vao_reading_a_buffer_is_made_after_a_frames_first_draw(gl_ctx, monkeypatch):
    """A VAO that reads a buffer, made once draws are queued, waits for the driver thread to run them (4-25 ms
    each on llvmpipe): the scene's meshes make all theirs (lit, shadow, mirror view, pre-passes) when they are
    made, in the frame's plan, and the spray its rings' with their buffers, in its upload. The first frames of a
    drive make every mesh, the door mirrors' and the road's mirror views and the spray's rings."""
    import moderngl

    from rain_core.bench.frame import heavy_rain_settings
    from rain_core.scene import Scene

    drawn, late = [False], []
    make, render = moderngl.Context.vertex_array, moderngl.VertexArray.render

    def vertex_array(self, program, *args, **kwargs):
        content = args[0] if args else kwargs.get("content", [])
        if drawn[0] and content:  # (a fullscreen triangle reads no buffer)
            late.append(program)
        return make(self, program, *args, **kwargs)

    def draw(self, *args, **kwargs):
        drawn[0] = True
        return render(self, *args, **kwargs)

    monkeypatch.setattr(moderngl.Context, "vertex_array", vertex_array)
    monkeypatch.setattr(moderngl.VertexArray, "render", draw)
    scene = Scene(gl_ctx, (48, 27), settings=heavy_rain_settings(2000), seed=1, gpu_timing=False)
    try:
        for effect in scene.effects:
            if effect.name == "ripples":
                effect.backend = "numpy32"
        scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 100 / 3.6
        made = []
        for _ in range(6):
            drawn[0] = False
            scene.step(1 / 30, None)
            frame = scene.render()
            made.append(len(late))
        spray = next(e for e in scene.effects if e.name == "spray")
        assert spray.active(frame) and all(vao is not None for vao in spray._vaos)  # the rings were made
        assert frame.camera.inside_car and scene.settings.camera.mirrors  # the mirror views were drawn
    finally:
        scene.release()
    assert made == [0] * 6, made
