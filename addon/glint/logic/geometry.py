"""Mesh arrays -> the rasterizer's view-space triangle soup.

Blender hands out flat arrays (vertex coordinates, loop triangles, corner
normals, UVs, tangents) through ``foreach_get``; these functions turn one mesh
instance into triangles in view space and concatenate instances. Everything is
vectorised: a million triangles is a handful of numpy operations.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional, Sequence

import numpy as np

from .projection import normal_matrix


@dataclass
class MeshArrays:
    """One mesh in its own (object) space, as gathered from Blender."""

    co: np.ndarray  # [V, 3] vertex positions
    tri_verts: np.ndarray  # [T, 3] vertex index per triangle corner
    tri_loops: np.ndarray  # [T, 3] loop (face corner) index per triangle corner
    tri_material: np.ndarray  # [T] material slot index
    corner_normals: np.ndarray  # [L, 3] one normal per loop
    corner_uvs: Optional[np.ndarray] = None  # [L, 2]
    corner_tangents: Optional[np.ndarray] = None  # [L, 4]: xyz + bitangent sign

    @property
    def triangle_count(self) -> int:
        return int(self.tri_verts.shape[0])


@dataclass
class Triangles:
    """The rasterizer's input (view space), float32 / int32 as the core wants."""

    positions: np.ndarray  # [T, 3, 3]
    normals: np.ndarray  # [T, 3, 3]
    material_index: np.ndarray  # [T]
    uvs: Optional[np.ndarray] = None  # [T, 3, 2]
    tangents: Optional[np.ndarray] = None  # [T, 3, 4]

    @property
    def count(self) -> int:
        return int(self.material_index.shape[0])


def _unit(v: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0)


def slot_table(slot_globals: Sequence[int], default: int) -> np.ndarray:
    """Material slot -> global material index. Faces whose index passes the last
    slot use the last slot, as Blender's renderers do; no slots -> ``default``."""
    if len(slot_globals) == 0:
        return np.array([default], dtype=np.int32)
    return np.asarray(slot_globals, dtype=np.int32)


def mesh_to_view(mesh: MeshArrays, view_from_local, slot_globals: Sequence[int], default_material: int,
                 with_uv_tangents: bool = False) -> Triangles:
    """One instance of ``mesh`` placed by ``view_from_local`` (4x4: view @ object-to-world)."""
    m = np.asarray(view_from_local, dtype=np.float64)
    tv = np.asarray(mesh.tri_verts, dtype=np.int64).reshape(-1, 3)
    tl = np.asarray(mesh.tri_loops, dtype=np.int64).reshape(-1, 3)
    co = np.asarray(mesh.co, dtype=np.float64).reshape(-1, 3)
    view_co = co @ m[:3, :3].T + m[:3, 3]
    positions = view_co[tv]
    nm = normal_matrix(m)
    cn = np.asarray(mesh.corner_normals, dtype=np.float64).reshape(-1, 3)
    normals = _unit(cn[tl] @ nm.T)
    table = slot_table(slot_globals, default_material)
    slots = np.clip(np.asarray(mesh.tri_material, dtype=np.int64).reshape(-1), 0, len(table) - 1)
    material = table[slots]
    uvs = tangents = None
    if with_uv_tangents and mesh.corner_uvs is not None:
        uvs = np.asarray(mesh.corner_uvs, dtype=np.float32).reshape(-1, 2)[tl]
        if mesh.corner_tangents is not None:
            t = np.asarray(mesh.corner_tangents, dtype=np.float64).reshape(-1, 4)[tl]
            # Tangents are directions on the surface: they go through the
            # linear part, not the inverse transpose.
            txyz = _unit(t[..., :3] @ m[:3, :3].T)
            # A mirroring transform flips the bitangent's handedness.
            sign = t[..., 3:4] * (1.0 if np.linalg.det(m[:3, :3]) >= 0 else -1.0)
            tangents = np.concatenate([txyz, sign], axis=-1).astype(np.float32)
    return Triangles(positions.astype(np.float32), normals.astype(np.float32), material.astype(np.int32),
                     uvs, tangents)


def concatenate(parts: List[Triangles]) -> Triangles:
    """All instances in one soup. UVs/tangents are kept when any part has them
    (zeros elsewhere: those triangles' materials have no normal map)."""
    if not parts:
        return Triangles(np.zeros((0, 3, 3), np.float32), np.zeros((0, 3, 3), np.float32),
                         np.zeros((0,), np.int32))
    positions = np.concatenate([p.positions for p in parts])
    normals = np.concatenate([p.normals for p in parts])
    material = np.concatenate([p.material_index for p in parts])
    uvs = tangents = None
    if any(p.uvs is not None for p in parts):
        uvs = np.concatenate([p.uvs if p.uvs is not None else np.zeros((p.count, 3, 2), np.float32)
                              for p in parts])
        tangents = np.concatenate([p.tangents if p.tangents is not None
                                   else np.zeros((p.count, 3, 4), np.float32) for p in parts])
    return Triangles(positions, normals, material, uvs, tangents)


def normal_map_with_strength(pixels: np.ndarray, strength: float) -> np.ndarray:
    """A tangent-space normal map (rgb = n * 0.5 + 0.5) with Blender's Normal Map
    strength baked in: the normal is mixed from (0, 0, 1) by ``strength`` and
    renormalised, which is what the Normal Map node does with its Strength."""
    px = np.asarray(pixels, dtype=np.float32)
    if px.ndim != 3 or px.shape[2] < 3:
        raise ValueError(f"normal map: expected [h, w, 3 or 4], got shape {px.shape}")
    if strength == 1.0:
        return np.ascontiguousarray(px[..., :3])
    n = px[..., :3].astype(np.float64) * 2.0 - 1.0
    flat = np.array([0.0, 0.0, 1.0])
    n = flat + (n - flat) * float(strength)
    n = _unit(n)
    n[np.linalg.norm(n, axis=-1) == 0] = flat
    return (n * 0.5 + 0.5).astype(np.float32)


def corner_triangles(corners: int) -> np.ndarray:
    """int32 [corners / 3, 3]: each triangle its own three corners (0 1 2, 3 4 5, ...),
    the index buffer of the export's unshared corners."""
    return np.arange(corners, dtype=np.int32).reshape(-1, 3)


def trace_mesh(triangles: Triangles):
    """``mesh=(vertices [3T, 3], triangles [T, 3])`` for marches that trace the scene's
    own triangles (the exact march): the export's corners, unshared."""
    vertices = np.ascontiguousarray(triangles.positions.reshape(-1, 3), dtype=np.float32)
    return vertices, corner_triangles(vertices.shape[0])


def world_vertices(triangles: Triangles, view_to_world) -> np.ndarray:
    """The export's corners (view space) carried into world space, float32 [3T, 3]:
    the frame the exact march's BVH is kept in between frames, where a camera
    move changes nothing (glint_core.ExactScene)."""
    m = np.asarray(view_to_world, dtype=np.float64)
    co = triangles.positions.reshape(-1, 3).astype(np.float64)
    return np.ascontiguousarray(co @ m[:3, :3].T + m[:3, 3], dtype=np.float32)
