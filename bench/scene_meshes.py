"""Triangle soups for the Python benches that call glint_core.rasterize directly
(bench/raster_bench.py, bench/backend_sweep.py): a floor of quads, UV spheres,
and Blender's perspective projection. numpy only, so a bench can import it
before it chooses which build of glint_core to load."""
from __future__ import annotations

import numpy as np


def floor(n=8, y=-1.0, x=(-10.0, 10.0), z=(-2.0, -20.0), mat=1):
    """An n x n grid of quads at height y, facing +y: (positions, normals, materials)."""
    xs, zs = np.linspace(*x, n + 1), np.linspace(*z, n + 1)
    tris = []
    for i in range(n):
        for j in range(n):
            a, b = (xs[i], y, zs[j]), (xs[i + 1], y, zs[j])
            c, d = (xs[i + 1], y, zs[j + 1]), (xs[i], y, zs[j + 1])
            tris += [(a, c, b), (a, d, c)]
    p = np.array(tris, np.float32)
    nrm = np.zeros_like(p)
    nrm[..., 1] = 1.0
    return p, nrm, np.full(len(p), mat, np.int32)


def sphere(seg, centre=(0.0, 0.0, -6.0), r=1.0, mat=2):
    """A UV sphere of 4 seg^2 triangles with exact vertex normals."""
    th, ph = np.linspace(0, np.pi, seg + 1), np.linspace(0, 2 * np.pi, 2 * seg + 1)
    t0, t1 = th[:-1, None], th[1:, None]
    f0, f1 = ph[None, :-1], ph[None, 1:]

    def at(t, f):
        d = np.stack(np.broadcast_arrays(np.sin(t) * np.cos(f), np.cos(t) + 0 * f, np.sin(t) * np.sin(f)), -1)
        return d.reshape(-1, 3)
    a, b, c, d = at(t0, f0), at(t1, f0), at(t1, f1), at(t0, f1)
    dirs = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    p = (np.asarray(centre) + r * dirs).astype(np.float32)
    return p, dirs.astype(np.float32), np.full(len(p), mat, np.int32)


# A box's 12 triangles over its corners, corner m taking hi on axis j where bit j of m is set.
BOX_FACES = np.array([[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                      [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5]])


def box(lo, hi):
    """An axis-aligned box from corner lo to corner hi: (corners [8, 3], triangles [12, 3])."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array([[hi[j] if (m >> j) & 1 else lo[j] for j in range(3)] for m in range(8)])
    return corners, BOX_FACES.copy()


def perspective(w, h, fov=np.radians(50.0), near=0.1, far=100.0):
    """Blender's OpenGL perspective projection for a w x h frame (sensor fit AUTO, w >= h)."""
    t = 1.0 / np.tan(fov / 2)
    return np.array([[t * h / w, 0, 0, 0], [0, t, 0, 0],
                     [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]], np.float32)
