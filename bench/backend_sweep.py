#!/usr/bin/env python3
"""CPU against GL for the rasterizer (with the back layer) and the trace, per frame size
and triangle count: the measurements behind Auto's rule (docs/addon.md, "Which backend
Auto picks"; addon/glint/logic/settings.auto_backend).

The scene is a floor of 128 triangles under a UV sphere of 2 * seg * 2 seg triangles,
in view space; the trace runs with the core's balanced preset. Each round runs both
backends (their order alternating); the medians over --repeat rounds are printed, after
one warm-up round (it makes the GL context). Usage, from a checkout after building:

  /usr/bin/python3 bench/backend_sweep.py --sizes 320x240,960x540,1920x1080 --segments 2,32,100 --repeat 3
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.environ.get("GLINT_BUILD_DIR", os.path.join(ROOT, "build")), "python"))

import glint_core  # noqa: E402


def floor(n=8, y=-1.0, x=(-10.0, 10.0), z=(-2.0, -20.0), mat=1):
    xs, zs = np.linspace(*x, n + 1), np.linspace(*z, n + 1)
    tris = []
    for i in range(n):
        for j in range(n):
            a, b = (xs[i], y, zs[j]), (xs[i + 1], y, zs[j])
            c, d = (xs[i + 1], y, zs[j + 1]), (xs[i], y, zs[j + 1])
            tris += [(a, c, b), (a, d, c)]
    p = np.array(tris, np.float32)
    n_ = np.zeros_like(p)
    n_[..., 1] = 1.0
    return p, n_, np.full(len(p), mat, np.int32)


def sphere(seg, centre=(0.0, 0.0, -6.0), r=1.0, mat=2):
    th, ph = np.linspace(0, np.pi, seg + 1), np.linspace(0, 2 * np.pi, 2 * seg + 1)
    c = np.array(centre)

    def at(t, f):
        return c + r * np.array([np.sin(t) * np.cos(f), np.cos(t), np.sin(t) * np.sin(f)])
    tris = []
    for i in range(seg):
        for j in range(2 * seg):
            a, b, cc, d = at(th[i], ph[j]), at(th[i + 1], ph[j]), at(th[i + 1], ph[j + 1]), at(th[i], ph[j + 1])
            tris += [(a, b, cc), (a, cc, d)]
    p = np.array(tris, np.float32)
    return p, ((p - c) / r).astype(np.float32), np.full(len(p), mat, np.int32)


def perspective(w, h, fov=np.radians(50.0), near=0.1, far=100.0):
    t = 1.0 / np.tan(fov / 2)
    return np.array([[t * h / w, 0, 0, 0], [0, t, 0, 0],
                     [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]], np.float32)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="320x240,960x540,1920x1080")
    ap.add_argument("--segments", default="2,32,100", help="sphere segments (triangles = 4 seg^2 + 128)")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    sizes = [tuple(int(v) for v in s.lower().split("x")) for s in a.sizes.split(",")]
    materials = np.array([[0, 0, 0, 0], [0.5, 0.5, 0.5, 127.75], [0, 0, 0, 0]], np.float32)
    kw = dict(glint_core.presets()["balanced"])
    for w, h in sizes:
        for seg in (int(s) for s in a.segments.split(",")):
            p, n, m = (np.concatenate(x) for x in zip(floor(), sphere(seg)))
            proj = perspective(w, h)
            res = {"cpu": [], "gl": []}
            for r in range(a.repeat + 1):
                for be in (("cpu", "gl") if r % 2 else ("gl", "cpu")):
                    t0 = time.perf_counter()
                    g = glint_core.rasterize(p, n, m, materials, proj, w, h, back_layer=True, backend=be)
                    t1 = time.perf_counter()
                    glint_core.trace(g["position"], g["normal"], proj, backend=be,
                                     back_position=g["back_position"], **kw)
                    t2 = time.perf_counter()
                    if r:
                        res[be].append((t1 - t0, t2 - t1))
            cols = [f"{be}: raster {statistics.median(x[0] for x in v) * 1e3:7.1f} ms, "
                    f"trace {statistics.median(x[1] for x in v) * 1e3:7.1f} ms" for be, v in res.items()]
            print(f"{w}x{h} {len(p):7d} triangles  " + "  |  ".join(cols), flush=True)


if __name__ == "__main__":
    main()
