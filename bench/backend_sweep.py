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

from scene_meshes import floor, perspective, sphere  # bench/, beside this script

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.environ.get("GLINT_BUILD_DIR", os.path.join(ROOT, "build")), "python"))

import glint_core  # noqa: E402


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
