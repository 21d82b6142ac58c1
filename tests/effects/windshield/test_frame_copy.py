"""The windshield's copy of the frame (``WindshieldEffect._copy_frame``): drawn, not blitted (a blit through
moderngl reads GL state back and makes the main thread wait for Mesa's driver thread), and the same texels: the
colour exactly, the depth to a step of its 24 bits."""

from types import SimpleNamespace

import numpy as np

from rain_core.effects.windshield import WindshieldEffect
from rain_core.gfx.targets import float_target


def test_the_frame_copy_is_the_frame_texel_for_texel(gl_ctx, shaders):
    effect = WindshieldEffect(gl_ctx, seed=1, shaders=shaders)
    size = (37, 21)  # odd sizes: a texel off anywhere would show
    frame = float_target(gl_ctx, size, 4, "f2", depth=True)
    rng = np.random.default_rng(5)
    color = rng.uniform(-4.0, 6e4, (size[1], size[0], 4)).astype(np.float16)
    depth = rng.uniform(0.0, 1.0, (size[1], size[0])).astype(np.float32)
    frame.color.write(color.tobytes())
    frame.depth.write(depth.tobytes())
    stored = np.frombuffer(frame.depth.read(), np.float32).reshape(depth.shape)  # as the 24-bit buffer keeps it
    try:
        copy = effect._copy_frame(SimpleNamespace(size=size, hdr=frame))
        got_color = np.frombuffer(copy.color.read(), np.float16).reshape(color.shape)
        got_depth = np.frombuffer(copy.depth.read(), np.float32).reshape(depth.shape)
        assert copy.color.size == size
        np.testing.assert_array_equal(got_color, color)
        assert np.abs(got_depth - stored).max() <= 1.0 / (1 << 24)
        assert np.abs(got_depth - depth).max() < 1e-6  # (and so the depth written, to the buffer's precision)
    finally:
        frame.release()
        effect.release()
