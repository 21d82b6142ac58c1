import numpy as np
import trimesh

from rain_core.mesh import VERTEX_DTYPE, from_trimesh, vertex_normals


def test_vertex_normals_of_a_sphere_point_outwards():
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    v = np.asarray(sphere.vertices)
    n = vertex_normals(v, np.asarray(sphere.faces))
    exact = v / np.linalg.norm(v, axis=1, keepdims=True)
    assert np.degrees(np.arccos(np.clip((n * exact).sum(axis=1), -1.0, 1.0))).max() < 1.0


def test_from_trimesh_flat_and_smooth():
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    flat = from_trimesh(box, (0.5, 0.5, 0.5))
    assert flat.dtype == VERTEX_DTYPE and len(flat) == 36
    np.testing.assert_allclose(np.linalg.norm(flat["normal"], axis=1), 1.0, atol=1e-6)
    smooth = from_trimesh(trimesh.creation.cylinder(radius=0.3, height=0.2), (0.1, 0.1, 0.1), smooth=True)
    assert np.isfinite(smooth["normal"]).all()
