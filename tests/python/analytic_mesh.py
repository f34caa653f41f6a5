"""Triangles of an analytic scene (tests/python/analytic.py), in view space for the
exact march's ``mesh=(vertices, triangles)``, or in world space for an ExactScene.

Planes and boxes are exact as triangles; a plane becomes a square of side
``2 * plane_extent`` around its point, and a sphere a UV sphere whose facets lie
inside the true sphere by at most r * (1 - cos(pi / segments)).
"""
from __future__ import annotations

import math

import numpy as np

import analytic


def _plane(obj: analytic.Plane, extent: float):
    n = np.asarray(obj.normal, float)
    n /= np.linalg.norm(n)
    a = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(n, a)
    p = np.asarray(obj.point, float)
    v = np.array([p - a * extent - b * extent, p + a * extent - b * extent,
                  p + a * extent + b * extent, p - a * extent + b * extent])
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def _box(obj: analytic.Box):
    lo, hi = np.asarray(obj.lo, float), np.asarray(obj.hi, float)
    v = np.array([[(lo, hi)[(k >> i) & 1][i] for i in range(3)] for k in range(8)])
    quads = [(0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5)]
    f = [(q[0], q[1], q[2]) for q in quads] + [(q[0], q[2], q[3]) for q in quads]
    return v, np.array(f)


def _sphere(obj: analytic.Sphere, segments: int):
    rings = max(segments // 2, 2)
    c = np.asarray(obj.center, float)
    verts = [c + [0.0, 0.0, obj.radius], c - [0.0, 0.0, obj.radius]]
    for i in range(1, rings):
        th = math.pi * i / rings
        for j in range(segments):
            ph = 2.0 * math.pi * j / segments
            verts.append(c + obj.radius * np.array([math.sin(th) * math.cos(ph),
                                                    math.sin(th) * math.sin(ph), math.cos(th)]))
    ring = lambda i, j: 2 + (i - 1) * segments + j % segments  # noqa: E731
    f = []
    for j in range(segments):
        f.append((0, ring(1, j), ring(1, j + 1)))
        f.append((1, ring(rings - 1, j + 1), ring(rings - 1, j)))
        for i in range(1, rings - 1):
            f.append((ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)))
            f.append((ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)))
    return np.array(verts), np.array(f)


def scene_mesh(scene: analytic.Scene, *, plane_extent: float = 500.0, segments: int = 96, world: bool = False):
    """(vertices float32 [N, 3] in view space, or world space with ``world``, triangles int32 [M, 3])."""
    verts, tris, base = [], [], 0
    for obj in scene.objects:
        if isinstance(obj, analytic.Plane):
            v, f = _plane(obj, plane_extent)
        elif isinstance(obj, analytic.Box):
            v, f = _box(obj)
        elif isinstance(obj, analytic.Sphere):
            v, f = _sphere(obj, segments)
        else:
            raise TypeError(f"no triangles for {type(obj).__name__}")
        verts.append(v)
        tris.append(f + base)
        base += len(v)
    pts = np.concatenate(verts)
    if not world:
        (pts,) = analytic._to_view(scene.camera.view_matrix(), pts=pts)
    return pts.astype(np.float32), np.concatenate(tris).astype(np.int32)


def view_to_world(camera: analytic.Camera) -> np.ndarray:
    """The camera's matrix from view space into world space (Blender's camera.matrix_world)."""
    return np.linalg.inv(camera.view_matrix())
