#!/usr/bin/env python3
"""Cost of march="exact" beside the screen-space presets, measured in one run: a rippled
mirror floor under a field of boxes, tessellated to about N triangles, rasterized to a
G-buffer at --size, then traced.

Against triangle count: the mesh passed as arrays, so every call builds its BVH, and the
same triangles as an ExactScene built once:

  /usr/bin/python3 bench/exact_cost.py --size 960x540 --triangles 10000,100000,1000000

An animation (--frames N): one glint_core.ExactScene in world space; the first frame
builds its BVH, then N frames move the camera with the geometry unchanged (update() finds
the same vertices: reused), then N frames move the boxes (update() refits). Every frame
also runs `balanced` on the same G-buffer; exact's frame is its update() plus its trace:

  /usr/bin/python3 bench/exact_cost.py --size 960x540 --triangles 1000000 --frames 8
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
from scene_meshes import box  # noqa: E402  (bench/, beside this script)

# The camera 2 above the floor, looking 20 degrees down along -z (world y is up).
EYE = np.array([0.0, 2.0, 0.0])
PITCH = math.radians(20.0)
MAX_DISTANCE = 40.0


def floor_world(n_tri: int):
    """A rippled floor of ~n_tri triangles in world space, in front of the camera."""
    side = max(2, int(math.sqrt(n_tri / 2)))
    xs = np.linspace(-20.0, 20.0, side + 1)
    zs = np.linspace(-1.0, -60.0, side + 1)
    X, Z = np.meshgrid(xs, zs)
    Y = 0.05 * np.sin(X * 2.0) * np.cos(Z * 1.5)
    i = np.arange(side)[:, None] * (side + 1) + np.arange(side)[None, :]
    quads = np.stack([i, i + 1, i + side + 2, i + side + 1], -1).reshape(-1, 4)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return np.stack([X, Y, Z], -1).reshape(-1, 3), tris.astype(np.int32)


def boxes(count: int, offset=(0.0, 0.0, 0.0)):
    """`count` boxes 0.4-1.2 wide, 0.3-1.5 up, in world space, moved by `offset`."""
    rng = np.random.default_rng(1)
    verts, tris = [], []
    for k in range(count):
        c = rng.uniform([-8, 0.3, -30], [8, 1.5, -4]) + offset
        s = rng.uniform(0.2, 0.6, 3)
        corners, f = box(c - s, c + s)
        verts.append(corners)
        tris.append(f + 8 * k)
    return np.concatenate(verts), np.concatenate(tris).astype(np.int32)


def scene(n_tri: int, box_offset=(0.0, 0.0, 0.0)):
    """(world vertices float64 [N, 3], triangles int32 [M, 3], material per triangle)."""
    fv, ft = floor_world(n_tri - 12 * 40)
    bv, bt = boxes(40, box_offset)
    v = np.concatenate([fv, bv])
    t = np.concatenate([ft, bt + len(fv)])
    mat = np.zeros(len(t), np.int32)
    mat[len(ft):] = 1
    return v, t, mat


def view_to_world(eye, yaw: float) -> np.ndarray:
    """The camera's matrix: pitched down by PITCH, turned by `yaw` about world y, at `eye`."""
    cp, sp, cy, sy = math.cos(PITCH), math.sin(PITCH), math.cos(yaw), math.sin(yaw)
    pitch = np.array([[1, 0, 0], [0, cp, -sp], [0, sp, cp]])
    turn = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    m = np.eye(4)
    m[:3, :3] = turn @ pitch.T
    m[:3, 3] = eye
    return m


def projection(w: int, h: int) -> np.ndarray:
    return np.array([[1.0 / math.tan(0.5) / (w / h), 0, 0, 0], [0, 1.0 / math.tan(0.5), 0, 0],
                     [0, 0, -(100.1) / 99.9, -2 * 100 * 0.1 / 99.9], [0, 0, -1, 0]])


def to_view(v_world, cam: np.ndarray):
    """World -> view for a camera matrix that is a rotation and a translation."""
    return (v_world - cam[:3, 3]) @ cam[:3, :3]


def gbuffer(v_view, t, mat, proj, w: int, h: int):
    """Position and normal of the view-space mesh, rasterized."""
    pos = v_view[t]
    e1, e2 = pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0]
    nrm = np.cross(e1, e2)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True) + 1e-30
    normals = np.repeat(nrm[:, None, :], 3, axis=1).astype(np.float32)
    materials = np.array([[1, 1, 1, 1], [0, 0, 0, 0]], np.float32)
    g = glint_core.rasterize(pos.astype(np.float32), normals, mat, materials, proj.astype(np.float32), w, h)
    return g["position"], g["normal"]


def timed(call):
    t0 = time.perf_counter()
    out = call()
    return out, (time.perf_counter() - t0) * 1e3


def median_ms(call, repeat):
    call()
    return statistics.median(timed(call)[1] for _ in range(repeat))


def balanced(P, N, proj):
    return glint_core.trace(P, N, proj, **dict(glint_core.presets()["balanced"], max_distance=MAX_DISTANCE))


