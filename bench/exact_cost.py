#!/usr/bin/env python3
"""Cost of march="exact" against triangle count, beside the screen-space presets,
measured in one run: a rippled mirror floor under a field of boxes, tessellated
to about N triangles, rasterized to a G-buffer at --size, then traced.

  /usr/bin/python3 bench/exact_cost.py --size 960x540 --triangles 10000,100000,1000000
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.environ.get("GLINT_BUILD_DIR", os.path.join(root, "build")), "python"))
import glint_core  # noqa: E402


def floor_mesh(n_tri: int):
    """A rippled floor of ~n_tri triangles in view space, camera 2 above looking 20 deg down."""
    side = max(2, int(math.sqrt(n_tri / 2)))
    xs = np.linspace(-20.0, 20.0, side + 1)
    zs = np.linspace(-1.0, -60.0, side + 1)
    X, Z = np.meshgrid(xs, zs)
    Y = 0.05 * np.sin(X * 2.0) * np.cos(Z * 1.5)
    world = np.stack([X, Y, Z], -1)
    # Tilt: the camera looks 20 degrees down from 2 units above the floor.
    a = math.radians(20.0)
    rot = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    v = (world - [0.0, 2.0, 0.0]) @ rot.T
    i = np.arange(side)[:, None] * (side + 1) + np.arange(side)[None, :]
    quads = np.stack([i, i + 1, i + side + 2, i + side + 1], -1).reshape(-1, 4)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return v.reshape(-1, 3).astype(np.float32), tris.astype(np.int32)


def boxes(count: int):
    rng = np.random.default_rng(1)
    verts, tris = [], []
    for k in range(count):
        c = rng.uniform([-8, 0.3, -30], [8, 1.5, -4])
        s = rng.uniform(0.2, 0.6, 3)
        corners = np.array([[(c - s)[j] if (m >> j) & 1 == 0 else (c + s)[j] for j in range(3)] for m in range(8)])
        f = np.array([[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                      [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5]]) + 8 * k
        verts.append(corners)
        tris.append(f)
    return np.concatenate(verts).astype(np.float32), np.concatenate(tris).astype(np.int32)


def median_ms(call, repeat):
    call()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        call()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="960x540")
    ap.add_argument("--triangles", default="10000,100000,1000000")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    proj = np.array([[1.0 / math.tan(0.5) / (w / h), 0, 0, 0], [0, 1.0 / math.tan(0.5), 0, 0],
                     [0, 0, -(100.1) / 99.9, -2 * 100 * 0.1 / 99.9], [0, 0, -1, 0]])
    print(f"| triangles | exact ms | balanced ms | seed ms | exact / balanced |  ({w}x{h}, median of {args.repeat})")
    print("|---|---|---|---|---|")
    for n in (int(v) for v in args.triangles.split(",")):
        fv, ft = floor_mesh(n - 12 * 40)
        bv, bt = boxes(40)
        v = np.concatenate([fv, bv])
        t = np.concatenate([ft, bt + len(fv)])
        pos = v[t]
        e1, e2 = pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0]
        nrm = np.cross(e1, e2)
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True) + 1e-30
        normals = np.repeat(nrm[:, None, :], 3, axis=1).astype(np.float32)
        mat = np.zeros(len(t), np.int32)
        mat[len(ft):] = 1
        materials = np.array([[1, 1, 1, 1], [0, 0, 0, 0]], np.float32)
        g = glint_core.rasterize(pos.astype(np.float32), normals, mat, materials, proj.astype(np.float32), w, h)
        P, N = g["position"], g["normal"]
        mesh = (v, t)
        exact = median_ms(lambda: glint_core.trace(P, N, proj, march="exact", mesh=mesh, max_distance=40.0), args.repeat)
        bal = median_ms(lambda: glint_core.trace(P, N, proj, **dict(glint_core.presets()["balanced"], max_distance=40.0)),
                        args.repeat)
        seed = median_ms(lambda: glint_core.trace(P, N, proj, max_distance=40.0), args.repeat)
        print(f"| {len(t):,} | {exact:.0f} | {bal:.0f} | {seed:.0f} | {exact / bal:.2f} |", flush=True)


if __name__ == "__main__":
    main()
