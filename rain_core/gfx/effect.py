"""The contract every effect follows (DESIGN §1). The renderer, once per frame, for every effect in order:

1. ``observe(frame)``: always, active or not — keep the little state that must follow the frame while the
   effect is idle (e.g. the last time seen, so waking up does not replay the idle interval). No GL work.
2. ``active(frame)``: a pure predicate — does the effect update and draw at all this frame? It changes nothing.
3. For active effects: ``frame_uniforms(frame)`` (uniforms every program of the frame receives, e.g. the rain
   medium; a function of the frame alone) and ``frame_lights(frame)`` (lights it adds, e.g. a flash), then in
   order ``update(frame, rc)`` (simulation, reading and writing ``rc.shared``), then ``render(stage, rc)`` for
   each stage in ``stages``; ``bind_scene`` before the scene pass draws. Every update runs before the frame's
   first draw, and so does every effect's ``upload`` (writes of what the update made new into buffers and
   textures, no draws): GL work that publishes an update's result with a draw (a pass into a texture) belongs
   in ``prepare``, so no draw leaves the CPU simulations after it with cold caches (llvmpipe runs vertex work on
   the calling thread). Uploads come before the draws because with Mesa's driver thread (``gfx/driver.py``) a
   buffer write of more than 8 KiB or a texture written from memory waits for that thread, and the calling
   thread then runs every call not yet handed over itself: after the shadow pass and the road's reflection that
   was ~28 ms of llvmpipe's vertex work a frame on the main thread; before the first draw there is nothing to
   run. An effect whose ``prepare`` is called without its ``upload`` (a benchmark, a test) uploads there.
   Inactive effects get ``unbind_scene`` so the scene shader sees their neutral values.
4. A frame nobody looks at (``Renderer.render(frame, draw=False)``: a headless run keeps only its last picture)
   runs 1–3 up to the updates, then only the ``state_stages`` (stages whose GL work the next frames build on);
   ``rc.drawn`` is False in its updates, which may skip what serves the picture alone.

Effects never assign renderer attributes; they share data only through ``rc.shared`` (``SharedResources``).
Every effect is built the same way: ``EffectClass(ctx, settings=None, *, seed=0, shaders=None)``.
"""

from __future__ import annotations

import moderngl

from rain_core.gfx.frame import Frame, RenderContext

STAGES = ("upload", "prepare", "transparent", "post", "overlay")
DRAW_STAGES = STAGES[2:]  # the stages the renderer runs after the scene pass, into the HDR target


class Effect:
    """Base class of an effect. Override what you need; the defaults do nothing and cost nothing."""

    name = "effect"
    stages: tuple[str, ...] = ()
    # The stages whose GL work carries the effect's state from one frame to the next (the spray's upload writes
    # only the new parcels into its rings; the windshield's prepare relaxes last frame's film texture). A frame
    # that is not drawn (Renderer.render(frame, draw=False)) runs these after the updates, and no other stage.
    state_stages: tuple[str, ...] = ()

    def observe(self, frame: Frame) -> None:
        """Follow the frame while idle (called for every effect, every frame, before ``active``)."""

    def active(self, frame: Frame) -> bool:
        """Whether this effect runs this frame. Pure: no state changes."""
        return False

    def update(self, frame: Frame, rc: RenderContext) -> None:
        """Advance the effect's simulation for this frame (CPU and/or GPU)."""

    def frame_uniforms(self, frame: Frame) -> dict:
        """Uniforms this effect sets in every program of the frame (before ``update``; active effects only)."""
        return {}

    def frame_lights(self, frame: Frame):
        """Lights this effect adds to the frame (a ``rain_core.lighting.LightSet``, world positions, or None):
        e.g. a lightning flash. Active effects only; they come first in the light list, before the nearest lamps
        and vehicle lights, so distance never culls them."""
        return None

    def render(self, stage: str, rc: RenderContext) -> None:
        """Draw for ``stage`` into ``rc.hdr`` (or offscreen targets for ``prepare``)."""

    def bind_scene(self, program: moderngl.Program, rc: RenderContext) -> None:
        """Set the scene shader's inputs this effect owns (called every frame while active)."""

    def unbind_scene(self, program: moderngl.Program, rc: RenderContext) -> None:
        """Reset those inputs to their neutral values (called when the effect is inactive)."""

    def describe(self) -> str:
        """A short state for the performance table (e.g. the backend a simulation chose)."""
        return ""

    def release(self) -> None:
        """Free every GL object the effect created."""