def by_triangle_count(w, h, counts, repeat):
    proj = projection(w, h)
    print(f"| triangles | exact ms | balanced ms | seed ms | exact / balanced |  ({w}x{h}, median of {repeat})")
    print("|---|---|---|---|---|")
    kept_rows = []
    for n in counts:
        # The boxes' coordinates taken as view space, as this table has always had them.
        fv, ft = floor_world(n - 12 * 40)
        bv, bt = boxes(40)
        v = np.concatenate([to_view(fv, view_to_world(EYE, 0.0)), bv]).astype(np.float32)
        t = np.concatenate([ft, bt + len(fv)])
        mat = np.zeros(len(t), np.int32)
        mat[len(ft):] = 1
        P, N = gbuffer(v, t, mat, proj, w, h)
        mesh = (v, t)
        exact = median_ms(lambda: glint_core.trace(P, N, proj, march="exact", mesh=mesh, max_distance=MAX_DISTANCE),
                          repeat)
        kept = glint_core.ExactScene(v, t)  # view space: mesh=kept needs no camera matrix
        kept_ms = median_ms(lambda: glint_core.trace(P, N, proj, march="exact", mesh=kept, max_distance=MAX_DISTANCE),
                            repeat)
        bal = median_ms(lambda: balanced(P, N, proj), repeat)
        seed = median_ms(lambda: glint_core.trace(P, N, proj, max_distance=MAX_DISTANCE), repeat)
        print(f"| {len(t):,} | {exact:.0f} | {bal:.0f} | {seed:.0f} | {exact / bal:.2f} |", flush=True)
        kept_rows.append(f"| {len(t):,} | {kept.last_update['ms']:.0f} | {kept_ms:.0f} | {bal:.0f} | {kept_ms / bal:.2f} |")
    print(f"\nThe same triangles as one ExactScene, built once, then traced:\n")
    print("| triangles | build ms | exact trace ms | balanced ms | exact / balanced |")
    print("|---|---|---|---|---|")
    print("\n".join(kept_rows))


def animation(w, h, n, frames):
    """Rows of (what, bvh work, bvh ms, exact trace ms, balanced ms) per frame."""
    proj = projection(w, h)
    v_world, t, mat = scene(n)
    rows = []

    def frame(what, cam, v, update):
        v_view = to_view(v, cam)
        P, N = gbuffer(v_view, t, mat, proj, w, h)  # the renderer's part, not timed
        report = update(v.astype(np.float32))
        uv, trace_ms = timed(lambda: glint_core.trace(P, N, proj, march="exact", mesh=kept.seen_from(cam),
                                                      max_distance=MAX_DISTANCE))
        _, bal_ms = timed(lambda: balanced(P, N, proj))
        rows.append((what, report["bvh"], report["ms"], trace_ms, bal_ms))
        print(f"  {what:8s} bvh {report['bvh']:6s} {report['ms']:7.1f} ms  trace {trace_ms:6.1f} ms  "
              f"balanced {bal_ms:6.1f} ms  hits {int((uv[..., 2] > 0).sum())}", file=sys.stderr, flush=True)
        if what == "camera":  # the call form without a scene: a BVH of its own every call
            mesh = (v_view.astype(np.float32), t)
            _, arrays_ms = timed(lambda: glint_core.trace(P, N, proj, march="exact", mesh=mesh,
                                                          max_distance=MAX_DISTANCE))
            rows.append(("arrays", "built", 0.0, arrays_ms, bal_ms))

    kept = None

    def build(v):
        nonlocal kept
        kept = glint_core.ExactScene(v, t)
        return kept.last_update

    frame("first", view_to_world(EYE, 0.0), v_world, build)
    for k in range(1, frames + 1):  # a dolly to the right, turning back towards the middle
        frame("camera", view_to_world(EYE + (0.15 * k, 0.02 * k, -0.1 * k), -0.01 * k), v_world, kept.update)
    cam = view_to_world(EYE + (0.15 * frames, 0.02 * frames, -0.1 * frames), -0.01 * frames)
    for k in range(1, frames + 1):  # the boxes slide along the floor
        moved, _, _ = scene(n, box_offset=(0.1 * k, 0.0, -0.05 * k))
        frame("objects", cam, moved, kept.update)
    return rows


def animation_table(rows, w, h, triangles, frames):
    print(f"| frames | bvh | bvh ms | exact trace ms | exact frame ms | balanced ms | exact / balanced |"
          f"  ({w}x{h}, {triangles:,} triangles; medians)")
    print("|---|---|---|---|---|---|---|")
    for what, label in (("first", "first frame"), ("camera", f"{frames} camera moves, geometry unchanged"),
                        ("objects", f"{frames} frames of moving boxes"),
                        ("arrays", "the camera moves, mesh=(vertices, triangles): a BVH every call")):
        sel = [r for r in rows if r[0] == what]
        work = "/".join(sorted({r[1] for r in sel}))
        bvh = statistics.median(r[2] for r in sel)
        trace = statistics.median(r[3] for r in sel)
        total = statistics.median(r[2] + r[3] for r in sel)
        bal = statistics.median(r[4] for r in sel)
        bvh_text = "in the trace" if what == "arrays" else f"{bvh:.1f}"
        print(f"| {label} | {work} | {bvh_text} | {trace:.0f} | {total:.0f} | {bal:.0f} | {total / bal:.2f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="960x540")
    ap.add_argument("--triangles", default="10000,100000,1000000")
    ap.add_argument("--repeat", type=int, default=3, help="calls per median, against triangle count")
    ap.add_argument("--frames", type=int, default=0,
                    help="an animation of this many camera frames and as many of moving boxes (0: the count sweep)")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    counts = [int(v) for v in args.triangles.split(",")]
    if args.frames <= 0:
        by_triangle_count(w, h, counts, args.repeat)
        return
    for n in counts:
        rows = animation(w, h, n, args.frames)
        animation_table(rows, w, h, len(scene(n)[1]), args.frames)


if __name__ == "__main__":
    main()
