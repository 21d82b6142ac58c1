"""One vertex format for every lit mesh, and the conversion from trimesh.

Meshes are flat lists of triangles (no index buffer) with per-vertex PBR attributes, so the world, the cars and the
cabin all draw with one shader (``shaders/scene.vert`` / ``scene.frag``).
"""

from __future__ import annotations

import numpy as np

# Material ids tell effects how a surface reacts to water (e.g. porous asphalt darkens a lot when wet, paint and
# metal little, glass not at all). Keep in sync with shaders/common/materials.glsl.
MAT_GENERIC = 0
MAT_ASPHALT = 1
MAT_PAINT = 2  # lane markings
MAT_CONCRETE = 3  # kerbs, sidewalks, building walls
MAT_METAL = 4
MAT_GLASS = 5
MAT_FOLIAGE = 6
MAT_EMISSIVE = 7  # lamp heads, light lenses: albedo is emitted radiance W/(sr·m²); ×683 lm/W = luminance cd/m²
MAT_CAR_PAINT = 8
MAT_RUBBER = 9

VERTEX_DTYPE = np.dtype(
    [
        ("position", np.float32, 3),  # m
        ("normal", np.float32, 3),
        ("albedo", np.float32, 3),  # linear RGB
        ("params", np.float32, 3),  # roughness [0,1], metallic [0,1], material id (float-coded int)
    ]
)
VERTEX_FORMAT = "3f 3f 3f 3f"
VERTEX_ATTRIBUTES = ("in_position", "in_normal", "in_albedo", "in_params")


def from_trimesh(mesh, albedo, roughness: float = 0.8, metallic: float = 0.0, material: int = MAT_GENERIC,
                 smooth: bool = False) -> np.ndarray:
    """Flatten a trimesh.Trimesh into VERTEX_DTYPE triangles.

    albedo: linear RGB (3,) for the whole mesh, or (n_faces, 3) per face. smooth=True uses vertex normals
    (for round things: trunks, foliage, wheels); otherwise face normals (hard edges: buildings, kerbs).
    """
    faces = np.asarray(mesh.faces)
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    out = np.zeros(len(faces) * 3, dtype=VERTEX_DTYPE)
    out["position"] = verts[faces].reshape(-1, 3)
    if smooth:
        out["normal"] = vertex_normals(verts, faces)[faces].reshape(-1, 3)
    else:
        out["normal"] = np.repeat(np.asarray(mesh.face_normals), 3, axis=0)
    albedo = np.asarray(albedo, dtype=np.float32)
    out["albedo"] = np.repeat(albedo, 3, axis=0) if albedo.ndim == 2 else albedo
    out["params"] = (roughness, metallic, float(material))
    return out


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals (unit). NumPy only: trimesh's own needs scipy, which we do not depend on
    (without it trimesh logs a traceback per mesh and falls back to a slow loop)."""
    tri = vertices[faces]
    face_n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])  # length = 2 × area
    acc = np.zeros_like(vertices, dtype=np.float64)
    for k in range(3):
        np.add.at(acc, faces[:, k], face_n)
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    return np.where(length > 0, acc / np.maximum(length, 1e-300), np.array([0.0, 1.0, 0.0]))


def concat(parts) -> np.ndarray:
    """Join vertex arrays (empty input gives an empty array of the right dtype)."""
    parts = [p for p in parts if len(p)]
    return np.concatenate(parts) if parts else np.zeros(0, dtype=VERTEX_DTYPE)


def transform(vertices: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4×4 rigid (rotation + translation) transform to positions and normals; returns a copy."""
    out = vertices.copy()
    m = np.asarray(matrix, dtype=np.float64)
    out["position"] = vertices["position"] @ m[:3, :3].T + m[:3, 3]
    out["normal"] = vertices["normal"] @ m[:3, :3].T
    return out
