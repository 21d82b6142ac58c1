"""Mesh primitives, vectorised over instances; all emit VERTEX_DTYPE triangle lists."""


from __future__ import annotations

import numpy as np
import trimesh

from rain_core.mesh import (
    MAT_CONCRETE,
    MAT_FOLIAGE,
    MAT_GENERIC,
    VERTEX_DTYPE,
)

# ----------------------------------------------------------------------------------------------------------------
# Mesh primitives (vectorised over instances; all emit VERTEX_DTYPE triangle lists)

NX_, PX_, NY_, PY_, NZ_, PZ_ = range(6)  # box face indices: -x, +x, -y, +y, -z, +z
_ALL_FACES = (0, 1, 2, 3, 4, 5)


def _box_template() -> tuple[np.ndarray, np.ndarray]:
    tris, normals = [], []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, 1):
            quad = np.zeros((4, 3))
            quad[:, axis] = side
            quad[:, u] = (0, 1, 1, 0)
            quad[:, v] = (0, 0, 1, 1)
            if side == 0:  # e_u × e_v = +e_axis; reverse the winding for the −axis face
                quad = quad[::-1]
            tris.append(quad[[0, 1, 2, 0, 2, 3]])
            n = np.zeros(3)
            n[axis] = 1.0 if side else -1.0
            normals.append(n)
    return np.array(tris), np.array(normals)


_BOX_TRIS, _BOX_NORMALS = _box_template()


def _pack(pos: np.ndarray, nrm: np.ndarray, albedo, rough=0.8, metal=0.0, mat=MAT_GENERIC) -> np.ndarray:
    """pos, nrm: (N, k, 3) for N instances of k vertices; albedo (3,) or (N, 3); rough/metal scalar or (N,)."""
    n_inst, k = pos.shape[:2]
    out = np.empty(n_inst * k, dtype=VERTEX_DTYPE)
    out["position"] = pos.reshape(-1, 3)
    out["normal"] = np.broadcast_to(nrm, pos.shape).reshape(-1, 3)
    alb = np.asarray(albedo, dtype=np.float32)
    out["albedo"] = np.repeat(alb, k, axis=0) if alb.ndim == 2 else alb
    params = np.empty((n_inst, 3), dtype=np.float32)
    params[:, 0] = rough
    params[:, 1] = metal
    params[:, 2] = float(mat)
    out["params"] = np.repeat(params, k, axis=0)
    return out


def _box_positions(lo, hi, faces=_ALL_FACES) -> tuple[np.ndarray, np.ndarray]:
    lo = np.atleast_2d(np.asarray(lo, dtype=np.float64))
    hi = np.atleast_2d(np.asarray(hi, dtype=np.float64))
    faces = list(faces)
    t = _BOX_TRIS[faces].reshape(-1, 3)
    pos = lo[:, None, :] + t[None] * (hi - lo)[:, None, :]
    nrm = np.repeat(_BOX_NORMALS[faces], 6, axis=0)[None]
    return pos, nrm


def _boxes(lo, hi, albedo, rough=0.8, metal=0.0, mat=MAT_CONCRETE, faces=_ALL_FACES) -> np.ndarray:
    """Axis-aligned boxes from corners lo, hi (N, 3) m; faces picks which sides to emit."""
    pos, nrm = _box_positions(lo, hi, faces)
    return _pack(pos, nrm, albedo, rough, metal, mat)


def _box_tris(lo, hi) -> np.ndarray:
    """Closed boxes as a triangle soup (N·12, 3, 3) for the occluder mesh."""
    pos, _ = _box_positions(lo, hi)
    return pos.reshape(-1, 3, 3)


def _quads(p0, u, v, albedo, rough=0.8, metal=0.0, mat=MAT_GENERIC) -> np.ndarray:
    """Parallelograms p0, p0+u, p0+u+v, p0+v (N, 3) m, facing u × v."""
    p0, u, v = (np.atleast_2d(np.asarray(a, dtype=np.float64)) for a in (p0, u, v))
    p0, u, v = np.broadcast_arrays(p0, u, v)
    pos = np.stack([p0, p0 + u, p0 + u + v, p0, p0 + u + v, p0 + v], axis=1)
    n = np.cross(u, v)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return _pack(pos, n[:, None, :], albedo, rough, metal, mat)


def _rects_up(x0, x1, z0, z1, y, albedo, rough=0.8, mat=MAT_GENERIC) -> np.ndarray:
    """Up-facing horizontal rectangles [x0, x1] × [z0, z1] at height y (m), arrays of N."""
    x0, x1, z0, z1, y = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=np.float64))
                                              for a in (x0, x1, z0, z1, y)))
    zeros = np.zeros_like(x0)
    p0 = np.stack([x0, y, z0], axis=1)
    u = np.stack([zeros, zeros, z1 - z0], axis=1)
    v = np.stack([x1 - x0, zeros, zeros], axis=1)
    return _quads(p0, u, v, albedo, rough, 0.0, mat)


