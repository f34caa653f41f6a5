#!/usr/bin/env python3
"""composite_layers' outputs, saved from one build and compared bit for bit with another's.

For engineering changes that must not move a single bit (speed work on the CPU trace):
every march, CPU and GL, a real 1080p frame G-buffer (an .npz with position, normal,
specular, projection and the add-on's kwargs as JSON), rough materials, a back layer,
rasterized scenes (with the mesh for the exact march) and a noise G-buffer with NaN, Inf
and zeros, threads 1 and 2.

  /usr/bin/python3 bench/composite_identity.py OLD_BUILD/python save  FRAME.npz KW.json OUT_DIR
  /usr/bin/python3 bench/composite_identity.py NEW_BUILD/python check FRAME.npz KW.json OUT_DIR
"""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, sys.argv[1])
sys.path.insert(0, HERE)
import glint_core as core  # noqa: E402
from scene_meshes import floor, perspective, sphere  # noqa: E402

mode, frame, kw_path, out_dir = sys.argv[2:6]
os.makedirs(out_dir, exist_ok=True)
d = np.load(frame)
kw = json.load(open(kw_path))
p, n, s, pr = d["position"], d["normal"], d["specular"], d["projection"]
cases = {}
def add(name, fn):
    cases[name] = fn
add("floor_kw", lambda: core.composite_layers(p, n, s, pr, backend="cpu", **kw))
add("floor_kw_t1crop", lambda: core.composite_layers(p[300:600, 500:1100].copy(), n[300:600, 500:1100].copy(), s[300:600, 500:1100].copy(), pr, backend="cpu", threads=1, **kw))
add("floor_high_none", lambda: core.composite_layers(p, n, s, pr, backend="cpu", **dict(kw, resolution=1.0, steps=16, blocked="miss")))
add("floor_seed", lambda: core.composite_layers(p, n, s, pr, backend="cpu", **dict(kw, march="seed")))
s2 = s.copy(); yy, xx = np.mgrid[0:s.shape[0], 0:s.shape[1]]
s2[..., 3] = np.where(s[..., 0] > 0, ((xx * 7 + yy * 3) % 101) / 100.0, s[..., 3]).astype(np.float32)
add("floor_rough", lambda: core.composite_layers(p, n, s2, pr, backend="cpu", **kw))
back = p.copy(); back[..., 2] -= 0.3
add("floor_back", lambda: core.composite_layers(p, n, s, pr, backend="cpu", back_position=back, **kw))
# rasterized scene with mesh: exact, hiz with back, seed, linear, ortho-ish sizes
mats = np.array([[0, 0, 0, 0], [0.5, 0.5, 0.5, 127.75], [0.04, 0.04, 0.04, 30.0]], np.float32)
tp, tn, tm = (np.concatenate(x) for x in zip(floor(), sphere(24)))
for (w, h) in [(320, 240), (333, 197)]:
    proj = perspective(w, h)
    g = core.rasterize(tp, tn, tm, mats, proj, w, h, back_layer=True, backend="cpu")
    verts = tp.reshape(-1, 3).astype(np.float32); tris = np.arange(len(verts), dtype=np.int32).reshape(-1, 3)
    for m in ["hiz", "seed", "linear", "exact"]:
        for res in [0.3, 1.0]:
            for be in ["cpu", "gl"]:
                if be == "gl" and m == "exact":
                    continue
                add(f"raster{w}_{m}_{res}_{be}", lambda g=g, proj=proj, m=m, res=res, be=be, verts=verts, tris=tris: core.composite_layers(
                    g["position"], g["normal"], g["specular"], proj, backend=be, back_position=g["back_position"] if m == "hiz" else None,
                    mesh=(verts, tris) if m == "exact" else None, max_distance=15.0, resolution=res, steps=10, thickness=0.5, march=m, blocked="occluder"))
# noise with NaN / inf / zeros
rng = np.random.default_rng(5)
H, W = 61, 97
np_ = rng.normal(0, 1, (H, W, 4)).astype(np.float32); np_[..., 2] = -np.abs(np_[..., 2]) * 5 - 0.5; np_[..., 3] = (rng.random((H, W)) > 0.2)
nn = rng.normal(0, 1, (H, W, 4)).astype(np.float32); nn[..., 3] = 0
ns = rng.random((H, W, 4)).astype(np.float32) - 0.2
for arr in (np_, nn, ns):
    m = rng.random((H, W, 4)) < 0.03; arr[m] = np.nan
    m = rng.random((H, W, 4)) < 0.02; arr[m] = np.inf
    m = rng.random((H, W, 4)) < 0.02; arr[m] = -np.inf
    m = rng.random((H, W, 4)) < 0.05; arr[m] = 0.0
nproj = perspective(W, H)
for m in ["hiz", "seed", "linear"]:
    for res in [0.3, 1.0]:
        for t in [1, 2]:
            add(f"noise_{m}_{res}_{t}", lambda m=m, res=res, t=t: core.composite_layers(np_, nn, ns, nproj, backend="cpu", threads=t, back_position=np_ if m == "hiz" else None,
                max_distance=15.0, resolution=res, steps=10, thickness=0.5, march=m, blocked="occluder"))
        add(f"noise_{m}_{res}_gl", lambda m=m, res=res: core.composite_layers(np_, nn, ns, nproj, backend="gl", max_distance=15.0, resolution=res, steps=10, thickness=0.5, march=m))
only = sys.argv[6].split(",") if len(sys.argv) > 6 else None
bad = 0
for name, fn in cases.items():
    if only and not any(o in name for o in only):
        continue
    L = fn()
    arrs = {"uv": L["uv"], "weight": L["weight"], "meta": np.array([L["reflective_pixels"], int(L["any_rough"])])}
    path = os.path.join(out_dir, f"{name}.npz")
    if mode == "save":
        np.savez(path, **arrs); print("saved", name, L["reflective_pixels"], L["any_rough"])
    else:
        ref = np.load(path)
        ok = all(np.array_equal(ref[k], arrs[k], equal_nan=True) and ref[k].tobytes() == arrs[k].tobytes() for k in ref)
        if not ok:
            bad += 1
            for k in ref:
                if ref[k].tobytes() != arrs[k].tobytes():
                    diff = ref[k] != arrs[k]
                    print("  ", k, "differs at", np.argwhere(diff & ~(np.isnan(ref[k]) & np.isnan(arrs[k])))[:5])
        print("OK " if ok else "BAD", name)
print("bad", bad)
sys.exit(1 if bad else 0)
