#!/usr/bin/env python3
"""Do two builds of glint_core.rasterize give the same buffers, bit for bit? For changes
that should only make the rasterizer faster (docs/rasterizer.md).

Each build runs in its own process (both are called glint_core) over the same scenes:
the benchmark's floor and spheres at 1k, 5k and 50k triangles, random soups (crossing
the near plane, some zero normals, one with normal maps), and a scene of more than one
chunk (72k triangles); at two sizes, 1 and 2 threads, with and without the back layer.
Every output buffer is hashed; the keys whose hashes differ are printed. Usage:

  /usr/bin/python3 bench/raster_identity.py --builds /tmp/old/build,build
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import raster_bench as rb  # noqa: E402


def soup(rng, t, spread=1.0):
    z = -0.2 - 12 * rng.random(t)
    c = np.stack([(rng.random(t) * 2 - 1) * -z * 0.6 * spread, (rng.random(t) * 2 - 1) * -z * 0.4 * spread, z], 1)
    p = c[:, None, :] + rng.normal(size=(t, 3, 3)) * (0.05 + 0.5 * rng.random((t, 1, 1))) * -z[:, None, None]
    n = rng.normal(size=(t, 3, 3))
    n[rng.random(t) < 0.05] = 0
    return p.astype(np.float32), n.astype(np.float32), rng.integers(0, len(rb.MATERIALS), t).astype(np.int32)


def hashes(build):
    sys.path.insert(0, os.path.join(os.path.abspath(build), "python"))
    import glint_core
    rng = np.random.default_rng(3)
    scenes = {f"scene{t}": rb.scene(t) for t in (1000, 5000, 50000)}
    scenes["soup"] = soup(rng, 3000)
    scenes["soup_wide"] = soup(rng, 500, 2.0)
    big, extra = rb.scene(70000), soup(rng, 2000)
    scenes["two_chunks"] = tuple(np.concatenate(x) for x in zip(big, extra))
    t = len(scenes["soup"][0])
    maps = dict(uvs=(rng.random((t, 3, 2)) * 3).astype(np.float32),
                tangents=rng.normal(size=(t, 3, 4)).astype(np.float32),
                material_normal_map=np.array([0, -1, 0, -1, 0], np.int32),
                normal_maps=[rng.random((16, 16, 3)).astype(np.float32)])
    out = {}
    for w, h in ((1920, 1080), (333, 197)):
        proj = rb.perspective(w, h)
        for name, (p, n, m) in scenes.items():
            for threads in (1, 2):
                for back in (False, True):
                    kw = maps if name == "soup" else {}
                    g = glint_core.rasterize(p, n, m, rb.MATERIALS, proj, w, h, back_layer=back,
                                             threads=threads, **kw)
                    for k, v in g.items():
                        out[f"{w}x{h} {name} threads={threads} back={int(back)} {k}"] = \
                            hashlib.sha256(np.ascontiguousarray(v).tobytes()).hexdigest()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--builds", required=True, help="two build directories, comma-separated")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    builds = a.builds.split(",")
    if a.worker:
        print(json.dumps(hashes(builds[0])))
        return
    if len(builds) != 2:
        raise ValueError("--builds: expected two build directories, comma-separated")
    got = [json.loads(subprocess.run([sys.executable, os.path.abspath(__file__), "--worker", "--builds", b],
                                     check=True, capture_output=True, text=True).stdout) for b in builds]
    differ = [k for k in got[0] if got[0][k] != got[1].get(k)] + [k for k in got[1] if k not in got[0]]
    for k in differ:
        print("differs:", k)
    print(f"{len(got[0])} buffers compared, {len(differ)} differ")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
