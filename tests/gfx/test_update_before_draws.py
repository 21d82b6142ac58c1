"""The effect contract (rain_core.gfx.effect): every update is CPU work and the renderer runs them all before the
frame's first draw; an effect's GL work (uploads, passes that publish a simulation's result) is in its stages.

On llvmpipe a draw runs its vertex work on the calling thread and leaves Python's caches cold for whatever runs
after it: one GL pass in the middle of the updates made the rainfall's and the windshield's updates after it cost
~130 and ~150 µs more a frame. The ripples (numpy32: its height upload and normals pass) and the spray (its new
parcels into the GPU rings) publish in ``prepare``."""

from __future__ import annotations

from rain_core.bench.frame import GLCounter, measure_case


def test_no_effect_update_makes_a_gl_call(gl_ctx):
    with GLCounter() as counter:
        result = measure_case(gl_ctx, (48, 27), budget=2000, speed_kmh=100.0, frames=2, warmup=2, counter=counter,
                              ripples_backend="numpy32", gpu_timing=False)
    rows = result["rows"]
    updates = [name for name in result["passes"] if name.endswith(".update")]
    assert {"spray.update", "ripples.update", "rainfall.update", "windshield.update"} <= set(updates)
    assert {name: rows[name]["gl_calls"] for name in updates} == dict.fromkeys(updates, 0)
    # what they publish is drawn and written in prepare: the ripples' normals pass, the spray's new parcels
    assert rows["ripples.prepare"]["gl_calls"] > 0 and rows["ripples.prepare"]["upload_kb"] > 0.0
    assert rows["spray.prepare"]["upload_kb"] > 0.0
