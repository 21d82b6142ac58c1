"""The per-frame matrix helpers give NumPy's bits."""

import numpy as np
import pytest

from rain_core.gfx.linalg import inverse
from rain_core.gfx.uniforms import mat4_bytes


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