def _rects_down(x0, x1, z0, z1, y, albedo, rough=0.8, mat=MAT_GENERIC) -> np.ndarray:
    """Down-facing horizontal rectangles (lamp lenses, canopy lights), arrays of N, m."""
    x0, x1, z0, z1, y = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=np.float64))
                                              for a in (x0, x1, z0, z1, y)))
    zeros = np.zeros_like(x0)
    p0 = np.stack([x0, y, z0], axis=1)
    u = np.stack([x1 - x0, zeros, zeros], axis=1)
    v = np.stack([zeros, zeros, z1 - z0], axis=1)
    return _quads(p0, u, v, albedo, rough, 0.0, mat)


def _facade_quads(x, facing, y0, y1, z0, z1, albedo, rough=0.8, mat=MAT_GENERIC) -> np.ndarray:
    """Vertical rectangles in the plane x = const (m) facing ``facing`` = ±1 along x; arrays of N."""
    x, facing, y0, y1, z0, z1 = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=np.float64))
                                                      for a in (x, facing, y0, y1, z0, z1)))
    zeros = np.zeros_like(x)
    p0 = np.stack([x, y0, z0], axis=1)
    along_z = np.stack([zeros, zeros, z1 - z0], axis=1)
    along_y = np.stack([zeros, y1 - y0, zeros], axis=1)
    pos_face = (facing > 0)[:, None]  # +x: e_y × e_z; −x: e_z × e_y
    u = np.where(pos_face, along_y, along_z)
    v = np.where(pos_face, along_z, along_y)
    return _quads(p0, u, v, albedo, rough, 0.0, mat)


def _cylinders(base, radius, height, segments: int, albedo, rough=0.8, metal=0.0, mat=MAT_GENERIC) -> np.ndarray:
    """Vertical capped cylinders (smooth sides) standing on base (N, 3) m; radius, height (N,) m."""
    base = np.atleast_2d(np.asarray(base, dtype=np.float64))
    n = len(base)
    radius = np.broadcast_to(np.asarray(radius, dtype=np.float64), (n,))
    height = np.broadcast_to(np.asarray(height, dtype=np.float64), (n,))
    th = 2 * np.pi * np.arange(segments) / segments
    ring = np.stack([np.cos(th), np.zeros(segments), np.sin(th)], axis=1)
    nxt = np.roll(ring, -1, axis=0)
    zero = np.zeros_like(ring)
    up_n = np.tile((0.0, 1.0, 0.0), (segments, 1))
    # Side: b_k, t_k, t_k1, b_k, t_k1, b_k1 (outward); cap: c, t_k1, t_k (up).
    radial = np.stack([ring, ring, nxt, ring, nxt, nxt, zero, nxt, ring], axis=1).reshape(-1, 3)
    up = np.tile(np.array([0, 1, 1, 0, 1, 0, 1, 1, 1], dtype=np.float64), segments)
    normals = np.stack([ring, ring, nxt, ring, nxt, nxt, up_n, up_n, up_n], axis=1).reshape(-1, 3)
    pos = (base[:, None, :] + radial[None] * radius[:, None, None]
           + (up[None, :, None] * height[:, None, None]) * np.array([0.0, 1.0, 0.0]))
    return _pack(pos, normals[None], albedo, rough, metal, mat)


def _blobs(centre, radii, template: trimesh.Trimesh, jitter: np.ndarray, albedo, rough=0.9,
           mat=MAT_FOLIAGE) -> np.ndarray:
    """Lumpy ellipsoids: the unit template scaled by radii (N, 3) m with per-vertex radial jitter (N, nv)."""
    verts = np.asarray(template.vertices)
    faces = np.asarray(template.faces)
    pts = centre[:, None, :] + verts[None] * radii[:, None, :] * (1.0 + jitter[:, :, None])
    tri = pts[:, faces]  # (N, nf, 3, 3)
    fn = np.cross(tri[:, :, 1] - tri[:, :, 0], tri[:, :, 2] - tri[:, :, 0])
    incidence = np.zeros((len(verts), len(faces)))
    incidence[faces.ravel(), np.repeat(np.arange(len(faces)), 3)] = 1.0
    vn = np.einsum("vf,nfc->nvc", incidence, fn)
    vn /= np.linalg.norm(vn, axis=2, keepdims=True)
    return _pack(tri.reshape(len(centre), -1, 3), vn[:, faces].reshape(len(centre), -1, 3), albedo, rough, 0.0,
                 mat)


def _span(side: float, d0, d1) -> tuple[np.ndarray, np.ndarray]:
    """x interval (lo, hi) for the distances d0..d1 from the centre line on side ±1."""
    a = side * np.asarray(d0, dtype=np.float64)
    b = side * np.asarray(d1, dtype=np.float64)
    return np.minimum(a, b), np.maximum(a, b)


def _in_zones(z0, z1, zones) -> np.ndarray:
    z0 = np.asarray(z0, dtype=np.float64)
    z1 = np.asarray(z1, dtype=np.float64)
    hit = np.zeros(np.broadcast(z0, z1).shape, dtype=bool)
    for a, b in zones:
        hit |= (z1 > a) & (z0 < b)
    return hit

