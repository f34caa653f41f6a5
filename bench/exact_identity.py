#!/usr/bin/env python3
"""march="exact"'s outputs, saved from one build and compared pixel by pixel with another's.

For speed work on the exact march, whose answers should not move: every analytic scene
of bench/sweep.py at 320x240 and 640x360 with antialias 0 and 4 (the mesh as arrays, a
BVH per call), and exact_cost.py's bench floor at 100k and 1M triangles, once as a kept
world-space ExactScene (antialias 4) and once as view-space arrays. The check prints each
output that differs, with its count of pixels, and exits 1 if any does.

  /usr/bin/python3 bench/exact_identity.py OLD_BUILD/python save  OUT.npz
  /usr/bin/python3 bench/exact_identity.py NEW_BUILD/python check OUT.npz
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, sys.argv[1])
sys.path.insert(0, HERE)
import glint_core as core  # noqa: E402
import exact_cost  # noqa: E402
import sweep  # noqa: E402


def outputs() -> dict:
    out = {}
    for name in sweep._analytic_scenes():
        for w, h in ((320, 240), (640, 360)):
            f = sweep.analytic_frame(name, w, h)
            mesh = (f["vertices"], f["triangles"])
            for aa in (0, 4):
                out[f"{name}_{w}x{h}_aa{aa}"] = core.trace(
                    f["position"], f["normal"], f["projection"], march="exact", mesh=mesh, antialias=aa,
                    max_distance=f.get("max_distance", 1e11))
    w, h = 960, 540
    proj = exact_cost.projection(w, h)
    cam = exact_cost.view_to_world(exact_cost.EYE, 0.0)
    for n in (100_000, 1_000_000):
        v, t, mat = exact_cost.scene(n)
        view = exact_cost.to_view(v, cam)
        P, N = exact_cost.gbuffer(view, t, mat, proj, w, h)
        kept = core.ExactScene(v.astype(np.float32), t)
        out[f"bench{n}_world"] = core.trace(P, N, proj, march="exact", mesh=kept.seen_from(cam),
                                            max_distance=exact_cost.MAX_DISTANCE, antialias=4)
        out[f"bench{n}_view"] = core.trace(P, N, proj, march="exact", mesh=(view.astype(np.float32), t),
                                           max_distance=exact_cost.MAX_DISTANCE)
    return out


def main() -> int:
    mode, path = sys.argv[2], sys.argv[3]
    now = outputs()
    if mode == "save":
        np.savez_compressed(path, **now)
        print(f"saved {len(now)} outputs to {path}")
        return 0
    before = np.load(path)
    differ = 0
    for key in before.files:
        pixels = int((before[key] != now[key]).any(-1).sum())
        if pixels:
            differ += 1
            print(f"{key}: {pixels} pixels differ")
    print(f"{len(before.files)} outputs, {differ} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
