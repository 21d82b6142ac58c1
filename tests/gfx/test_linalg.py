"""The per-frame matrix helpers give NumPy's bits."""

import numpy as np
import pytest

from rain_core.camera import Camera
from rain_core.effects.road.mirror import MIRROR_Y
from rain_core.gfx.frame import inverse_view_proj
from rain_core.gfx.linalg import inverse
from rain_core.gfx.uniforms import mat4_bytes, rows_bytes


@pytest.mark.parametrize("seed", range(20))
def test_inverse_is_numpys_inverse_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(4, 4)) * 10.0 ** rng.uniform(-3, 3)
    assert np.array_equal(inverse(a), np.linalg.inv(a))
    view_like = np.eye(4)
    view_like[:3, 3] = rng.normal(size=3) * 100.0
    assert np.array_equal(inverse(view_like), np.linalg.inv(view_like))


def test_inverse_of_a_singular_matrix_raises_like_numpy():
    with pytest.raises(np.linalg.LinAlgError), np.errstate(invalid="ignore"):
        inverse(np.zeros((4, 4)))
    assert np.array_equal(inverse([[2.0, 0.0], [0.0, 4.0]]), np.linalg.inv([[2.0, 0.0], [0.0, 4.0]]))  # a list


@pytest.mark.parametrize("seed", range(10))
def test_mat4_bytes_is_the_contiguous_float32_transpose(seed):
    rng = np.random.default_rng(seed)
    for m in (rng.normal(size=(4, 4)) * 1e3, rng.normal(size=(3, 3)), rng.normal(size=(4, 4)).astype(np.float32),
              rng.normal(size=(4, 4)).T, rng.normal(size=(4, 4)).tolist(), rng.normal(size=(8, 8))[::2, ::2]):
        expected = np.ascontiguousarray(np.asarray(m, dtype=np.float32).T).tobytes()
        assert mat4_bytes(m) == expected


def test_mat4_bytes_of_special_values_is_numpys():
    """The struct path (float 4×4) casts as NumPy does: signed zeros, NaN, infinities, subnormals, and values
    beyond float32 (struct refuses them: NumPy's path makes them inf)."""
    rng = np.random.default_rng(7)
    specials = np.array([0.0, -0.0, np.nan, np.inf, -np.inf, 1e-45, 7e-46, 3.4028235e38, 3.4028236e38, 1e39, -1e300])
    for _ in range(200):
        m = rng.normal(size=(4, 4))
        m[rng.random((4, 4)) < 0.4] = rng.choice(specials)
        with np.errstate(over="ignore", invalid="ignore"):  # NumPy warns where a value overflows float32
            for a in (m, m.astype(np.float32)):
                expected = np.ascontiguousarray(np.asarray(a, dtype=np.float32).T).tobytes()
                assert mat4_bytes(a) == expected
                assert rows_bytes(a.tolist()) == expected


def _camera_matrices(rng, level: bool):
    fwd = rng.normal(size=3)
    if level:
        fwd[1] = 0.0  # the driver's camera at pitch 0: zeros in the matrices
    camera = Camera(position=rng.normal(size=3) * rng.uniform(0.1, 100.0), forward=fwd,
                    fov_y_deg=rng.uniform(20.0, 90.0))
    view = camera.view_matrix(shift=(0.0, 0.0, float(rng.choice([0.0, 300.0, -600.0]))))
    return view, camera.projection_matrix(float(rng.uniform(0.5, 3.0)))


@pytest.mark.parametrize("level", [True, False])
def test_inverse_view_proj_of_the_road_mirror_view_is_lapacks(level):
    """The main view and the road's mirror view (view @ MIRROR_Y, as Renderer.draw_mirror_view makes it), in
    either order: the second inverse, made from the first, has LAPACK's bits (signed zeros included)."""
    rng = np.random.default_rng(11 if level else 12)
    for _ in range(500):
        view, projection = _camera_matrices(rng, level)
        main, mirror = projection @ view, projection @ (view @ MIRROR_Y)
        for first, second in ((main, mirror), (mirror, main)):
            assert inverse_view_proj(first).tobytes() == inverse(first).tobytes()
            derived = inverse_view_proj(second)
            assert derived.tobytes() == inverse(second).tobytes()
            assert not derived.flags.writeable


def test_inverse_view_proj_takes_no_shortcut_for_other_matrices():
    """Only an exact mirror image of the last matrix reuses its inverse: one ulp off, another view, or the same
    matrix again (not a mirror of itself) is inverted afresh."""
    rng = np.random.default_rng(5)
    view, projection = _camera_matrices(rng, False)
    main = projection @ view
    mirror = projection @ (view @ MIRROR_Y)
    off = mirror.copy()
    off[0, 0] = np.nextafter(off[0, 0], np.inf)
    other = projection @ _camera_matrices(rng, False)[0]
    for a, b in ((main, off), (main, other), (main, main), (other, mirror)):
        inverse_view_proj(a)
        assert inverse_view_proj(b).tobytes() == inverse(b).tobytes()
