#!/usr/bin/env python3
"""glint_core.rasterize at one frame size: ms per call (medians), CPU and GL, with and
without the back layer, for a few triangle counts; optionally two builds side by side.

The scene is the kind the add-on exports: a floor (a 16 x 16 grid) under closed UV
spheres (so the back layer has far sides to find), scaled to about --triangles in all.
Timed is the whole Python call, binding copies included, since that is what a frame pays.

Every round runs each build in a fresh process (so two builds of glint_core, which share
the name, can be compared in one run: rounds alternate between them, and each process
warms up once, which makes the GL context, before it times). Usage, from a checkout:

  /usr/bin/python3 bench/raster_bench.py --size 1920x1080 --triangles 1000,5000,50000 \
      --rounds 3 --repeat 3 [--builds build,/tmp/old/build]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

from scene_meshes import floor, perspective, sphere  # bench/, beside this script

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def scene(triangles):
    """The floor and four spheres, ~`triangles` in all (4 spheres of 4 seg^2 each)."""
    seg = max(2, round(np.sqrt(max(0, triangles - 512) / 16)))
    parts = [floor(n=16, mat=0)] + [sphere(seg, c, r, k + 1) for k, (c, r) in enumerate(
        [((-2.5, 0.0, -7.0), 1.0), ((0.0, 0.2, -9.0), 1.2), ((2.5, -0.2, -6.0), 0.8), ((0.8, 1.5, -12.0), 1.5)])]
    return tuple(np.concatenate(x) for x in zip(*parts))


MATERIALS = np.array([[0.5, 0.5, 0.5, 127.75], [0.9, 0.1, 0.1, 40.0], [0.1, 0.9, 0.1, 60.0],
                      [0.1, 0.1, 0.9, 80.0], [0.9, 0.9, 0.1, 100.0]], np.float32)


def worker(build, w, h, counts, backends, repeat):
    """One process, one build: {"<tris> <backend> <back>": [(wall ms, cpu ms), ...]}.

    cpu ms is the process's CPU time over all its threads (GL's llvmpipe threads too):
    on a shared machine it moves less than the wall time does."""
    sys.path.insert(0, os.path.join(os.path.abspath(build), "python"))
    import glint_core
    proj = perspective(w, h)
    out = {}
    for want in counts:
        p, n, m = scene(want)
        for be in backends:
            for back in (False, True):
                call = lambda: glint_core.rasterize(p, n, m, MATERIALS, proj, w, h, back_layer=back, backend=be)  # noqa: E731
                call()  # warm-up: the GL context, first-touch of the allocator's pages
                times = []
                for _ in range(repeat):
                    t0, c0 = time.perf_counter(), time.process_time()
                    call()
                    times.append(((time.perf_counter() - t0) * 1e3, (time.process_time() - c0) * 1e3))
                out[f"{len(p)} {be} {int(back)}"] = times
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--triangles", default="1000,5000,50000")
    ap.add_argument("--backends", default="cpu,gl")
    ap.add_argument("--rounds", type=int, default=3, help="processes per build, alternating builds")
    ap.add_argument("--repeat", type=int, default=3, help="timed calls per configuration and process")
    ap.add_argument("--builds", default=os.environ.get("GLINT_BUILD_DIR", os.path.join(ROOT, "build")),
                    help="comma-separated build directories (each with python/glint_core*.so)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.lower().split("x"))
    counts = [int(c) for c in a.triangles.split(",")]
    backends = a.backends.split(",")
    builds = a.builds.split(",")
    if a.worker:
        print(json.dumps(worker(builds[0], w, h, counts, backends, a.repeat)))
        return
    results = {b: {} for b in builds}
    for r in range(a.rounds):
        for b in (builds if r % 2 == 0 else builds[::-1]):
            cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--builds", b, "--size", a.size,
                   "--triangles", a.triangles, "--backends", a.backends, "--repeat", str(a.repeat)]
            got = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
            for k, v in got.items():
                results[b].setdefault(k, []).extend(v)
    keys = list(results[builds[0]])
    print(f"rasterize at {w}x{h}: median wall ms (cpu ms, all threads) of {a.rounds} x {a.repeat} calls per cell")
    for i, b in enumerate(builds):
        print(f"  build {i}: {b}")
    print(f"{'triangles':>9} {'backend':>7} {'back':>4} " + " ".join(f"{'build ' + str(i):>17}" for i in range(len(builds)))
          + ("  wall ratio 1/0" if len(builds) == 2 else ""))
    for k in keys:
        tris, be, back = k.split()
        meds = [(statistics.median(t[0] for t in results[b][k]), statistics.median(t[1] for t in results[b][k]))
                for b in builds]
        line = f"{tris:>9} {be:>7} {'yes' if back == '1' else 'no':>4} " + " ".join(
            f"{wall:8.1f} ({cpu:6.1f})" for wall, cpu in meds)
        if len(builds) == 2:
            line += f"  {meds[1][0] / meds[0][0]:15.2f}"
        print(line, flush=True)


if __name__ == "__main__":
    main()
